#pragma once
// The output stage of `normals` out of core: a streaming merge of the tiles' results back into
// the input's order, block by block, with the join's flips applied; the bytes the in-memory path
// writes.
#include <vector>

#include "ooc/tile_store.h"

namespace linesurf::ooc::detail {

void writeNormals(const Run& r, const std::vector<uint8_t>& flip, const std::vector<size_t>& nodeOffset, float avgSpacing);

}  // namespace linesurf::ooc::detail
