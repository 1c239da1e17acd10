// Outliers of a scanned cloud (geometry/outliers.h): planted outliers off a noisy surface, single
// and in clusters of up to five, are found and the surface's points kept.
#include <gtest/gtest.h>

#include <random>

#include "linesurf/core/error.h"
#include "linesurf/geometry/outliers.h"
#include "shapes.h"

namespace linesurf {
namespace {

struct Planted {
  HybridModel cloud;
  size_t surface = 0;             ///< the first `surface` points are the scan's
  std::vector<uint8_t> farEnough;  ///< per outlier: more than 2 spacings from the surface
};

/// A sphere (radius 1) scanned with noise 0.1 spacing, plus 1% outliers: 3 to 10 spacings off
/// the surface along its normal, singles and clusters of 2 to 5 within half a spacing, and some
/// uniform in 1.1 x the bounding box.
Planted planted(uint64_t seed) {
  Planted p;
  p.cloud = shapes::sphere(1, 40000, {.noise = 0.1f, .irregular = true, .seed = seed});
  p.surface = p.cloud.points.size();
  const float s = std::sqrt(4 * 3.14159265f / float(p.surface));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0, 1), box(-1.1f, 1.1f);
  std::normal_distribution<float> g(0, 1);
  const size_t want = p.surface / 100;
  auto add = [&](const Vec3f& q) {
    p.cloud.points.push_back({.position = q});
    p.farEnough.push_back(std::abs(q.norm() - 1.0f) > 2 * s);
  };
  while (p.cloud.points.size() - p.surface < want) {
    if (u(rng) < 0.2f) {
      add(Vec3f(box(rng), box(rng), box(rng)));
      continue;
    }
    const Vec3f d = Vec3f(g(rng), g(rng), g(rng)).normalized();
    const float off = (3 + 7 * u(rng)) * s * (u(rng) < 0.5f ? 1.0f : -1.0f);
    const int members = u(rng) < 0.5f ? 1 : 2 + int(4 * u(rng));
    for (int m = 0; m < members; ++m) add(d * (1 + off) + 0.5f * s * Vec3f(g(rng), g(rng), g(rng)) / 1.7f);
  }
  return p;
}

TEST(Outliers, PlantedOutliersFoundSurfaceKept) {
  const Planted p = planted(4);
  GeometryOptions o;
  o.k = kOutlierNeighbours;
  o.recomputeNormals = true;
  o.orientNormals = o.delaunayNeighbours = o.curvature = o.coverRadius = false;
  const PointGeometry g = computePointGeometry(p.cloud, o);
  std::vector<Vec3f> pos;
  for (const Point& q : p.cloud.points) pos.push_back(q.position);
  const OutlierReport r = findOutliers(g, pos);
  size_t found = 0, counted = 0, lost = 0;
  for (size_t i = 0; i < p.cloud.points.size(); ++i) {
    if (i < p.surface) {
      lost += r.kind[i] != kNotOutlier;
    } else if (p.farEnough[i - p.surface]) {
      ++counted, found += r.kind[i] != kNotOutlier;
    }
  }
  EXPECT_GT(counted, 300u);
  EXPECT_GE(double(found), 0.95 * double(counted)) << found << " of " << counted;
  EXPECT_LE(double(lost), 0.005 * double(p.surface)) << lost;
  const HybridModel clean = withoutOutliers(p.cloud, r);
  EXPECT_EQ(clean.points.size(), p.cloud.points.size() - r.total);
}

TEST(Outliers, ACleanClosedScanLosesNothing) {
  const HybridModel torus = shapes::torus(2, 0.6f, 200, 60, {.noise = 0.2f, .irregular = true, .seed = 8});
  GeometryOptions o;
  o.k = kOutlierNeighbours;
  o.recomputeNormals = true;
  o.orientNormals = o.delaunayNeighbours = o.curvature = o.coverRadius = false;
  const PointGeometry g = computePointGeometry(torus, o);
  std::vector<Vec3f> pos;
  for (const Point& q : torus.points) pos.push_back(q.position);
  EXPECT_LE(double(findOutliers(g, pos).total), 0.001 * double(torus.points.size()));
}

TEST(Outliers, MeaninglessThresholdsAreRefused) {
  OutlierOptions o;
  o.offSurface = std::nanf("");
  EXPECT_THROW(validate(o), Error);
  o = {};
  o.isolated = 0.5f;
  EXPECT_THROW(validate(o), Error);
}

}  // namespace
}  // namespace linesurf
