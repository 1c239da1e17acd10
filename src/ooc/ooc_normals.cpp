// Out-of-core normals, thesis §6.1 on tiles (see ooc/ooc_normals.h; folder format in
// docs/file-format.md "Tile folder"; design in docs/decisions.md).
//
// Passes over the input: (1) bounding box, (2) a 64^3 histogram that sizes the tiles, (3) binning
// into one file per tile. Then every tile is processed with its halo by computePointGeometry
// (tiles in flight in parallel, each with the in-memory code inside), its results written to
// a file of its own (a killed run resumes from them). The orientation pass joins the tiles'
// MST orientations through the points they share, and the write pass merges the tiles back
// into the input's order.
#include "linesurf/ooc/ooc_normals.h"

#include <fmt/format.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <map>
#include <mutex>
#include <numeric>
#include <tuple>

#include "geometry/detail/point_geometry_tile.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/ooc/point_stream.h"

namespace linesurf::ooc {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kFineCells = 64;           // histogram resolution along the longest axis
constexpr uint64_t kBlock = 1u << 20;    // write-pass window (points), also the binning's count unit
constexpr double kHaloStart = 1.0 / 16;  // first halo width, as a fraction of the tile width
constexpr double kHaloShare = 1.35;      // tile points with halo / interior points, for sizing
constexpr int kTilesInFlight = 2;
constexpr uint32_t kVotesPerPair = 1024;  // shared points kept per (neighbour tile, component)        // tiles processed at once (each parallel inside)
constexpr const char* kFormat = "linesurf tile folder";
constexpr int kVersion = 1;

uint32_t floatBits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
float bitsFloat(uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

// --- small binary file helpers (errors: Kind::Io, exit 3) ---------------------------------------
void writeWhole(const fs::path& path, const std::string& bytes) {
  // tmp + rename: a result file exists only when complete (a killed run resumes from it)
  const fs::path tmp = path.string() + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throwIo(tmp.string(), std::string("cannot create file: ") + std::strerror(errno));
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  const int e = errno;
  if (std::fclose(f) != 0 || !ok) {
    ::unlink(tmp.c_str());
    throwIo(path.string(), std::string("write failed: ") + std::strerror(ok ? errno : e));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throwIo(path.string(), std::string("rename failed: ") + std::strerror(errno));
}

void appendBytes(const fs::path& path, const char* data, size_t n) {
  std::FILE* f = std::fopen(path.c_str(), "ab");
  if (!f) throwIo(path.string(), std::string("cannot open: ") + std::strerror(errno));
  const bool ok = std::fwrite(data, 1, n, f) == n;
  const int e = errno;
  if (std::fclose(f) != 0 || !ok) throwIo(path.string(), std::string("write failed: ") + std::strerror(ok ? errno : e));
}

std::string readRange(const fs::path& path, uint64_t offset, uint64_t n) {
  std::string out(n, '\0');
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throwIo(path.string(), std::string("cannot open: ") + std::strerror(errno));
  const bool ok = std::fseek(f, long(offset), SEEK_SET) == 0 && std::fread(out.data(), 1, n, f) == n;
  std::fclose(f);
  if (!ok) throwIo(path.string(), "tile file shorter than its manifest says (the folder was changed during the run?)");
  return out;
}

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

// --- tile cell files: u64 index, float x y z [, float nx ny nz] [, float radius] ---------------
struct Points {
  std::vector<uint64_t> idx;
  std::vector<Vec3f> pos, nrm;
  std::vector<float> rad;
  size_t size() const { return idx.size(); }
};

size_t recordSize(bool normals, bool radius) { return 8 + 12 + (normals ? 12 : 0) + (radius ? 4 : 0); }

void decodeRecords(const std::string& bytes, bool normals, bool radius, Points& out) {
  const size_t rs = recordSize(normals, radius), n = bytes.size() / rs;
  const char* p = bytes.data();
  for (size_t i = 0; i < n; ++i) {
    out.idx.push_back(getRaw<uint64_t>(p));
    Vec3f v;
    std::memcpy(v.data(), p, 12), p += 12;
    out.pos.push_back(v);
    if (normals) {
      std::memcpy(v.data(), p, 12), p += 12;
      out.nrm.push_back(v);
    }
    if (radius) out.rad.push_back(getRaw<float>(p));
  }
}

// --- per-tile results -----------------------------------------------------------------------------
struct Extreme {
  float value = -std::numeric_limits<float>::infinity();
  uint64_t index = UINT64_MAX;
  Vec3f normal = Vec3f::Zero();
};
const std::array<Vec3f, 6> kSeedDirs = {Vec3f(0, 0, 1), Vec3f(0, 0, -1), Vec3f(1, 0, 0),
                                        Vec3f(-1, 0, 0), Vec3f(0, 1, 0), Vec3f(0, -1, 0)};

struct InteriorResult {  // 28 bytes on disk
  Vec3f normal;
  float cover, spacing;
  uint32_t component;
  uint8_t flags;
};
constexpr size_t kResultRecord = 28;
constexpr size_t kSharedRecord = 24;  // u64 index, u32 component, float n[3]

struct TileSummary {
  uint32_t tile = 0, interior = 0, components = 0;
  double spacingSum = 0;
  uint64_t spacingCount = 0;
  uint64_t flagCounts[4] = {0, 0, 0, 0};  // duplicate, few, flat, isolated
  uint64_t inexact = 0;
  uint32_t widenings = 0, withHalo = 0;
};

struct SharedPoint {
  uint64_t index;
  uint32_t component;
  Vec3f normal;
};

/// Result file layout: summary, interior records, per component 6 extremes, then sections of
/// shared (halo) points per owner tile.
std::string encodeResult(const TileSummary& s, const std::vector<InteriorResult>& r, const std::vector<std::array<Extreme, 6>>& ext,
                         const std::map<uint32_t, std::vector<SharedPoint>>& shared) {
  std::string b;
  b.append("LSTILE01", 8);
  putRaw(b, s);
  for (const InteriorResult& x : r) {
    putRaw(b, x.normal), putRaw(b, x.cover), putRaw(b, x.spacing), putRaw(b, x.component), putRaw(b, x.flags);
    b.append(3, '\0');
  }
  for (const auto& e6 : ext)
    for (const Extreme& e : e6) putRaw(b, e.value), putRaw(b, e.index), putRaw(b, e.normal);
  putRaw(b, uint32_t(shared.size()));
  for (const auto& [owner, pts] : shared) {
    putRaw(b, owner), putRaw(b, uint32_t(pts.size()));
    for (const SharedPoint& p : pts) putRaw(b, p.index), putRaw(b, p.component), putRaw(b, p.normal);
  }
  return b;
}

struct ResultView {
  TileSummary summary;
  size_t interiorOffset = 0;  // byte offset of the interior records
  std::vector<std::array<Extreme, 6>> extremes;
  std::map<uint32_t, std::vector<SharedPoint>> shared;
};

ResultView decodeResultMeta(const std::string& b, const fs::path& path, bool withShared) {
  ResultView v;
  if (b.size() < 8 + sizeof(TileSummary) || b.compare(0, 8, "LSTILE01") != 0) throwIo(path.string(), "not a tile result file");
  const char* p = b.data() + 8;
  v.summary = getRaw<TileSummary>(p);
  v.interiorOffset = 8 + sizeof(TileSummary);
  p += size_t(v.summary.interior) * kResultRecord;
  const size_t extBytes = size_t(v.summary.components) * 6 * (4 + 8 + 12);
  if (size_t(p - b.data()) + extBytes + 4 > b.size()) throwIo(path.string(), "truncated tile result file");
  v.extremes.resize(v.summary.components);
  for (auto& e6 : v.extremes)
    for (Extreme& e : e6) e.value = getRaw<float>(p), e.index = getRaw<uint64_t>(p), e.normal = getRaw<Vec3f>(p);
  if (!withShared) return v;
  const uint32_t sections = getRaw<uint32_t>(p);
  for (uint32_t s = 0; s < sections; ++s) {
    const uint32_t owner = getRaw<uint32_t>(p), n = getRaw<uint32_t>(p);
    if (size_t(p - b.data()) + size_t(n) * kSharedRecord > b.size()) throwIo(path.string(), "truncated tile result file");
    auto& out = v.shared[owner];
    out.resize(n);
    for (SharedPoint& sp : out) sp.index = getRaw<uint64_t>(p), sp.component = getRaw<uint32_t>(p), sp.normal = getRaw<Vec3f>(p);
  }
  return v;
}

InteriorResult decodeInterior(const char* p) {
  InteriorResult r;
  r.normal = getRaw<Vec3f>(p), r.cover = getRaw<float>(p), r.spacing = getRaw<float>(p), r.component = getRaw<uint32_t>(p);
  r.flags = getRaw<uint8_t>(p);
  return r;
}

// --- the run ------------------------------------------------------------------------------------
struct Run {
  const OocNormalsOptions& o;
  fs::path in, out, dir;
  /// The extraction a run ends with, if any: (ε,δ) (§3.1) or shape approximation (§3.2).
  const EpsDeltaOptions* epsDelta = nullptr;
  const ShapeApproxOptions* shapeApprox = nullptr;
  bool extracting() const { return epsDelta || shapeApprox; }
  PointFileInfo info;
  bool normalsIn = false;
  /// The input's radii travel with the points for the extraction, which keeps them as the
  /// in-memory path does (`normals` sets every radius again and leaves them).
  bool radiusIn = false;
  size_t recordBytes() const { return recordSize(normalsIn, radiusIn); }
  Grid grid;
  Bounds3f bounds;
  float dupTol = 0;
  std::vector<uint32_t> tileIds;     ///< non-empty tiles, ascending
  std::vector<uint64_t> tileCounts;  ///< their interior counts
  std::map<uint32_t, size_t> denseOf;
  size_t blocks = 0;
  std::vector<uint32_t> blockCounts;  ///< [dense tile][block]: points of the tile among indices of that block
  size_t concurrent = 1;
  double ioBytes = 0;

  fs::path cellPath(uint32_t t) const { return dir / "cells" / fmt::format("cell_{:06d}.bin", t); }
  fs::path resultPath(uint32_t t) const { return dir / "results" / fmt::format("tile_{:06d}.res", t); }
  fs::path extractPath(uint32_t t) const { return dir / "results" / fmt::format("extract_{:06d}.res", t); }
  /// Curvature of a tile's interior points (§6.1.2, with `normals --curvature`), in the order of
  /// its result records: k_min, k_max, min and max directions, under the tile's own orientation.
  fs::path curvaturePath(uint32_t t) const { return dir / "results" / fmt::format("curv_{:06d}.res", t); }
  /// A tile's own points with the geometry the extraction needs, from the first pass: the
  /// second pass reads it instead of computing the tile's neighbourhoods again.
  fs::path ownGeometryPath(uint32_t t) const { return dir / "results" / fmt::format("geom_{:06d}.bin", t); }
  /// `normals --curvature`: the output carries the curvature.
  bool curvatureOut() const { return o.geometry.curvature && !extracting(); }
  /// The tiles compute curvature: for the output, or for the shape approximation's k_min directions.
  bool tileCurvature() const { return o.geometry.curvature && (!extracting() || shapeApprox); }
};
constexpr size_t kCurvatureRecord = 32;
constexpr size_t kExtractStats = 16;  // counters in a tile extraction file

json argumentsJson(const OocNormalsOptions& o, const EpsDeltaOptions* e, const ShapeApproxOptions* sa) {
  const GeometryOptions& g = o.geometry;
  json x = nullptr;
  if (e)
    x = json{{"epsilon", e->epsilon}, {"epsilon_relative", e->epsilonRelative}, {"delta", e->delta},
             {"min_replaced", e->minReplaced}, {"max_replaced", e->maxReplaced}, {"endpoint_normals", e->endpointNormals}};
  if (sa) {
    const ClusteringOptions& c = sa->clustering;
    x = json{{"method", sa->method == ClusteringMethod::Hierarchical ? "hierarchical" : "greedy"},
             {"delta_n_bits", floatBits(c.deltaN)},
             {"max_iterations", c.maxIterations},
             {"seed", c.seed},
             {"seeding", int(c.seeding)},
             {"min_cluster_size", sa->minClusterSize},
             {"min_run_points", sa->minRunPoints},
             {"curvature_switch_bits", floatBits(sa->curvatureSwitchDegrees)},
             {"curvature_coherence_bits", floatBits(sa->curvatureCoherence)},
             {"radius_scale_bits", floatBits(sa->radiusScale)},
             {"endpoint_normals", sa->endpointNormals}};
  }
  return json{{"extract", x},
              {"k", g.k},
              {"orientation_penalty_bits", floatBits(g.orientationPenalty)},
              {"orient", g.orientNormals},
              {"recompute", g.recomputeNormals},
              {"memory_bytes", o.memoryBytes},
              {"curvature", g.curvature && (!e || sa)},
              {"curvature_fit", int(g.curvatureFit)},
              {"min_tiles", o.minTiles}};
}

json identityJson(const fs::path& in, const FileIdentity& id) {
  return json{{"path", fs::absolute(in).lexically_normal().string()},
              {"size", id.size},
              {"mtime_ns", id.mtimeNs},
              {"hash", fmt::format("{:016x}", id.hash)}};
}

/// Chooses the tile size from the fine histogram: the largest tiles that fit the per-tile point
/// budget (with the halo's share) and give at least minTiles non-empty tiles.
void chooseTiles(Run& r, const std::vector<uint64_t>& hist, double tilePoints) {
  Grid& g = r.grid;
  const int longest = *std::max_element(g.dims.begin(), g.dims.end());
  // Tile sizes from the number of tiles along the longest axis (1, 2, 3, ...): even tiles, not a
  // large one beside slivers.
  int previous = 0;
  for (int along = 1; along <= longest; ++along) {
    const int s = (longest + along - 1) / along;
    if (s == previous) continue;
    previous = s;
    g.s = s;
    for (int a = 0; a < 3; ++a) g.tiles[size_t(a)] = (g.dims[size_t(a)] + s - 1) / s;
    std::map<uint32_t, uint64_t> counts;
    for (int z = 0; z < g.dims[2]; ++z)
      for (int y = 0; y < g.dims[1]; ++y)
        for (int x = 0; x < g.dims[0]; ++x) {
          const uint64_t c = hist[(size_t(z) * size_t(g.dims[1]) + size_t(y)) * size_t(g.dims[0]) + size_t(x)];
          if (c) counts[g.tileOfFine(x, y, z)] += c;
        }
    uint64_t most = 0;
    for (auto& [t, c] : counts) most = std::max(most, c);
    const bool fits = double(most) * kHaloShare <= tilePoints;
    const bool enough = r.o.minTiles <= 0 || counts.size() >= size_t(r.o.minTiles);
    if ((fits && enough) || s == 1) {
      r.tileIds.clear();
      r.tileCounts.clear();
      for (auto& [t, c] : counts) r.tileIds.push_back(t), r.tileCounts.push_back(c);
      return;
    }
  }
}

void scanAndPartition(Run& r, OocNormalsReport& rep) {
  const ProgressFn& progress = r.o.progress;
  PointReader reader(r.in);
  r.info = reader.info();
  r.normalsIn = r.info.normals;
  r.radiusIn = r.info.radius && r.extracting();
  const uint64_t n = r.info.count;
  const size_t chunk = 1 << 20;
  std::vector<Vec3f> pos, nrm;
  Timer t;
  // Pass 1: bounding box (and every value checked: a bad file fails here, before any tile work).
  Bounds3f bb;
  while (reader.read(pos, nrm, chunk) > 0) {
    for (const Vec3f& p : pos) bb.extend(p);
    reportProgress(progress, "bounding box", double(reader.position()) / double(n));
  }
  r.bounds = bb;
  rep.tBbox = t.seconds();
  t.reset();
  Grid& g = r.grid;
  g.lo = bb.min;
  const Vec3f ext = bb.diagonal();
  const float longest = ext.maxCoeff();
  g.cell = longest > 0 ? longest / float(kFineCells) : 1.0f;
  for (int a = 0; a < 3; ++a)
    g.dims[size_t(a)] = std::clamp(int(std::ceil(ext[a] / g.cell)), 1, kFineCells);
  // Pass 2: histogram.
  std::vector<uint64_t> hist(size_t(g.dims[0]) * size_t(g.dims[1]) * size_t(g.dims[2]), 0);
  reader.rewind();
  while (reader.read(pos, nrm, chunk) > 0) {
    for (const Vec3f& p : pos) ++hist[g.fineOf(p)];
    reportProgress(progress, "histogram", double(reader.position()) / double(n));
  }
  // (ε,δ) also holds Delaunay lists and candidates per tile: a quarter more.
  // Curvature keeps the Delaunay lists (~12 entries of index + weight) and its results.
  const double perPoint = inMemoryNormalsBytesPerPoint(r.o.geometry.k) * (r.extracting() ? 1.25 : 1.0) + (r.tileCurvature() ? 140.0 : 0.0);
  // Sized for kTilesInFlight tiles whatever the thread count, so the tiles (and the output) do
  // not depend on it.
  const double base = std::min(64.0 * 1024 * 1024, r.o.memoryBytes / 4);
  const double tileBytes = std::max(1.0, (r.o.memoryBytes - r.ioBytes - base) / double(kTilesInFlight));
  chooseTiles(r, hist, tileBytes / perPoint);
  for (size_t i = 0; i < r.tileIds.size(); ++i) r.denseOf[r.tileIds[i]] = i;
  r.blocks = size_t((n + kBlock - 1) / kBlock);
  r.blockCounts.assign(r.tileIds.size() * r.blocks, 0);
  // Pass 3: binning, buffered per tile, flushed when the buffers reach the I/O budget.
  fs::create_directories(r.dir / "cells");
  fs::create_directories(r.dir / "results");
  for (uint32_t tile : r.tileIds) fs::remove(r.cellPath(tile));
  std::vector<std::string> buf(r.tileIds.size());
  size_t buffered = 0;
  auto flush = [&] {
    for (size_t d = 0; d < buf.size(); ++d)
      if (!buf[d].empty()) {
        appendBytes(r.cellPath(r.tileIds[d]), buf[d].data(), buf[d].size());
        std::string().swap(buf[d]);
      }
    buffered = 0;
  };
  reader.rewind();
  uint64_t index = 0;
  std::vector<float> rad;
  while (reader.read(pos, nrm, chunk, &rad) > 0) {
    for (size_t i = 0; i < pos.size(); ++i, ++index) {
      const size_t d = r.denseOf.at(g.tileOf(pos[i]));
      std::string& b = buf[d];
      putRaw(b, index);
      b.append(reinterpret_cast<const char*>(pos[i].data()), 12);
      if (r.normalsIn) b.append(reinterpret_cast<const char*>(nrm[i].data()), 12);
      if (r.radiusIn) putRaw(b, rad[i]);
      ++r.blockCounts[d * r.blocks + size_t(index / kBlock)];
      buffered += r.recordBytes();
    }
    if (double(buffered) > r.ioBytes) flush();
    reportProgress(progress, "partition", double(reader.position()) / double(n));
  }
  flush();
  rep.tPartition = t.seconds();
}

json manifestJson(const Run& r, const FileIdentity& id) {
  json tiles = json::array();
  for (size_t d = 0; d < r.tileIds.size(); ++d) tiles.push_back({r.tileIds[d], r.tileCounts[d]});
  return json{{"format", kFormat},
              {"version", kVersion},
              {"input", identityJson(r.in, id)},
              {"arguments", argumentsJson(r.o, r.epsDelta, r.shapeApprox)},
              {"points", r.info.count},
              {"normals", r.normalsIn},
              {"radius", r.radiusIn},
              {"comments", r.info.comments},
              {"bounds_bits", {floatBits(r.bounds.min.x()), floatBits(r.bounds.min.y()), floatBits(r.bounds.min.z()),
                               floatBits(r.bounds.max.x()), floatBits(r.bounds.max.y()), floatBits(r.bounds.max.z())}},
              {"grid", {{"cell_bits", floatBits(r.grid.cell)}, {"dims", r.grid.dims}, {"tile_cells", r.grid.s}, {"tiles", r.grid.tiles}}},
              {"block", kBlock},
              {"tiles", tiles},
              {"partitioned", true}};
}

void loadManifest(Run& r, const json& m) {
  r.info.count = m.at("points").get<uint64_t>();
  r.normalsIn = m.at("normals").get<bool>();
  r.radiusIn = m.value("radius", false);
  r.info.normals = r.normalsIn;
  r.info.comments = m.at("comments").get<std::vector<std::string>>();
  const auto bb = m.at("bounds_bits").get<std::vector<uint32_t>>();
  r.bounds.min = Vec3f(bitsFloat(bb[0]), bitsFloat(bb[1]), bitsFloat(bb[2]));
  r.bounds.max = Vec3f(bitsFloat(bb[3]), bitsFloat(bb[4]), bitsFloat(bb[5]));
  const json& g = m.at("grid");
  r.grid.lo = r.bounds.min;
  r.grid.cell = bitsFloat(g.at("cell_bits").get<uint32_t>());
  r.grid.dims = g.at("dims").get<std::array<int, 3>>();
  r.grid.s = g.at("tile_cells").get<int>();
  r.grid.tiles = g.at("tiles").get<std::array<int, 3>>();
  for (const json& t : m.at("tiles")) r.tileIds.push_back(t.at(0).get<uint32_t>()), r.tileCounts.push_back(t.at(1).get<uint64_t>());
  for (size_t i = 0; i < r.tileIds.size(); ++i) r.denseOf[r.tileIds[i]] = i;
  r.blocks = size_t((r.info.count + kBlock - 1) / kBlock);
  const std::string b = readRange(r.dir / "blocks.bin", 0, r.tileIds.size() * r.blocks * 4);
  r.blockCounts.resize(r.tileIds.size() * r.blocks);
  std::memcpy(r.blockCounts.data(), b.data(), b.size());
}

/// One tile with its halo through computePointGeometryTile: the halo is widened until every
/// interior point's queries stay inside it (or it is one tile wide).
struct TileGeometry {
  Points all;                   ///< interior + halo, in input order
  std::vector<uint32_t> owner;  ///< tile of each point of `all`
  std::vector<uint8_t> exact;   ///< per point of `all`: its queries stayed inside the halo
  HybridModel model;
  PointGeometry geo;
  detail::TileGeometryExtras extras;
  uint64_t inexact = 0;
  uint32_t widenings = 0;
};

TileGeometry tileGeometry(const Run& r, uint32_t tile, bool delaunay) {
  const Grid& g = r.grid;
  const size_t rs = r.recordBytes();
  Points interior;
  decodeRecords(readRange(r.cellPath(tile), 0, r.tileCounts[r.denseOf.at(tile)] * rs), r.normalsIn, r.radiusIn, interior);
  Vec3d bmin, bmax;
  g.box(tile, bmin, bmax);
  const auto c = g.coords(tile);
  // Neighbour tiles (26-ring) that hold points, and whether a face of the box borders the grid.
  std::vector<uint32_t> neighbours;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int x = c[0] + dx, y = c[1] + dy, z = c[2] + dz;
        if ((dx | dy | dz) == 0 || x < 0 || y < 0 || z < 0 || x >= g.tiles[0] || y >= g.tiles[1] || z >= g.tiles[2]) continue;
        const uint32_t u = uint32_t((size_t(z) * size_t(g.tiles[1]) + size_t(y)) * size_t(g.tiles[0]) + size_t(x));
        if (r.denseOf.count(u)) neighbours.push_back(u);
      }
  bool openLow[3], openHigh[3];
  for (int a = 0; a < 3; ++a) openLow[a] = c[size_t(a)] == 0, openHigh[a] = c[size_t(a)] == g.tiles[size_t(a)] - 1;

  GeometryOptions go = r.o.geometry;
  go.curvature = r.tileCurvature();
  go.delaunayNeighbours = delaunay || go.curvature;
  // The cover radius is the radius `normals` writes; the extractions do not use it.
  go.coverRadius = !r.extracting();
  go.progress = {};
  double h = g.width() * kHaloStart;
  TileGeometry tg;
  for (;;) {
    // Halo: the neighbours' points inside the box widened by h.
    Points all = interior;
    std::vector<uint32_t> owner(interior.size(), tile);
    for (uint32_t u : neighbours) {
      Points p;
      decodeRecords(readRange(r.cellPath(u), 0, r.tileCounts[r.denseOf.at(u)] * rs), r.normalsIn, r.radiusIn, p);
      for (size_t i = 0; i < p.size(); ++i) {
        const Vec3d q = p.pos[i].cast<double>();
        if ((q.array() >= bmin.array() - h).all() && (q.array() <= bmax.array() + h).all()) {
          all.idx.push_back(p.idx[i]);
          all.pos.push_back(p.pos[i]);
          if (r.normalsIn) all.nrm.push_back(p.nrm[i]);
          if (r.radiusIn) all.rad.push_back(p.rad[i]);
          owner.push_back(u);
        }
      }
    }
    // In the input's order, so that ties between equal distances break as in memory.
    const size_t n = all.size();
    std::vector<uint32_t> perm(n);
    std::iota(perm.begin(), perm.end(), 0u);
    std::sort(perm.begin(), perm.end(), [&](uint32_t a, uint32_t b) { return all.idx[a] < all.idx[b]; });
    tg.all = Points();
    tg.owner.resize(n);
    tg.model = HybridModel();
    tg.model.points.resize(n);
    for (size_t i = 0; i < n; ++i) {
      tg.all.idx.push_back(all.idx[perm[i]]);
      tg.all.pos.push_back(all.pos[perm[i]]);
      tg.owner[i] = owner[perm[i]];
      tg.model.points[i].position = all.pos[perm[i]];
      if (r.normalsIn) tg.model.points[i].normal = all.nrm[perm[i]];
      if (r.radiusIn) tg.model.points[i].radius = all.rad[perm[i]];
    }
    tg.model.attributes.normals = r.normalsIn;
    tg.model.attributes.radii = r.radiusIn;
    tg.geo = detail::computePointGeometryTile(tg.model, go, r.dupTol, &tg.extras);
    // Distance from a point to the halo's outer boundary (faces on the grid's border: none).
    auto room = [&](const Vec3f& pf) {
      const Vec3d p = pf.cast<double>();
      double d = std::numeric_limits<double>::infinity();
      for (int a = 0; a < 3; ++a) {
        if (!openLow[a]) d = std::min(d, p[a] - (bmin[a] - h));
        if (!openHigh[a]) d = std::min(d, (bmax[a] + h) - p[a]);
      }
      return d;
    };
    tg.exact.assign(n, 0);
    tg.inexact = 0;
    for (size_t i = 0; i < n; ++i) {
      tg.exact[i] = double(tg.extras.reach[i]) < room(tg.all.pos[i]);
      if (tg.owner[i] == tile && !tg.exact[i]) ++tg.inexact;
    }
    if (tg.inexact > 0 && h < g.width()) {
      h = std::min(2 * h, g.width());
      ++tg.widenings;
      continue;
    }
    return tg;
  }
}

/// Runs f on every tile of `todo`, at most r.concurrent at once (the memory budget holds that
/// many tiles), each worker taking the next tile as soon as it is free: tiles differ in size by
/// orders of magnitude, and running them in fixed groups left a core idle while the largest tile
/// of a group finished (the per-tile MST is serial). Results do not depend on the schedule: each
/// tile writes its own files. Progress follows the points done.
template <class F>
void forEachTile(const Run& r, const std::vector<uint32_t>& todo, std::string_view stage, const F& f) {
  uint64_t total = 0;
  for (uint32_t tile : todo) total += r.tileCounts[r.denseOf.at(tile)];
  std::atomic<size_t> next{0};
  std::atomic<bool> failed{false};
  std::mutex progressMutex;
  uint64_t done = 0;
  const size_t workers = std::min(r.concurrent, std::max<size_t>(todo.size(), 1));
  parallelFor(0, workers, [&](size_t) {
    for (;;) {
      const size_t i = next++;
      if (i >= todo.size() || failed) return;
      try {
        f(todo[i]);
      } catch (...) {
        failed = true;
        throw;
      }
      std::lock_guard<std::mutex> lock(progressMutex);
      done += r.tileCounts[r.denseOf.at(todo[i])];
      reportProgress(r.o.progress, stage, total ? double(done) / double(total) : 1.0);
    }
  }, 1);
}

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
  size_t size() const { return idx.size(); }
};

template <class T>
void putColumn(std::string& s, const std::vector<T>& v) {
  s.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

template <class T>
void getColumn(const std::string& s, size_t& at, size_t n, std::vector<T>& v, const fs::path& path) {
  if (at + n * sizeof(T) > s.size()) throwIo(path.string(), "tile geometry file is truncated");
  v.resize(n);
  if (n) std::memcpy(static_cast<void*>(v.data()), s.data() + at, n * sizeof(T));
  at += n * sizeof(T);
}

OwnGeometry ownGeometry(const TileGeometry& tg, uint32_t tile, bool curvature) {
  const PointGeometry& g = tg.geo;
  const size_t n = tg.all.size();
  OwnGeometry og;
  std::vector<uint32_t> local(n, PointGeometry::kNoNeighbour);
  for (size_t i = 0; i < n; ++i)
    if (tg.owner[i] == tile) local[i] = uint32_t(og.idx.size()), og.idx.push_back(tg.all.idx[i]);
  og.starOffsets.push_back(0);
  for (size_t i = 0; i < n; ++i) {
    if (local[i] == PointGeometry::kNoNeighbour) continue;
    og.pos.push_back(tg.all.pos[i]);
    og.normal.push_back(g.normals[i]);
    og.radius.push_back(tg.model.points[i].radius);  // the input's, as the extractions keep it in memory
    og.spacing.push_back(g.spacing[i]);
    og.variation.push_back(g.surfaceVariation[i]);
    og.component.push_back(tg.extras.component.empty() ? 0 : tg.extras.component[i]);
    og.flags.push_back(g.flags[i]);
    if (curvature) og.minDir.push_back(g.minCurvatureDir[i]), og.maxDir.push_back(g.maxCurvatureDir[i]);
    for (uint32_t q : g.delaunayOf(i))
      if (local[q] != PointGeometry::kNoNeighbour) og.star.push_back(local[q]);
    og.starOffsets.push_back(uint32_t(og.star.size()));
  }
  return og;
}

std::string encodeOwnGeometry(const OwnGeometry& og) {
  std::string s = "LSGEO001";
  putRaw(s, uint64_t(og.size())), putRaw(s, uint64_t(og.star.size())), putRaw(s, uint8_t(!og.minDir.empty()));
  putColumn(s, og.idx), putColumn(s, og.pos), putColumn(s, og.normal), putColumn(s, og.radius), putColumn(s, og.spacing);
  putColumn(s, og.variation), putColumn(s, og.component), putColumn(s, og.flags), putColumn(s, og.minDir);
  putColumn(s, og.maxDir), putColumn(s, og.starOffsets), putColumn(s, og.star);
  return s;
}

OwnGeometry decodeOwnGeometry(const fs::path& path) {
  const std::string s = readRange(path, 0, fs::file_size(path));
  if (s.size() < 25 || s.compare(0, 8, "LSGEO001") != 0) throwIo(path.string(), "not a tile geometry file");
  const char* q = s.data() + 8;
  const uint64_t m = getRaw<uint64_t>(q), stars = getRaw<uint64_t>(q);
  const bool curvature = getRaw<uint8_t>(q) != 0;
  if (m > s.size() || stars > s.size()) throwIo(path.string(), "tile geometry file is damaged");
  size_t at = 25;
  OwnGeometry og;
  getColumn(s, at, m, og.idx, path), getColumn(s, at, m, og.pos, path), getColumn(s, at, m, og.normal, path);
  getColumn(s, at, m, og.radius, path), getColumn(s, at, m, og.spacing, path), getColumn(s, at, m, og.variation, path);
  getColumn(s, at, m, og.component, path), getColumn(s, at, m, og.flags, path);
  getColumn(s, at, curvature ? m : 0, og.minDir, path), getColumn(s, at, curvature ? m : 0, og.maxDir, path);
  getColumn(s, at, m + 1, og.starOffsets, path), getColumn(s, at, stars, og.star, path);
  if (at != s.size() || og.starOffsets.back() != stars) throwIo(path.string(), "tile geometry file is damaged");
  for (size_t j = 0; j < m; ++j)
    if (og.starOffsets[j] > og.starOffsets[j + 1]) throwIo(path.string(), "tile geometry file is damaged");
  for (uint32_t v : og.star)
    if (v >= m) throwIo(path.string(), "tile geometry file is damaged");
  return og;
}

/// Processes one tile for the normals: writes its result file.
void processTile(const Run& r, uint32_t tile) {
  TileGeometry tg = tileGeometry(r, tile, r.extracting());
  const PointGeometry& geo = tg.geo;
  const detail::TileGeometryExtras& extras = tg.extras;
  const size_t n = tg.all.size();
  TileSummary sum;
  sum.tile = tile;
  sum.widenings = tg.widenings;
  const uint64_t inexact = tg.inexact;
  {
    // Results of the interior points (in index order = the cell file's order).
    const bool oriented = !extras.component.empty();
    uint32_t comps = 0;
    for (uint32_t cpt : extras.component) comps = std::max(comps, cpt + 1);
    if (!oriented) comps = 1;
    std::vector<InteriorResult> res;
    res.reserve(n);
    std::vector<std::array<Extreme, 6>> ext(comps);
    std::map<uint32_t, std::vector<SharedPoint>> shared;
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> votesOf;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t comp = oriented ? extras.component[i] : 0;
      const uint64_t gi = tg.all.idx[i];
      if (tg.owner[i] != tile) {
        // A shared point: its normal here votes on the orientation of the two tiles when its
        // queries stayed inside this halo (then it is the owner's normal up to sign).
        // At most kVotesPerPair per (owner, component): exact shared normals vote unanimously, and
        // the cap bounds what the join holds in memory (20% of the points would be shared).
        if (tg.exact[i] && ++votesOf[{tg.owner[i], comp}] <= kVotesPerPair) shared[tg.owner[i]].push_back({gi, comp, geo.normals[i]});
        continue;
      }
      InteriorResult x;
      x.normal = geo.normals[i];
      x.cover = geo.coverRadius.empty() ? 0.0f : geo.coverRadius[i];  // none in the extraction's first pass
      x.spacing = geo.spacing[i];
      x.component = comp;
      x.flags = geo.flags[i];
      res.push_back(x);
      if (geo.neighbours[i * size_t(geo.k)] != PointGeometry::kNoNeighbour) sum.spacingSum += geo.spacing[i], ++sum.spacingCount;
      if (x.flags & kPointDuplicate) ++sum.flagCounts[0];
      if (x.flags & kPointFewNeighbours) ++sum.flagCounts[1];
      if (x.flags & kPointFlatNeighbourhood) ++sum.flagCounts[2];
      if (x.flags & kPointIsolated) ++sum.flagCounts[3];
      for (size_t d = 0; d < 6; ++d) {
        const float v = tg.all.pos[i].dot(kSeedDirs[d]);
        Extreme& e = ext[comp][d];
        if (v > e.value || (v == e.value && gi < e.index)) e.value = v, e.index = gi, e.normal = geo.normals[i];
      }
    }
    sum.interior = uint32_t(res.size());
    sum.components = comps;
    sum.inexact = inexact;
    sum.withHalo = uint32_t(n);
    if (r.curvatureOut()) {  // before the result file, whose presence marks the tile done
      std::string c;
      c.reserve(res.size() * kCurvatureRecord);
      for (size_t i = 0; i < n; ++i)
        if (tg.owner[i] == tile)
          putRaw(c, geo.kMin[i]), putRaw(c, geo.kMax[i]), putRaw(c, geo.minCurvatureDir[i]), putRaw(c, geo.maxCurvatureDir[i]);
      writeWhole(r.curvaturePath(tile), c);
    }
    if (r.extracting()) writeWhole(r.ownGeometryPath(tile), encodeOwnGeometry(ownGeometry(tg, tile, r.tileCurvature())));
    writeWhole(r.resultPath(tile), encodeResult(sum, res, ext, shared));
  }
}

// --- orientation across tiles ---------------------------------------------------------------------
struct Dsu {
  std::vector<uint32_t> p;
  explicit Dsu(size_t n) : p(n) { std::iota(p.begin(), p.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
  }
};

/// Flip per (tile, component) node so that the tiles agree on their shared points: a maximum
/// spanning forest of the vote graph (weight |agree - disagree|), one seed per connected part
/// chosen by the in-memory rule (extreme points along +z, -z, +x, -x, +y, -y).
std::vector<uint8_t> orientTiles(const Run& r, OocNormalsReport& rep, std::vector<size_t>& nodeOffset) {
  const size_t T = r.tileIds.size();
  std::vector<ResultView> views(T);
  nodeOffset.assign(T + 1, 0);
  for (size_t d = 0; d < T; ++d) {
    const fs::path p = r.resultPath(r.tileIds[d]);
    const std::string b = readRange(p, 0, fs::file_size(p));
    views[d] = decodeResultMeta(b, p, true);
    nodeOffset[d + 1] = nodeOffset[d] + views[d].summary.components;
  }
  const size_t nodes = nodeOffset[T];
  std::map<std::pair<uint32_t, uint32_t>, std::array<uint64_t, 2>> votes;  // (lo, hi) -> agree, disagree
  for (size_t b = 0; b < T; ++b) {
    // The owner's interior records for the points the neighbours share with it.
    const uint32_t tile = r.tileIds[b];
    bool any = false;
    for (size_t a = 0; a < T && !any; ++a) any = views[a].shared.count(tile) > 0;
    if (!any) continue;
    const size_t count = views[b].summary.interior;
    Points pts;
    decodeRecords(readRange(r.cellPath(tile), 0, count * r.recordBytes()), r.normalsIn, r.radiusIn, pts);
    const std::string res = readRange(r.resultPath(tile), views[b].interiorOffset, count * kResultRecord);
    for (size_t a = 0; a < T; ++a) {
      auto it = views[a].shared.find(tile);
      if (it == views[a].shared.end()) continue;
      size_t j = 0;
      for (const SharedPoint& sp : it->second) {
        while (j < count && pts.idx[j] < sp.index) ++j;
        if (j >= count || pts.idx[j] != sp.index) continue;
        const InteriorResult own = decodeInterior(res.data() + j * kResultRecord);
        const uint32_t na = uint32_t(nodeOffset[a] + sp.component), nb = uint32_t(nodeOffset[b] + own.component);
        if (na == nb) continue;
        const bool agree = own.normal.dot(sp.normal) >= 0;
        auto& v = votes[{std::min(na, nb), std::max(na, nb)}];
        ++v[agree ? 0 : 1];
      }
    }
  }
  struct Edge {
    uint64_t strength;
    uint32_t a, b;
    bool flip;
  };
  std::vector<Edge> edges;
  for (auto& [k, v] : votes)
    edges.push_back({v[0] > v[1] ? v[0] - v[1] : v[1] - v[0], k.first, k.second, v[1] > v[0]});
  std::stable_sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) { return x.strength > y.strength; });
  Dsu dsu(nodes);
  std::vector<std::vector<std::pair<uint32_t, bool>>> forest(nodes);
  for (const Edge& e : edges) {
    const uint32_t ra = dsu.find(e.a), rb = dsu.find(e.b);
    if (ra == rb) continue;
    dsu.p[std::max(ra, rb)] = std::min(ra, rb);
    forest[e.a].push_back({e.b, e.flip});
    forest[e.b].push_back({e.a, e.flip});
  }
  // Extremes per connected part, then its seed by the in-memory rule.
  std::vector<std::array<Extreme, 6>> partExt(nodes);
  std::vector<uint32_t> nodeTile(nodes);
  for (size_t d = 0; d < T; ++d)
    for (uint32_t c = 0; c < views[d].summary.components; ++c) {
      const uint32_t node = uint32_t(nodeOffset[d] + c);
      nodeTile[node] = uint32_t(d);
      const uint32_t root = dsu.find(node);
      for (size_t k = 0; k < 6; ++k) {
        const Extreme& e = views[d].extremes[c][k];
        Extreme& best = partExt[root][k];
        if (e.index == UINT64_MAX) continue;
        if (e.value > best.value || (e.value == best.value && e.index < best.index)) best = e;
      }
    }
  std::vector<uint8_t> flip(nodes, 0), seen(nodes, 0);
  std::vector<uint32_t> queue;
  for (uint32_t node = 0; node < nodes; ++node) {
    const uint32_t root = dsu.find(node);
    if (root != node) continue;
    // The seed node: the one holding the chosen extreme point.
    const auto& pe = partExt[root];
    if (pe[0].index != UINT64_MAX) ++rep.orientationComponents;  // parts made of halo points only are not counted
    int chosen = -1;
    float bestAlign = -1;
    for (size_t k = 0; k < 6; ++k) {
      if (pe[k].index == UINT64_MAX) continue;
      const float align = std::abs(pe[k].normal.dot(kSeedDirs[k]));
      if (align > bestAlign) bestAlign = align, chosen = int(k);
      if (align >= 0.866f) break;
    }
    // Find the node that owns the extreme (the first node of this part whose extreme it is).
    uint32_t seed = root;
    bool seedFlip = false;
    if (chosen >= 0) {
      for (uint32_t v = 0; v < nodes; ++v) {
        if (dsu.find(v) != root) continue;
        const auto& e = views[nodeTile[v]].extremes[v - nodeOffset[nodeTile[v]]][size_t(chosen)];
        if (e.index == pe[size_t(chosen)].index) {
          seed = v;
          seedFlip = e.normal.dot(kSeedDirs[size_t(chosen)]) < 0;
          break;
        }
      }
    }
    flip[seed] = seedFlip;
    seen[seed] = 1;
    queue.assign(1, seed);
    for (size_t h = 0; h < queue.size(); ++h) {
      const uint32_t u = queue[h];
      for (auto [v, rel] : forest[u])
        if (!seen[v]) seen[v] = 1, flip[v] = uint8_t(flip[u] ^ uint8_t(rel)), queue.push_back(v);
    }
  }
  for (uint8_t f : flip) rep.tileFlips += f;
  for (auto& [k, v] : votes) rep.disagreeingVotes += (flip[k.first] ^ flip[k.second]) ? v[0] : v[1];
  return flip;
}

void writeOutput(const Run& r, const std::vector<uint8_t>& flip, const std::vector<size_t>& nodeOffset, float avgSpacing) {
  const uint64_t n = r.info.count;
  // Curvature properties in the order writeModel writes them (addCurvatureProperties' names, sorted).
  const bool curv = r.curvatureOut();
  const std::vector<std::string> extraNames =
      curv ? std::vector<std::string>{"dmin_x", "dmin_y", "dmin_z", "k_max", "k_min"} : std::vector<std::string>{};
  PlyPointWriter w(r.out, n, r.info.comments, true, true, "", extraNames);
  const size_t T = r.tileIds.size();
  std::vector<uint64_t> done(T, 0);  // records consumed per tile
  std::vector<Vec3f> pos, nrm;
  std::vector<float> rad, extra;
  std::vector<uint8_t> filled;
  const size_t rs = r.recordBytes();
  for (size_t blk = 0; blk < r.blocks; ++blk) {
    const uint64_t b0 = uint64_t(blk) * kBlock, b1 = std::min(n, b0 + kBlock);
    const size_t m = size_t(b1 - b0);
    pos.assign(m, Vec3f::Zero());
    nrm.assign(m, Vec3f::Zero());
    rad.assign(m, 0.0f);
    extra.assign(m * extraNames.size(), 0.0f);
    filled.assign(m, 0);
    for (size_t d = 0; d < T; ++d) {
      const uint32_t cnt = r.blockCounts[d * r.blocks + blk];
      if (cnt == 0) continue;
      Points p;
      decodeRecords(readRange(r.cellPath(r.tileIds[d]), done[d] * rs, uint64_t(cnt) * rs), r.normalsIn, r.radiusIn, p);
      const std::string cv = curv ? readRange(r.curvaturePath(r.tileIds[d]), done[d] * kCurvatureRecord,
                                              uint64_t(cnt) * kCurvatureRecord)
                                  : std::string();
      const std::string res = readRange(r.resultPath(r.tileIds[d]), 8 + sizeof(TileSummary) + done[d] * kResultRecord,
                                        uint64_t(cnt) * kResultRecord);
      for (size_t i = 0; i < cnt; ++i) {
        const uint64_t gi = p.idx[i];
        if (gi < b0 || gi >= b1 || filled[gi - b0]) throwIo(r.cellPath(r.tileIds[d]).string(), "tile files do not match the manifest");
        const InteriorResult x = decodeInterior(res.data() + i * kResultRecord);
        const size_t o = size_t(gi - b0);
        filled[o] = 1;
        pos[o] = p.pos[i];
        nrm[o] = flip[nodeOffset[d] + x.component] ? Vec3f(-x.normal) : x.normal;
        // Radius rule of applyGeometry: cover radius, else spacing, else the average spacing.
        rad[o] = x.cover > 0 ? x.cover : x.spacing > 0 ? x.spacing : avgSpacing;
        if (curv) {
          const char* q = cv.data() + i * kCurvatureRecord;
          float kMin = getRaw<float>(q), kMax = getRaw<float>(q);
          Vec3f dMin = getRaw<Vec3f>(q);
          const Vec3f dMax = getRaw<Vec3f>(q);
          // A flipped tile component: with -n every directional curvature changes sign, so the
          // principal values swap and negate and the minimum direction is the maximum one.
          if (flip[nodeOffset[d] + x.component]) std::tie(kMin, kMax, dMin) = std::make_tuple(-kMax, -kMin, dMax);
          float* e = extra.data() + o * 5;
          e[0] = dMin.x(), e[1] = dMin.y(), e[2] = dMin.z(), e[3] = kMax, e[4] = kMin;
        }
      }
      done[d] += cnt;
    }
    for (uint8_t f : filled)
      if (!f) throwIo(r.dir.string(), "a point is missing from the tiles (the folder was changed during the run?)");
    w.write(pos.data(), nrm.data(), rad.data(), m, curv ? extra.data() : nullptr);
    reportProgress(r.o.progress, "write", double(b1) / double(n));
  }
  w.finish();
}

void prepareFolder(Run& r, OocNormalsReport& rep, const FileIdentity& id, const json& wantInput, const json& wantArgs) {
  const fs::path manifestPath = r.dir / "manifest.json";
  bool reuse = false;
  std::error_code ec;
  if (fs::exists(r.dir, ec)) {
    if (!fs::is_directory(r.dir, ec)) throwBadParameter("workDir", "'" + r.dir.string() + "' exists and is not a folder");
    if (fs::exists(manifestPath, ec)) {
      json m;
      try {
        std::ifstream f(manifestPath);
        m = json::parse(f);
      } catch (const std::exception&) {
        m = json();
      }
      if (m.is_object() && m.value("format", "") == kFormat && m.value("version", 0) == kVersion && m.value("partitioned", false) &&
          m.at("input") == wantInput && m.at("arguments") == wantArgs) {
        loadManifest(r, m);
        reuse = true;
      } else {
        if (!(m.is_object() && m.value("format", "") == kFormat))
          throwBadParameter("workDir", "'" + r.dir.string() + "' holds a manifest.json that is not a linesurf tile folder's (not reused)");
        // Another input's (or other arguments') tiles: not reused.
        fs::remove_all(r.dir / "cells", ec);
        fs::remove_all(r.dir / "results", ec);
        fs::remove(r.dir / "blocks.bin", ec);
        fs::remove(manifestPath, ec);
        rep.folderCleared = true;
      }
    } else if (!fs::is_empty(r.dir, ec)) {
      throwBadParameter("workDir", "'" + r.dir.string() + "' is not empty and is not a linesurf tile folder (no manifest.json)");
    }
  }
  const bool created = !fs::exists(r.dir, ec);
  fs::create_directories(r.dir, ec);
  if (ec) throwIo(r.dir.string(), "cannot create the tile folder: " + ec.message());
  if (!reuse) {
    try {
      scanAndPartition(r, rep);
      std::string blocks(r.blockCounts.size() * 4, '\0');
      std::memcpy(blocks.data(), r.blockCounts.data(), blocks.size());
      writeWhole(r.dir / "blocks.bin", blocks);
      writeWhole(manifestPath, manifestJson(r, id).dump(1) + "\n");
    } catch (...) {
      // Nothing to resume from a partition that did not finish: leave no folder behind.
      if (created) fs::remove_all(r.dir, ec);
      throw;
    }
  }
}


// --- (ε,δ) extraction per tile (§3.1) ---------------------------------------------------------------
void writeOrientation(const Run& r, const std::vector<size_t>& nodeOffset, const std::vector<uint8_t>& flip, float avg) {
  std::string b;
  putRaw(b, uint64_t(nodeOffset.size()));
  for (size_t v : nodeOffset) putRaw(b, uint64_t(v));
  b.append(reinterpret_cast<const char*>(flip.data()), flip.size());
  putRaw(b, avg);
  writeWhole(r.dir / "orientation.bin", b);
}

void readOrientation(const Run& r, std::vector<size_t>& nodeOffset, std::vector<uint8_t>& flip, float& avg) {
  const fs::path p = r.dir / "orientation.bin";
  const std::string b = readRange(p, 0, fs::file_size(p));
  const char* q = b.data();
  nodeOffset.resize(size_t(getRaw<uint64_t>(q)));
  for (size_t& v : nodeOffset) v = size_t(getRaw<uint64_t>(q));
  flip.assign(q, q + nodeOffset.back());
  q += nodeOffset.back();
  avg = getRaw<float>(q);
}

/// What the extraction pass adds up over the tiles.
struct ExtractTotals {
  uint64_t kept = 0, segments = 0;
  double epsilon = 0;
  /// The extraction's counters, summed: (ε,δ) seed directions, candidates, candidate members,
  /// degenerate neighbours; shape approximation: see shapeApproxStats().
  std::array<uint64_t, kExtractStats> stats{};
  double tExtract = 0, tWrite = 0;
};

std::array<uint64_t, kExtractStats> statsOf(const EpsDeltaStats& st) {
  return {st.seedDirections, st.candidateDirections, st.candidateMembers, st.degenerateNeighbours};
}
std::array<uint64_t, kExtractStats> statsOf(const ShapeApproxStats& st) {
  std::array<uint64_t, kExtractStats> v{st.clusters, st.smallClusters, st.clustersWithSegments, st.curvatureDirectionUsed,
                                        st.degenerateClusters, st.degenerateRuns};
  for (size_t b = 0; b < 6; ++b) v[6 + b] = st.sizeHistogram[b];
  v[12] = st.largeClusters, v[13] = st.largeClusterPoints, v[14] = st.splits, v[15] = st.iterations;
  return v;
}
ShapeApproxStats shapeApproxStats(const ExtractTotals& t, uint64_t points) {
  ShapeApproxStats st;
  const auto& v = t.stats;
  st.inputPoints = points, st.pointsKept = t.kept, st.pointsReplaced = points - t.kept, st.segments = t.segments;
  st.clusters = v[0], st.smallClusters = v[1], st.clustersWithSegments = v[2], st.curvatureDirectionUsed = v[3];
  st.degenerateClusters = v[4], st.degenerateRuns = v[5];
  for (size_t b = 0; b < 6; ++b) st.sizeHistogram[b] = v[6 + b];
  st.largeClusters = v[12], st.largeClusterPoints = v[13], st.splits = v[14], st.iterations = v[15];
  return st;
}

/// Extracts one tile's own points, as a cloud of their own, from the geometry the first pass
/// left, with the join's flips applied. Writes the tile's extraction file: counts, the
/// extraction's counters, kept-per-block counts, kept points, segments with provenance (input
/// indices).
void extractTile(const Run& r, uint32_t tile, double epsilon, const std::vector<size_t>& nodeOffset,
                 const std::vector<uint8_t>& flip, float avg) {
  const OwnGeometry og = decodeOwnGeometry(r.ownGeometryPath(tile));
  const size_t m = og.size(), d = r.denseOf.at(tile);
  const bool curvature = !og.minDir.empty();
  HybridModel c;
  c.points.resize(m);
  c.attributes.normals = true;
  c.attributes.radii = r.radiusIn;
  PointGeometry sg;
  sg.k = r.o.geometry.k;
  sg.averageSpacing = avg;
  sg.normals.resize(m);
  sg.spacing = og.spacing;
  sg.surfaceVariation = og.variation;
  sg.flags = og.flags;
  sg.delaunayOffsets = og.starOffsets;
  sg.delaunayIndices = og.star;
  if (curvature) sg.minCurvatureDir.resize(m), sg.maxCurvatureDir.resize(m);
  for (size_t j = 0; j < m; ++j) {
    // A flipped component's curvature: k_min, k_max become -k_max, -k_min, so the directions swap.
    const bool f = flip[nodeOffset[d] + og.component[j]] != 0;
    sg.normals[j] = f ? Vec3f(-og.normal[j]) : og.normal[j];
    if (curvature) sg.minCurvatureDir[j] = f ? og.maxDir[j] : og.minDir[j], sg.maxCurvatureDir[j] = f ? og.minDir[j] : og.maxDir[j];
    c.points[j].position = og.pos[j];
    c.points[j].normal = sg.normals[j];
    c.points[j].radius = og.radius[j];
  }
  HybridModel x;
  std::array<uint64_t, kExtractStats> stats{};
  if (r.epsDelta) {
    EpsDeltaOptions eo = *r.epsDelta;
    eo.epsilon = epsilon;
    eo.provenance = true;
    eo.progress = {};
    EpsDeltaStats st;
    x = extractEpsDelta(c, sg, eo, &st);
    stats = statsOf(st);
  } else {
    ShapeApproxOptions so = *r.shapeApprox;
    so.provenance = true;
    so.progress = {};
    so.clustering.progress = {};
    ShapeApproxStats st;
    x = extractShapeApprox(c, sg, so, &st);
    stats = statsOf(st);
  }
  std::vector<uint8_t> replaced(m, 0);
  for (const auto& prov : x.provenance)
    for (uint32_t j : prov) replaced[j] = 1;
  std::string b = "LSEXT002";
  const uint64_t kept = uint64_t(x.points.size());
  putRaw(b, kept), putRaw(b, uint64_t(x.segments.size()));
  for (uint64_t v : stats) putRaw(b, v);
  std::vector<uint32_t> perBlock(r.blocks, 0);
  for (size_t j = 0; j < m; ++j)
    if (!replaced[j]) ++perBlock[size_t(og.idx[j] / kBlock)];
  for (uint32_t v : perBlock) putRaw(b, v);
  size_t at = 0;
  for (size_t j = 0; j < m; ++j) {
    if (replaced[j]) continue;
    const Point& p = x.points[at++];
    putRaw(b, og.idx[j]), putRaw(b, p.position), putRaw(b, p.normal), putRaw(b, p.radius);
  }
  if (at != x.points.size()) throw std::logic_error("extractTile: kept points do not match the provenance");
  for (size_t sI = 0; sI < x.segments.size(); ++sI) {
    const Segment& sgm = x.segments[sI];
    putRaw(b, sgm.p0), putRaw(b, sgm.p1), putRaw(b, sgm.normal), putRaw(b, sgm.normal0), putRaw(b, sgm.normal1), putRaw(b, sgm.radius);
    putRaw(b, uint32_t(x.provenance[sI].size()));
    for (uint32_t j : x.provenance[sI]) putRaw(b, uint32_t(og.idx[j]));
  }
  writeWhole(r.extractPath(tile), b);
  // The tile's geometry is spent: free its disk now rather than at the end of the run.
  std::error_code ec;
  fs::remove(r.ownGeometryPath(tile), ec);
}

void extractTiles(const Run& r, const std::vector<size_t>& nodeOffset, const std::vector<uint8_t>& flip, float avg,
                  ExtractTotals& et) {
  Timer t;
  if (r.epsDelta) et.epsilon = r.epsDelta->epsilon > 0 ? r.epsDelta->epsilon : r.epsDelta->epsilonRelative * double(avg);
  std::vector<uint32_t> todo;
  std::error_code ec;
  for (size_t d = 0; d < r.tileIds.size(); ++d)
    if (int(d % size_t(r.o.ranks)) == r.o.rank && !fs::exists(r.extractPath(r.tileIds[d]), ec)) todo.push_back(r.tileIds[d]);
  forEachTile(r, todo, r.epsDelta ? "eps-delta tiles" : "shape-approx tiles",
              [&](uint32_t tile) { extractTile(r, tile, et.epsilon, nodeOffset, flip, avg); });
  et.tExtract = t.seconds();
}

void writeHybrid(const Run& r, ExtractTotals& et) {
  const size_t T = r.tileIds.size();
  const size_t headBytes = 8 + 16 + kExtractStats * 8 + r.blocks * 4;
  std::vector<uint64_t> kept(T), segs(T);
  std::vector<std::vector<uint32_t>> perBlock(T);
  for (size_t d = 0; d < T; ++d) {
    const fs::path p = r.extractPath(r.tileIds[d]);
    const std::string h = readRange(p, 0, headBytes);
    if (h.compare(0, 8, "LSEXT002") != 0) throwIo(p.string(), "not a tile extraction file");
    const char* q = h.data() + 8;
    kept[d] = getRaw<uint64_t>(q), segs[d] = getRaw<uint64_t>(q);
    for (uint64_t& v : et.stats) v += getRaw<uint64_t>(q);
    perBlock[d].resize(r.blocks);
    for (uint32_t& v : perBlock[d]) v = getRaw<uint32_t>(q);
    et.kept += kept[d];
    et.segments += segs[d];
  }
  std::vector<std::string> comments = r.info.comments;
  bool endpointNormals = false, provenance = false;
  if (r.epsDelta) {
    const EpsDeltaOptions& e = *r.epsDelta;
    char buf[160];
    std::snprintf(buf, sizeof buf, "eps-delta: epsilon=%.9g delta=%.9g k=%d", et.epsilon, e.delta, r.o.geometry.k);
    comments.push_back(buf);
    comments.push_back(std::string("eps-delta: normals=") + (r.normalsIn && !r.o.geometry.recomputeNormals ? "file" : "computed"));
    endpointNormals = e.endpointNormals, provenance = e.provenance;
  } else {
    const ShapeApproxOptions& sa = *r.shapeApprox;
    comments.push_back(std::string("linesurf: shape-approximation extraction (§3.2), ") +
                       (sa.method == ClusteringMethod::Hierarchical ? "hierarchical" : "greedy") + " clustering, delta_n " +
                       std::to_string(sa.clustering.deltaN));
    endpointNormals = sa.endpointNormals, provenance = sa.provenance;
  }
  // The segment element as writePlyModel declares it.
  std::string segHead;
  if (et.segments > 0) {
    segHead = "element segment " + std::to_string(et.segments) + "\n";
    segHead += "property float x0\nproperty float y0\nproperty float z0\nproperty float x1\nproperty float y1\nproperty float z1\n";
    segHead += "property float nx\nproperty float ny\nproperty float nz\n";
    segHead += "property float radius\n";
    if (endpointNormals)
      segHead += "property float nx0\nproperty float ny0\nproperty float nz0\nproperty float nx1\nproperty float ny1\nproperty float nz1\n";
    if (provenance) segHead += "property list uint uint provenance\n";
  }
  PlyPointWriter w(r.out, et.kept, comments, true, true, segHead);
  constexpr size_t kKeptRecord = 8 + 12 + 12 + 4;
  std::vector<uint64_t> used(T, 0);
  std::vector<Vec3f> pos, nrm;
  std::vector<float> rad;
  std::vector<std::pair<uint64_t, uint32_t>> order;  // (input index, slot) of a block's kept points
  for (size_t blk = 0; blk < r.blocks; ++blk) {
    pos.clear(), nrm.clear(), rad.clear(), order.clear();
    for (size_t d = 0; d < T; ++d) {
      const uint32_t cnt = perBlock[d][blk];
      if (!cnt) continue;
      const std::string rec = readRange(r.extractPath(r.tileIds[d]), headBytes + used[d] * kKeptRecord, uint64_t(cnt) * kKeptRecord);
      const char* q = rec.data();
      for (uint32_t i = 0; i < cnt; ++i) {
        order.emplace_back(getRaw<uint64_t>(q), uint32_t(pos.size()));
        pos.push_back(getRaw<Vec3f>(q)), nrm.push_back(getRaw<Vec3f>(q)), rad.push_back(getRaw<float>(q));
      }
      used[d] += cnt;
    }
    std::sort(order.begin(), order.end());
    std::vector<Vec3f> p2(pos.size()), n2(pos.size());
    std::vector<float> r2(pos.size());
    for (size_t i = 0; i < order.size(); ++i) p2[i] = pos[order[i].second], n2[i] = nrm[order[i].second], r2[i] = rad[order[i].second];
    w.write(p2.data(), n2.data(), r2.data(), p2.size());
    reportProgress(r.o.progress, "write points", double(blk + 1) / double(r.blocks));
  }
  // Segments, tile after tile, streamed in pieces.
  for (size_t d = 0; d < T; ++d) {
    if (!segs[d]) continue;
    const fs::path p = r.extractPath(r.tileIds[d]);
    const uint64_t start = headBytes + kept[d] * kKeptRecord;
    const std::string all = readRange(p, start, fs::file_size(p) - start);
    const char* q = all.data();
    std::string rows;
    for (uint64_t sI = 0; sI < segs[d]; ++sI) {
      Vec3f v[5];
      for (Vec3f& x : v) x = getRaw<Vec3f>(q);
      const float radius = getRaw<float>(q);
      const uint32_t cnt = getRaw<uint32_t>(q);
      for (int a = 0; a < 3; ++a) putRaw(rows, v[a]);
      putRaw(rows, radius);
      if (endpointNormals) putRaw(rows, v[3]), putRaw(rows, v[4]);
      if (provenance) putRaw(rows, cnt);
      for (uint32_t i = 0; i < cnt; ++i) {
        const uint32_t idx = getRaw<uint32_t>(q);
        if (provenance) putRaw(rows, idx);
      }
      if (rows.size() > (8u << 20)) w.writeRaw(rows), rows.clear();
    }
    w.writeRaw(rows);
  }
  w.finish();
}

void joinTiles(const Run& r, OocNormalsReport& rep, std::vector<size_t>& nodeOffset, std::vector<uint8_t>& flip);

OocNormalsReport runPipeline(const fs::path& in, const fs::path& out, const OocNormalsOptions& o, const EpsDeltaOptions* epsDelta,
                             const ShapeApproxOptions* shapeApprox, ExtractTotals* et) {
  validate(o.geometry);
  if (o.workDir.empty()) throwBadParameter("workDir", "empty path");
  if (o.ranks < 1 || o.rank < 0 || o.rank >= o.ranks) throwBadParameter("rank", "must be in [0, ranks)");
  OocNormalsReport rep;
  Run r{o, in, out, o.workDir};
  r.epsDelta = epsDelta;
  r.shapeApprox = shapeApprox;
  const bool extract = r.extracting();
  r.concurrent = size_t(std::max(1, std::min(currentThreadCount(), kTilesInFlight)));
  r.ioBytes = std::clamp(o.memoryBytes / 8, 8.0 * 1024 * 1024, 256.0 * 1024 * 1024);

  if (o.ranks > 1 && !o.barrier) throwBadParameter("barrier", "needed when ranks > 1");
  const FileIdentity id = fileIdentity(in);
  const json wantInput = identityJson(in, id), wantArgs = argumentsJson(o, epsDelta, shapeApprox);
  const fs::path manifestPath = r.dir / "manifest.json";
  std::error_code ec;
  if (o.rank == 0) prepareFolder(r, rep, id, wantInput, wantArgs);
  if (o.barrier) o.barrier();
  if (o.rank != 0) {
    // The other ranks take the partition rank 0 has just written (same input, same arguments).
    json m;
    try {
      std::ifstream f(manifestPath);
      m = json::parse(f);
    } catch (const std::exception&) {
      throwIo(manifestPath.string(), "rank " + std::to_string(o.rank) + " cannot read the manifest (is the tile folder shared by all ranks?)");
    }
    if (m.at("input") != wantInput || m.at("arguments") != wantArgs)
      throwIo(manifestPath.string(), "rank " + std::to_string(o.rank) + " sees another input or other arguments than rank 0");
    loadManifest(r, m);
  }
  rep.points = r.info.count;
  rep.tiles = r.tileIds.size();
  {
    const Vec3f diag = r.bounds.diagonal();
    r.dupTol = 1e-6f * (r.info.count > 0 ? diag.norm() : 0.0f);
  }

  // Tiles: this rank's share, those without a result file, a few in flight at once.
  Timer t;
  std::vector<uint32_t> todo;
  for (size_t d = 0; d < r.tileIds.size(); ++d) {
    if (int(d % size_t(o.ranks)) != o.rank) continue;
    const uint32_t tile = r.tileIds[d];
    // Done: its result, with the curvature of `normals --curvature`, or with the geometry the
    // extraction reads (unless the tile is extracted already, which removes it).
    if (fs::exists(r.resultPath(tile), ec) && (!r.curvatureOut() || fs::exists(r.curvaturePath(tile), ec)) &&
        (!extract || fs::exists(r.ownGeometryPath(tile), ec) || fs::exists(r.extractPath(tile), ec)))
      ++rep.tilesReused;
    else todo.push_back(r.tileIds[d]);
  }
  reportProgress(o.progress, "tiles", 0.0);
  forEachTile(r, todo, "tiles", [&](uint32_t tile) { processTile(r, tile); });
  rep.tTiles = t.seconds();
  if (o.barrier) o.barrier();
  if (o.rank != 0 && !extract) return rep;  // rank 0 joins the orientations and writes the output
  std::vector<size_t> nodeOffset;
  std::vector<uint8_t> flip;
  if (o.rank != 0) {
    // The extraction needs rank 0's orientation: wait for it, then read it.
    o.barrier();
    readOrientation(r, nodeOffset, flip, rep.averageSpacing);
  } else {
    joinTiles(r, rep, nodeOffset, flip);
    if (extract && o.ranks > 1) {
      writeOrientation(r, nodeOffset, flip, rep.averageSpacing);
      o.barrier();
    }
  }
  if (extract) {
    extractTiles(r, nodeOffset, flip, rep.averageSpacing, *et);
    if (o.barrier) o.barrier();
    if (o.rank != 0) return rep;
    t.reset();
    writeHybrid(r, *et);
    et->tWrite = t.seconds();
  } else {
    t.reset();
    writeOutput(r, flip, nodeOffset, rep.averageSpacing);
    rep.tWrite = t.seconds();
  }
  if (!o.keepWorkDir) fs::remove_all(r.dir, ec);
  return rep;
}

void joinTiles(const Run& r, OocNormalsReport& rep, std::vector<size_t>& nodeOffset, std::vector<uint8_t>& flip) {
  const OocNormalsOptions& o = r.o;
  std::error_code ec;
  Timer t;
  // Summaries: spacing, flags, halo statistics.
  double spacingSum = 0;
  uint64_t spacingCount = 0;
  for (uint32_t tile : r.tileIds) {
    const fs::path p = r.resultPath(tile);
    if (!fs::exists(p, ec)) throwIo(p.string(), "tile result missing (did every rank finish?)");
  }
  const bool orient = o.geometry.orientNormals && !(r.normalsIn && !o.geometry.recomputeNormals);
  {
    // The summaries (read whole: the extremes follow the interior records).
    for (uint32_t tile : r.tileIds) {
      const fs::path p = r.resultPath(tile);
      TileSummary s;
      const std::string b = readRange(p, 8, sizeof(TileSummary));
      std::memcpy(&s, b.data(), sizeof s);
      spacingSum += s.spacingSum;
      spacingCount += s.spacingCount;
      rep.duplicate += s.flagCounts[0], rep.fewNeighbours += s.flagCounts[1], rep.flat += s.flagCounts[2];
      rep.isolated += s.flagCounts[3];
      rep.inexactPoints += s.inexact;
      rep.haloWidenings += s.widenings;
      rep.tilePointsMax = std::max<size_t>(rep.tilePointsMax, s.withHalo);
    }
  }
  rep.averageSpacing = spacingCount > 0 ? float(spacingSum / double(spacingCount)) : 0.0f;
  if (orient) {
    reportProgress(o.progress, "orientation", 0.0);
    flip = orientTiles(r, rep, nodeOffset);
    reportProgress(o.progress, "orientation", 1.0);
  } else {
    nodeOffset.assign(r.tileIds.size() + 1, 0);
    for (size_t d = 0; d < r.tileIds.size(); ++d) {
      TileSummary s;
      const std::string b = readRange(r.resultPath(r.tileIds[d]), 8, sizeof(TileSummary));
      std::memcpy(&s, b.data(), sizeof s);
      nodeOffset[d + 1] = nodeOffset[d] + s.components;
    }
    flip.assign(nodeOffset.back(), 0);
  }
  rep.tOrient = t.seconds();
}

}  // namespace

double inMemoryNormalsBytesPerPoint(int k) {
  // Model point (~64 B), neighbour rows (8k), PCA and flags (~40), symmetrised adjacency with its
  // edge keys (~11k, packed) and the forest's per-point sets (~50) while the orientation runs,
  // later the Delaunay scratch (8k + 4), spacing and cover radius (8), kd-tree (~8), plus the
  // reader's copy of the file's rows while the model is built (~24). Measured at k = 12: 386 B a
  // point at 2 M points, 372 at 10 M, under the 478 this gives.
  return 190.0 + 24.0 * double(k);
}

OocNormalsReport computeNormalsOutOfCore(const fs::path& in, const fs::path& out, const OocNormalsOptions& o) {
  return runPipeline(in, out, o, nullptr, nullptr, nullptr);
}

OocEpsDeltaReport extractEpsDeltaOutOfCore(const fs::path& in, const fs::path& out, const OocNormalsOptions& o,
                                           const EpsDeltaOptions& extract) {
  validate(extract);
  OocEpsDeltaReport er;
  ExtractTotals et;
  er.geometry = runPipeline(in, out, o, &extract, nullptr, &et);
  er.keptPoints = et.kept, er.segments = et.segments, er.replacedPoints = er.geometry.points - et.kept;
  er.epsilon = et.epsilon;
  er.seedDirections = et.stats[0], er.candidateDirections = et.stats[1];
  er.tExtract = et.tExtract, er.tWrite = et.tWrite;
  return er;
}

OocShapeApproxReport extractShapeApproxOutOfCore(const fs::path& in, const fs::path& out, const OocNormalsOptions& o,
                                                 const ShapeApproxOptions& extract) {
  validate(extract);
  OocShapeApproxReport sr;
  ExtractTotals et;
  sr.geometry = runPipeline(in, out, o, nullptr, &extract, &et);
  sr.stats = shapeApproxStats(et, sr.geometry.points);
  sr.tExtract = et.tExtract, sr.tWrite = et.tWrite;
  return sr;
}

}  // namespace linesurf::ooc
