#pragma once
/// What one frame of the splatting pipeline did (renderer.h): the prepare stage's outcome per
/// primitive kind, the Z^3 buffer's counters and the stages' times.
#include <cstdint>

namespace linesurf {

struct RenderStats {
  // per primitive kind: drawn = rasterised (including clipped ones)
  uint64_t pointsDrawn = 0, pointsClipped = 0, pointsCulled = 0, pointsOutside = 0, pointsDegenerate = 0;
  uint64_t segmentsDrawn = 0, segmentsClipped = 0, segmentsCulled = 0, segmentsOutside = 0, segmentsDegenerate = 0;
  uint64_t segmentsFallback = 0;  ///< Approx (§5.2.3) construction failed; drawn with ScreenSpace
  uint64_t segmentsLod = 0;  ///< drawn as one point splat (RenderOptions::segmentLod; among segmentsDrawn)
  // Z^3 (summed over tiles)
  uint64_t fragments = 0, merged = 0, allocated = 0, occluded = 0, compressed = 0;
  uint64_t tileBins = 0;  ///< (primitive, tile) pairs rasterised
  // seconds
  double prepareSeconds = 0, binSeconds = 0, rasterSeconds = 0, totalSeconds = 0;
  /// Within the raster stage: CPU time spent rasterising primitives (fragments into Z^3) and
  /// resolving pixels, each summed over the worker threads (for per-fragment costs: robust
  /// against other processes on a shared machine).
  double fragmentThreadSeconds = 0, resolveThreadSeconds = 0;
  /// CPU time of the prepare and binning stages, summed over the worker threads (per-point
  /// set-up costs, robust against other processes as above).
  double prepareThreadSeconds = 0, binThreadSeconds = 0;
  /// Which side of the surface the picture shows (RenderOptions::facingCheck; else 0): pixels of
  /// a reduced-resolution copy of the view that a two-sided render covers, those of them whose
  /// nearest surface faces away from the viewer (culled, so the picture shows nothing there or a
  /// farther surface), and those the culled render leaves empty. A closed, outward-oriented model
  /// shows a few back faces at its silhouette; normals pointing away show most.
  uint64_t facingPixels = 0, facingBackPixels = 0, facingEmptyPixels = 0;
  double facingSeconds = 0;
  double backFacingShare() const { return facingPixels ? double(facingBackPixels) / double(facingPixels) : 0.0; }
  /// Adds every counter and time of `o` (several views, or the parts of one frame).
  RenderStats& operator+=(const RenderStats& o);
};

}  // namespace linesurf
