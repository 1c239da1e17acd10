#pragma once
/// Tail coverage (RenderOptions::tailCoverage > 0 with tail layers; beyond the thesis, see
/// docs/decisions.md, "Tail coverage"): a pixel that only prefilter tails reached (Z3Tile's
/// tail-only layer, opaque flag -1; tail layers: z3_buffer.h) and that borders an empty pixel lies
/// past a silhouette; it is composited over the background with alpha min(1, s W) instead of the
/// normalised 1 (W its weight sum, s the frame's scale: the gain times the model's median coverage
/// constant, coverage.h). The resolve collects the candidates per tile (collectTailPixels); the
/// renderer composites them after every tile (compositeTailPixels).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "linesurf/core/image.h"
#include "pixel_rect.h"
#include "z3_buffer.h"

namespace linesurf::detail {

/// A tail-only pixel whose faded alpha is below 1.
struct TailPixel {
  uint32_t x, y;
  float alpha;
};

/// Row y of the resolved tile `z3` (its counts rowCounts from rect.x0): which pixels hold a layer
/// (coveredRow, rect.width() bytes of the frame's mask from rect.x0), and the tail-only pixels
/// with their faded alpha min(1, scale W) below 1 appended to `out`. A tail-only layer is always a
/// pixel's only one in an opaque frame (Z3Tile::setTailLayers).
inline void collectTailPixels(Z3Tile& z3, const PixelRect& rect, int y, const int32_t* rowCounts,
                              uint8_t* coveredRow, float scale, std::vector<TailPixel>& out) {
  const size_t p0 = z3.index(rect.x0, y);
  const float* flag = z3.plane(0, Z3Tile::kOpaque) + p0;
  const float* W = z3.plane(0, Z3Tile::kW) + p0;
  const int n = rect.width();
  for (int i = 0; i < n; ++i) coveredRow[i] = rowCounts[i] > 0;  // (two loops: this one vectorises)
  for (int i = 0; i < n; ++i)
    if (flag[i] < 0 && rowCounts[i] == 1) {
      const float a = std::min(1.0f, scale * W[i]);
      if (a < 1.0f) out.push_back({uint32_t(rect.x0 + i), uint32_t(y), a});
    }
}

/// The frame's pass (after every tile): a collected tail pixel next to an empty one (3 x 3) lies
/// past a silhouette, where only the prefilter reached: its colour in `color` (written opaque) is
/// composited over the background with its faded alpha (and that alpha written to `alpha`, when
/// given). One that no empty pixel borders fills a gap inside a surface and stays opaque. Reads
/// only the covered mask, writes only these pixels: independent of the order of the tiles.
void compositeTailPixels(const std::vector<std::vector<TailPixel>>& tailPixels, size_t tiles, const uint8_t* covered,
                         const Color& background, Image& color, Image* alpha);

}  // namespace linesurf::detail
