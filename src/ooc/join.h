#pragma once
// The join stage of the out-of-core pipeline: each tile oriented its normals by the §6.1 MST on
// its own; the tiles are made to agree by flip votes on the points they share (a maximum spanning
// forest of the vote graph, seeded by the in-memory rule), and the summaries are added up.
#include <vector>

#include "ooc/tile_store.h"

namespace linesurf::ooc::detail {

/// Fills the report's totals (spacing, flags, halo figures, orientation), the per-tile offsets of
/// the (tile, component) nodes and one flip per node.
void joinTiles(const Run& r, OocNormalsReport& rep, std::vector<size_t>& nodeOffset, std::vector<uint8_t>& flip);

}  // namespace linesurf::ooc::detail
