// Tests of contour polyline merging (beyond the thesis; src/extract/detail/contour_merge.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/extract/contour.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

using namespace linesurf;

namespace {

// Closed 64-sided prism around the z axis, z in [-1, 1], widening with z (radius 1 + 0.3 z, so
// that no face is parallel to the z planes' normal: every face cuts at sin = 0.958, level 1,
// spacing d / 2 (§3.3), whatever the rounding of its normal). No seam, no caps.
constexpr int kSides = 64;
TriangleMesh coneMesh() {
  TriangleMesh m;
  const int nAlong = 4;
  for (int j = 0; j <= nAlong; ++j)
    for (int i = 0; i < kSides; ++i) {
      const double a = 2 * std::numbers::pi * i / kSides, z = 2.0 * j / nAlong - 1, r = 1 + 0.3 * z;
      m.positions.emplace_back(float(r * std::cos(a)), float(r * std::sin(a)), float(z));
    }
  auto id = [&](int i, int j) { return uint32_t(j * kSides + (i % kSides)); };
  for (int j = 0; j < nAlong; ++j)
    for (int i = 0; i < kSides; ++i) {
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

// Horizontal planes z = 0.025 + 0.05 k (level 1 of d = 0.1; never through a vertex row): 40
// closed contours, each a 64-gon cut into 128 pieces (two triangles per side).
constexpr size_t kCircles = 40;
ContourOptions horizontalCuts() {
  ContourOptions o;
  o.spacing = 0.1f;
  o.familySwitchSine = 0;  // P= wherever it cuts: closed contours
  o.planes = ContourPlanes{{Vec3d(0, 0, 1), Vec3d(1, 0, 0)}, {0.025 - 0.05, 0.0}};
  return o;
}

double distanceToSegment(const Vec3d& p, const Segment& s) {
  const Vec3d a = s.p0.cast<double>(), e = (s.p1 - s.p0).cast<double>();
  const double t = std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
  return (a + t * e - p).norm();
}

// The largest distance of an endpoint of `original` from the nearest segment of `merged` on the
// same plane (plane value of family 0 equal within 1e-5 d), and checks that every merged segment
// lies in one plane of that family.
double worstDeviation(const HybridModel& original, const HybridModel& merged, const ContourStats& st) {
  const Vec3d n = st.planes.normal[0];
  auto plane = [&](const Vec3f& p) { return (n.dot(p.cast<double>()) - st.planes.offset[0]) / st.spacing; };
  double worst = 0;
  for (const Segment& s : merged.segments) EXPECT_NEAR(plane(s.p0), plane(s.p1), 1e-5);
  for (const Segment& o : original.segments)
    for (const Vec3f& p : {o.p0, o.p1}) {
      double best = 1e30;
      for (const Segment& s : merged.segments)
        if (std::abs(plane(s.p0) - plane(p)) < 1e-5) best = std::min(best, distanceToSegment(p.cast<double>(), s));
      worst = std::max(worst, best);
    }
  return worst;
}

// The model cut with `o` and the same cut without merging.
struct MergedAndOriginal {
  HybridModel merged, original;
  ContourStats st, st0;
};
MergedAndOriginal cutBoth(const TriangleMesh& mesh, const ContourOptions& o) {
  ContourOptions off = o;
  off.mergeNormalDeviation = 0;
  MergedAndOriginal r;
  r.merged = extractContour(mesh, o, &r.st);
  r.original = extractContour(mesh, off, &r.st0);
  return r;
}

}  // namespace

TEST(ContourMerge, ConeCirclesBecomeTheirPolygonSides) {
  // Flat normals, a tiny deviation: the collinear pieces of a side merge and the corners (5.6
  // degrees of turn, >= 8e-4 of sagitta) stop it: 64 sides per circle, 65 when the loop starts
  // inside a side.
  const TriangleMesh mesh = coneMesh();
  ContourOptions o = horizontalCuts();
  o.endpointNormals = false;
  o.mergeNormalDeviation = o.mergeTangentDeviation = 1e-3f;  // x d = 1e-4
  o.mergeAngle = 1;
  const auto [merged, original, st, st0] = cutBoth(mesh, o);
  ASSERT_EQ(st0.halvedSpacing, mesh.faces.size());
  ASSERT_EQ(original.segments.size(), kCircles * 2 * kSides);
  EXPECT_EQ(st.segmentsBeforeMerge, original.segments.size());
  EXPECT_EQ(st.polylines, kCircles);
  EXPECT_GE(merged.segments.size(), kCircles * kSides);
  EXPECT_LE(merged.segments.size(), kCircles * (kSides + 1));
  EXPECT_EQ(st.segments, merged.segments.size());
  const double side = 2 * 1.3 * std::sin(std::numbers::pi / kSides);
  for (const Segment& s : merged.segments) EXPECT_LE(s.length(), side * (1 + 1e-5));
  EXPECT_LE(worstDeviation(original, merged, st), 1e-4);
  EXPECT_EQ(st0.polylines, 0u);  // no merging: no polylines looked for
}

TEST(ContourMerge, DeviationStaysWithinTheToleranceAndCountsFallAsItGrows) {
  // Across corners the chord of k sides of a 64-gon of radius r deviates by up to
  // r (1 - cos(k pi / 64)) (radially: 0.958 of it along the cone's normal, 0.29 along the
  // surface). Each tolerance bounds the deviation of every original vertex, and counts fall as it
  // grows.
  const TriangleMesh mesh = coneMesh();
  ContourOptions off = horizontalCuts();
  off.mergeNormalDeviation = 0;
  const HybridModel original = extractContour(mesh, off);
  size_t last = original.segments.size();
  for (float tol : {0.01f, 0.05f, 0.2f, 0.5f}) {
    SCOPED_TRACE(tol);
    ContourOptions o = horizontalCuts();
    o.mergeNormalDeviation = tol;
    o.mergeTangentDeviation = tol;
    o.mergeAngle = o.mergeStripAngle = 89;  // the deviation binds here
    ContourStats st;
    const HybridModel merged = extractContour(mesh, o, &st);
    EXPECT_LT(merged.segments.size(), last);
    last = merged.segments.size();
    EXPECT_LE(worstDeviation(original, merged, st), 1.0001 * std::hypot(tol, tol) * st.spacing);
    // Sides per merged segment: at most kMax (the smallest circle, the normal component alone
    // binding), and the greedy runs reach at least half of kMin (the largest circle, the radial
    // deviation within tol).
    auto sides = [&](double r, double tolRadial) {
      int k = 1;
      while (k < kSides && r * (1 - std::cos((k + 1) * std::numbers::pi / kSides)) <= tolRadial) ++k;
      return size_t(k);
    };
    const size_t kMax = sides(0.7, tol * st.spacing / 0.95), kMin = sides(1.3, tol * st.spacing);
    EXPECT_GE(merged.segments.size(), kCircles * (kSides / (kMax + 1)));
    EXPECT_LE(merged.segments.size(), kCircles * (kSides / std::max<size_t>(1, kMin / 2) + 2));
  }
  // At most mergeMaxPieces originals per segment.
  ContourOptions o = horizontalCuts();
  o.mergeNormalDeviation = o.mergeTangentDeviation = 1;
  o.mergeAngle = o.mergeStripAngle = 89;
  o.mergeMaxPieces = 4;
  const HybridModel four = extractContour(mesh, o);
  EXPECT_EQ(four.segments.size(), kCircles * 2 * kSides / 4);
}

TEST(ContourMerge, SmoothSphereKeepsNormalsAndNeverCrossesPlanes) {
  // Smooth model of a sphere: merged endpoint normals interpolated along a segment stay within the
  // angle of the radial direction (the sphere's normal) at every original vertex it replaced.
  const TriangleMesh mesh = shapes::sphereMesh(1.0f, 4);
  ContourOptions o;
  o.mergeAngle = 3;
  o.mergeNormalDeviation = 0.05f;
  const auto [merged, original, st, st0] = cutBoth(mesh, o);
  EXPECT_EQ(st.segmentsBeforeMerge, original.segments.size());
  EXPECT_LT(merged.segments.size(), original.segments.size() * 3 / 4);
  ASSERT_TRUE(merged.attributes.endpointNormals);
  // Every merged segment lies in one plane of one family.
  for (const Segment& s : merged.segments) {
    bool onePlane = false;
    for (int f = 0; f < 2; ++f) {
      const double v0 = st.planes.normal[f].dot(s.p0.cast<double>()), v1 = st.planes.normal[f].dot(s.p1.cast<double>());
      onePlane |= std::abs(v0 - v1) < 1e-5;
    }
    EXPECT_TRUE(onePlane);
    EXPECT_NEAR(s.normal0.norm(), 1, 1e-5);
    EXPECT_NEAR(s.normal1.norm(), 1, 1e-5);
    // the vertex normals at the ends, along-segment part kept (shading normals): radial on this
    // mesh
    EXPECT_GT(s.normal0.dot(s.p0.normalized()), 1 - 1e-5);
    EXPECT_GT(s.normal1.dot(s.p1.normalized()), 1 - 1e-5);
  }
  // At the original vertices a merged segment replaced (nearest merged segment of the same plane,
  // within the deviation): the endpoint normals interpolated as the renderer does agree with the
  // mesh's normal there (radial on the sphere up to the mesh's faceting): 3 degrees + 2 of slack.
  const double tol = std::hypot(o.mergeNormalDeviation, o.mergeTangentDeviation) * st.spacing * 1.0001;
  size_t checked = 0;
  for (const Segment& o0 : original.segments) {
    const Vec3d p = o0.p0.cast<double>();
    for (const Segment& s : merged.segments) {
      const Vec3d e = (s.p1 - s.p0).cast<double>();
      const double t = (p - s.p0.cast<double>()).dot(e) / e.squaredNorm();
      if (t <= 1e-3 || t >= 1 - 1e-3 || distanceToSegment(p, s) > tol) continue;
      bool samePlane = false;
      for (int f = 0; f < 2; ++f)
        samePlane |= std::abs(st.planes.normal[f].dot(p - s.p0.cast<double>())) < 1e-6 &&
                     std::abs(st.planes.normal[f].dot(e)) < 1e-6;
      if (!samePlane) continue;
      const Vec3d n = (s.normal0.cast<double>() + t * (s.normal1 - s.normal0).cast<double>()).normalized();
      Vec3d radial = p.normalized();
      radial -= radial.dot(e.normalized()) * e.normalized();
      EXPECT_GT(n.dot(radial.normalized()), std::cos(5 * std::numbers::pi / 180));
      ++checked;
    }
  }
  EXPECT_GT(checked, original.segments.size() / 4);
}

TEST(ContourMerge, StripTiltHasItsOwnLimitOnSmoothModelsOnly) {
  // Smooth sphere: a looser strip limit merges more, each merged strip plane stays within it of
  // the sphere's normal (up to the faceting of the pieces' planes), and the shading normals keep
  // mergeAngle (checked in SmoothSphereKeepsNormalsAndNeverCrossesPlanes). Flat models ignore it.
  const TriangleMesh mesh = shapes::sphereMesh(1.0f, 4);
  auto cut = [&](float strip, bool smooth) {
    ContourOptions o;
    o.mergeAngle = 2;
    o.mergeStripAngle = strip;
    o.mergeNormalDeviation = 0.05f;
    o.endpointNormals = smooth;
    return extractContour(mesh, o);
  };
  const HybridModel tight = cut(2, true), loose = cut(6, true);
  EXPECT_LT(loose.segments.size(), tight.segments.size());
  auto worstTilt = [](const HybridModel& m) {
    double worst = 0;
    for (const Segment& s : m.segments) {
      const Vec3d e = (s.p1 - s.p0).cast<double>().normalized();
      Vec3d radial = (0.5 * (s.p0 + s.p1)).cast<double>().normalized();
      radial = (radial - radial.dot(e) * e).normalized();
      worst = std::max(worst, std::acos(std::clamp(s.normal.cast<double>().dot(radial), -1.0, 1.0)) * 180 / std::numbers::pi);
    }
    return worst;
  };
  const double faceting = 3;  // the pieces' planes lean from the radial direction by up to ~3 degrees here
  EXPECT_LE(worstTilt(tight), 2 + faceting);
  EXPECT_LE(worstTilt(loose), 6 + faceting);
  EXPECT_GT(worstTilt(loose), worstTilt(tight));
  const HybridModel flatTight = cut(2, false), flatLoose = cut(6, false);
  ASSERT_EQ(flatTight.segments.size(), flatLoose.segments.size());
  for (size_t i = 0; i < flatTight.segments.size(); ++i) EXPECT_EQ(flatTight.segments[i].p1, flatLoose.segments[i].p1);
  ContourOptions bad;
  bad.mergeStripAngle = 90;
  EXPECT_THROW(validate(bad), OptionError);
}

TEST(ContourMerge, NeverAcrossAPolylineBreak) {
  // Two flat grids meeting along x = 0.5 with duplicated vertices there (a seam): every contour
  // is one straight line, but the polylines break at the seam, so no merged segment crosses it.
  TriangleMesh a = shapes::gridMesh(8, 8), mesh = a;
  for (Vec3f& p : a.positions) p.x() += 1.0f;
  const uint32_t nv = uint32_t(mesh.positions.size());
  mesh.positions.insert(mesh.positions.end(), a.positions.begin(), a.positions.end());
  for (auto f : a.faces) mesh.faces.push_back({f[0] + nv, f[1] + nv, f[2] + nv});
  mesh.cornerUVs.clear();
  mesh.normals.clear();
  float xmin = 1e9f, xmax = -1e9f;
  for (const Vec3f& p : shapes::gridMesh(8, 8).positions) xmin = std::min(xmin, p.x()), xmax = std::max(xmax, p.x());
  const float seam = xmax;  // the first grid's right edge = the second's left edge
  ASSERT_NEAR(xmin + 1.0f, seam, 1e-6f) << "gridMesh is expected to span 1 in x";
  ContourOptions o;
  o.spacing = 0.07f;
  o.planes = ContourPlanes{{Vec3d(0, 1, 0).normalized(), Vec3d(1, 0, 0)}, {0.013, 0.0}};
  o.familySwitchSine = 0;
  o.mergeMaxPieces = 1000;
  ContourStats st;
  const HybridModel merged = extractContour(mesh, o, &st);
  ASSERT_GT(merged.segments.size(), 0u);
  for (const Segment& s : merged.segments) {
    const float lo = std::min(s.p0.x(), s.p1.x()), hi = std::max(s.p0.x(), s.p1.x());
    EXPECT_TRUE(hi <= seam + 1e-6f || lo >= seam - 1e-6f) << lo << " .. " << hi;
  }
  // Planes y = 0.013 + 0.07 k, k = 0..14, cross both grids: 15 straight contours, each broken
  // at the seam into two polylines, each polyline one segment (its flat collinear pieces merged).
  EXPECT_EQ(st.polylines, 2u * 15u);
  EXPECT_EQ(merged.segments.size(), st.polylines);
  EXPECT_EQ(st.segmentsBeforeMerge, 2u * 15u * 16u);  // two triangles per column, 8 columns
}

TEST(ContourMerge, DeterministicForAnyThreadCountAndReportedByTheCli) {
  const TriangleMesh mesh = shapes::sphereMesh(1.0f, 4);
  ContourStats st;
  const HybridModel a = extractContour(mesh, {}, &st);
  ASSERT_LT(st.segments, st.segmentsBeforeMerge);  // the default merges
  HybridModel b;
  {
    ThreadLimit one(1);
    b = extractContour(mesh);
  }
  ASSERT_EQ(a.segments.size(), b.segments.size());
  for (size_t i = 0; i < a.segments.size(); ++i) {
    const Segment &x = a.segments[i], &y = b.segments[i];
    ASSERT_TRUE(x.p0 == y.p0 && x.p1 == y.p1 && x.normal == y.normal && x.normal0 == y.normal0 && x.normal1 == y.normal1 &&
                x.color == y.color)
        << i;
  }
  // The CLI on the mesh as written (and read back: the counts of that mesh).
  auto dir = test::scratchDir("contour_merge_cli");
  writeMesh(dir / "sphere.ply", mesh);
  extractContour(readMesh(dir / "sphere.ply"), {}, &st);
  auto r = test::runCli(fmt::format("extract contour {} -o {}", (dir / "sphere.ply").string(), (dir / "lines.ply").string()));
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find(fmt::format("{} segments merged into {} along {} contour polylines", st.segmentsBeforeMerge,
                                   st.segments, st.polylines)),
            std::string::npos)
      << r.out;
  EXPECT_EQ(readModel(dir / "lines.ply").segments.size(), st.segments);
  auto none = test::runCli(fmt::format("extract contour {} -o {} --merge-normal-deviation 0", (dir / "sphere.ply").string(),
                                       (dir / "raw.ply").string()));
  ASSERT_EQ(none.exitCode, 0) << none.out;
  EXPECT_EQ(readModel(dir / "raw.ply").segments.size(), st.segmentsBeforeMerge);
  EXPECT_EQ(test::runCli(fmt::format("extract contour {} -o {} --merge-angle 90", (dir / "sphere.ply").string(),
                                     (dir / "x.ply").string()))
                .exitCode,
            1);
}
