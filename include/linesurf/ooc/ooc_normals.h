#pragma once
/// Out-of-core normals (thesis §6.1 on clouds larger than memory): the cloud is streamed from its
/// file into tiles of a spatial grid written to a working folder; each tile is processed with
/// its halo (the points of the neighbouring tiles within a margin) by the same code as the
/// in-memory path (computePointGeometry), so every point whose neighbour queries stay inside the
/// halo gets exactly the in-memory kNN, PCA normal, spacing and cover radius; the tiles' MST
/// orientations are then joined by flip votes on the points they share; the output is written
/// in the input's order by a streaming merge. Memory is bounded by the tile size, not by the
/// cloud. See docs/file-format.md ("Tile folder") and docs/decisions.md for the design.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

#include "linesurf/core/progress.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf::ooc {

struct OocNormalsOptions {
  /// k, orientationPenalty, orientNormals, recomputeNormals, curvature and curvatureFit are used
  /// (curvature: the k_min k_max dmin_x dmin_y dmin_z properties of `normals --curvature`);
  /// Delaunay neighbour lists are not written (cover radii are).
  GeometryOptions geometry;
  /// Working folder for the tiles (created; reused by a run with the same input and arguments,
  /// cleared when it belongs to another input or other arguments).
  std::filesystem::path workDir;
  /// Memory budget of the run in bytes: the peak resident set of the process (binary and
  /// libraries included). The tiles follow the points until each fits its share; a budget below
  /// what the process, the stages' buffers and the smallest tiles need is refused before any work.
  double memoryBytes = 1024.0 * 1024 * 1024;
  /// The budget's name in messages ("--max-mb" in the CLI); figures are in MiB.
  std::string budgetName = "memoryBytes";
  /// At least this many tiles (0: as few as the budget allows).
  int minTiles = 0;
  /// Keep the working folder after a successful run (default: removed).
  bool keepWorkDir = false;
  /// This process's share of the tile jobs (MPI): the non-empty tiles d (in id order) with
  /// d % ranks == rank. Rank 0 partitions, joins the orientations and writes the output; the
  /// folder must be shared by all ranks. Output is the same for any number of ranks.
  int rank = 0, ranks = 1;
  /// Waits for every rank (MPI_Barrier); called by every rank after the partition and after the
  /// tiles. Needed when ranks > 1.
  std::function<void()> barrier;
  ProgressFn progress;
};

struct OocNormalsReport {
  uint64_t points = 0;
  size_t tiles = 0;            ///< non-empty tiles
  size_t tilesReused = 0;      ///< finished tiles found in the working folder (a resumed run)
  /// Tiles whose working files failed their proof (another tile's, another input's, damaged,
  /// truncated) and were computed again.
  size_t tilesRecomputed = 0;
  bool folderCleared = false;  ///< the folder held another input's (or other arguments') tiles
  size_t tilePointsMax = 0;    ///< largest tile with its halo (points)
  uint64_t tileInteriorMax = 0;  ///< largest tile without its halo (points)
  /// The most points a tile may hold without its halo: the budget's share of one tile in flight
  /// over a point's bytes, less the halo's share. Every tile holds at most this many, unless its
  /// points share one spot (nothing to cut).
  double tileInteriorBudget = 0;
  size_t refinedTiles = 0;     ///< tiles over the budget cut again over their own points' box
  uint64_t inexactPoints = 0;  ///< interior points whose queries reached past the widest halo
  size_t haloWidenings = 0;    ///< tiles recomputed with a wider halo
  size_t orientationComponents = 0;
  size_t tileFlips = 0;        ///< tile components flipped to agree with their neighbours
  uint64_t disagreeingVotes = 0;  ///< shared points whose tiles disagree after the flips
  float averageSpacing = 0;
  uint64_t duplicate = 0, fewNeighbours = 0, flat = 0, isolated = 0;
  double tBbox = 0, tPartition = 0, tTiles = 0, tOrient = 0, tWrite = 0;
};

/// Bytes per point the in-memory `normals` path holds (model, neighbour graph, orientation and
/// Delaunay scratch), measured: used to decide whether a cloud fits a budget.
double inMemoryNormalsBytesPerPoint(int k);

/// Throws Error (BadParameter, naming o.budgetName) when o.memoryBytes is below what an
/// out-of-core run of `in` needs whatever its tiles: the process's resident set now, the largest
/// stage's buffers and two tiles of the smallest size that holds a neighbourhood; the message
/// gives the figure. `extraction`: the run ends with a point extraction. Every out-of-core run
/// checks this first; callers may check it before saying anything.
void requireOutOfCoreBudget(const std::filesystem::path& in, const OocNormalsOptions& o, bool extraction);

/// Reads `in` (binary PLY or XYZ with x y z [nx ny nz]) and writes `out` (binary PLY with
/// x y z nx ny nz radius), as `linesurf normals` does in memory. Throws linesurf::Error.
OocNormalsReport computeNormalsOutOfCore(const std::filesystem::path& in, const std::filesystem::path& out,
                                         const OocNormalsOptions& options);

}  // namespace linesurf::ooc
