#pragma once
// The tile folder of an out-of-core run (thesis §6.1 on tiles; format in docs/file-format.md
// "Tile folder"): the grid, the run's state, the working files' paths and record layouts, and
// the small binary helpers every stage reads and writes them with. Each stage has a file of its
// own: partition.cpp (cells and manifest), tile_geometry.cpp (per-tile §6.1 geometry and results),
// join.cpp (orientation across tiles), normals_writer.cpp and tile_extract.cpp (outputs), one file
// per extraction method (eps_delta_tiles.cpp, shape_approx_tiles.cpp), pipeline.cpp (the order).
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include "geometry/detail/orientation_side.h"
#include "linesurf/core/math.h"
#include "linesurf/ooc/ooc_normals.h"
#include "linesurf/ooc/point_stream.h"
#include "ooc/scan_hash.h"

namespace linesurf::ooc::detail {

namespace fs = std::filesystem;

inline constexpr int kFineCells = 64;           ///< histogram resolution along the longest axis
inline constexpr uint64_t kBlock = 1u << 20;    ///< write-pass window (points), also the binning's count unit
inline constexpr double kHaloStart = 1.0 / 16;  ///< first halo width, as a fraction of the tile width
inline constexpr double kHaloShare = 1.35;      ///< tile points with halo / interior points, for sizing
inline constexpr int kTilesInFlight = 2;        ///< tiles processed at once (each parallel inside)
inline constexpr uint32_t kVotesPerPair = 1024;  ///< shared points kept per (neighbour tile, component)
inline constexpr const char* kFormat = "linesurf tile folder";
inline constexpr int kVersion = 4;  ///< 4: every binary working file ends in a proof
inline constexpr size_t kExtractStats = 16;  ///< counters in a tile extraction file

uint32_t floatBits(float f);
float bitsFloat(uint32_t u);

// --- small binary file helpers (errors: Kind::Io, exit 3) ---------------------------------------
/// tmp + rename: a result file exists only when complete (a killed run resumes from it).
void writeWhole(const fs::path& path, const std::string& bytes);
void appendBytes(const fs::path& path, const char* data, size_t n);
std::string readRange(const fs::path& path, uint64_t offset, uint64_t n);

template <class T>
void putRaw(std::string& s, const T& v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(T));
}
template <class T>
T getRaw(const char*& p) {
  T v;
  if constexpr (std::is_same_v<T, Vec3f>) std::memcpy(v.data(), p, 12);
  else std::memcpy(&v, p, sizeof(T));
  p += sizeof(T);
  return v;
}

// --- the proof every binary working file ends with (docs/file-format.md "Tile folder") ----------
/// What a working file is: a file is used only when its proof names the stage, format, input,
/// arguments and tile the reader expects and its payload has the stated length and checksum.
enum class Stage : uint32_t { Result = 1, Curvature = 2, Geometry = 3, Extraction = 4, Orientation = 5 };
inline constexpr uint32_t kProofFormat = 1;
inline constexpr size_t kProofBytes = 64;
/// The checksum is hash64 (ooc/scan_hash.h).

// --- the grid -----------------------------------------------------------------------------------
struct Grid {
  Vec3f lo = Vec3f::Zero();
  float cell = 1;
  std::array<int, 3> dims{1, 1, 1};  ///< fine cells per axis
  int s = 1;                          ///< fine cells per tile side
  std::array<int, 3> tiles{1, 1, 1};  ///< tiles per axis

  int fine(float v, int a) const {
    const float f = std::floor((v - lo[a]) / cell);
    return f < 0 ? 0 : f >= float(dims[size_t(a)]) ? dims[size_t(a)] - 1 : int(f);
  }
  size_t fineOf(const Vec3f& p) const {
    return (size_t(fine(p.z(), 2)) * size_t(dims[1]) + size_t(fine(p.y(), 1))) * size_t(dims[0]) + size_t(fine(p.x(), 0));
  }
  uint32_t tileOfFine(int fx, int fy, int fz) const {
    return uint32_t((size_t(fz / s) * size_t(tiles[1]) + size_t(fy / s)) * size_t(tiles[0]) + size_t(fx / s));
  }
  uint32_t tileOf(const Vec3f& p) const { return tileOfFine(fine(p.x(), 0), fine(p.y(), 1), fine(p.z(), 2)); }
  std::array<int, 3> coords(uint32_t t) const {
    return {int(t % uint32_t(tiles[0])), int((t / uint32_t(tiles[0])) % uint32_t(tiles[1])), int(t / uint32_t(tiles[0] * tiles[1]))};
  }
  double width() const { return double(s) * double(cell); }
  void box(uint32_t t, Vec3d& bmin, Vec3d& bmax) const {
    const auto c = coords(t);
    for (int a = 0; a < 3; ++a) {
      bmin[a] = double(lo[a]) + double(c[size_t(a)]) * width();
      bmax[a] = bmin[a] + width();
    }
  }
};

/// An overfull tile re-gridded over its own points' bounding box (beyond the thesis): the tiles of
/// one uniform grid over the whole cloud are as many points as the budget allows only when the
/// points fill the box, so a tile that holds more (a far outlier stretches the box and leaves the
/// scan in one cell) is cut again, recursively, until each tile fits. Its non-empty children take
/// the ids firstId + their tile index in `grid`.
struct Refinement {
  uint32_t parent = 0, firstId = 0;
  Grid grid;
  uint32_t count() const { return uint32_t(grid.tiles[0] * grid.tiles[1] * grid.tiles[2]); }
};

// --- tile cell files: u64 index, float x y z [, float nx ny nz] [, float radius] [, attributes] --
/// The attributes are PointFileInfo::attributeFloats() floats: the colour, then the further
/// properties (a point's own, carried to the output and to the extraction's segments).
struct Points {
  std::vector<uint64_t> idx;
  std::vector<Vec3f> pos, nrm;
  std::vector<float> rad;
  std::vector<float> att;  ///< `attrs` floats a point (when decoded with them)
  size_t size() const { return idx.size(); }
};

inline size_t recordSize(bool normals, bool radius, size_t attrs) {
  return 8 + 12 + (normals ? 12 : 0) + (radius ? 4 : 0) + 4 * attrs;
}
/// Appends the records of `bytes` to `out`; the attributes only with `keepAttrs` (the halo's
/// points need none).
void decodeRecords(const std::string& bytes, bool normals, bool radius, size_t attrs, Points& out, bool keepAttrs = true);

class TileExtraction;

// --- the run ------------------------------------------------------------------------------------
struct Run {
  const OocNormalsOptions& o;
  fs::path in, out, dir;
  /// The extraction a run ends with, if any ((ε,δ) §3.1, shape approximation §3.2, ...).
  const TileExtraction* extraction = nullptr;
  bool extracting() const { return extraction != nullptr; }
  PointFileInfo info;
  bool normalsIn = false;
  /// The input's radii travel with the points for the extraction, which keeps them as the
  /// in-memory path does (`normals` sets every radius again and leaves them).
  bool radiusIn = false;
  /// Floats of a point's attributes in the cell records (info.colors, info.properties).
  size_t attrFloats() const { return info.attributeFloats(); }
  size_t recordBytes() const { return recordSize(normalsIn, radiusIn, attrFloats()); }
  /// Decodes cell records of this run's layout.
  void decode(const std::string& bytes, Points& out, bool keepAttrs = true) const {
    decodeRecords(bytes, normalsIn, radiusIn, attrFloats(), out, keepAttrs);
  }
  Grid grid;
  Bounds3f bounds;
  float dupTol = 0;
  std::vector<uint32_t> tileIds;     ///< non-empty tiles, ascending
  std::vector<uint64_t> tileCounts;  ///< their interior counts
  std::vector<Bounds3f> tileBounds;  ///< their points' bounding boxes
  std::map<uint32_t, size_t> denseOf;
  /// Tiles cut again, by firstId (ascending); the ids below grid.tiles' product are the grid's.
  std::vector<Refinement> refinements;
  std::map<uint32_t, size_t> refinedOf;  ///< parent id -> its refinement
  uint32_t gridTiles() const { return uint32_t(grid.tiles[0] * grid.tiles[1] * grid.tiles[2]); }
  /// The tile (a leaf of the refinements) that holds p.
  uint32_t tileOf(const Vec3f& p) const;
  /// A tile's box and width (a cube: the grid's or its refinement's tile).
  void tileBox(uint32_t t, Vec3d& bmin, Vec3d& bmax) const;
  double tileWidth(uint32_t t) const;
  /// The grid tile a tile descends from.
  uint32_t gridAncestor(uint32_t t) const;
  /// The most points a tile may hold with its halo (its interior points x kHaloShare).
  double tilePoints = 0;
  size_t blocks = 0;
  std::vector<uint32_t> blockCounts;  ///< [dense tile][block]: points of the tile among indices of that block
  size_t concurrent = 1;
  double ioBytes = 0;

  /// The input's content hash and the shaping arguments' hash, in every working file's proof.
  uint64_t inputHash = 0, argsHash = 0;

  fs::path cellPath(uint32_t t) const;
  fs::path resultPath(uint32_t t) const;
  fs::path extractPath(uint32_t t) const;
  /// Curvature of a tile's interior points (§6.1.2, with `normals --curvature`), in the order of
  /// its result records: k_min, k_max, min and max directions, under the tile's own orientation.
  fs::path curvaturePath(uint32_t t) const;
  /// A tile's own points with the geometry the extraction needs, from the first pass: the
  /// second pass reads it instead of computing the tile's neighbourhoods again.
  fs::path ownGeometryPath(uint32_t t) const;
  fs::path orientationPath() const { return dir / "orientation.bin"; }
  /// `normals --curvature`: the output carries the curvature.
  bool curvatureOut() const { return o.geometry.curvature && !extracting(); }
  /// The extraction uses the §6.1.2 curvature directions (the shape approximation's k_min).
  bool extractionCurvature = false;
  /// The tiles compute curvature: for the output, or for an extraction that uses it.
  bool tileCurvature() const { return o.geometry.curvature && (!extracting() || extractionCurvature); }
};

// --- per-tile results -----------------------------------------------------------------------------
/// What a tile's piece of a component says about the component's side, over the tile's own
/// points (geometry/detail/orientation_side.h): the join adds up a component's pieces.
using SideSummary = linesurf::detail::SideSummary;

struct InteriorResult {  // 28 bytes on disk
  Vec3f normal;
  float cover, spacing;
  uint32_t component;
  uint8_t flags;
};
inline constexpr size_t kResultRecord = 28;
inline constexpr size_t kSharedRecord = 24;  // u64 index, u32 component, float n[3]
inline constexpr size_t kCurvatureRecord = 32;
inline constexpr size_t kSideRecord = 8 + 8 + 12 + 4;   // vote, first index, first normal, entries
inline constexpr size_t kSideEntryRecord = 4 + 4 + 8 + 4;  // key, value, index, vote

struct TileSummary {
  uint32_t tile = 0, interior = 0, components = 0;
  double spacingSum = 0;
  uint64_t spacingCount = 0;
  uint64_t flagCounts[4] = {0, 0, 0, 0};  // duplicate, few, flat, isolated
  uint64_t inexact = 0;
  uint32_t widenings = 0, withHalo = 0;
};
/// Byte offset of a result file's interior records.
inline constexpr size_t kResultHeader = 8 + sizeof(TileSummary);

struct SharedPoint {
  uint64_t index;
  uint32_t component;
  Vec3f normal;
};

/// Result file layout: summary, interior records, per component its side summary, then sections
/// of shared (halo) points per owner tile.
std::string encodeResult(const TileSummary& s, const std::vector<InteriorResult>& r, const std::vector<SideSummary>& sides,
                         const std::map<uint32_t, std::vector<SharedPoint>>& shared);

struct ResultView {
  TileSummary summary;
  size_t interiorOffset = 0;  // byte offset of the interior records
  std::vector<SideSummary> sides;  ///< per component
  std::map<uint32_t, std::vector<SharedPoint>> shared;
};

ResultView decodeResultMeta(const std::string& b, const fs::path& path, bool withShared);
InteriorResult decodeInterior(const char* p);
/// A result file's summary alone.
TileSummary readSummary(const fs::path& path);

/// A tile's own points with what an extraction needs of their geometry (§6.1), written by the
/// first pass and read by the second, so that the tile's kNN, PCA, MST and Delaunay stars are
/// computed once per run. Normals and curvature directions are under the tile's own
/// orientation (the join's flips are applied when the file is read); the Delaunay stars keep
/// only own points, so a segment or cluster can only take own points.
struct OwnGeometry {
  std::vector<uint64_t> idx;  ///< input indices, ascending
  std::vector<Vec3f> pos, normal;
  std::vector<float> radius, spacing, variation;
  std::vector<uint32_t> component;
  std::vector<uint8_t> flags;
  std::vector<Vec3f> minDir, maxDir;        ///< with curvature (shape approximation, §3.2.4.2)
  std::vector<uint32_t> starOffsets, star;  ///< CSR over local indices
  std::vector<float> attrs;                 ///< the points' attributes (Run::attrFloats() a point)
  size_t size() const { return idx.size(); }
};

std::string encodeOwnGeometry(const OwnGeometry& og);
/// `attrFloats`: the run's attribute floats a point (the file does not record it).
OwnGeometry decodeOwnGeometry(const fs::path& path, size_t attrFloats);

/// The join's outcome, for ranks other than 0 (which join nothing): the per-tile component
/// offsets, one flip per (tile, component) node, and the average spacing.
void writeOrientation(const Run& r, const std::vector<size_t>& nodeOffset, const std::vector<uint8_t>& flip, float avg);
void readOrientation(const Run& r, std::vector<size_t>& nodeOffset, std::vector<uint8_t>& flip, float& avg);

/// `payload` with its proof appended (stage, tile, this run's input and arguments).
std::string sealed(const Run& r, Stage stage, uint32_t tile, std::string payload);
/// Whether the file at `path` ends in a proof for (stage, tile) of this run whose length and
/// checksum match its payload. Never throws: a missing or unreadable file is not proven.
bool proven(const Run& r, Stage stage, uint32_t tile, const fs::path& path);

}  // namespace linesurf::ooc::detail
