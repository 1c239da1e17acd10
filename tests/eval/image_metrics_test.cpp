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

// A 20x20 frame: a covered square [5, 15)^2, its left half at depth 1 and its right half at depth
// 2 (an inner silhouette at x = 9 | 10), one partly covered pixel at (12, 12).
TEST(ImageMetrics, SilhouetteBandHoldsOutlinesDepthStepsAndPartialPixels) {
  Image alpha(20, 20, Color(0, 0, 0, 0)), depth(20, 20, Color(0, 0, 0, 0));
  for (int y = 5; y < 15; ++y)
    for (int x = 5; x < 15; ++x) {
      alpha.at(x, y) = Color(1, 1, 1, 1);
      const float z = x < 10 ? 1.0f : 2.0f;
      depth.at(x, y) = Color(z, z, z, 1);
    }
  alpha.at(12, 12) = Color(0.5f, 0.5f, 0.5f, 0.5f);
  auto in = [](const std::vector<uint8_t>& b, int x, int y) { return b[size_t(y) * 20 + x] != 0; };
  const std::vector<uint8_t> b0 = silhouetteBand(alpha, depth, 0, 0.5);
  ASSERT_EQ(b0.size(), 400u);
  EXPECT_TRUE(in(b0, 4, 7) && in(b0, 5, 7));     // both sides of the outline
  EXPECT_TRUE(in(b0, 9, 7) && in(b0, 10, 7));    // both sides of the depth step
  EXPECT_TRUE(in(b0, 12, 12));                   // partly covered
  EXPECT_FALSE(in(b0, 7, 7) || in(b0, 3, 7) || in(b0, 0, 0) || in(b0, 12, 8));
  const std::vector<uint8_t> b1 = silhouetteBand(alpha, depth, 1, 0.5);
  EXPECT_TRUE(in(b1, 3, 7) && in(b1, 6, 6) && in(b1, 8, 7) && in(b1, 11, 11));
  EXPECT_FALSE(in(b1, 2, 7) || in(b1, 7, 7) || in(b1, 12, 8));
  EXPECT_TRUE(silhouetteBand(alpha, depth, 2, 0.5)[size_t(7) * 20 + 7]);
  // a step of 1 at depth 1 is no silhouette when the jump allowed is 2 x the depth
  const std::vector<uint8_t> flat = silhouetteBand(alpha, depth, 0, 2.0);
  EXPECT_FALSE(in(flat, 9, 7) || in(flat, 10, 7));
  EXPECT_TRUE(in(flat, 4, 7));
  EXPECT_THROW(silhouetteBand(alpha, depth, -1, 0.5), Error);
  EXPECT_THROW(silhouetteBand(alpha, depth, 1, 0.0), Error);
  EXPECT_THROW(silhouetteBand(alpha, Image(10, 10), 1, 0.5), Error);
}

TEST(ImageMetrics, HoleMapCountsWhatTheReferenceCoversAndTheTestDoesNot) {
  // A 40x40 disc of radius 15; the test misses a 4x5 block inside it and adds 3 pixels outside.
  for (bool alpha : {false, true}) {
    const Color bg = alpha ? Color(0, 0, 0, 0) : Color(1, 1, 1, 1), ink(0.4f, 0.5f, 0.6f, 1);
    Image ref(40, 40, bg), test(40, 40, bg);
    size_t disc = 0;
    for (int y = 0; y < 40; ++y)
      for (int x = 0; x < 40; ++x)
        if ((x - 20) * (x - 20) + (y - 20) * (y - 20) <= 15 * 15) {
          ref.at(x, y) = ink, ++disc;
          if (!(x >= 10 && x < 14 && y >= 18 && y < 23)) test.at(x, y) = ink;
        }
    test.at(0, 0) = test.at(1, 0) = test.at(39, 39) = ink;
    const HoleMap h = holeMap(ref, test);
    EXPECT_EQ(h.byAlpha, alpha);
    EXPECT_EQ(h.referencePixels, disc);
    EXPECT_EQ(h.holes, 20u);
    EXPECT_EQ(h.extra, 3u);
    EXPECT_DOUBLE_EQ(h.holeShare(), 20.0 / double(disc));
    EXPECT_GT(h.map.at(11, 20).x(), 0.8f);  // a hole: red
    EXPECT_LT(h.map.at(11, 20).y(), 0.2f);
    EXPECT_EQ(h.map.at(20, 20).x(), h.map.at(20, 20).y());  // covered by both: grey
    EXPECT_EQ(holeMap(ref, ref).holes, 0u);
  }
  EXPECT_THROW(holeMap(Image(4, 4), Image(4, 5)), Error);
}
