#include "linesurf/eval/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "linesurf/core/error.h"

namespace linesurf {
namespace {

/// 8-bit quantisation as in a PNG file: clamp to [0,1], round to 1/255.
inline double q8(float v) {
  if (!(v > 0)) return 0;
  return std::round(std::min(v, 1.0f) * 255.0f);
}

void checkSizes(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height || a.empty())
    throwBadParameter("images", "sizes differ or are empty (" + std::to_string(a.width) + "x" + std::to_string(a.height) +
                                    " vs " + std::to_string(b.width) + "x" + std::to_string(b.height) + ")");
}

/// SSIM on luma with a uniform 8x8 window moved by 4 pixels (Wang, Bovik, Sheikh, Simoncelli 2004).
double ssimLuma(const Image& a, const Image& b) {
  const int w = a.width, h = a.height;
  auto luma = [](const Color& c) { return 0.299 * q8(c[0]) + 0.587 * q8(c[1]) + 0.114 * q8(c[2]); };
  std::vector<double> la(size_t(w) * h), lb(size_t(w) * h);
  for (size_t i = 0; i < la.size(); ++i) {
    la[i] = luma(a.pixels[i]);
    lb[i] = luma(b.pixels[i]);
  }
  const double c1 = std::pow(0.01 * 255, 2), c2 = std::pow(0.03 * 255, 2);
  const int win = std::min({8, w, h});
  double sum = 0;
  long count = 0;
  for (int y0 = 0; y0 + win <= h; y0 += std::max(1, win / 2))
    for (int x0 = 0; x0 + win <= w; x0 += std::max(1, win / 2)) {
      double ma = 0, mb = 0;
      for (int y = y0; y < y0 + win; ++y)
        for (int x = x0; x < x0 + win; ++x) {
          ma += la[size_t(y) * w + x];
          mb += lb[size_t(y) * w + x];
        }
      const double n = double(win) * win;
      ma /= n;
      mb /= n;
      double va = 0, vb = 0, cov = 0;
      for (int y = y0; y < y0 + win; ++y)
        for (int x = x0; x < x0 + win; ++x) {
          double da = la[size_t(y) * w + x] - ma, db = lb[size_t(y) * w + x] - mb;
          va += da * da;
          vb += db * db;
          cov += da * db;
        }
      va /= n - 1;
      vb /= n - 1;
      cov /= n - 1;
      sum += ((2 * ma * mb + c1) * (2 * cov + c2)) / ((ma * ma + mb * mb + c1) * (va + vb + c2));
      ++count;
    }
  return count ? sum / count : 1.0;
}

}  // namespace

ImageMetrics compareImages(const Image& a, const Image& b) {
  checkSizes(a, b);
  ImageMetrics m;
  double se = 0, ab = 0, aa = 0, sumAbs = 0, sumAbs2 = 0, maxAbs = 0;
  size_t differing = 0;
  const size_t n = a.pixels.size();
  for (size_t i = 0; i < n; ++i) {
    bool differs = false;
    for (int c = 0; c < 3; ++c) {
      const double va = q8(a.pixels[i][c]), vb = q8(b.pixels[i][c]);
      const double d = std::abs(va - vb);
      se += (d / 255) * (d / 255);
      ab += (va / 255) * (vb / 255);
      aa += (va / 255) * (va / 255);
      sumAbs += d;
      sumAbs2 += d * d;
      maxAbs = std::max(maxAbs, d);
      differs |= d > 1;
    }
    differing += differs;
  }
  const double count = 3.0 * double(n);
  m.mse = se / count;
  m.psnr = m.mse > 0 ? 10 * std::log10(1.0 / m.mse) : std::numeric_limits<double>::infinity();
  m.nccm = aa > 0 ? ab / aa : (ab == 0 ? 1.0 : 0.0);
  m.meanAbsDiff = sumAbs / count;
  m.stdAbsDiff = std::sqrt(std::max(0.0, sumAbs2 / count - m.meanAbsDiff * m.meanAbsDiff));
  m.maxAbsDiff = maxAbs;
  m.differingPixels = double(differing) / double(n);
  m.ssim = ssimLuma(a, b);
  return m;
}

Image differenceHeatmap(const Image& a, const Image& b, double saturate) {
  checkSizes(a, b);
  Image out(a.width, a.height, Color(0, 0, 0, 1));
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    double d = 0;
    for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(q8(a.pixels[i][c]) - q8(b.pixels[i][c])));
    const float t = float(std::clamp(d / std::max(saturate, 1e-9), 0.0, 1.0));
    // black -> red -> yellow -> white
    out.pixels[i] = Color(std::min(1.0f, 3 * t), std::clamp(3 * t - 1, 0.0f, 1.0f), std::clamp(3 * t - 2, 0.0f, 1.0f), 1);
  }
  return out;
}

std::vector<uint8_t> silhouetteBand(const Image& alpha, const Image& depth, int reach, double jump) {
  checkSizes(alpha, depth);
  if (reach < 0) throwBadParameter("silhouette band reach", "must be >= 0");
  if (!(jump > 0)) throwBadParameter("silhouette band depth jump", "must be > 0");
  const int W = alpha.width, H = alpha.height;
  auto covered = [&](int x, int y) { return alpha.at(x, y)[0] > 0; };
  auto apart = [&](int x0, int y0, int x1, int y1) {
    const bool c0 = covered(x0, y0), c1 = covered(x1, y1);
    if (c0 != c1) return true;
    if (!c0) return false;
    const double z0 = depth.at(x0, y0)[0], z1 = depth.at(x1, y1)[0];
    return std::abs(z0 - z1) > jump * std::min(z0, z1);
  };
  // silhouette pixels: both pixels of a pair that lies apart, and the partly covered ones
  std::vector<uint8_t> sil(size_t(W) * H, 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const float a = alpha.at(x, y)[0];
      if (a > 0 && a < 1) sil[size_t(y) * W + x] = 1;
      if (x + 1 < W && apart(x, y, x + 1, y)) sil[size_t(y) * W + x] = sil[size_t(y) * W + x + 1] = 1;
      if (y + 1 < H && apart(x, y, x, y + 1)) sil[size_t(y) * W + x] = sil[size_t(y + 1) * W + x] = 1;
    }
  // square dilation by `reach`, separable: rows, then columns
  std::vector<uint8_t> rows(sil.size(), 0), band(sil.size(), 0);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (sil[size_t(y) * W + x])
        for (int u = std::max(0, x - reach); u <= std::min(W - 1, x + reach); ++u) rows[size_t(y) * W + u] = 1;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if (rows[size_t(y) * W + x])
        for (int v = std::max(0, y - reach); v <= std::min(H - 1, y + reach); ++v) band[size_t(v) * W + x] = 1;
  return band;
}

HoleMap holeMap(const Image& reference, const Image& test, const Color& background) {
  checkSizes(reference, test);
  auto hasAlpha = [](const Image& im) {
    return std::any_of(im.pixels.begin(), im.pixels.end(), [](const Color& c) { return q8(c[3]) < 255; });
  };
  HoleMap h;
  h.byAlpha = hasAlpha(reference) && hasAlpha(test);
  const double bg[3] = {q8(background[0]), q8(background[1]), q8(background[2])};
  auto covered = [&](const Color& c) {
    if (h.byAlpha) return c[3] > 0.5f;
    for (int k = 0; k < 3; ++k)
      if (std::abs(q8(c[k]) - bg[k]) > 1) return true;
    return false;
  };
  h.map = Image(reference.width, reference.height, Color(1, 1, 1, 1));
  for (size_t i = 0; i < reference.pixels.size(); ++i) {
    const bool r = covered(reference.pixels[i]), t = covered(test.pixels[i]);
    h.referencePixels += r, h.holes += r && !t, h.extra += t && !r;
    if (r) h.map.pixels[i] = t ? Color(0.75f, 0.75f, 0.75f, 1) : Color(0.9f, 0.05f, 0.05f, 1);
  }
  return h;
}

}  // namespace linesurf
