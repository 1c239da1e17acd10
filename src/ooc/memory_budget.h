#pragma once
// The memory budget of the out-of-core pipeline (beyond the thesis): the budget is the peak
// resident set of the process (VmHWM: binary and libraries included). What each stage holds
// besides its tiles is counted here, the tiles get the rest, and a budget below what the fixed
// parts and the smallest useful tiles need is refused before any work.
#include <filesystem>

#include "linesurf/ooc/ooc_normals.h"

namespace linesurf::ooc::detail {

class TileExtraction;

/// The smallest tile the budget must allow (interior points): its first halo, 1/16 of its width,
/// then still holds a neighbourhood (4,096 points of a surface are 64 spacings across, the halo
/// 4 spacings: the reach of a k = 12 neighbourhood and its neighbours').
inline constexpr double kMinTilePoints = 4096;

/// The partition's and the merge's buffers (bytes): an eighth of the budget, 8 to 256 MiB.
double ioBufferBytes(const OocNormalsOptions& o);
/// Points the partition reads at once: within the I/O buffers' share.
size_t readChunkPoints(const OocNormalsOptions& o);
/// Bytes a tile's point costs while its geometry (and its extraction) is computed.
double bytesPerTilePoint(const OocNormalsOptions& o, bool extraction, bool extractionCurvature);
/// The most points a tile may hold with its halo, the same for any thread count (so are the tiles
/// and the output).
double tilePointBudget(const OocNormalsOptions& o, bool extraction, bool extractionCurvature);

/// What the budget must be at least for this run, and what makes it up (bytes).
struct BudgetFloor {
  double process = 0;  ///< resident now: binary, libraries, what the caller holds
  double buffers = 0;  ///< the largest stage's own buffers (reader, partition, merge window)
  double tiles = 0;    ///< kTilesInFlight tiles of kMinTilePoints with halo
  double total = 0;    ///< the smallest budget that holds them (the buffers grow with it)
};
BudgetFloor budgetFloor(const std::filesystem::path& in, const OocNormalsOptions& o, bool extraction, bool extractionCurvature);

/// Hands the heap's free pages back to the system between stages: the tile workers' arenas keep
/// what a tile freed resident, and the next stage's buffers would come on top of it.
void releaseFreedMemory();

/// Throws BadParameter naming o.budgetName with the floor's figure when the budget is below it.
void requireBudget(const std::filesystem::path& in, const OocNormalsOptions& o, bool extraction, bool extractionCurvature);

}  // namespace linesurf::ooc::detail
