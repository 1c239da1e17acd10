#pragma once
/// Line-segment splats, thesis §5 (owned by the segment-splatting work; this first version is a
/// placeholder written by the pipeline so that hybrid models render end to end).
///
/// Contract with the pipeline (see splat_context.h for the two stages):
///  - prepareSegment is called once per segment per frame, in parallel, with the segment's
///    index in model.segments. It must fill out.bounds (screen pixels, clamped to the viewport,
///    empty when nothing is drawn) and return the PrimitiveStatus that the pipeline counts.
///    Colour through frame.primitiveColor(segment.color) (default colour, alpha override);
///    texture (§5.2.4) through frame.texture when non-null and the model has texcoords.
///  - rasterizeSegment is called for every screen tile that out.bounds touches, in segment index
///    order within the tile (after the tile's points); it must write only through
///    ctx.tile.insert(x, y, fragment) for pixels inside ctx.rect. Fragment.zThreshold via
///    frame.zThreshold(depth extent), interpolated along the segment in PerPrimitive mode.
///  - frame.opt().segmentMethod selects the filter evaluation (SegmentMethod).
/// PreparedSegment's fields beyond `bounds` and `index` belong to the implementation.
///
/// Placeholder implementation (src/render/segment_splat_stub.cpp): a segment of length l and
/// radius r is drawn as ceil(l / r) + 1 EWA point splats evenly spaced from p0 to p1.
#include <cstdint>
#include <vector>

#include "linesurf/core/model.h"
#include "linesurf/render/point_splat.h"
#include "linesurf/render/splat_context.h"

namespace linesurf {

struct PreparedSegment {
  PixelRect bounds;        ///< screen bounding box (clamped to the viewport); bins the segment
  uint32_t index = 0;      ///< index in model.segments
  // --- placeholder implementation --------------------------------------------------------
  std::vector<PreparedPoint> pieces;  ///< the point splats standing in for the segment
};

/// Prepare stage for one segment (see above and splat_context.h).
PrimitiveStatus prepareSegment(const Segment& segment, uint32_t index, const FrameContext& frame,
                               PreparedSegment& out);

/// Rasterise stage for one segment on one tile (see above and splat_context.h).
void rasterizeSegment(const PreparedSegment& segment, const SplatContext& ctx);

}  // namespace linesurf
