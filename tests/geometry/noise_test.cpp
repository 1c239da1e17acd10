// Noise of a scan along its normals (geometry/noise.h): clouds with Gaussian noise of known sigma
// along the true normal, from a tenth of a spacing to two spacings, on curved and flat shapes.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/geometry/noise.h"
#include "shapes.h"
#include "test_util.h"

namespace linesurf {
namespace {

/// Positions of `clean` moved along their exact normals by N(0, sigma²).
std::vector<Vec3f> noisy(const HybridModel& clean, double sigma, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  std::vector<Vec3f> out;
  out.reserve(clean.points.size());
  for (const Point& p : clean.points) out.push_back(p.position + float(sigma * g(rng)) * p.normal);
  return out;
}

TEST(Noise, SphereWithinTwentyPercentFromATenthToTwoSpacings) {
  const int n = 60000;
  const HybridModel sphere = shapes::sphere(1, n, {.irregular = true, .seed = 3});
  const double s = std::sqrt(4 * 3.14159265358979 / n);
  for (double f : {0.1, 0.5, 1.0, 2.0}) {
    const NoiseEstimate e = estimateNoise(noisy(sphere, f * s, 7));
    EXPECT_NEAR(e.sigma / (f * s), 1.0, 0.2) << "sigma " << f << " spacings";
    EXPECT_GT(e.fitted, e.samples * 9 / 10);
    EXPECT_LE(e.lowerQuartile, e.sigma);
    EXPECT_GE(e.upperQuartile, e.sigma);
  }
}

TEST(Noise, PlaneAndTorus) {
  const HybridModel plane = shapes::plane(1, 1, 200, 200, {.irregular = true, .seed = 5});
  const double sp = 1.0 / 200;
  EXPECT_NEAR(estimateNoise(noisy(plane, 0.5 * sp, 1)).sigma / (0.5 * sp), 1.0, 0.2);
  const HybridModel torus = shapes::torus(1, 0.3f, 400, 120);
  const double st = std::sqrt(4 * 3.14159265358979 * 3.14159265358979 * 0.3 / (400 * 120));
  EXPECT_NEAR(estimateNoise(noisy(torus, 0.25 * st, 2)).sigma / (0.25 * st), 1.0, 0.2);
}

TEST(Noise, CurvatureIsNotNoise) {
  // A clean, curved sampling: the height fit absorbs the curvature, a plane fit would not.
  const int n = 20000;
  const HybridModel sphere = shapes::sphere(1, n, {.irregular = true, .seed = 4});
  const double s = std::sqrt(4 * 3.14159265358979 / n);
  std::vector<Vec3f> pts;
  for (const Point& p : sphere.points) pts.push_back(p.position);
  const NoiseEstimate e = estimateNoise(pts);
  EXPECT_LT(e.sigma, 0.02 * s);
  EXPECT_EQ(e.unresolved, 0u);
  EXPECT_EQ(e.medianNeighbours, 24);
}

TEST(Noise, SameForAnyThreadCount) {
  const HybridModel sphere = shapes::sphere(1, 20000, {.irregular = true, .seed = 6});
  const std::vector<Vec3f> pts = noisy(sphere, 0.01, 9);
  NoiseEstimate one, two;
  {
    ThreadLimit t(1);
    one = estimateNoise(pts);
  }
  {
    ThreadLimit t(2);
    two = estimateNoise(pts);
  }
  EXPECT_EQ(one.sigma, two.sigma);
  EXPECT_EQ(one.fitted, two.fitted);
  EXPECT_EQ(one.upperQuartile, two.upperQuartile);
}

TEST(Noise, DegenerateCloudsAndOptions) {
  EXPECT_EQ(estimateNoise(std::vector<Vec3f>{}).fitted, 0u);
  std::vector<Vec3f> six(6, Vec3f(1, 2, 3));
  EXPECT_EQ(estimateNoise(six).fitted, 0u);
  std::vector<Vec3f> line, same(100, Vec3f(1, 1, 1));
  for (int i = 0; i < 100; ++i) line.push_back(Vec3f(float(i), 0, 0));
  EXPECT_EQ(estimateNoise(line).fitted, 0u);
  EXPECT_EQ(estimateNoise(same).fitted, 0u);
  std::vector<Vec3f> nan = line;
  nan[50].y() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(estimateNoise(nan), Error);
  EXPECT_THROW(estimateNoise(line, {.samples = 3}), Error);
  EXPECT_THROW(estimateNoise(line, {.maxNeighbours = 8}), Error);
  EXPECT_THROW(estimateNoise(line, {.footprint = std::numeric_limits<float>::quiet_NaN()}), Error);
}

// (eps,delta) with epsilonNoise: epsilon follows the noise where it exceeds the thesis's 0.05 x
// spacing, and more of a noisy scan is replaced; where the noise is below, nothing changes.
TEST(Noise, EpsilonFollowsTheNoiseWhenAskedFor) {
  const int n = 20000;
  const HybridModel sphere = shapes::sphere(1, n, {.irregular = true, .seed = 8});
  const double s = std::sqrt(4 * 3.14159265358979 / n);
  HybridModel cloud = sphere;
  const std::vector<Vec3f> pos = noisy(sphere, 0.3 * s, 11);
  for (size_t i = 0; i < pos.size(); ++i) cloud.points[i].position = pos[i], cloud.points[i].normal = Vec3f::Zero();
  cloud.attributes.normals = false;
  GeometryOptions go;
  go.curvature = false;
  const PointGeometry g = computePointGeometry(cloud, go);
  EpsDeltaStats plain, scaled;
  extractEpsDelta(cloud, g, {}, &plain);
  extractEpsDelta(cloud, g, {.epsilonNoise = 2}, &scaled);
  EXPECT_EQ(plain.noiseSigma, 0.0);
  EXPECT_NEAR(scaled.noiseSigma / (0.3 * s), 1.0, 0.25);
  EXPECT_DOUBLE_EQ(scaled.epsilon, std::max(0.05 * g.averageSpacing, 2 * scaled.noiseSigma));
  EXPECT_GT(scaled.epsilon, 4 * plain.epsilon);
  EXPECT_GT(scaled.replacedFraction(), plain.replacedFraction() + 0.1)
      << plain.replacedFraction() << " -> " << scaled.replacedFraction();
  // A clean sphere: the noise is below 0.05 x spacing and epsilon stays the thesis's.
  EpsDeltaStats clean;
  const PointGeometry gc = computePointGeometry(sphere, go);
  extractEpsDelta(sphere, gc, {.epsilonNoise = 2}, &clean);
  EXPECT_DOUBLE_EQ(clean.epsilon, 0.05 * gc.averageSpacing);
  EXPECT_THROW(extractEpsDelta(sphere, gc, {.epsilonNoise = -1}), Error);
  EXPECT_THROW(extractEpsDelta(sphere, gc, {.epsilonNoise = 1e3}), Error);
}

TEST(Noise, CliInfoAndEpsDeltaSayIt) {
  const auto dir = test::scratchDir("noise_cli");
  const int n = 8000;
  HybridModel cloud = shapes::sphere(1, n, {.irregular = true, .seed = 2});
  const double s = std::sqrt(4 * 3.14159265358979 / n);
  const std::vector<Vec3f> pos = noisy(cloud, 0.5 * s, 5);
  for (size_t i = 0; i < pos.size(); ++i) cloud.points[i].position = pos[i];
  writeModel(dir / "noisy.ply", cloud);
  const std::string in = "'" + (dir / "noisy.ply").string() + "'";
  auto info = test::runCli("info " + in);
  ASSERT_EQ(info.exitCode, 0) << info.out;
  EXPECT_NE(info.out.find("noise:      sigma"), std::string::npos) << info.out;
  auto plain = test::runCli("extract eps-delta " + in + " -o '" + (dir / "a.ply").string() + "'");
  ASSERT_EQ(plain.exitCode, 0) << plain.out;
  EXPECT_NE(plain.out.find("the scan's noise exceeds epsilon"), std::string::npos) << plain.out;
  auto scaled = test::runCli("extract eps-delta " + in + " -o '" + (dir / "b.ply").string() + "' --epsilon-noise 2");
  ASSERT_EQ(scaled.exitCode, 0) << scaled.out;
  EXPECT_NE(scaled.out.find("2 x sigma"), std::string::npos) << scaled.out;
  EXPECT_EQ(scaled.out.find("exceeds epsilon"), std::string::npos) << scaled.out;
  // --epsilon is absolute: the two are exclusive, refused before any work and no output written.
  auto both = test::runCli("extract eps-delta " + in + " -o '" + (dir / "c.ply").string() + "' --epsilon 0.01 --epsilon-noise 2");
  EXPECT_NE(both.exitCode, 0) << both.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "c.ply"));
}

}  // namespace
}  // namespace linesurf
