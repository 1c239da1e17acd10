#pragma once
/// The extractions out of core: (ε,δ) (thesis §3.1), shape approximation (§3.2) and lines of
/// curvature (§9.2) on clouds
/// larger than memory, as the normals pipeline of ooc_normals.h followed by the extraction run on
/// each tile's own points under the joined orientation.
#include <filesystem>

#include "linesurf/extract/curvature_lines.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/ooc/ooc_normals.h"

namespace linesurf::ooc {

struct OocEpsDeltaReport {
  OocNormalsReport geometry;
  uint64_t keptPoints = 0, segments = 0, replacedPoints = 0;
  uint64_t seedDirections = 0, candidateDirections = 0;  ///< as EpsDeltaStats, summed over the tiles
  double epsilon = 0;
  double tExtract = 0, tWrite = 0;
};

/// (ε,δ) extraction (§3.1) out of core: the normals pipeline above, whose tiles also compute
/// their local Delaunay neighbours and keep their own points' geometry in the working folder;
/// once the join has fixed the orientation, extractEpsDelta runs on each tile's own points with
/// that geometry (neighbourhoods are computed once per run), epsilon resolved from the whole
/// cloud's average spacing. A segment never crosses a tile border, so every input point ends
/// as exactly one output point or in exactly one segment. Output as extractEpsDelta's: kept
/// points in input order, then the segments tile after tile (with provenance in input indices
/// when `extract.provenance`).
OocEpsDeltaReport extractEpsDeltaOutOfCore(const std::filesystem::path& in, const std::filesystem::path& out,
                                           const OocNormalsOptions& options, const EpsDeltaOptions& extract);

struct OocShapeApproxReport {
  OocNormalsReport geometry;
  /// Summed over the tiles (clusters never cross a tile border); the seconds are not filled.
  ShapeApproxStats stats;
  double tExtract = 0, tWrite = 0;
};

/// Shape-approximation extraction (§3.2) out of core, as extractEpsDeltaOutOfCore: the tiles
/// compute their Delaunay neighbours and (with geometry.curvature) the k_min directions of
/// §3.2.4.2, then extractShapeApprox clusters and cuts each tile's own points under the joined
/// orientation. Clusters stop at tile borders, so a cluster that spans tiles gives a bunch of
/// segments per tile. Output as extractShapeApprox's: kept points in input order, then the
/// segments tile after tile.
OocShapeApproxReport extractShapeApproxOutOfCore(const std::filesystem::path& in, const std::filesystem::path& out,
                                                 const OocNormalsOptions& options, const ShapeApproxOptions& extract);

struct OocCurvatureLineReport {
  OocNormalsReport geometry;
  uint64_t keptPoints = 0, segments = 0, replacedPoints = 0;
  /// As CurvatureLineStats, summed over the tiles.
  uint64_t lines = 0, closedLines = 0, shortLines = 0, prunedLines = 0, steps = 0;
  uint64_t stopSeparation = 0, stopSingularity = 0, stopBoundary = 0, stopClosed = 0;
  double lineLength = 0;  ///< object space, to 1e-6
  double epsilon = 0;
  double tExtract = 0, tWrite = 0;
};

/// Lines of curvature (§9.2) out of core, as extractEpsDeltaOutOfCore: once the join has fixed the
/// orientation, extractCurvatureLines runs on each tile's own points (its own MLS surface, field
/// and lines; epsilon from the whole cloud's average spacing). Lines stop at tile borders (a line
/// meeting one ends there as it would at a boundary), so every input point ends as exactly one
/// output point or in exactly one strip. Output: kept points in input order, then the chains
/// tile after tile.
OocCurvatureLineReport extractCurvatureLinesOutOfCore(const std::filesystem::path& in, const std::filesystem::path& out,
                                                      const OocNormalsOptions& options, const CurvatureLineOptions& extract);

}  // namespace linesurf::ooc
