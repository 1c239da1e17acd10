// Smooth line models (issue 14): endpoint normals filled by the three extraction methods, kept
// through PLY (nx0 ny0 nz0 nx1 ny1 nz1 in `element segment`).
#include <gtest/gtest.h>

#include "linesurf/core/shapes.h"
#include "linesurf/extract/contour.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

namespace linesurf {
namespace {

// Every segment's endpoint normals: unit, perpendicular to it, within `cosTol` of the sphere's
// radial direction at the endpoint (the exact normal of a sphere about the origin).
template <class Exact>
void expectEndpointNormals(const HybridModel& m, float cosTol, Exact&& exact) {
  ASSERT_TRUE(m.attributes.endpointNormals);
  ASSERT_FALSE(m.segments.empty());
  float worst = 1, worstPerp = 0;
  for (const Segment& s : m.segments) {
    const Vec3f dir = (s.p1 - s.p0).normalized();
    for (const auto& [p, n] : {std::pair{s.p0, s.normal0}, std::pair{s.p1, s.normal1}}) {
      EXPECT_NEAR(n.norm(), 1.0f, 1e-5f);
      worstPerp = std::max(worstPerp, std::abs(n.dot(dir)));
      worst = std::min(worst, n.dot(exact(p)));
    }
  }
  EXPECT_LT(worstPerp, 1e-5f);
  EXPECT_GT(worst, cosTol);
}
void expectRadialEndpointNormals(const HybridModel& m, float cosTol) {
  expectEndpointNormals(m, cosTol, [](const Vec3f& p) { return Vec3f(p.normalized()); });
}

TEST(SmoothLines, ContourEndpointNormalsFromAreaWeightedVertexNormals) {
  TriangleMesh mesh = shapes::sphereMesh(1, 2);
  mesh.normals.clear();  // area-weighted normals are computed
  ContourOptions smooth;
  smooth.mergeNormalDeviation = 0;  // one segment per face and plane, as the flat cut below
  const HybridModel lines = extractContour(mesh, smooth);
  // the interpolated vertex normal is exactly radial on a chord of the sphere; made
  // perpendicular to the segment it stays within ~11 degrees on a 320-face icosphere, and on
  // average it is twice as close to the radial direction as the face normal (measured)
  expectRadialEndpointNormals(lines, 0.98f);
  ContourOptions flat = smooth;
  flat.endpointNormals = false;
  const HybridModel thesis = extractContour(mesh, flat);
  EXPECT_FALSE(thesis.attributes.endpointNormals);
  ASSERT_EQ(thesis.segments.size(), lines.segments.size());
  double endMean = 0, faceMean = 0;
  for (size_t i = 0; i < lines.segments.size(); ++i) {
    const Segment& s = lines.segments[i];
    const Segment& t = thesis.segments[i];  // same cut, the triangle's normal
    endMean += 0.5 * (s.normal0.dot(s.p0.normalized()) + s.normal1.dot(s.p1.normalized()));
    faceMean += 0.5 * (t.normal.dot(t.p0.normalized()) + t.normal.dot(t.p1.normalized()));
    // the smooth segment's strip plane follows the vertex normals too: interpolated at the
    // midpoint, perpendicular to the segment, at most 10 degrees from the triangle's normal
    EXPECT_LT(std::abs(s.normal.dot((s.p1 - s.p0).normalized())), 1e-4f);
    EXPECT_GE(s.normal.dot(t.normal), std::cos(10.0f * 3.14159265f / 180.0f) - 1e-5f);
    EXPECT_GT(s.normal.dot((0.5f * (s.p0 + s.p1)).normalized()), 0.98f);
  }
  endMean /= double(lines.segments.size());
  faceMean /= double(lines.segments.size());
  EXPECT_GT(1 - faceMean, 1.5 * (1 - endMean)) << endMean << " " << faceMean;
}

TEST(SmoothLines, PlyRoundTripKeepsEndpointNormals) {
  const HybridModel lines = extractContour(shapes::sphereMesh(1, 2));
  const auto dir = test::scratchDir("smooth_lines_ply");
  for (bool ascii : {false, true}) {
    const auto path = dir / (ascii ? "a.ply" : "b.ply");
    WriteOptions wo;
    if (ascii) wo.encoding = PlyEncoding::Ascii;
    writeModel(path, lines, wo);
    const HybridModel back = readModel(path);
    ASSERT_TRUE(back.attributes.endpointNormals);
    ASSERT_EQ(back.segments.size(), lines.segments.size());
    for (size_t i = 0; i < lines.segments.size(); ++i) {
      EXPECT_EQ(back.segments[i].normal0, lines.segments[i].normal0) << i;
      EXPECT_EQ(back.segments[i].normal1, lines.segments[i].normal1) << i;
    }
  }
  HybridModel plain = lines;
  plain.attributes.endpointNormals = false;
  writeModel(dir / "c.ply", plain);
  EXPECT_FALSE(readModel(dir / "c.ply").attributes.endpointNormals);
}

TEST(SmoothLines, PointCloudMethodsTakeTheEndPointsNormals) {
  // a cylinder about z: rows along the axis for (eps, delta), exact normals radial in xy
  HybridModel cloud = shapes::cylinder(1, 2, 120, 60);
  GeometryOptions go;
  const PointGeometry geo = computePointGeometry(cloud, go);
  applyGeometry(cloud, geo);
  const HybridModel ed = extractEpsDelta(cloud, geo);
  ShapeApproxOptions so;
  const HybridModel sa = extractShapeApprox(cloud, geo, clusterShapeApprox(geo, so), so);
  auto radialXY = [](const Vec3f& p) { return Vec3f(Vec3f(p.x(), p.y(), 0).normalized()); };
  expectEndpointNormals(ed, 0.999f, radialXY);
  expectEndpointNormals(sa, 0.999f, radialXY);
  EpsDeltaOptions flat;
  flat.endpointNormals = false;
  EXPECT_FALSE(extractEpsDelta(cloud, geo, flat).attributes.endpointNormals);
}

}  // namespace
}  // namespace linesurf
