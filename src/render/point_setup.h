#pragma once
/// The prepare stage of point splats in batches (thesis §4.2.2, §6.2): the pipeline's fast path
/// around the SIMD set-up detail::pointSetup (point_setup.cpp). Back-facing points are culled on
/// their world-space position and normal before any other work (only those that are clearly
/// back-facing: the rest meet the exact test of the set-up); the survivors are set up in SIMD,
/// with the lanes it cannot handle passed to the scalar reference preparePoint (point_splat.h);
/// only the visible points are written, densely and in primitive order.
#include <cstdint>

#include "detail/splat_rows.h"
#include "point_splat.h"

namespace linesurf {

/// How many points of a batch ended in each PrimitiveStatus (the RenderStats counters).
struct PointSetupCounts {
  uint32_t drawn = 0, clipped = 0, culled = 0, outside = 0, degenerate = 0;
  PointSetupCounts& operator+=(const PointSetupCounts& o) {
    drawn += o.drawn, clipped += o.clipped, culled += o.culled, outside += o.outside, degenerate += o.degenerate;
    return *this;
  }
};

/// The per-frame constants of preparePoints.
detail::PointSetupFrame pointSetupFrame(const FrameContext& frame);

/// Prepares points [first, first + count) of `points` (count <= detail::kSetupBatch): constructs
/// the visible ones (Drawn or Clipped) in slots 0 .. k of `out` (storage for `count` slots, not
/// necessarily constructed: untouched slots stay untouched) in index order and returns k; adds
/// every point's status to `counts`. Same results as preparePoint for each point up to float
/// rounding; out.gouraud[j] is written only when PreparedPoint::gouraud(out.bounds[j], ...).
int preparePoints(const Point* points, uint32_t first, int count, const FrameContext& frame,
                  const detail::PointSetupFrame& setup, const PointSlots& out, PointSetupCounts& counts);

}  // namespace linesurf
