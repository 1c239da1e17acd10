#pragma once
// Half-widths of the segments of a hybrid (beyond the thesis: narrow segments where
// they can be, and no holes). Shared by the (ε,δ) (§3.1.5) and shape-approximation
// (§3.2.4.5) extractions. Rule and measurements: docs/decisions.md "Hybrid segment widths".
#include <cstdint>
#include <span>

#include "linesurf/core/model.h"

namespace linesurf {
struct PointGeometry;
}

namespace linesurf::detail {

/// owner[j] of an input point that stays a point.
inline constexpr uint32_t kKeptPoint = UINT32_MAX;

/// Sets segments[s].radius for every segment of a hybrid extracted from `cloud`:
/// owner[j] = the segment that replaced input point j, or kKeptPoint; radii[j] = the disc radius
/// point j has (or had) in the point model. The rule (docs/decisions.md "Hybrid segment widths"):
///  - cover, as the hole-free point radius does (geometry stage 3: 1.1 x the farthest Voronoi
///    vertex): the Voronoi cell of every replaced point j (the circumcentres of its local
///    Delaunay star's triangles, in j's tangent plane) is covered by strips, each point of it
///    with a margin of 0.1 x the distance of the cell's vertices from q_j. Checked on a grid
///    over each fan triangle (q_j, V_t, V_t+1); a point of it may be covered by the segment of
///    j or of a star neighbour the triangle touches;
///  - a segment starts at max(distance of its farthest member, radius of its thinnest member)
///    and is widened, replaced point by replaced point in index order, by the least that covers
///    an uncovered grid point (the candidate segment that needs the least; ties: smaller index);
///  - a member without a closed star (boundary, degenerate, no stage 3) makes its segment cover
///    its whole disc, r_j + d_j, the rule of before, which also bounds every width from above.
/// Deterministic (sequential, index order).
void setSegmentWidths(std::span<Segment> segments, std::span<const uint32_t> owner, std::span<const double> radii,
                      const HybridModel& cloud, const PointGeometry& geometry);

/// The margin of the hole-free point radius (geometry stage 3): 1.1 x the farthest Voronoi vertex.
inline constexpr double kCoverMargin = 1.1;

}  // namespace linesurf::detail
