#pragma once
// computePointGeometry for one tile of an out-of-core run (src/ooc): the same §6.1 stages, with
// the duplicate tolerance of the whole cloud instead of the tile's, and what the tile needs to
// check its halo and to join its orientation with its neighbours'.
#include <cstdint>
#include <vector>

#include "linesurf/core/model.h"

namespace linesurf {
// Declared, not included: point_geometry.cpp defines computePointGeometryTile and includes this
// header, so including point_geometry.h back would tie the two rooms in a cycle.
struct GeometryOptions;
struct PointGeometry;
}  // namespace linesurf

namespace linesurf::detail {

struct TileGeometryExtras {
  /// Per point: the distance of the farthest point its neighbour queries looked at (the k-th
  /// neighbour, or the 2k/4k-th of a grown cover-radius star).
  std::vector<float> reach;
  /// Per point: its connected component of the symmetrised kNN graph (MST orientation), in the
  /// order orientNormals numbers them; empty when no orientation ran.
  std::vector<uint32_t> component;
};

/// dupTolOverride < 0: 1e-6 x the cloud's bounding-box diagonal (computePointGeometry's rule).
PointGeometry computePointGeometryTile(const HybridModel& cloud, const GeometryOptions& options, float dupTolOverride,
                                       TileGeometryExtras* extras);

}  // namespace linesurf::detail
