#pragma once
// The per-tile extraction stage of the out-of-core pipeline and its output: once the join has
// fixed the orientation, an extraction method runs on each tile's own points with the geometry
// the first pass left (neighbourhoods are computed once per run), writes the tile's extraction
// file, and the hybrid model is merged from those files. A method is one file: a TileExtraction
// and its public entry point (eps_delta_tiles.cpp §3.1, shape_approx_tiles.cpp §3.2).
#include <array>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "linesurf/core/model.h"
#include "ooc/tile_store.h"

namespace linesurf::ooc::detail {

/// An extraction's counters, summed over the tiles (their meaning is the method's).
using ExtractStats = std::array<uint64_t, kExtractStats>;

/// What the tile pipeline needs to know of an extraction method.
class TileExtraction {
 public:
  virtual ~TileExtraction() = default;
  /// The progress label of its pass ("eps-delta tiles").
  virtual std::string_view stage() const = 0;
  /// Its arguments as the manifest records them (a folder is reused only under the same).
  virtual nlohmann::json arguments() const = 0;
  /// Whether its tiles need the §6.1.2 principal directions (when geometry.curvature is set).
  virtual bool usesCurvature() const = 0;
  /// Its ε, from the whole cloud's average spacing, fixed before any tile runs (0: none).
  virtual double epsilon(float /*averageSpacing*/) const { return 0; }
  /// Extracts one tile's own points (a cloud of their own, with their geometry under the joined
  /// orientation): the hybrid model with provenance in the cloud's indices; counters into stats.
  virtual HybridModel extract(const HybridModel& cloud, const PointGeometry& geometry, double epsilon, ExtractStats& stats) const = 0;
  /// The output's header comments after the input's.
  virtual std::vector<std::string> comments(double epsilon, const Run& r) const = 0;
  virtual bool endpointNormals() const = 0;
  virtual bool provenance() const = 0;
};

/// What the extraction pass adds up over the tiles.
struct ExtractTotals {
  uint64_t kept = 0, segments = 0;
  double epsilon = 0;
  ExtractStats stats{};
  double tExtract = 0, tWrite = 0;
};

/// Extracts this rank's tiles that have no extraction file yet (a killed run resumes).
void extractTiles(const Run& r, const std::vector<size_t>& nodeOffset, const std::vector<uint8_t>& flip, float avg,
                  ExtractTotals& et);

/// Merges the tiles' extraction files into the output: kept points in input order, then the
/// segments tile after tile, as the in-memory writer writes them.
void writeHybrid(const Run& r, ExtractTotals& et);

}  // namespace linesurf::ooc::detail
