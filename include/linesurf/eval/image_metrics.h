#pragma once
/// Image-quality measures of thesis §7 (mse and nccm of Tables 1-3, the absolute-difference
/// statistics of Table 5) plus PSNR and SSIM. Definitions in docs/metrics.md.
#include <cstdint>
#include <vector>

#include "linesurf/core/image.h"

namespace linesurf {

struct ImageMetrics {
  double mse = 0;        ///< mean squared error over R, G, B, values in [0,1]
  double psnr = 0;       ///< 10 log10(1 / mse) dB, +inf for identical images
  double nccm = 0;       ///< Σ A·B / Σ A² over R, G, B (Eskicioglu & Fisher; 1 = identical, may exceed 1)
  double ssim = 0;       ///< mean SSIM of the luma channel, 8x8 windows, stride 4 (Wang et al. 2004)
  double meanAbsDiff = 0;///< mean |A-B| over the R, G, B composite, in grey levels of 255 (Table 5)
  double stdAbsDiff = 0; ///< standard deviation of |A-B| over the same composite, grey levels
  double maxAbsDiff = 0; ///< largest |A-B| of any channel, grey levels
  double differingPixels = 0;  ///< fraction of pixels with any channel differing by > 1 grey level
};

/// Compares two images of equal size (throws linesurf::Error BadParameter otherwise). Both are
/// quantised to 8 bits first, as the thesis compares 256-level images; alpha is ignored.
ImageMetrics compareImages(const Image& a, const Image& b);

/// A heat-map of the per-pixel maximum channel difference (black = equal, through red and yellow
/// to white at `saturate` grey levels and above).
Image differenceHeatmap(const Image& a, const Image& b, double saturate = 32);

/// Beyond the thesis (docs/decisions.md "Mesh ground truth and the silhouette band"): the pixels
/// within `reach` pixels (a (2 reach + 1)^2 square) of a silhouette of a rendered surface, 1 in the
/// returned mask (width * height, row-major). A silhouette lies between two 4-neighbours of which
/// one is covered (alpha > 0) and the other not, between two covered ones whose depths differ by
/// more than `jump` times the nearer depth (an inner silhouette: a surface in front of another),
/// and on every partly covered pixel (0 < alpha < 1). `alpha` and `depth` as a renderer writes them
/// (R channel; depth linear). Throws linesurf::Error BadParameter on sizes that differ or
/// reach < 0, jump <= 0.
std::vector<uint8_t> silhouetteBand(const Image& alpha, const Image& depth, int reach = 2, double jump = 0.02);

/// Beyond the thesis (§9.1's question, docs/decisions.md "Hole maps"): the pixels a reference
/// picture covers and a test picture does not. A pixel is covered where its alpha exceeds 0.5
/// when both images carry alpha (some pixel below 1), else where any channel differs from
/// `background` by more than 1 grey level. The map shows the reference's covered pixels in grey
/// and the holes in red, on the background.
struct HoleMap {
  Image map;
  size_t referencePixels = 0;  ///< covered in the reference
  size_t holes = 0;            ///< of those, not covered in the test
  size_t extra = 0;            ///< covered in the test, not in the reference
  bool byAlpha = false;        ///< coverage read from alpha (else from the background colour)
  double holeShare() const { return referencePixels ? double(holes) / double(referencePixels) : 0.0; }
};
/// Throws linesurf::Error BadParameter on sizes that differ.
HoleMap holeMap(const Image& reference, const Image& test, const Color& background = Color(1, 1, 1, 1));

}  // namespace linesurf
