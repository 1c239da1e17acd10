// Smooth line models (beyond the thesis): endpoint normals filled by the three extraction methods,
// kept through PLY (nx0 ny0 nz0 nx1 ny1 nz1 in `element segment`); point shading normals (snx sny
// snz in `element vertex`) filled by contour extraction, kept through PLY, bad ones refused.
#include <gtest/gtest.h>

#include <fstream>

#include "linesurf/core/error.h"
#include "shapes.h"
#include "linesurf/extract/contour.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

namespace linesurf {
namespace {

// Every segment's endpoint normals: unit, perpendicular to it, within `cosTol` of the exact
// normal at the endpoint (e.g. the radial direction on a sphere about the origin).
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
  smooth.shadingNormals = false;    // endpoint normals made perpendicular (no shading normals)
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

// `model` written to the scratch folder `name` as binary and as ascii PLY, each read back and
// handed to check(back); returns the folder.
template <class Check>
std::filesystem::path roundTripBothEncodings(const HybridModel& model, const std::string& name, Check&& check) {
  const auto dir = test::scratchDir(name);
  for (bool ascii : {false, true}) {
    const auto path = dir / (ascii ? "a.ply" : "b.ply");
    WriteOptions wo;
    if (ascii) wo.encoding = PlyEncoding::Ascii;
    writeModel(path, model, wo);
    check(readModel(path));
  }
  return dir;
}

TEST(SmoothLines, PlyRoundTripKeepsEndpointNormals) {
  const HybridModel lines = extractContour(shapes::sphereMesh(1, 2));
  roundTripBothEncodings(lines, "smooth_lines_ply", [&](const HybridModel& back) {
    ASSERT_TRUE(back.attributes.endpointNormals);
    ASSERT_EQ(back.segments.size(), lines.segments.size());
    for (size_t i = 0; i < lines.segments.size(); ++i) {
      EXPECT_EQ(back.segments[i].normal0, lines.segments[i].normal0) << i;
      EXPECT_EQ(back.segments[i].normal1, lines.segments[i].normal1) << i;
    }
  });
}

// Shading normals (default): on a sphere mesh with exact radial vertex normals the interpolated
// vertex normal at any point of a face is exactly radial (sum of w_i v_i is the point itself),
// so every contour point's shading normal and every endpoint normal is the radial direction,
// while the points' planes stay as without shading normals.
TEST(SmoothLines, ContourShadingNormalsAreTheInterpolatedVertexNormals) {
  const TriangleMesh mesh = shapes::sphereMesh(1, 2);
  ASSERT_EQ(mesh.normals.size(), mesh.positions.size());
  ContourOptions o;
  o.allPoints = true;
  const HybridModel pts = extractContour(mesh, o);
  ASSERT_TRUE(pts.attributes.shadingNormals);
  ASSERT_EQ(pts.pointShadingNormals.size(), pts.points.size());
  ASSERT_GT(pts.points.size(), 500u);
  ContourOptions without = o;
  without.shadingNormals = false;
  const HybridModel plain = extractContour(mesh, without);
  EXPECT_FALSE(plain.attributes.shadingNormals);
  EXPECT_TRUE(plain.pointShadingNormals.empty());
  ASSERT_EQ(plain.points.size(), pts.points.size());
  size_t differ = 0;
  for (size_t i = 0; i < pts.points.size(); ++i) {
    const Vec3f& n = pts.pointShadingNormals[i];
    EXPECT_NEAR(n.norm(), 1.0f, 1e-6f) << i;
    EXPECT_GT(n.dot(pts.points[i].position.normalized()), 1 - 1e-6f) << i;
    EXPECT_EQ(pts.points[i].normal, plain.points[i].normal) << i;  // the plane is unchanged
    differ += n.dot(pts.points[i].normal) < std::cos(1.0f * 3.14159265f / 180.0f);
  }
  EXPECT_GT(differ, pts.points.size() / 4);  // shading and plane normals are separate

  // lines (merged polylines too): endpoint normals radial, keeping their along-segment part
  const HybridModel lines = extractContour(mesh);
  ASSERT_TRUE(lines.attributes.endpointNormals);
  EXPECT_FALSE(lines.attributes.shadingNormals);  // no points
  float along = 0;
  for (const Segment& s : lines.segments) {
    const Vec3f dir = (s.p1 - s.p0).normalized();
    for (const auto& [p, n] : {std::pair{s.p0, s.normal0}, std::pair{s.p1, s.normal1}}) {
      EXPECT_NEAR(n.norm(), 1.0f, 1e-6f);
      EXPECT_GT(n.dot(p.normalized()), 1 - 1e-5f);
      along = std::max(along, std::abs(n.dot(dir)));
    }
  }
  EXPECT_GT(along, 0.1f);
}

TEST(SmoothLines, PlyRoundTripKeepsPointShadingNormalsAndMasses) {
  ContourOptions o;
  o.allPoints = true;
  const HybridModel pts = extractContour(shapes::sphereMesh(1, 1), o);
  ASSERT_TRUE(pts.attributes.shadingNormals);
  const auto dir = roundTripBothEncodings(pts, "shading_normals_ply", [&](const HybridModel& back) {
    ASSERT_TRUE(back.attributes.shadingNormals);
    // the shading normals are not read as extra properties; the masses are the one property
    ASSERT_EQ(back.pointProperties.size(), 1u);
    ASSERT_NE(pointMasses(back), nullptr);
    EXPECT_EQ(*pointMasses(back), *pointMasses(pts));
    ASSERT_EQ(back.pointShadingNormals.size(), pts.points.size());
    for (size_t i = 0; i < pts.points.size(); ++i) {
      EXPECT_EQ(back.pointShadingNormals[i], pts.pointShadingNormals[i]) << i;
      EXPECT_EQ(back.points[i].normal, pts.points[i].normal) << i;
    }
  });
  HybridModel plain = pts;
  plain.attributes.shadingNormals = false;
  writeModel(dir / "c.ply", plain);
  const HybridModel back = readModel(dir / "c.ply");
  EXPECT_FALSE(back.attributes.shadingNormals);
  EXPECT_TRUE(back.pointShadingNormals.empty());
}

// Bad shading normals: one line naming the file and the row, when reading and when writing.
TEST(SmoothLines, BadShadingNormalsAreRefused) {
  const auto dir = test::scratchDir("shading_normals_bad");
  auto write = [&](const std::string& name, const std::string& props, const std::string& rows) {
    const auto path = dir / name;
    std::ofstream(path) << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                           "property float z\n" << props << "end_header\n" << rows;
    return path;
  };
  auto messageOf = [](const std::filesystem::path& path) -> std::string {
    try {
      readModel(path);
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), Error::Kind::BadInput);
      return e.what();
    }
    return "(no error)";
  };
  const std::string sn = "property float snx\nproperty float sny\nproperty float snz\n";
  const auto zero = write("zero.ply", sn, "0 0 0 0 0 1\n1 0 0 0 0 0\n");
  EXPECT_EQ(messageOf(zero), zero.string() + ": element vertex 1: shading normal (0, 0, 0) is not unit length (|n| = 0)");
  const auto longer = write("long.ply", sn, "0 0 0 0 0 1\n1 0 0 0 2 0\n");
  EXPECT_EQ(messageOf(longer), longer.string() + ": element vertex 1: shading normal (0, 2, 0) is not unit length (|n| = 2)");
  const auto nan = write("nan.ply", sn, "0 0 0 nan 0 1\n1 0 0 0 0 1\n");
  EXPECT_EQ(messageOf(nan).rfind(nan.string() + ": line ", 0), 0u) << messageOf(nan);
  const auto partial = write("partial.ply", "property float snx\nproperty float sny\n", "0 0 0 0 1\n1 0 0 0 1\n");
  EXPECT_NE(messageOf(partial).find("some but not all of the properties 'snx sny snz' (no 'snz')"), std::string::npos)
      << messageOf(partial);
  const auto good = write("good.ply", sn, "0 0 0 0 0 1\n1 0 0 0.6 0 0.8\n");
  EXPECT_EQ(readModel(good).pointShadingNormals.size(), 2u);

  // writing: the same validation (kind Io), and the count must match the points
  HybridModel m = readModel(good);
  m.pointShadingNormals[0] = Vec3f(NAN, 0, 1);
  try {
    writeModel(dir / "out.ply", m);
    ADD_FAILURE() << "NaN shading normal written";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::Io);
    EXPECT_NE(std::string(e.what()).find("element vertex 0: shading normal has a non-finite component (nan)"), std::string::npos)
        << e.what();
  }
  m.pointShadingNormals.pop_back();
  try {
    writeModel(dir / "out.ply", m);
    ADD_FAILURE() << "1 shading normal for 2 points written";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("1 shading normals for 2 points"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "out.ply"));
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
