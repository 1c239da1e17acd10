// Sums of render statistics (render_stats.h).
#include "linesurf/render/render_stats.h"

namespace linesurf {

RenderStats& RenderStats::operator+=(const RenderStats& o) {
  pointsDrawn += o.pointsDrawn, pointsClipped += o.pointsClipped, pointsCulled += o.pointsCulled;
  pointsOutside += o.pointsOutside, pointsDegenerate += o.pointsDegenerate;
  segmentsDrawn += o.segmentsDrawn, segmentsClipped += o.segmentsClipped, segmentsCulled += o.segmentsCulled;
  segmentsOutside += o.segmentsOutside, segmentsDegenerate += o.segmentsDegenerate;
  segmentsFallback += o.segmentsFallback, segmentsLod += o.segmentsLod;
  fragments += o.fragments, merged += o.merged, allocated += o.allocated, occluded += o.occluded;
  compressed += o.compressed, tileBins += o.tileBins;
  prepareSeconds += o.prepareSeconds, binSeconds += o.binSeconds, rasterSeconds += o.rasterSeconds;
  totalSeconds += o.totalSeconds;
  fragmentThreadSeconds += o.fragmentThreadSeconds, resolveThreadSeconds += o.resolveThreadSeconds;
  prepareThreadSeconds += o.prepareThreadSeconds, binThreadSeconds += o.binThreadSeconds;
  facingPixels += o.facingPixels, facingBackPixels += o.facingBackPixels, facingEmptyPixels += o.facingEmptyPixels;
  facingSeconds += o.facingSeconds;
  return *this;
}

}  // namespace linesurf
