#pragma once
/// Coverage alpha at silhouettes only (RenderOptions::coverageGain > 0, coverageReach > 0; beyond
/// the thesis, see docs/decisions.md, "The silhouette fringe" and "Coverage alpha (opt-in)"): the
/// frame keeps an opaque frame's Z^3 layers (Z3Tile::setCoverageOccludes(false)); the resolve
/// writes every pixel with its front layer opaque and keeps the partly covered ones as candidates
/// (resolve.h); a candidate at a silhouette then takes its coverage result, composited over what
/// lay behind its front layer and over its farther neighbour. The coverage constants themselves:
/// coverage.h. The renderer runs this stage after every tile is resolved (renderer.cpp).
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "linesurf/core/image.h"
#include "pixel_rect.h"

namespace linesurf::detail {

/// Coverage at silhouettes only (RenderOptions::coverageReach > 0).
/// The resolve writes every pixel with its front layer opaque (the normalised alpha of an opaque
/// model) and the depth of its front layer to a frame-wide buffer (+inf where empty); a pixel
/// whose front layer is partly covered is also kept as a candidate with its coverage result.
struct SilhouettePixel {
  uint32_t x, y;
  float zThreshold;  ///< of the front layer
  float rgba[4];     ///< the coverage result composited over the background, as the image stores it
  float alpha;       ///< its coverage alpha before the background (the alpha buffer)
  /// what lay behind its front layer (Z3Tile::resolveBehind: premultiplied, coverage alpha)
  float behind[4] = {0, 0, 0, 0};
};

/// Whether the candidate at (x, y) lies at a silhouette: a pixel within `reach` (Chebyshev, inside
/// the w x h frame) whose front depth exceeds this one's by more than its z threshold and 2 % of
/// its depth (the background is +inf). Reads frontZ only.
bool atSilhouette(const SilhouettePixel& c, const float* frontZ, int w, int h, int reach);

/// What a silhouette candidate's partial coverage is composited over (the frame's layers are those
/// of an opaque frame, Z3Tile::setCoverageOccludes(false): nothing behind the front layer is kept):
/// of the pixels within `reach` (Chebyshev) whose front depth lies beyond the candidate's as in
/// atSilhouette, the nearest that is fully covered or shows the background (partial[i] == 0: not
/// a candidate itself, whose opaque-frame colour would hide the coverage), ties to the farthest
/// depth (the background first), then row-major order; where every one is partial, the farthest.
/// Its index y * w + x, or -1 where there is none (not at a silhouette). Its front depth is +inf
/// where it shows the background.
int64_t silhouetteBehind(const SilhouettePixel& c, const float* frontZ, const uint8_t* partial, int w, int h, int reach);

/// Of a tile's candidates (in `cands`, resolved with an opaque front layer), those whose
/// neighbourhood (reach) lies inside the tile `rect` are decided now, their front depths all known
/// (atSilhouette: the same test as after the frame); the others wait for every tile. The kept ones
/// take what lay behind their front layer, behindAt(x, y) (Z3Tile::resolveBehind), while the tile
/// still holds it. w x h: the frame.
template <class BehindAt>
void keepSilhouetteCandidates(std::vector<SilhouettePixel>& cands, const PixelRect& rect, const float* frontZ, int w,
                              int h, int reach, BehindAt&& behindAt) {
  size_t kept = 0;
  for (SilhouettePixel& c : cands) {
    const int x = int(c.x), y = int(c.y);
    const bool inTile = std::max(0, x - reach) >= rect.x0 && std::min(w - 1, x + reach) < rect.x1 &&
                        std::max(0, y - reach) >= rect.y0 && std::min(h - 1, y + reach) < rect.y1;
    if (inTile && !atSilhouette(c, frontZ, w, h, reach)) continue;
    const Color b = behindAt(x, y);
    for (int k = 0; k < 4; ++k) c.behind[k] = b[k];
    cands[kept++] = c;
  }
  cands.resize(kept);
}

/// The frame's pass (after every tile): each kept candidate at a silhouette takes its coverage
/// result composited over what lay behind it and over its farther neighbour (silhouetteBehind)
/// in `color` (and its alpha in `alpha`, when given). Two passes, the second writing what the
/// first computed from the opaque images alone, so that the result depends neither on the order
/// of the tiles nor on the threads. cands[tile]: the tiles' kept candidates; partial: scratch
/// (one byte per pixel); resolveSeconds[tile] gets the thread time spent on the tile's pixels.
void compositeSilhouettes(const std::vector<std::vector<SilhouettePixel>>& cands, size_t tiles, const float* frontZ,
                          std::vector<uint8_t>& partial, int reach, const Color& background, Image& color,
                          Image* alpha, double* resolveSeconds);

}  // namespace linesurf::detail
