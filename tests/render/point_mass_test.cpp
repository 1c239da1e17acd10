// Point masses (pointMasses, the "mass" point property; beyond the thesis): a splat of
// mass m weighs as m coincident ones, masses of 1 change nothing, rows of points of unequal
// spacing weighted by the length they stand for render as the segments through them do, and bad
// masses are refused by the renderer and by the model reader.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/io/model_io.h"
#include "linesurf/render/renderer.h"
#include "test_util.h"

namespace linesurf {
namespace {

using test::maxAbsDiff;

Camera headOn(float distance, int size) {
  return Camera::lookAt(Vec3f(0, 0, distance), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, size, size);
}

// A jittered grid of points on the plane z = 0 with a colour ramp, every third point twice (or once
// with mass 2).
HybridModel rampGrid(bool duplicates) {
  HybridModel m = shapes::plane(2, 2, 31, 31);
  std::vector<float> mass;
  HybridModel out;
  out.attributes = m.attributes;
  out.attributes.colors = true;
  for (size_t i = 0; i < m.points.size(); ++i) {
    Point p = m.points[i];
    p.position += 0.02f * Vec3f(std::sin(float(i) * 1.7f), std::cos(float(i) * 2.3f), 0);
    p.radius = 0.05f;
    p.color = Color(0.5f + 0.5f * p.position.x(), 0.3f, 0.5f - 0.4f * p.position.y(), 1);
    const bool twice = i % 3 == 0;
    out.points.push_back(p);
    if (duplicates && twice) out.points.push_back(p);
    mass.push_back(twice && !duplicates ? 2.0f : 1.0f);
    if (duplicates && twice) mass.push_back(1.0f);
  }
  if (!duplicates) out.pointProperties[kPointMassProperty] = mass;
  return out;
}

TEST(PointMasses, AMassOfTwoDrawsAsTwoCoincidentPoints) {
  const Camera cam = headOn(4, 160);
  for (int threads : {1, 0}) {
    ThreadLimit limit(threads);
    RenderOptions o;
    const HybridModel twice = rampGrid(true), massive = rampGrid(false);
    ASSERT_NE(pointMasses(massive), nullptr);
    ASSERT_EQ(pointMasses(twice), nullptr);
    const Image a = renderImage(twice, cam, o).color, b = renderImage(massive, cam, o).color;
    HybridModel plain = massive;
    plain.pointProperties.clear();
    const Image c = renderImage(plain, cam, o).color;
    std::printf("threads %d: |two points - mass 2| %.2e, |mass 2 - mass 1| %.3f\n", threads, maxAbsDiff(a, b), maxAbsDiff(b, c));
    EXPECT_LT(maxAbsDiff(a, b), 1e-4f);  // the same sums, in another order
    EXPECT_GT(maxAbsDiff(b, c), 3e-3f);  // and the masses do change the picture
  }
}

TEST(PointMasses, MassesOfOneChangeNothing) {
  const Camera cam = headOn(4, 128);
  HybridModel m = rampGrid(false);
  m.pointProperties.clear();
  RenderOptions o;
  const Image plain = renderImage(m, cam, o).color;
  m.pointProperties[kPointMassProperty].assign(m.points.size(), 1.0f);
  EXPECT_EQ(renderImage(m, cam, o).color.pixels, plain.pixels);
  // with coverage alpha the constants see the masses too: ones change nothing there either
  o.coverageGain = 1.25f;
  const Image covered = renderImage(m, cam, o).color;
  m.pointProperties.clear();
  EXPECT_EQ(renderImage(m, cam, o).color.pixels, covered.pixels);
}

// Rows along x, h apart: even rows black and dense (spacing h/4), odd rows white and sparse
// (spacing h), as points of radius 0.55 h (a contour model's) or as the segments through them.
HybridModel rows(bool segments, bool masses) {
  HybridModel m;
  m.attributes.colors = true;
  const float h = 0.1f, r = 0.55f * h;
  std::vector<float> mass;
  for (int j = -10; j <= 10; ++j) {
    const bool dense = j % 2 == 0;
    const Color col = dense ? Color(0, 0, 0, 1) : Color(1, 1, 1, 1);
    const float y = float(j) * h;
    if (segments) {
      Segment s;
      s.p0 = Vec3f(-1, y, 0), s.p1 = Vec3f(1, y, 0), s.normal = Vec3f(0, 0, 1), s.radius = r, s.color = col;
      m.segments.push_back(s);
      continue;
    }
    const int n = dense ? 81 : 21;
    const float spacing = 2.0f / float(n - 1);
    for (int i = 0; i < n; ++i) {
      Point p;
      p.position = Vec3f(-1 + float(i) * spacing, y, 0), p.normal = Vec3f(0, 0, 1), p.radius = r, p.color = col;
      m.points.push_back(p);
      mass.push_back((i == 0 || i == n - 1 ? 0.5f : 1.0f) * spacing / r);  // as extractContour writes them
    }
  }
  if (masses && !segments) m.pointProperties[kPointMassProperty] = mass;
  return m;
}

TEST(PointMasses, UnevenRowsWeightedByLengthRenderAsTheirSegments) {
  // h ~ 1.5 pixels, so that the kernels of neighbouring rows overlap (as neighbouring contours'
  // do where the screen prefilter is as wide as the spacing)
  const Camera cam = headOn(11.7f, 128);
  RenderOptions o;
  auto meanGrey = [](const Image& im) {  // over the middle 16 x 16 pixels (the rows span ~30)
    double s = 0;
    for (int y = 56; y < 72; ++y)
      for (int x = 56; x < 72; ++x) s += im.at(x, y).head<3>().mean();
    return s / (16.0 * 16.0);
  };
  const double seg = meanGrey(renderImage(rows(true, false), cam, o).color);
  const double weighted = meanGrey(renderImage(rows(false, true), cam, o).color);
  const double plain = meanGrey(renderImage(rows(false, false), cam, o).color);
  std::printf("mean grey: segments %.3f, points weighted by length %.3f, points of mass 1 %.3f\n", seg, weighted, plain);
  EXPECT_NEAR(weighted, seg, 0.02);
  EXPECT_GT(seg - plain, 0.05);  // unweighted, the dense black rows outweigh the white ones (0.10 here)
}

TEST(PointMasses, BadMassesAreRefused) {
  for (float bad : {0.0f, -1.0f, NAN, INFINITY, 1e7f}) {
    HybridModel m = rampGrid(false);
    (*const_cast<std::vector<float>*>(pointMasses(m)))[5] = bad;
    EXPECT_THROW(Renderer(m, RenderOptions{}), Error) << bad;
    const auto path = test::scratchDir("point_mass_bad") / "bad.ply";
    EXPECT_THROW(writeModel(path, m), Error) << bad;
  }
  // a file written with a bad mass (by someone else) is refused on reading, naming the file
  const auto path = test::scratchDir("point_mass_bad") / "zero_mass.ply";
  {
    std::ofstream f(path);
    f << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
         "property float nx\nproperty float ny\nproperty float nz\nproperty float radius\nproperty float mass\n"
         "end_header\n0 0 0 0 0 1 0.1 1\n1 0 0 0 0 1 0.1 0\n";
  }
  try {
    (void)readModel(path);
    ADD_FAILURE() << "read a zero mass";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("zero_mass.ply"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("mass"), std::string::npos) << e.what();
  }
  auto r = test::runCli("render " + path.string() + " -o " + (path.parent_path() / "x.png").string());
  EXPECT_EQ(r.exitCode, 2) << r.out;  // bad input
  EXPECT_NE(r.out.find("zero_mass.ply"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(path.parent_path() / "x.png"));
}

}  // namespace
}  // namespace linesurf
