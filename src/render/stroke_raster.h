#pragma once
/// The screen-space half of a drawing (thesis §9.4, §9.5; render/drawing.h): silhouettes traced
/// from the depth and normal buffers, and visible runs rasterised as anti-aliased strokes of
/// constant width. Internal to src/render.
#include <vector>

#include "linesurf/core/image.h"
#include "linesurf/core/math.h"
#include "linesurf/render/stroke_run.h"

namespace linesurf::detail {

/// §9.5: the boundaries between 4-neighbouring pixels where one is covered and the other not,
/// where the depth jumps by more than 16 pixel footprints, or where the camera-space normal's z
/// changes sign, chained through the pixel corners they join (a corner where more than two meet
/// ends them) and written through the boundaries' midpoints. Deterministic scan order.
std::vector<StrokeRun> traceSilhouettes(const Image& depth, const Image& normal, float focalPixels);

/// Every run drawn as a stroke of `width` pixels (box-filtered coverage of its distance to the
/// centre line, the largest over the run's pieces), runs composited over each other in order as
/// ink over the paper. Tiles in parallel, runs in order in each tile.
Image rasterRuns(const std::vector<StrokeRun>& runs, int width, int height, float strokeWidth, const Color& paper,
                 const Color& ink);

}  // namespace linesurf::detail
