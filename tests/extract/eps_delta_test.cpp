// Tests of the (epsilon, delta) extraction (thesis §3.1) and of its verifier.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/verify.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

using namespace linesurf;

namespace {

// A stand-in for computePointGeometry on synthetic shapes: exact normals from the sampler and the
// k nearest neighbours (brute force) as the neighbour graph, so these tests isolate §3.1.
PointGeometry syntheticGeometry(const HybridModel& cloud, int k = 8) {
  const size_t n = cloud.points.size();
  PointGeometry g;
  g.k = k;
  g.normals.resize(n);
  g.spacing.resize(n);
  g.flags.assign(n, 0);
  g.delaunayOffsets.push_back(0);
  double total = 0;
  std::vector<std::pair<float, uint32_t>> d(n);
  for (size_t i = 0; i < n; ++i) {
    g.normals[i] = cloud.points[i].normal;
    for (size_t j = 0; j < n; ++j) d[j] = {(cloud.points[j].position - cloud.points[i].position).norm(), uint32_t(j)};
    d[i].first = INFINITY;
    size_t kk = std::min<size_t>(k, n - 1);
    std::partial_sort(d.begin(), d.begin() + kk, d.end());
    double s = 0;
    for (size_t a = 0; a < kk; ++a) {
      g.delaunayIndices.push_back(d[a].second);
      s += d[a].first;
    }
    g.delaunayOffsets.push_back(uint32_t(g.delaunayIndices.size()));
    g.spacing[i] = kk ? float(s / kk) : 0.f;
    total += g.spacing[i];
  }
  g.averageSpacing = n ? float(total / n) : 0.f;
  return g;
}

bool sameModel(const HybridModel& a, const HybridModel& b) {
  if (a.points.size() != b.points.size() || a.segments.size() != b.segments.size()) return false;
  for (size_t i = 0; i < a.points.size(); ++i)
    if (a.points[i].position != b.points[i].position) return false;
  for (size_t i = 0; i < a.segments.size(); ++i)
    if (a.segments[i].p0 != b.segments[i].p0 || a.segments[i].p1 != b.segments[i].p1 ||
        a.segments[i].normal != b.segments[i].normal || a.segments[i].radius != b.segments[i].radius)
      return false;
  return a.provenance == b.provenance;
}

void expectVerified(const HybridModel& in, const PointGeometry& g, const HybridModel& out, double eps, double delta) {
  VerifyReport r = verifyExtraction(in, &g, out, eps, delta);
  EXPECT_TRUE(r.ok()) << (r.messages.empty() ? std::string("?") : r.messages.front());
  EXPECT_EQ(r.keptPoints + r.replacedPoints, in.points.size());
  EXPECT_LE(r.maxDistance, eps * (1 + 1e-4) + 1e-6);
  EXPECT_LE(r.maxNormalDeviation, delta + 1e-6);
}

}  // namespace

TEST(EpsDelta, RegularPlaneIsAlmostAllSegments) {
  HybridModel cloud = shapes::plane(2.0f, 1.0f, 60, 30);
  PointGeometry g = syntheticGeometry(cloud);
  EpsDeltaStats st;
  HybridModel out = extractEpsDelta(cloud, g, {.provenance = true}, &st);
  EXPECT_EQ(st.inputPoints, 1800u);
  EXPECT_GE(st.replacedFraction(), 0.99);  // every grid row is one straight run
  EXPECT_GT(st.dataReduction(), 0.9);
  EXPECT_EQ(out.points.size() + std::accumulate(out.provenance.begin(), out.provenance.end(), size_t(0),
                                                [](size_t s, auto& p) { return s + p.size(); }),
            cloud.points.size());
  for (const Segment& s : out.segments) {
    EXPECT_NEAR(s.normal.z(), 1.0f, 1e-6f);
    EXPECT_GT(s.length(), 0.0f);
    // Radius covers the replaced discs: input radius (the grid spacing) + distance <= epsilon.
    EXPECT_GE(s.radius, cloud.points[0].radius - 1e-6f);
    EXPECT_LE(s.radius, cloud.points[0].radius + float(st.epsilon) + 1e-6f);
  }
  expectVerified(cloud, g, out, st.epsilon, st.delta);
}

TEST(EpsDelta, RegularCylinderSegmentsFollowGenerators) {
  HybridModel cloud = shapes::cylinder(1.0f, 2.0f, 48, 24);
  PointGeometry g = syntheticGeometry(cloud);
  EpsDeltaStats st;
  HybridModel out = extractEpsDelta(cloud, g, {.provenance = true}, &st);
  EXPECT_GE(st.replacedFraction(), 0.95);
  // Around the axis the surface curves away from any tangent line, so segments run along z.
  for (const Segment& s : out.segments) {
    Vec3f d = (s.p1 - s.p0).normalized();
    EXPECT_GT(std::abs(d.z()), 0.999f);
  }
  expectVerified(cloud, g, out, st.epsilon, st.delta);
}

TEST(EpsDelta, EveryReplacedPointWithinBoundsOnCurvedAndNoisyShapes) {
  shapes::SampleOptions noisy{.noise = 0.02f, .seed = 7};
  for (const HybridModel& cloud : {shapes::sphere(1.0f, 1500), shapes::torus(2.0f, 0.6f, 80, 24, noisy),
                                   shapes::plane(1, 1, 40, 40, {.noise = 0.03f, .seed = 3})}) {
    PointGeometry g = syntheticGeometry(cloud);
    for (double delta : {0.004, 0.05}) {
      EpsDeltaStats st;
      EpsDeltaOptions o{.epsilonRelative = 0.2, .delta = delta, .provenance = true};
      HybridModel out = extractEpsDelta(cloud, g, o, &st);
      expectVerified(cloud, g, out, st.epsilon, st.delta);
    }
  }
}

TEST(EpsDelta, NoiseDegradesGracefully) {
  // Noise below epsilon barely matters; noise well above it and random sampling leave most points
  // as points but still give a valid model.
  double previous = 1.0;
  for (float noise : {0.0f, 0.01f, 0.05f, 0.2f}) {
    HybridModel cloud = shapes::plane(1, 1, 40, 40, {.noise = noise, .seed = 11});
    PointGeometry g = syntheticGeometry(cloud);
    EpsDeltaStats st;
    HybridModel out = extractEpsDelta(cloud, g, {.provenance = true}, &st);
    expectVerified(cloud, g, out, st.epsilon, st.delta);
    if (noise <= 0.01f) { EXPECT_GE(st.replacedFraction(), 0.8) << noise; }
    EXPECT_LE(st.replacedFraction(), previous + 0.05) << noise;
    previous = st.replacedFraction();
  }
  HybridModel random = shapes::plane(1, 1, 40, 40, {.irregular = true, .seed = 5});
  PointGeometry g = syntheticGeometry(random);
  EpsDeltaStats st;
  HybridModel out = extractEpsDelta(random, g, {.provenance = true}, &st);
  expectVerified(random, g, out, st.epsilon, st.delta);
  EXPECT_EQ(st.keptPoints + st.replacedPoints, random.points.size());
}

TEST(EpsDelta, LazyHeapEqualsEagerDefinition) {
  size_t reinserts = 0;
  for (const HybridModel& cloud : {shapes::plane(1, 1, 30, 30, {.noise = 0.03f, .seed = 2}), shapes::sphere(1.0f, 900),
                                   shapes::cylinder(1.0f, 1.0f, 30, 20, {.noise = 0.02f, .seed = 4})}) {
    PointGeometry g = syntheticGeometry(cloud);
    EpsDeltaOptions o{.epsilonRelative = 0.4, .delta = 0.1, .provenance = true};
    EpsDeltaStats lazyStats;
    HybridModel lazy = extractEpsDelta(cloud, g, o, &lazyStats);
    o.update = EpsDeltaUpdate::Eager;
    HybridModel eager = extractEpsDelta(cloud, g, o);
    EXPECT_GT(lazy.segments.size(), 5u);
    reinserts += lazyStats.heapReinserts;
    EXPECT_TRUE(sameModel(lazy, eager));
  }
  EXPECT_GT(reinserts, 0u);  // the lazy path was exercised
}

TEST(EpsDelta, MaxReplacedBoundsSegments) {
  HybridModel cloud = shapes::plane(2.0f, 1.0f, 60, 30);
  PointGeometry g = syntheticGeometry(cloud);
  EpsDeltaStats st;
  HybridModel out = extractEpsDelta(cloud, g, {.maxReplaced = 16, .provenance = true}, &st);
  for (auto& p : out.provenance) EXPECT_LE(p.size(), 16u);
  EXPECT_GE(st.replacedFraction(), 0.9);
  expectVerified(cloud, g, out, st.epsilon, st.delta);
  EXPECT_THROW(extractEpsDelta(cloud, g, {.maxReplaced = 3}), Error);
}

TEST(EpsDelta, SegmentsComeInDecreasingCount) {
  HybridModel cloud = shapes::sphere(1.0f, 1200);
  PointGeometry g = syntheticGeometry(cloud);
  HybridModel out = extractEpsDelta(cloud, g, {.epsilonRelative = 0.3, .delta = 0.03, .provenance = true});
  ASSERT_GT(out.provenance.size(), 3u);
  for (size_t s = 1; s < out.provenance.size(); ++s) EXPECT_LE(out.provenance[s].size(), out.provenance[s - 1].size());
  for (auto& p : out.provenance) EXPECT_GE(p.size(), 4u);  // "3 or less are rejected"
}

TEST(EpsDelta, DeterministicForAnyThreadCount) {
  HybridModel cloud = shapes::torus(2.0f, 0.7f, 90, 30, {.noise = 0.01f, .seed = 9});
  PointGeometry g = syntheticGeometry(cloud);
  EpsDeltaOptions o{.epsilonRelative = 0.2, .delta = 0.01, .provenance = true};
  HybridModel one, many;
  {
    ThreadLimit limit(1);
    one = extractEpsDelta(cloud, g, o);
  }
  {
    ThreadLimit limit(4);
    many = extractEpsDelta(cloud, g, o);
  }
  EXPECT_GT(one.segments.size(), 0u);
  EXPECT_TRUE(sameModel(one, many));
}

TEST(EpsDelta, ColoursArePerSegmentMeans) {
  HybridModel cloud = shapes::plane(1, 1, 10, 3);
  for (size_t i = 0; i < cloud.points.size(); ++i) cloud.points[i].color = Color(float(i % 10) / 9.0f, 0, 0, 1);
  PointGeometry g = syntheticGeometry(cloud);
  HybridModel out = extractEpsDelta(cloud, g, {.provenance = true});
  ASSERT_EQ(out.segments.size(), 3u);  // the three rows
  for (const Segment& s : out.segments) EXPECT_NEAR(s.color.x(), 0.5f, 1e-5f);
  EXPECT_TRUE(out.attributes.colors);
  EXPECT_NE(std::find_if(out.comments.begin(), out.comments.end(),
                         [](auto& c) { return c.rfind("eps-delta: epsilon=", 0) == 0; }),
            out.comments.end());
}

TEST(EpsDelta, DegenerateInputsAreHandled) {
  // Empty, single point, coincident points, a line of points (no tangent plane spread).
  HybridModel empty;
  PointGeometry g0;
  EXPECT_TRUE(extractEpsDelta(empty, g0).empty());
  HybridModel same;
  for (int i = 0; i < 20; ++i) same.points.push_back({Vec3f(1, 2, 3), Vec3f(0, 0, 1)});
  PointGeometry gs = syntheticGeometry(same);
  EpsDeltaStats st;
  HybridModel out = extractEpsDelta(same, gs, {.epsilon = 0.1, .provenance = true}, &st);
  EXPECT_EQ(out.segments.size(), 0u);
  EXPECT_EQ(out.points.size(), 20u);
  for (const Point& p : out.points) EXPECT_TRUE(p.position.allFinite() && std::isfinite(p.radius));
  EXPECT_EQ(st.degenerateNeighbours, 20u * 8u);
}

TEST(EpsDelta, AbsurdParametersThrow) {
  HybridModel cloud = shapes::plane(1, 1, 5, 5);
  PointGeometry g = syntheticGeometry(cloud);
  EXPECT_THROW(extractEpsDelta(cloud, g, {.epsilon = -1}), Error);
  EXPECT_THROW(extractEpsDelta(cloud, g, {.epsilon = NAN}), Error);
  EXPECT_THROW(extractEpsDelta(cloud, g, {.epsilonRelative = 0}), Error);
  EXPECT_THROW(extractEpsDelta(cloud, g, {.delta = -0.1}), Error);
  EXPECT_THROW(extractEpsDelta(cloud, g, {.delta = 3}), Error);
  EXPECT_THROW(extractEpsDelta(cloud, g, {.minReplaced = 1}), Error);
  PointGeometry noDelaunay = g;
  noDelaunay.delaunayOffsets.clear();
  EXPECT_THROW(extractEpsDelta(cloud, noDelaunay), Error);
  HybridModel other = shapes::plane(1, 1, 4, 4);
  EXPECT_THROW(extractEpsDelta(other, g), Error);
}

TEST(EpsDeltaVerify, CatchesViolations) {
  HybridModel cloud = shapes::plane(1, 1, 20, 20);
  PointGeometry g = syntheticGeometry(cloud);
  EpsDeltaStats st;
  HybridModel out = extractEpsDelta(cloud, g, {.provenance = true}, &st);
  ASSERT_TRUE(verifyExtraction(cloud, &g, out, st.epsilon, st.delta).ok());
  {  // move a segment off its points
    HybridModel bad = out;
    bad.segments[0].p0.z() += 10 * float(st.epsilon);
    bad.segments[0].p1.z() += 10 * float(st.epsilon);
    VerifyReport r = verifyExtraction(cloud, &g, bad, st.epsilon, st.delta);
    EXPECT_FALSE(r.ok());
    EXPECT_GT(r.distanceViolations, 0u);
  }
  {  // a replaced point's normal tilted beyond delta
    PointGeometry tilted = g;
    tilted.normals[out.provenance[0].back()] = Vec3f(0.2f, 0, 1).normalized();
    VerifyReport r = verifyExtraction(cloud, &tilted, out, st.epsilon, st.delta);
    EXPECT_EQ(r.normalViolations, 1u);
  }
  {  // a point replaced twice, one missing
    HybridModel bad = out;
    bad.provenance[1].push_back(bad.provenance[0][1]);
    bad.provenance[0].erase(bad.provenance[0].begin() + 2);
    VerifyReport r = verifyExtraction(cloud, &g, bad, st.epsilon, st.delta);
    EXPECT_EQ(r.replacedTwice, 1u);
    EXPECT_EQ(r.missing, 1u);
  }
  {  // no provenance
    HybridModel bad = out;
    bad.provenance.clear();
    EXPECT_THROW(verifyExtraction(cloud, &g, bad, st.epsilon, st.delta), Error);
  }
}

// With the real §6.1 pipeline (PCA normals, local Delaunay neighbours) instead of exact normals.
TEST(EpsDelta, GeometryPipelineOnRegularPlaneAndCylinder) {
  GeometryOptions go;
  go.curvature = false;
  for (const HybridModel& given : {shapes::plane(2.0f, 1.0f, 60, 30), shapes::cylinder(1.0f, 2.0f, 48, 24)}) {
    HybridModel cloud = given;
    cloud.attributes.normals = false;  // normals come from PCA + MST orientation
    for (Point& p : cloud.points) p.normal = Vec3f::Zero();
    PointGeometry g = computePointGeometry(cloud, go);
    EpsDeltaStats st;
    HybridModel out = extractEpsDelta(cloud, g, {.provenance = true}, &st);
    EXPECT_GE(st.replacedFraction(), 0.9) << cloud.points.size();
    expectVerified(cloud, g, out, st.epsilon, st.delta);
  }
}

TEST(EpsDelta, CliExtractThenVerify) {
  auto dir = test::scratchDir("eps_delta_cli");
  HybridModel cloud = shapes::cylinder(1.0f, 2.0f, 40, 20, {.noise = 0.01f, .seed = 3});
  writeModel(dir / "in.ply", cloud);
  auto r = test::runCli("extract eps-delta " + (dir / "in.ply").string() + " -o " + (dir / "out.ply").string() +
                        " --provenance --epsilon-rel 0.1");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("reduction"), std::string::npos) << r.out;
  HybridModel out = readModel(dir / "out.ply");
  EXPECT_GT(out.segments.size(), 0u);
  EXPECT_EQ(out.provenance.size(), out.segments.size());
  r = test::runCli("verify-extraction " + (dir / "in.ply").string() + " " + (dir / "out.ply").string());
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("ok"), std::string::npos) << r.out;
  // A tighter epsilon than the one used must fail the check, with exit code 3.
  r = test::runCli("verify-extraction " + (dir / "in.ply").string() + " " + (dir / "out.ply").string() +
                   " --epsilon 1e-9");
  EXPECT_EQ(r.exitCode, 3) << r.out;
  // Bad parameters are usage errors (exit 1).
  r = test::runCli("extract eps-delta " + (dir / "in.ply").string() + " -o " + (dir / "x.ply").string() +
                   " --delta 5");
  EXPECT_EQ(r.exitCode, 1) << r.out;
  r = test::runCli("extract eps-delta " + (dir / "in.ply").string() + " -o " + (dir / "x.ply").string() +
                   " --epsilon 0.1 --epsilon-rel 0.1");
  EXPECT_EQ(r.exitCode, 1) << r.out;
}

TEST(SharedEpsDelta, SmallModelsVerify) {
  LINESURF_REQUIRE_SHARED_DATA();
  GeometryOptions go;
  go.curvature = false;
  for (const char* name : {"screwdriver_points.ply", "rockerarm_points.ply", "santa_points.ply"}) {
    HybridModel cloud = readModel(test::sharedData() / name);
    PointGeometry g = computePointGeometry(cloud, go);
    EpsDeltaStats st;
    HybridModel out = extractEpsDelta(cloud, g, {.provenance = true}, &st);
    EXPECT_GT(st.segments, 0u) << name;
    EXPECT_EQ(st.keptPoints + st.replacedPoints, cloud.points.size());
    EXPECT_NEAR(st.epsilon, 0.05 * g.averageSpacing, 1e-12) << name;
    expectVerified(cloud, g, out, st.epsilon, st.delta);
  }
}
