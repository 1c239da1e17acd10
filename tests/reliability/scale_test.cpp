// Scale-free geometry and rendering (docs/decisions.md "CLI and reliability"): the same model
// scaled by 1e-12, 1 and 1e12 renders images within 1 grey level of each other from the auto-framed
// camera (points with normals and radii, raw points whose normals and radii the geometry stage
// estimates, and line segments without radius), and `normals --curvature` output reads back with
// finite values that scale as they should (spacing x s, curvature / s).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "linesurf/io/image_io.h"
#include "linesurf/io/model_io.h"
#include "sphere_fixture.h"
#include "test_util.h"

using namespace linesurf;
namespace fs = std::filesystem;

namespace {

HybridModel sphere(float s, bool attributes) { return test::randomSphere(600, s, attributes, 3); }

/// Rows of segments on a unit square (no radius: estimated from their spacing).
HybridModel rows(float s) {
  HybridModel m;
  for (int j = 0; j <= 20; ++j) {
    Segment seg;
    seg.p0 = Vec3f(-1, -1 + 0.1f * j, 0) * s;
    seg.p1 = Vec3f(1, -1 + 0.1f * j, 0) * s;
    seg.normal = Vec3f(0, 0, 1);
    m.segments.push_back(seg);
  }
  m.attributes.normals = true;
  return m;
}

int maxGreyDifference(const Image& a, const Image& b) {
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  int worst = 0;
  for (size_t i = 0; i < a.pixels.size() && i < b.pixels.size(); ++i)
    for (int c = 0; c < 3; ++c)
      worst = std::max(worst, int(std::lround(std::abs(a.pixels[i][c] - b.pixels[i][c]) * 255.0f)));
  return worst;
}

int coveredPixels(const Image& a) {
  int n = 0;
  for (const Color& c : a.pixels) n += c.head<3>().minCoeff() < 0.99f;
  return n;
}

void expectSameAcrossScales(const std::string& name, HybridModel (*make)(float, bool), bool attributes,
                            const std::string& ext) {
  const fs::path dir = test::scratchDir("scale_" + name);
  std::vector<Image> images;
  for (float s : {1e-12f, 1.0f, 1e12f}) {
    const fs::path model = dir / (name + std::to_string(images.size()) + ext);
    writeModel(model, make(s, attributes));
    const fs::path png = dir / (name + std::to_string(images.size()) + ".png");
    test::CliResult r = test::runCli("render '" + model.string() + "' -o '" + png.string() + "' --size 128x128 -q");
    ASSERT_EQ(r.exitCode, 0) << r.out;
    images.push_back(readImage(png));
  }
  EXPECT_GT(coveredPixels(images[1]), 128 * 128 / 10) << "the unit model must draw a picture";
  EXPECT_LE(maxGreyDifference(images[1], images[0]), 1) << name << ": 1e-12 vs 1";
  EXPECT_LE(maxGreyDifference(images[1], images[2]), 1) << name << ": 1e12 vs 1";
}

HybridModel rowsModel(float s, bool) { return rows(s); }

}  // namespace

TEST(ScaleFree, PointsWithNormalsAndRadiiRenderTheSamePicture) { expectSameAcrossScales("pts", sphere, true, ".ply"); }

TEST(ScaleFree, RawPointsRenderTheSamePicture) { expectSameAcrossScales("raw", sphere, false, ".xyz"); }

TEST(ScaleFree, SegmentsWithoutRadiusRenderTheSamePicture) { expectSameAcrossScales("rows", rowsModel, true, ".ply"); }

TEST(ScaleFree, NormalsAndCurvatureReadBackFiniteAndScaled) {
  const fs::path dir = test::scratchDir("scale_normals");
  std::vector<HybridModel> out;
  const float scales[3] = {1e-12f, 1.0f, 1e12f};
  for (float s : scales) {
    const fs::path in = dir / ("in" + std::to_string(out.size()) + ".xyz"), o = dir / ("out" + std::to_string(out.size()) + ".ply");
    writeModel(in, sphere(s, false));
    test::CliResult r = test::runCli("normals '" + in.string() + "' -o '" + o.string() + "' --curvature -q");
    ASSERT_EQ(r.exitCode, 0) << r.out;
    out.push_back(readModel(o));  // the reader's validation: every value finite
  }
  for (size_t k = 0; k < 3; ++k) {
    const HybridModel& m = out[k];
    ASSERT_EQ(m.points.size(), 600u);
    ASSERT_TRUE(m.pointProperties.count("k_max"));
    for (size_t i = 0; i < m.points.size(); i += 37) {
      // Radius (spacing) scales with s, curvature with 1/s, normals do not change.
      EXPECT_NEAR(m.points[i].radius / scales[k], out[1].points[i].radius, 1e-3f * out[1].points[i].radius);
      const float kUnit = out[1].pointProperties.at("k_max")[i];
      EXPECT_NEAR(m.pointProperties.at("k_max")[i] * scales[k], kUnit, 1e-3f * std::abs(kUnit) + 1e-4f);
      EXPECT_LT((m.points[i].normal - out[1].points[i].normal).norm(), 1e-3f);
    }
  }
}
