// Tests of the segment half-width rule of the hybrids (as narrow as the replaced points' cells
// allow, no holes; src/extract/detail/segment_width.h): bounds, cover of the replaced points'
// cells, and that the strips are narrower than the disc cover of before. Rendered hole-freeness:
// Holes.*.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "shapes.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"

using namespace linesurf;

namespace {

double distanceToSegment(const Vec3d& p, const Segment& s) {
  const Vec3d a = s.p0.cast<double>(), ab = s.p1.cast<double>() - a;
  const double ab2 = ab.squaredNorm();
  const double t = ab2 > 0 ? std::clamp((p - a).dot(ab) / ab2, 0.0, 1.0) : 0.0;
  return (p - a - t * ab).norm();
}

struct Fixture {
  HybridModel cloud;
  PointGeometry geo;
};

/// A uniformly random sphere sample with normals and hole-free radii from the geometry stage
/// (as `linesurf normals` computes them).
Fixture randomSphere(int n) {
  shapes::SampleOptions so;
  so.irregular = true;
  so.seed = 7;
  Fixture f{shapes::sphere(1, n, so), {}};
  GeometryOptions go;
  go.recomputeNormals = true;
  go.curvature = true;
  f.geo = computePointGeometry(f.cloud, go);
  f.cloud.attributes.radii = false;
  applyGeometry(f.cloud, f.geo);
  return f;
}

/// Checks one hybrid against its input; returns mean(radius / disc cover of before).
double checkWidths(const Fixture& f, const HybridModel& hybrid) {
  const size_t n = f.cloud.points.size();
  EXPECT_EQ(hybrid.provenance.size(), hybrid.segments.size());
  std::vector<uint32_t> owner(n, UINT32_MAX);
  double ratioSum = 0;
  for (size_t s = 0; s < hybrid.segments.size(); ++s) {
    const Segment& seg = hybrid.segments[s];
    double discCover = 0, thinnest = HUGE_VAL, farthest = 0;
    for (uint32_t j : hybrid.provenance[s]) {
      owner[j] = uint32_t(s);
      const double d = distanceToSegment(f.cloud.points[j].position.cast<double>(), seg);
      discCover = std::max(discCover, f.cloud.points[j].radius + d);
      thinnest = std::min(thinnest, double(f.cloud.points[j].radius));
      farthest = std::max(farthest, d);
    }
    // never wider than every member's disc plus its distance, never thinner than the thinnest
    // member's radius or than needed to reach every member
    EXPECT_LE(seg.radius, discCover * (1 + 1e-6)) << "segment " << s;
    EXPECT_GE(seg.radius, std::min(discCover, std::max(thinnest, farthest)) * (1 - 1e-6)) << "segment " << s;
    ratioSum += seg.radius / discCover;
  }
  // Cover: the point halfway between a replaced point and each of its star neighbours lies on
  // their common Voronoi edge or in a nearby point's cell; a primitive (strip or kept disc) of
  // one of the two points or of their star neighbours must reach it.
  auto covers = [&](uint32_t i, const Vec3d& p) {
    if (owner[i] == UINT32_MAX) return (f.cloud.points[i].position.cast<double>() - p).norm() <= f.cloud.points[i].radius;
    return distanceToSegment(p, hybrid.segments[owner[i]]) <= hybrid.segments[owner[i]].radius;
  };
  size_t checked = 0, open = 0;
  for (size_t j = 0; j < n; ++j) {
    if (owner[j] == UINT32_MAX) continue;
    for (uint32_t k : f.geo.delaunayOf(j)) {
      const Vec3d mid = 0.5 * (f.cloud.points[j].position + f.cloud.points[k].position).cast<double>();
      bool covered = covers(uint32_t(j), mid) || covers(k, mid);
      for (uint32_t i : {uint32_t(j), k})
        for (uint32_t l : f.geo.delaunayOf(i)) covered = covered || covers(l, mid);
      ++checked;
      open += !covered;
    }
  }
  EXPECT_GT(checked, n);
  EXPECT_EQ(open, 0u) << "of " << checked << " edge midpoints";
  return hybrid.segments.empty() ? 1.0 : ratioSum / double(hybrid.segments.size());
}

}  // namespace

TEST(SegmentWidth, EpsDeltaStripsCoverTheCellsWithinTheOldBound) {
  const Fixture f = randomSphere(20000);
  EpsDeltaOptions eo;
  eo.provenance = true;
  const HybridModel h = extractEpsDelta(f.cloud, f.geo, eo);
  ASSERT_GT(h.segments.size(), 100u);
  const double ratio = checkWidths(f, h);
  // (ε,δ) rows: the cell across the row is narrower than the farthest-vertex disc
  EXPECT_LT(ratio, 0.97);
}

TEST(SegmentWidth, ShapeApproxStripsAreNarrowerThanTheDiscCover) {
  const Fixture f = randomSphere(20000);
  for (ClusteringMethod m : {ClusteringMethod::Greedy, ClusteringMethod::Hierarchical}) {
    ShapeApproxOptions so;
    so.method = m;
    so.provenance = true;
    const HybridModel h = extractShapeApprox(f.cloud, f.geo, so);
    ASSERT_GT(h.segments.size(), 100u);
    // Neighbouring strips of a cluster share the cover of the points between them: the
    // measured mean is about 0.7 on the shared scans and random spheres.
    EXPECT_LT(checkWidths(f, h), 0.85);
  }
}
