// Tests of the §3.2.4 shape-approximation segment extraction.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"

using namespace linesurf;

namespace {

/// Geometry of a grid-sampled shape (index j * nu + i) built by hand: exact normals, the
/// triangulated grid as local Delaunay neighbours, a given minimum-curvature direction.
PointGeometry gridGeometry(const HybridModel& cloud, int nu, int nv, bool wrapU, Vec3f kmin = Vec3f::Zero()) {
  PointGeometry g;
  const size_t n = cloud.points.size();
  for (const Point& p : cloud.points) {
    g.normals.push_back(p.normal);
    g.surfaceVariation.push_back(0.0f);
    g.spacing.push_back(p.radius);
  }
  if (kmin.squaredNorm() > 0) g.minCurvatureDir.assign(n, kmin);
  g.flags.assign(n, 0);
  g.delaunayOffsets.push_back(0);
  const int di[6] = {1, -1, 0, 0, 1, -1}, dj[6] = {0, 0, 1, -1, 1, -1};
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      for (int e = 0; e < 6; ++e) {
        int a = i + di[e], b = j + dj[e];
        if (wrapU) a = (a + nu) % nu;
        if (a < 0 || a >= nu || b < 0 || b >= nv) continue;
        g.delaunayIndices.push_back(uint32_t(b * nu + a));
      }
      g.delaunayOffsets.push_back(uint32_t(g.delaunayIndices.size()));
    }
  return g;
}

double angleDegrees(const Vec3f& a, const Vec3f& b) {
  double c = std::abs(double(a.normalized().dot(b.normalized())));
  return std::acos(std::min(1.0, c)) * 180.0 / std::numbers::pi;
}

/// Every input point is either kept or replaced by exactly one segment.
void expectPartition(const HybridModel& in, const HybridModel& out) {
  ASSERT_EQ(out.provenance.size(), out.segments.size());
  std::vector<int> count(in.points.size(), 0);
  for (const auto& prov : out.provenance) {
    EXPECT_GE(prov.size(), 4u);
    for (uint32_t p : prov) ++count[p];
  }
  size_t replaced = 0;
  for (int c : count) {
    EXPECT_LE(c, 1);
    replaced += c;
  }
  EXPECT_EQ(out.points.size() + replaced, in.points.size());
}

}  // namespace

TEST(ShapeApprox, MinAreaRectangleOfRotatedRectangle) {
  const double a = 0.4;
  const Vec2d u(std::cos(a), std::sin(a)), v(-std::sin(a), std::cos(a));
  std::vector<Vec2d> pts;
  for (int i = 0; i <= 30; ++i)
    for (int j = 0; j <= 10; ++j) pts.push_back(Vec2d(3, -1) + (i / 10.0) * u + (j / 10.0) * v);
  Rectangle2 r = minAreaRectangle(pts);
  EXPECT_NEAR(r.longLength, 3.0, 1e-9);
  EXPECT_NEAR(r.shortLength, 1.0, 1e-9);
  EXPECT_NEAR(std::abs(r.longAxis.dot(u)), 1.0, 1e-9);
  EXPECT_TRUE(r.center.isApprox(Vec2d(3, -1) + 1.5 * u + 0.5 * v, 1e-9));
  // Collinear and single points.
  std::vector<Vec2d> line = {{0, 0}, {1, 1}, {2, 2}};
  Rectangle2 l = minAreaRectangle(line);
  EXPECT_NEAR(l.longLength, std::sqrt(8.0), 1e-12);
  EXPECT_EQ(l.shortLength, 0.0);
  std::vector<Vec2d> one = {{1, 2}, {1, 2}};
  EXPECT_EQ(minAreaRectangle(one).longLength, 0.0);
  EXPECT_EQ(minAreaRectangle({}).longLength, 0.0);
}

TEST(ShapeApprox, PlaneGivesParallelSegmentsAtPointSpacing) {
  // 2 x 1 plane, 41 x 21 samples at spacing 0.05: one cluster, segments along the long side,
  // one per sample row.
  HybridModel plane = shapes::plane(2.0f, 1.0f, 41, 21);
  PointGeometry g = gridGeometry(plane, 41, 21, false);
  ShapeApproxStats st;
  HybridModel out = extractShapeApprox(plane, g, {.provenance = true}, &st);
  expectPartition(plane, out);
  EXPECT_EQ(st.clusters, 1u);
  EXPECT_EQ(out.segments.size(), 21u);
  EXPECT_EQ(out.points.size(), 0u);
  std::vector<double> offsets;
  for (const Segment& s : out.segments) {
    EXPECT_LT(angleDegrees(s.p1 - s.p0, out.segments[0].p1 - out.segments[0].p0), 0.01);
    EXPECT_LT(angleDegrees(s.p1 - s.p0, Vec3f::UnitX()), 0.01);
    EXPECT_NEAR(s.length(), 2.0f, 1e-4f);
    EXPECT_NEAR(std::abs(s.normal.z()), 1.0f, 1e-5f);
    EXPECT_NEAR(s.radius, 0.05f, 1e-4f);
    offsets.push_back(s.p0.y());
  }
  std::sort(offsets.begin(), offsets.end());
  for (size_t i = 1; i < offsets.size(); ++i) EXPECT_NEAR(offsets[i] - offsets[i - 1], 0.05, 1e-4);
  // §7.2.2: 21 segments replace 861 points: 1 - 9*21 / (6*861).
  EXPECT_NEAR(st.dataReduction(), 1.0 - 9.0 * 21 / (6.0 * 861), 1e-12);
}

TEST(ShapeApprox, CylinderSegmentsFollowTheAxis) {
  // Radius 1, height 2, 120 x 40 samples (spacing about 0.052): clusters are 3 columns wide and
  // run the full height, so the rectangle direction is the axis.
  HybridModel cyl = shapes::cylinder(1.0f, 2.0f, 120, 40);
  PointGeometry g = gridGeometry(cyl, 120, 40, true, Vec3f::UnitZ());
  for (ClusteringMethod method : {ClusteringMethod::Greedy, ClusteringMethod::Hierarchical}) {
    ShapeApproxStats st;
    HybridModel out = extractShapeApprox(cyl, g, {.method = method, .provenance = true}, &st);
    expectPartition(cyl, out);
    ASSERT_GT(out.segments.size(), 60u);
    size_t along = 0;
    for (const Segment& s : out.segments) {
      along += angleDegrees(s.p1 - s.p0, Vec3f::UnitZ()) <= 10.0;
      EXPECT_LT(std::abs(s.normal.dot((s.p1 - s.p0).normalized())), 1e-4f);
      EXPECT_NEAR(s.normal.norm(), 1.0f, 1e-5f);
      // Normal points outward like the samples it replaced.
      Vec3f mid = 0.5f * (s.p0 + s.p1);
      EXPECT_GT(s.normal.dot(Vec3f(mid.x(), mid.y(), 0).normalized()), 0.99f);
    }
    EXPECT_GE(double(along), 0.9 * double(out.segments.size()));
    EXPECT_GT(st.dataReduction(), 0.5);
  }
}

TEST(ShapeApprox, ShortWideCylinderPatchUsesCurvatureDirection) {
  // §3.2.4.2: with delta_n = 0.1 (about 18 degrees) a cluster on a short cylinder is wider than
  // tall; the minimum-curvature direction (the axis) must replace the rectangle's direction.
  HybridModel cyl = shapes::cylinder(1.0f, 0.3f, 180, 9);
  PointGeometry g = gridGeometry(cyl, 180, 9, true, Vec3f::UnitZ());
  ShapeApproxOptions o;
  o.clustering.deltaN = 0.1f;
  ShapeApproxStats st;
  HybridModel out = extractShapeApprox(cyl, g, o, &st);
  EXPECT_GT(st.curvatureDirectionUsed, 0u);
  ASSERT_FALSE(out.segments.empty());
  for (const Segment& s : out.segments) EXPECT_LT(angleDegrees(s.p1 - s.p0, Vec3f::UnitZ()), 10.0);
  // Without curvature directions the segments run around the cylinder instead.
  g.minCurvatureDir.clear();
  HybridModel around = extractShapeApprox(cyl, g, o, &st);
  EXPECT_EQ(st.curvatureDirectionUsed, 0u);
  ASSERT_FALSE(around.segments.empty());
  EXPECT_GT(angleDegrees(around.segments[0].p1 - around.segments[0].p0, Vec3f::UnitZ()), 45.0);
}

TEST(ShapeApprox, SameResultForAnyThreadCount) {
  HybridModel torus = shapes::torus(2.0f, 0.6f, 120, 40);
  PointGeometry g = gridGeometry(torus, 120, 40, true);
  // Torus rows wrap in both directions: add the wrap of the second index by hand.
  {
    PointGeometry w = g;
    w.delaunayIndices.clear();
    w.delaunayOffsets = {0};
    for (size_t i = 0; i < g.size(); ++i) {
      for (uint32_t q : g.delaunayOf(i)) w.delaunayIndices.push_back(q);
      int row = int(i / 120), col = int(i % 120);
      if (row == 0) w.delaunayIndices.push_back(uint32_t(39 * 120 + col));
      if (row == 39) w.delaunayIndices.push_back(uint32_t(col));
      w.delaunayOffsets.push_back(uint32_t(w.delaunayIndices.size()));
    }
    g = std::move(w);
  }
  for (ClusteringMethod method : {ClusteringMethod::Greedy, ClusteringMethod::Hierarchical}) {
    ShapeApproxOptions o{.method = method, .provenance = true};
    HybridModel many = extractShapeApprox(torus, g, o);
    HybridModel one;
    {
      ThreadLimit limit(1);
      one = extractShapeApprox(torus, g, o);
    }
    ASSERT_EQ(many.segments.size(), one.segments.size());
    ASSERT_EQ(many.points.size(), one.points.size());
    for (size_t i = 0; i < many.segments.size(); ++i) {
      EXPECT_EQ(many.segments[i].p0, one.segments[i].p0);
      EXPECT_EQ(many.segments[i].p1, one.segments[i].p1);
      EXPECT_EQ(many.segments[i].normal, one.segments[i].normal);
    }
    EXPECT_EQ(many.provenance, one.provenance);
    expectPartition(torus, many);
  }
}

TEST(ShapeApprox, SmallClustersAndShortRunsStayPoints) {
  HybridModel tiny = shapes::plane(1, 1, 3, 1);  // 3 points: one cluster of 3
  PointGeometry g = gridGeometry(tiny, 3, 1, false);
  ShapeApproxStats st;
  HybridModel out = extractShapeApprox(tiny, g, {}, &st);
  EXPECT_EQ(out.points.size(), 3u);
  EXPECT_TRUE(out.segments.empty());
  EXPECT_EQ(st.smallClusters, 1u);
  EXPECT_EQ(st.dataReduction(), 0.0);
  // Rows of 3 points on a plane: runs too short, points stay.
  HybridModel strip = shapes::plane(1, 0.1f, 3, 12);
  PointGeometry gs = gridGeometry(strip, 3, 12, false);
  HybridModel so = extractShapeApprox(strip, gs, {.minRunPoints = 13}, &st);
  EXPECT_TRUE(so.segments.empty());
  EXPECT_EQ(so.points.size(), strip.points.size());
  // Kept points carry the geometry's normals and the input radius.
  EXPECT_EQ(so.points[0].normal, gs.normals[0]);
  EXPECT_EQ(so.points[0].radius, strip.points[0].radius);
}

TEST(ShapeApprox, DegenerateInputIsCountedNotFatal) {
  // All points coincide: the projection is a point, the cluster is kept as points.
  HybridModel same;
  for (int i = 0; i < 6; ++i) same.points.push_back({.position = Vec3f(1, 2, 3), .normal = Vec3f::UnitZ()});
  PointGeometry g;
  g.normals.assign(6, Vec3f::UnitZ());
  g.surfaceVariation.assign(6, 0.0f);
  g.delaunayOffsets = {0};
  for (uint32_t i = 0; i < 6; ++i) {
    for (uint32_t j = 0; j < 6; ++j)
      if (i != j) g.delaunayIndices.push_back(j);
    g.delaunayOffsets.push_back(uint32_t(g.delaunayIndices.size()));
  }
  ShapeApproxStats st;
  HybridModel out = extractShapeApprox(same, g, {}, &st);
  EXPECT_EQ(out.points.size(), 6u);
  EXPECT_EQ(st.degenerateClusters, 1u);
  for (const Point& p : out.points) EXPECT_TRUE(p.position.allFinite());
  // Empty cloud.
  HybridModel empty;
  PointGeometry eg;
  eg.delaunayOffsets = {0};
  EXPECT_TRUE(extractShapeApprox(empty, eg).empty());
}

TEST(ShapeApprox, RejectsAbsurdParametersAndMismatchedGeometry) {
  HybridModel plane = shapes::plane(1, 1, 5, 5);
  PointGeometry g = gridGeometry(plane, 5, 5, false);
  EXPECT_THROW(extractShapeApprox(plane, g, {.minClusterSize = 1}), Error);
  EXPECT_THROW(extractShapeApprox(plane, g, {.minRunPoints = 0}), Error);
  EXPECT_THROW(extractShapeApprox(plane, g, {.curvatureSwitchDegrees = 120}), Error);
  EXPECT_THROW(extractShapeApprox(plane, g, {.radiusScale = 0}), Error);
  ShapeApproxOptions o;
  o.clustering.deltaN = 2.5f;
  EXPECT_THROW(extractShapeApprox(plane, g, o), Error);
  HybridModel other = shapes::plane(1, 1, 4, 4);
  EXPECT_THROW(extractShapeApprox(other, g), Error);
}

// ---------------------------------------------------------------------------------------------
// Through the real §6.1 geometry pipeline.

#include <filesystem>

#include "linesurf/io/model_io.h"
#include "test_util.h"

namespace {

void expectInvariant(const Clustering& c, const PointGeometry& g, float delta) {
  ASSERT_EQ(c.labels.size(), g.size());
  size_t total = 0;
  for (size_t k = 0; k < c.size(); ++k) {
    ASSERT_LE(clusterMaxVariation(c, g, k), delta) << "cluster " << k;
    total += c.clusterSize(k);
  }
  EXPECT_EQ(total, g.size());
}

}  // namespace

TEST(ShapeApprox, ComputedGeometryCylinderSegmentsFollowTheAxis) {
  for (bool irregular : {false, true}) {
    HybridModel cyl = shapes::cylinder(1.0f, 2.0f, 120, 40, {.irregular = irregular, .seed = 5});
    PointGeometry g = computePointGeometry(cyl, {.recomputeNormals = true});
    for (ClusteringMethod method : {ClusteringMethod::Greedy, ClusteringMethod::Hierarchical}) {
      ShapeApproxOptions o{.method = method};
      Clustering c = clusterShapeApprox(g, o);
      expectInvariant(c, g, o.clustering.deltaN);
      HybridModel out = extractShapeApprox(cyl, g, c, o);
      ASSERT_GT(out.segments.size(), 20u) << irregular;
      size_t along = 0;
      for (const Segment& s : out.segments) along += angleDegrees(s.p1 - s.p0, Vec3f::UnitZ()) <= 10.0;
      EXPECT_GE(double(along), 0.9 * double(out.segments.size()))
          << (irregular ? "irregular" : "grid") << " method " << int(method);
    }
  }
}

TEST(ShapeApprox, ComputedGeometryIrregularPlaneSpacingMatchesDensity) {
  // 3000 uniform random samples on a 2 x 1 plane: density rho = 1500, nominal spacing
  // 1/sqrt(rho) = 0.026. Segments of one cluster are parallel and spaced like the samples.
  HybridModel plane = shapes::plane(2.0f, 1.0f, 60, 50, {.irregular = true, .seed = 9});
  PointGeometry g = computePointGeometry(plane, {.recomputeNormals = true});
  ShapeApproxStats st;
  HybridModel out = extractShapeApprox(plane, g, {.provenance = true}, &st);
  EXPECT_EQ(st.clusters, 1u);
  ASSERT_GT(out.segments.size(), 10u);
  const Vec3f d0 = (out.segments[0].p1 - out.segments[0].p0).normalized();
  const Vec3f across = Vec3f::UnitZ().cross(d0).normalized();
  std::vector<double> offsets;
  double longest = 0;
  for (const Segment& s : out.segments) longest = std::max(longest, double(s.length()));
  for (const Segment& s : out.segments) {
    // Long segments follow the cluster direction (short ones join two jittered samples).
    if (s.length() > 0.5 * longest) {
      EXPECT_LT(angleDegrees(s.p1 - s.p0, d0), 5.0);
    }
    offsets.push_back(double(0.5f * (s.p0 + s.p1).dot(across)));
  }
  std::sort(offsets.begin(), offsets.end());
  offsets.erase(std::unique(offsets.begin(), offsets.end(), [](double a, double b) { return b - a < 0.004; }), offsets.end());
  const double extent = offsets.back() - offsets.front();
  const double meanGap = extent / double(offsets.size() - 1);
  const double nominal = 1.0 / std::sqrt(3000.0 / 2.0);
  EXPECT_GT(meanGap, 0.6 * nominal);
  EXPECT_LT(meanGap, 1.4 * nominal);
}

TEST(ShapeApproxCli, WritesHybridAndClusterColouredCloud) {
  auto dir = test::scratchDir("shape_approx_cli");
  HybridModel cyl = shapes::cylinder(1.0f, 2.0f, 90, 30);
  cyl.attributes.normals = false;  // let the CLI compute them
  writeModel(dir / "cyl.ply", cyl);
  const std::string in = (dir / "cyl.ply").string(), out = (dir / "out.ply").string(),
                    clusters = (dir / "clusters.ply").string();
  auto r = test::runCli("extract shape-approx " + in + " -o " + out + " --clustering hierarchical --seed 3 --clusters-out " +
                        clusters);
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("clusters"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("reduction"), std::string::npos) << r.out;
  HybridModel hybrid = readModel(out);
  EXPECT_GT(hybrid.segments.size(), 0u);
  HybridModel coloured = readModel(clusters);
  EXPECT_EQ(coloured.points.size(), cyl.points.size());
  EXPECT_TRUE(coloured.attributes.colors);
  // Same seed, same output.
  auto again = test::runCli("extract shape-approx " + in + " -o " + (dir / "out2.ply").string() +
                            " --clustering hierarchical --seed 3");
  ASSERT_EQ(again.exitCode, 0) << again.out;
  HybridModel second = readModel(dir / "out2.ply");
  ASSERT_EQ(second.segments.size(), hybrid.segments.size());
  for (size_t i = 0; i < second.segments.size(); ++i) EXPECT_EQ(second.segments[i].p0, hybrid.segments[i].p0);
  // Bad parameters exit 1 with the option's name.
  auto bad = test::runCli("extract shape-approx " + in + " -o " + out + " --delta-n 2.5");
  EXPECT_EQ(bad.exitCode, 1) << bad.out;
  EXPECT_NE(bad.out.find("delta-n"), std::string::npos) << bad.out;
  auto badMethod = test::runCli("extract shape-approx " + in + " -o " + out + " --clustering kmeans");
  EXPECT_EQ(badMethod.exitCode, 1) << badMethod.out;
}

TEST(SharedShapeApprox, RockerArmInvariantAndPartition) {
  LINESURF_REQUIRE_SHARED_DATA();
  HybridModel cloud = readModel(test::sharedData() / "rockerarm_points.ply");
  PointGeometry g = computePointGeometry(cloud);
  for (ClusteringMethod method : {ClusteringMethod::Greedy, ClusteringMethod::Hierarchical}) {
    ShapeApproxOptions o{.method = method, .provenance = true};
    Clustering c = clusterShapeApprox(g, o);
    expectInvariant(c, g, o.clustering.deltaN);
    ShapeApproxStats st;
    HybridModel out = extractShapeApprox(cloud, g, c, o, &st);
    expectPartition(cloud, out);
    EXPECT_GT(st.segments, 0u);
    EXPECT_GT(st.dataReduction(), 0.0);
    for (const Segment& s : out.segments) {
      EXPECT_NEAR(s.normal.norm(), 1.0f, 1e-4f);
      EXPECT_LT(std::abs(s.normal.dot((s.p1 - s.p0).normalized())), 1e-3f);
      EXPECT_GT(s.radius, 0.0f);
    }
  }
}
