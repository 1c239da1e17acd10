#pragma once
// The partition stage of the out-of-core pipeline: streams the input into one cell file per tile
// of a spatial grid and records it in the folder's manifest (docs/file-format.md "Tile folder").
#include <nlohmann/json.hpp>

#include "ooc/tile_store.h"

namespace linesurf::ooc::detail {

using nlohmann::json;

/// The run's arguments as the manifest records them: a folder is reused only under the same.
json argumentsJson(const OocNormalsOptions& o, const TileExtraction* extraction);
/// The input's identity as the manifest records it (path, size, mtime, sampled hash).
json identityJson(const fs::path& in, const FileIdentity& id);

/// Rank 0: reuses the folder when its manifest names this input and these arguments, else
/// clears it (or refuses a folder that is not a tile folder) and partitions the input into it.
void prepareFolder(Run& r, OocNormalsReport& rep, const FileIdentity& id, const json& wantInput, const json& wantArgs);

/// Ranks other than 0: the partition rank 0 has just written, checked against what this rank
/// was started with.
void loadSharedManifest(Run& r, const json& wantInput, const json& wantArgs);

}  // namespace linesurf::ooc::detail
