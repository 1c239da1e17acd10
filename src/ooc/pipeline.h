#pragma once
// The out-of-core pipeline's order of stages (thesis §6.1 on tiles, then an extraction):
// partition, per-tile geometry, join, then either the normals' writer or the per-tile extraction
// and the hybrid writer; every rank of an MPI run calls it with its own rank.
#include <filesystem>

#include "linesurf/ooc/ooc_normals.h"
#include "ooc/tile_extract.h"

namespace linesurf::ooc::detail {

/// `extraction` null: `normals` (its output in `out`); else that extraction, its totals in *et.
OocNormalsReport runPipeline(const std::filesystem::path& in, const std::filesystem::path& out, const OocNormalsOptions& o,
                             const TileExtraction* extraction, ExtractTotals* et);

}  // namespace linesurf::ooc::detail
