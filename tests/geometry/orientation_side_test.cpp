// The side a component's oriented normals face (geometry/detail/orientation_side.h): terrain up
// by default, closed shapes outward, a viewpoint's side on request, and the summaries of a
// component's pieces adding up to the whole's (what the out-of-core join relies on).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "geometry/detail/orientation_side.h"
#include "linesurf/core/error.h"
#include "linesurf/geometry/point_geometry.h"
#include "shapes.h"

namespace linesurf {
namespace {

GeometryOptions sideOptions(OrientSide side, Vec3f viewpoint = Vec3f::Zero()) {
  GeometryOptions o;
  o.recomputeNormals = true;
  o.delaunayNeighbours = o.curvature = o.coverRadius = false;
  o.orient = side;
  o.viewpoint = viewpoint;
  return o;
}

/// Rolling ground z = h(x, y) over 40 x 40 with a flat-roofed block (6 x 6 x 3) and a spike of
/// clutter above the highest ground: the highest point of the scene is a tree top whose normal
/// says nothing about the side (the rule that took the +z extreme's normal failed here). True
/// normals face up (walls: outward).
struct Terrain {
  HybridModel cloud;
  std::vector<Vec3f> truth;  ///< zero for the clutter
};

Terrain terrain(uint64_t seed) {
  Terrain t;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(-20, 20);
  std::normal_distribution<float> noise(0, 0.01f);
  auto h = [](float x, float y) { return 0.8f * std::sin(0.21f * x) * std::cos(0.17f * y) + 0.02f * x; };
  auto add = [&](Vec3f p, Vec3f n) {
    t.cloud.points.push_back({.position = p + noise(rng) * n});
    t.truth.push_back(n);
  };
  for (int i = 0; i < 60000; ++i) {
    const float x = u(rng), y = u(rng);
    if (x > 2 && x < 8 && y > -3 && y < 3) {  // the block's roof
      add(Vec3f(x, y, 3.0f + h(5, 0)), Vec3f(0, 0, 1));
      continue;
    }
    const float dx = 0.8f * 0.21f * std::cos(0.21f * x) * std::cos(0.17f * y) + 0.02f;
    const float dy = -0.8f * 0.17f * std::sin(0.21f * x) * std::sin(0.17f * y);
    add(Vec3f(x, y, h(x, y)), Vec3f(-dx, -dy, 1).normalized());
  }
  // The block's walls, sampled as densely as the ground.
  std::uniform_real_distribution<float> along(0, 6), up(0, 1);
  for (int i = 0; i < 4000; ++i) {
    const float s = along(rng), z = h(5, 0) + 3.0f * up(rng);
    const int side = i % 4;
    if (side == 0) add(Vec3f(2, -3 + s, z), Vec3f(-1, 0, 0));
    if (side == 1) add(Vec3f(8, -3 + s, z), Vec3f(1, 0, 0));
    if (side == 2) add(Vec3f(2 + s, -3, z), Vec3f(0, -1, 0));
    if (side == 3) add(Vec3f(2 + s, 3, z), Vec3f(0, 1, 0));
  }
  // Clutter: a thin vertical spike of scattered points, higher than anything else.
  std::normal_distribution<float> g(0, 0.3f);
  for (int i = 0; i < 600; ++i) {
    t.cloud.points.push_back({.position = Vec3f(-10 + g(rng), -10 + g(rng), h(-10, -10) + 8.0f * up(rng))});
    t.truth.push_back(Vec3f::Zero());
  }
  return t;
}

double shareFacing(const PointGeometry& g, const std::vector<Vec3f>& truth) {
  size_t agree = 0, counted = 0;
  for (size_t i = 0; i < truth.size(); ++i)
    if (truth[i] != Vec3f::Zero()) ++counted, agree += g.normals[i].dot(truth[i]) > 0;
  return double(agree) / double(counted);
}

TEST(OrientationSide, TerrainFacesUpByDefault) {
  const Terrain t = terrain(3);
  const PointGeometry g = computePointGeometry(t.cloud, sideOptions(OrientSide::Auto));
  EXPECT_GE(shareFacing(g, t.truth), 0.99);
  const PointGeometry up = computePointGeometry(t.cloud, sideOptions(OrientSide::Up));
  EXPECT_GE(shareFacing(up, t.truth), 0.99);
  // Seen from below, the same sheet faces down.
  const PointGeometry below = computePointGeometry(t.cloud, sideOptions(OrientSide::Towards, Vec3f(0, 0, -100)));
  EXPECT_LE(shareFacing(below, t.truth), 0.01);
}

TEST(OrientationSide, ClosedShapesFaceOutwardUnderTheColumnRules) {
  shapes::SampleOptions so{.noise = 0.05f, .irregular = true, .seed = 9};
  for (const HybridModel& shape : {shapes::sphere(1, 6000, so), shapes::torus(2, 0.6f, 120, 40, so)}) {
    for (OrientSide side : {OrientSide::Auto, OrientSide::Outward}) {
      const PointGeometry g = computePointGeometry(shape, sideOptions(side));
      size_t out = 0;
      for (size_t i = 0; i < shape.points.size(); ++i) out += g.normals[i].dot(shape.points[i].normal) > 0;
      EXPECT_EQ(out, shape.points.size()) << "rule " << int(side);
    }
  }
}

TEST(OrientationSide, AViewpointsSide) {
  const HybridModel ball = shapes::sphere(1, 4000);
  // A room scanned from inside: towards the centre is inward; away from it, outward.
  const PointGeometry in = computePointGeometry(ball, sideOptions(OrientSide::Towards, Vec3f(0.1f, 0.2f, 0)));
  const PointGeometry out = computePointGeometry(ball, sideOptions(OrientSide::AwayFrom, Vec3f(0.1f, 0.2f, 0)));
  for (size_t i = 0; i < ball.points.size(); ++i) {
    EXPECT_LT(in.normals[i].dot(ball.points[i].normal), 0) << i;
    EXPECT_GT(out.normals[i].dot(ball.points[i].normal), 0) << i;
  }
  EXPECT_EQ(in.orientationComponents, 1u);
}

TEST(OrientationSide, AFlipsCountIsTheNormalsTurnedFromTheirPcaSign) {
  const Terrain t = terrain(5);
  GeometryOptions raw = sideOptions(OrientSide::Auto);
  raw.orientNormals = false;
  const PointGeometry pca = computePointGeometry(t.cloud, raw);
  for (OrientSide side : {OrientSide::Up, OrientSide::Towards}) {
    const PointGeometry g = computePointGeometry(t.cloud, sideOptions(side, Vec3f(0, 0, -50)));
    size_t turned = 0;
    for (size_t i = 0; i < t.cloud.points.size(); ++i) {
      ASSERT_TRUE(g.normals[i] == pca.normals[i] || g.normals[i] == Vec3f(-pca.normals[i])) << i;
      turned += g.normals[i] != pca.normals[i];
    }
    EXPECT_EQ(turned, g.orientationFlips);
  }
}

// Any split of a component, one piece's normals negated, merges to the whole's summary with
// that piece flipped back: the out-of-core join's sum equals the in-memory one.
TEST(OrientationSide, PiecesAddUpToTheWhole) {
  const Terrain t = terrain(7);
  const PointGeometry g = computePointGeometry(t.cloud, sideOptions(OrientSide::Auto));
  const size_t n = t.cloud.points.size();
  std::vector<Vec3f> pos(n), nrm(n), flipped(n);
  std::vector<uint32_t> comp(n, 0);
  std::vector<uint8_t> first(n), second(n);
  Bounds3f b;
  for (size_t i = 0; i < n; ++i) {
    pos[i] = t.cloud.points[i].position, nrm[i] = g.normals[i], flipped[i] = -g.normals[i];
    first[i] = pos[i].x() < 1.5f, second[i] = !first[i];
    b.extend(pos[i]);
  }
  const detail::SideGrid grid(b);
  for (OrientSide side : {OrientSide::Auto, OrientSide::Outward, OrientSide::Up, OrientSide::Towards}) {
    const Vec3f vp(3, 1, 40);
    const auto whole = detail::sideSummaries(side, vp, grid, pos, nrm, comp, 1);
    auto a = detail::sideSummaries(side, vp, grid, pos, nrm, comp, 1, {}, first);
    const auto bPiece = detail::sideSummaries(side, vp, grid, pos, flipped, comp, 1, {}, second);
    detail::mergeSides(a[0], bPiece[0], true);
    EXPECT_EQ(a[0].vote, whole[0].vote);
    EXPECT_EQ(a[0].firstIndex, whole[0].firstIndex);
    EXPECT_EQ(a[0].firstNormal, whole[0].firstNormal);
    ASSERT_EQ(a[0].envelope.size(), whole[0].envelope.size());
    for (size_t e = 0; e < whole[0].envelope.size(); ++e) {
      EXPECT_EQ(a[0].envelope[e].key, whole[0].envelope[e].key);
      EXPECT_EQ(a[0].envelope[e].index, whole[0].envelope[e].index);
      EXPECT_EQ(a[0].envelope[e].vote, whole[0].envelope[e].vote);
    }
    EXPECT_EQ(detail::flipForSide(a[0], side), detail::flipForSide(whole[0], side));
    EXPECT_FALSE(detail::flipForSide(whole[0], side));  // g already faces the auto rule's side
    if (side == OrientSide::Auto) {
      EXPECT_GT(whole[0].envelope.size(), 1000u);
    }
  }
}

TEST(OrientationSide, ANonFiniteViewpointIsRefused) {
  GeometryOptions o = sideOptions(OrientSide::Towards, Vec3f(0, std::nanf(""), 0));
  EXPECT_THROW(validate(o), Error);
}

}  // namespace
}  // namespace linesurf
