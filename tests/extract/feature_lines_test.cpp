// Feature lines (extract/feature_lines.h): folds with known creases at dihedral angles of 30 to
// 150 degrees, ridges and valleys, measured by length within 2 spacings (precision and recall);
// smooth shapes give none; the same bytes for any thread count; bad input refused.
#include "linesurf/extract/feature_lines.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "shapes.h"
#include "test_util.h"

namespace linesurf {
namespace {


struct Score {
  double precision = 0, recall = 0;
  double f1() const { return precision + recall > 0 ? 2 * precision * recall / (precision + recall) : 0; }
};

double distanceToSegment(const Vec3d& x, const Vec3d& a, const Vec3d& b) {
  const Vec3d d = b - a;
  const double t = std::clamp((x - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (x - a - t * d).norm();
}

/// Precision and recall by length within `tol` of the true crease (the y axis, |y| <= 0.5).
Score score(const HybridModel& lines, double tol) {
  const Vec3d e0(0, -0.5, 0), e1(0, 0.5, 0);
  double on = 0, total = 0;
  for (const Segment& s : lines.segments) {
    const int steps = std::max(1, int(s.length() / (0.1 * tol)));
    for (int k = 0; k < steps; ++k) {
      const Vec3d x = (s.p0 + (s.p1 - s.p0) * ((k + 0.5f) / float(steps))).cast<double>();
      total += 1, on += distanceToSegment(x, e0, e1) <= tol;
    }
  }
  Score sc;
  sc.precision = total > 0 ? on / total : 0;
  int covered = 0;
  const int steps = 400;
  for (int k = 0; k < steps; ++k) {
    const Vec3d x = e0 + (e1 - e0) * ((k + 0.5) / steps);
    for (const Segment& s : lines.segments)
      if (distanceToSegment(x, s.p0.cast<double>(), s.p1.cast<double>()) <= tol) {
        ++covered;
        break;
      }
  }
  sc.recall = double(covered) / steps;
  return sc;
}

TEST(FeatureLines, FoldsFromThirtyToOneHundredFiftyDegrees) {
  const double spacing = 1.0 / 60;
  for (double theta : {30.0, 60.0, 90.0, 120.0, 150.0})
    for (bool ridge : {true, false}) {
      const HybridModel m = shapes::fold(theta, spacing, 0.1, ridge, uint64_t(theta) + ridge);
      FeatureLineStats st;
      const HybridModel lines = extractFeatureLines(m, {}, &st);
      const Score sc = score(lines, 2 * spacing);
      std::printf("fold %3.0f deg %s, %zu points, noise 0.1 spacing: %zu segments in %zu polylines, length %.3f; "
                  "precision %.3f recall %.3f F1 %.3f\n",
                  theta, ridge ? "ridge " : "valley", m.points.size(), st.segments, st.polylines, st.length,
                  sc.precision, sc.recall, sc.f1());
      EXPECT_GE(sc.f1(), 0.9) << theta << (ridge ? " ridge" : " valley");
      for (const Segment& s : lines.segments) {
        EXPECT_NEAR(s.normal.norm(), 1.0f, 1e-4f);
        EXPECT_LT(std::abs(s.normal.dot((s.p1 - s.p0).normalized())), 1e-3f);
        EXPECT_GT(s.radius, 0.0f);
      }
    }
}

TEST(FeatureLines, SmoothShapesHaveNone) {
  // A sphere of 20,000 points (normals 2.3 degrees apart between neighbours) and a gently folded
  // sheet (160 degrees, below the default 25-degree threshold) give no feature lines.
  FeatureLineStats st;
  EXPECT_TRUE(extractFeatureLines(shapes::sphere(1, 20000), {}, &st).segments.empty()) << st.segments;
  EXPECT_TRUE(extractFeatureLines(shapes::fold(160, 1.0 / 60, 0.1, true, 3)).segments.empty());
}

TEST(FeatureLines, SameBytesForAnyThreadCount) {
  const HybridModel m = shapes::fold(90, 1.0 / 50, 0.2, true, 9);
  HybridModel one, two;
  {
    ThreadLimit t(1);
    one = extractFeatureLines(m);
  }
  {
    ThreadLimit t(2);
    two = extractFeatureLines(m);
  }
  ASSERT_EQ(one.segments.size(), two.segments.size());
  ASSERT_FALSE(one.segments.empty());
  for (size_t i = 0; i < one.segments.size(); ++i) {
    EXPECT_EQ(one.segments[i].p0, two.segments[i].p0);
    EXPECT_EQ(one.segments[i].p1, two.segments[i].p1);
    EXPECT_EQ(one.segments[i].normal, two.segments[i].normal);
  }
}

TEST(FeatureLines, BadInputIsRefused) {
  HybridModel m = shapes::fold(90, 1.0 / 20, 0, true, 1);
  EXPECT_THROW(extractFeatureLines(m, {.angle = 1}), Error);
  EXPECT_THROW(extractFeatureLines(m, {.linkRadius = 0}), Error);
  EXPECT_THROW(extractFeatureLines(m, {.tolerance = std::nan("")}), Error);
  HybridModel noNormals = m;
  noNormals.attributes.normals = false;
  EXPECT_THROW(extractFeatureLines(noNormals), Error);
  EXPECT_THROW(extractFeatureLines(HybridModel{}), Error);
  HybridModel nan = m;
  nan.points[3].position.x() = NAN;
  EXPECT_THROW(extractFeatureLines(nan), Error);
  HybridModel same = m;
  for (Point& p : same.points) p.position = Vec3f(1, 2, 3);
  EXPECT_THROW(extractFeatureLines(same), Error);
}

TEST(FeatureLines, CliWritesTheCreasesAndRefusesASmoothCloud) {
  const auto dir = test::scratchDir("features_cli");
  writeModel(dir / "fold.ply", shapes::fold(90, 1.0 / 40, 0.1, true, 4));
  writeModel(dir / "ball.ply", shapes::sphere(1, 4000));
  auto r = test::runCli("extract features '" + (dir / "fold.ply").string() + "' -o '" + (dir / "f.ply").string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("polylines"), std::string::npos) << r.out;
  const HybridModel lines = readModel(dir / "f.ply");
  EXPECT_TRUE(lines.points.empty());
  EXPECT_GE(score(lines, 2.0 / 40).f1(), 0.9);
  r = test::runCli("extract features '" + (dir / "ball.ply").string() + "' -o '" + (dir / "g.ply").string() + "'");
  EXPECT_EQ(r.exitCode, 2) << r.out;
  EXPECT_NE(r.out.find("no crease sharper than 25 degrees"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "g.ply"));
  r = test::runCli("extract features '" + (dir / "fold.ply").string() + "' -o '" + (dir / "h.ply").string() + "' --angle 200");
  EXPECT_EQ(r.exitCode, 1) << r.out;
}

}  // namespace
}  // namespace linesurf
