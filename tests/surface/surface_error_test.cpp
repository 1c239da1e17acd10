// The surface error of an extraction (surface/surface_error.h): shapes with known answers (an
// extraction lying on its surface, a known offset, a cut-off cap), meshes, bad input, threads.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <string>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/surface/surface_error.h"
#include "linesurf/extract/contour.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/geometry/point_geometry.h"
#include "shapes.h"

namespace linesurf {
namespace {

struct Extraction {
  HybridModel cloud, hybrid;
  double spacing = 0;
};

Extraction epsDelta(HybridModel cloud) {
  GeometryOptions go;
  const PointGeometry geo = computePointGeometry(cloud, go);
  Extraction e;
  applyGeometry(cloud, geo);
  e.hybrid = extractEpsDelta(cloud, geo, {});
  e.cloud = std::move(cloud);
  e.spacing = geo.averageSpacing;
  return e;
}

HybridModel moved(HybridModel m, const std::function<Vec3f(const Vec3f&)>& f) {
  for (Point& p : m.points) p.position = f(p.position);
  for (Segment& s : m.segments) s.p0 = f(s.p0), s.p1 = f(s.p1);
  return m;
}

std::string messageOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(SurfaceError, AnExtractionOnItsPlaneHasNoError) {
  const Extraction e = epsDelta(shapes::plane(2, 1, 80, 40));
  ASSERT_GT(e.hybrid.segments.size(), 20u);
  const SurfaceError r = surfaceError(e.cloud, e.hybrid);
  EXPECT_NEAR(r.epsilonRef, 0.05 * e.spacing, 0.05 * e.spacing * 0.2);  // its own spacing, within 20% of §6.1's
  EXPECT_EQ(r.fromReference.samples, 3200u);
  EXPECT_GT(r.fromModel.samples, 2000u);  // points plus points along the segments, an average spacing apart
  EXPECT_EQ(r.failures(), 0u);
  EXPECT_LT(r.both.max, 0.01 * r.epsilonRef);
  EXPECT_NEAR(r.diagonal, std::sqrt(5.0), 0.05);
}

TEST(SurfaceError, AnExtractionOfASphereStaysWellBelowEpsilon) {
  const Extraction e = epsDelta(shapes::sphere(1, 20000, {.seed = 2}));
  ASSERT_GT(e.hybrid.segments.size(), 1000u);
  const SurfaceError r = surfaceError(e.cloud, e.hybrid);
  // Segments are chords within epsilon of the points they replace, sagging inside the sphere
  // (measured: RMS 0.44, 99th percentile 0.97 epsilon_ref).
  EXPECT_LT(r.both.rms, 0.6 * r.epsilonRef);
  EXPECT_LT(r.both.p99, 1.5 * r.epsilonRef);
  EXPECT_LT(double(r.failures()), 1e-3 * double(r.both.samples));
}

TEST(SurfaceError, AModelMovedAlongTheNormalReadsItsOffset) {
  const HybridModel plane = shapes::plane(2, 1, 80, 40);
  const float d = 0.004f;  // a sixth of the spacing
  const SurfaceError p = surfaceError(plane, moved(plane, [&](const Vec3f& x) -> Vec3f { return x + Vec3f(0, 0, d); }));
  EXPECT_NEAR(p.both.rms, d, 1e-3 * d);  // f is exactly the distance to z = d
  EXPECT_NEAR(p.both.max, d, 1e-3 * d);
  EXPECT_EQ(p.failures(), 0u);
  // A sphere moved outward by d: the same sampling on a sphere of radius 1 + d, so the surfaces'
  // curvature biases cancel to O(d) and every sample reads d.
  const Extraction e = epsDelta(shapes::sphere(1, 20000, {.seed = 2}));
  const double offset = 0.25 * e.spacing;  // 5 epsilon_ref
  const auto out = [&](const Vec3f& x) -> Vec3f { return x * float(1 + offset); };
  const SurfaceError c = surfaceError(e.cloud, moved(e.cloud, out));
  EXPECT_NEAR(c.both.rms, offset, 0.02 * offset);
  EXPECT_NEAR(c.both.p99, offset, 0.05 * offset);
  EXPECT_EQ(c.failures(), 0u);
  // Its hybrid moved so: the offset adds to the extraction's own error (RMS 0.44 epsilon_ref).
  const SurfaceError h0 = surfaceError(e.cloud, e.hybrid);
  const SurfaceError h = surfaceError(e.cloud, moved(e.hybrid, out));
  EXPECT_NEAR(h.both.rms, offset, h0.both.rms + 0.02 * offset);
  EXPECT_NEAR(h.fromReference.rms, offset, h0.fromReference.rms + 0.02 * offset);
  EXPECT_NEAR(h.fromModel.rms, offset, h0.fromModel.rms + 0.02 * offset);
  EXPECT_GT(h.both.rms / h.epsilonRef, 4.0);
}

TEST(SurfaceError, BothWaysCatchAMissingCap) {
  const HybridModel sphere = shapes::sphere(1, 20000, {.seed = 4});
  HybridModel cut = sphere;
  std::erase_if(cut.points, [](const Point& p) { return p.position.z() > 0.8f; });
  const SurfaceError r = surfaceError(sphere, cut);
  // The input's points on the cap find no model surface there: far in the max, and counted.
  EXPECT_GT(r.fromReference.max, 0.3);  // the cap's radius is 0.6
  EXPECT_GT(r.fromReference.failedModel, 100u);
  EXPECT_EQ(r.both.max, r.fromReference.max);
  // The model's own samples lie on the input's surface: only one way sees the hole.
  EXPECT_LT(r.fromModel.p99, r.epsilonRef);
  EXPECT_EQ(r.fromModel.failedReference, 0u);
}

TEST(SurfaceError, ContourLinesAgainstTheirMesh) {
  const TriangleMesh mesh = shapes::sphereMesh(1, 5);
  const HybridModel lines = extractContour(mesh, {});
  ASSERT_GT(lines.segments.size(), 1000u);
  const SurfaceError r = surfaceError(mesh, lines);
  EXPECT_TRUE(r.meshReference);
  EXPECT_EQ(r.failures(), 0u);
  // The lines lie on the mesh's faces; their surface leaves the flat faces by a fraction of the
  // faces' own sag (measured: RMS 0.036, max 0.096 epsilon_ref).
  EXPECT_LT(r.both.rms, 0.1 * r.epsilonRef);
  EXPECT_LT(r.both.max, 0.3 * r.epsilonRef);
  // A grid mesh against its vertices lifted by a tenth of an edge: the closest points are exact
  // and the cloud's surface is its plane, so both ways read the lift.
  const TriangleMesh grid = shapes::gridMesh(40, 40);
  HybridModel lifted;
  for (const Vec3f& v : grid.positions) {
    Point p;
    p.position = v + Vec3f(0, 0, 0.1f / 40);
    p.normal = Vec3f(0, 0, 1);
    lifted.points.push_back(p);
  }
  lifted.attributes.normals = true;
  const SurfaceError m = surfaceError(grid, lifted);
  EXPECT_EQ(m.failures(), 0u);
  EXPECT_EQ(m.fromReference.samples, 41u * 41u);
  EXPECT_NEAR(m.fromReference.rms, 0.1 / 40, 1e-6);
  EXPECT_NEAR(m.fromModel.max, 0.1 / 40, 1e-6);
}

TEST(SurfaceError, SamplesAreStridedAndTheSameForAnyThreadCount) {
  const Extraction e = epsDelta(shapes::sphere(1, 8000, {.irregular = true, .seed = 6}));
  SurfaceErrorOptions o;
  o.samples = 1000;
  SurfaceError one, two;
  {
    ThreadLimit limit(1);
    one = surfaceError(e.cloud, e.hybrid, o);
  }
  {
    ThreadLimit limit(2);
    two = surfaceError(e.cloud, e.hybrid, o);
  }
  EXPECT_EQ(one.fromReference.samples, 1000u);
  EXPECT_EQ(one.fromModel.samples, 1000u);
  EXPECT_EQ(one.both.rms, two.both.rms);
  EXPECT_EQ(one.both.p99, two.both.p99);
  EXPECT_EQ(one.both.max, two.both.max);
  EXPECT_EQ(one.failures(), two.failures());
}

TEST(SurfaceError, RefusesBadInputInOneLine) {
  const HybridModel sphere = shapes::sphere(1, 2000);
  HybridModel noNormals = sphere;
  noNormals.attributes.normals = false;
  HybridModel nan = sphere;
  nan.points[7].position.x() = NAN;
  const HybridModel empty;
  TriangleMesh flat;
  flat.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(2, 0, 0)};
  flat.faces = {{0, 1, 2}};
  TriangleMesh outOfRange = flat;
  outOfRange.faces = {{0, 1, 5}};
  const std::string cases[] = {
      messageOf([&] { surfaceError(noNormals, sphere); }), messageOf([&] { surfaceError(sphere, noNormals); }),
      messageOf([&] { surfaceError(nan, sphere); }),       messageOf([&] { surfaceError(sphere, nan); }),
      messageOf([&] { surfaceError(empty, sphere); }),     messageOf([&] { surfaceError(sphere, empty); }),
      messageOf([&] { surfaceError(flat, sphere); }),      messageOf([&] { surfaceError(outOfRange, sphere); }),
      messageOf([&] { surfaceError(TriangleMesh{}, sphere); }),
  };
  const char* names[] = {"cloud", "model", "cloud", "model", "cloud", "model", "mesh", "mesh", "mesh"};
  for (size_t i = 0; i < std::size(cases); ++i) {
    EXPECT_NE(cases[i].find(names[i]), std::string::npos) << i << ": " << cases[i];
    EXPECT_EQ(cases[i].find('\n'), std::string::npos) << i;
  }
  EXPECT_NE(cases[0].find("normals"), std::string::npos) << cases[0];
  SurfaceErrorOptions o;
  o.samples = 10;
  EXPECT_THROW(validate(o), OptionError);
  o.samples = 1000;
  o.mls.supportScale = 0.5f;
  EXPECT_THROW(validate(o), OptionError);
}

}  // namespace
}  // namespace linesurf
