#include <gtest/gtest.h>

#include <cmath>

#include "linesurf/core/error.h"
#include "linesurf/eval/image_metrics.h"

using namespace linesurf;

namespace {
Image gradient(int w, int h) {
  Image img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at(x, y) = Color(float(x) / w, float(y) / h, 0.5f, 1);
  return img;
}
}  // namespace

TEST(ImageMetrics, IdenticalImagesArePerfect) {
  Image a = gradient(64, 48);
  ImageMetrics m = compareImages(a, a);
  EXPECT_EQ(m.mse, 0);
  EXPECT_TRUE(std::isinf(m.psnr));
  EXPECT_DOUBLE_EQ(m.nccm, 1.0);
  EXPECT_NEAR(m.ssim, 1.0, 1e-12);
  EXPECT_EQ(m.meanAbsDiff, 0);
  EXPECT_EQ(m.maxAbsDiff, 0);
}

TEST(ImageMetrics, KnownOffsetGivesKnownNumbers) {
  Image a(10, 10, Color(100 / 255.f, 100 / 255.f, 100 / 255.f, 1));
  Image b(10, 10, Color(110 / 255.f, 100 / 255.f, 100 / 255.f, 1));
  ImageMetrics m = compareImages(a, b);
  // One channel of three differs by 10 grey levels everywhere.
  EXPECT_NEAR(m.meanAbsDiff, 10.0 / 3.0, 1e-9);
  EXPECT_NEAR(m.stdAbsDiff, std::sqrt(100.0 / 3.0 - 100.0 / 9.0), 1e-9);
  EXPECT_NEAR(m.mse, (10.0 / 255) * (10.0 / 255) / 3.0, 1e-12);
  EXPECT_NEAR(m.nccm, (100.0 * 110 + 2 * 100 * 100) / (3 * 100.0 * 100), 1e-9);
  EXPECT_EQ(m.maxAbsDiff, 10);
  EXPECT_DOUBLE_EQ(m.differingPixels, 1.0);
}

TEST(ImageMetrics, SsimDropsWithNoiseAndMismatchedSizesThrow) {
  Image a = gradient(64, 64), b = a;
  for (size_t i = 0; i < b.pixels.size(); i += 3) b.pixels[i] = Color(1, 1, 1, 1);
  ImageMetrics m = compareImages(a, b);
  EXPECT_LT(m.ssim, 0.9);
  EXPECT_GT(m.mse, 0);
  EXPECT_THROW(compareImages(a, gradient(32, 64)), Error);
}

TEST(ImageMetrics, HeatmapBlackWhereEqualBrightWhereDifferent) {
  Image a(4, 1, Color(0, 0, 0, 1)), b = a;
  b.at(3, 0) = Color(1, 1, 1, 1);
  Image h = differenceHeatmap(a, b);
  EXPECT_EQ(h.at(0, 0), Color(0, 0, 0, 1));
  EXPECT_EQ(h.at(3, 0), Color(1, 1, 1, 1));
}
