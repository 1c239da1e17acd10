// Tail coverage (RenderOptions::tailCoverage; beyond the thesis): a pixel reached only by
// prefilter tails with nothing behind it fades towards the background, as a box-filtered surface's
// edge does; nothing inside a surface changes, alpha only falls, the SIMD rows agree with the pixel
// resolve and the image does not depend on the thread count.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "render/coverage.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/render/renderer.h"
#include "test_util.h"

namespace linesurf {
namespace {

using test::maxAbsDiff;

// A square 2 x 2 as points on a 41 x 41 grid (spacing h = 0.05), or as strips along x at the same
// spacing, seen head-on from so far that a sample spacing is ~1 pixel: the splats are small
// against the screen prefilter, so the prefilter's tails reach past the square's edge.
constexpr int kSize = 128;
// 8.578: the square's half side is 20.5 px, so the column of pixel centres just outside each edge
// lies 1.0 px past the edge samples: past 1.5 disc radii (0.84 px: tails), within the resampling
// filter's cut-off (1.16 px)
constexpr float kDistance = 8.578f;
HybridModel squareStrips() { return test::squareStrips(0.55f); }  // the contour models' radius (0.55 d)
HybridModel squarePoints() {
  HybridModel m = shapes::plane(2, 2, 41, 41);
  for (Point& p : m.points) p.radius = 0.55f * 0.05f;  // the contour models' radius (0.55 d)
  return m;
}
Camera headOn() { return Camera::lookAt(Vec3f(0, 0, kDistance), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, kSize, kSize); }

// The box-filtered coverage of pixel (x, y) by the square grown by half a spacing (the samples'
// cells), 16 x 16 samples per pixel.
float boxCoverage(const Camera& cam, int x, int y) {
  const float half = (1.0f + 0.025f) * cam.focalPixels() / kDistance;
  int in = 0;
  for (int j = 0; j < 16; ++j)
    for (int i = 0; i < 16; ++i) {
      const float dx = std::abs(float(x) + (float(i) + 0.5f) / 16 - 0.5f * kSize);
      const float dy = std::abs(float(y) + (float(j) + 0.5f) / 16 - 0.5f * kSize);
      in += std::max(dx, dy) <= half;
    }
  return float(in) / 256.0f;
}

TEST(TailCoverage, FadesTheFringeTowardsTheBoxFilteredEdge) {
  const Camera cam = headOn();
  const float half = cam.focalPixels() / kDistance;  // the square's half side in pixels
  for (bool strips : {false, true}) {
    const HybridModel m = strips ? squareStrips() : squarePoints();
    RenderOptions o;
    o.alphaBuffer = true;
    o.tailCoverage = 0;
    const RenderResult off = renderImage(m, cam, o);
    o.tailCoverage = 1;
    const RenderResult on = renderImage(m, cam, o);
    double errOff = 0, errOn = 0;
    int changed = 0, inside = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const float a0 = off.alpha->at(x, y).w(), a1 = on.alpha->at(x, y).w();
        EXPECT_LE(a1, a0 + 1e-6f) << x << "," << y;  // alpha only falls
        changed += a1 < a0 - 1e-3f;
        const float dx = std::abs(float(x) + 0.5f - 0.5f * kSize), dy = std::abs(float(y) + 0.5f - 0.5f * kSize);
        if (std::max(dx, dy) <= half) {  // inside the square: untouched
          ++inside;
          EXPECT_EQ((on.color.at(x, y) - off.color.at(x, y)).cwiseAbs().maxCoeff(), 0.0f) << x << "," << y;
        }
        const float box = boxCoverage(cam, x, y);
        errOff += std::abs(a0 - box), errOn += std::abs(a1 - box);
      }
    std::printf("%s: %d fringe pixels faded; |alpha - box-filtered square| summed %.1f -> %.1f\n",
                strips ? "strips" : "points", changed, errOff, errOn);
    EXPECT_GT(inside, 1000);
    EXPECT_GT(changed, 40) << strips;           // the prefilter's tails do reach past the edge here
    EXPECT_LT(errOn, 0.8 * errOff) << strips;   // and the faded edge is nearer the box-filtered one
  }
}

TEST(TailCoverage, SimdRowsMatchThePixelResolveAndThreads) {
  // a sphere of small points in front of a strip plane: fringes against the background and over
  // the plane (a tail-only front over a layer stays skipped)
  HybridModel m = shapes::sphere(0.6f, 20000);
  for (Point& p : m.points) p.position.z() += 0.8f;
  m.segments = squareStrips().segments;
  const Camera cam = Camera::lookAt(Vec3f(0.3f, 0.2f, 9), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 120, 90);
  RenderOptions o;
  o.tailCoverage = 1;
  const RenderResult simd = renderImage(m, cam, o);
  o.alphaBuffer = true;  // every pixel through Z3Tile::resolve
  const RenderResult pixel = renderImage(m, cam, o);
  EXPECT_LT(maxAbsDiff(simd.color, pixel.color), 1e-6f);
  int faded = 0;
  for (const Color& c : pixel.alpha->pixels) faded += c.w() > 0 && c.w() < 0.99f;
  EXPECT_GT(faded, 20);
  RenderResult one;
  {
    ThreadLimit single(1);
    one = renderImage(m, cam, o);
  }
  EXPECT_EQ(maxAbsDiff(one.color, pixel.color), 0.0f);
  // off, and without tail layers, the gain changes nothing
  o.tailCoverage = 0;
  const Image plain = renderImage(m, cam, o).color;
  EXPECT_GT(maxAbsDiff(plain, pixel.color), 0.05f);
  o.tailLayers = false;
  const Image noTails = renderImage(m, cam, o).color;
  o.tailCoverage = 1;
  EXPECT_EQ(maxAbsDiff(renderImage(m, cam, o).color, noTails), 0.0f);
}

TEST(TailCoverage, MedianConstantIsTheModelsInverseDensity) {
  // a regular grid of points: every primitive's constant is alike, so the median of a sample is
  // that of all of them
  const HybridModel m = squarePoints();
  std::vector<float> all = detail::coverageConstants(m, 0.5f, 2.0f, false);
  std::nth_element(all.begin(), all.begin() + ptrdiff_t(all.size() / 2), all.end());
  const float med = detail::medianCoverageConstant(m, 0.5f, 2.0f);
  EXPECT_GT(med, 0.0f);
  EXPECT_NEAR(med, all[all.size() / 2], 0.02f * all[all.size() / 2]);
  EXPECT_EQ(detail::medianCoverageConstant(HybridModel{}, 0.5f, 2.0f), 0.0f);
}

TEST(TailCoverage, RejectsBadGains) {
  const HybridModel m = squarePoints();
  for (float g : {-1.0f, 101.0f, std::nanf(""), INFINITY}) {
    RenderOptions bad;
    bad.tailCoverage = g;
    EXPECT_THROW(Renderer(m, bad), Error) << g;
  }
}

}  // namespace
}  // namespace linesurf
