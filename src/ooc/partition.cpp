// The partition stage of the out-of-core pipeline (see partition.h): the input's bounding box and
// a 64^3 histogram size the tiles, then one pass bins the points into one cell file per tile; the
// manifest records what the folder was built from, so that a later run reuses it or clears it.
#include "ooc/partition.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <fstream>

#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "ooc/tile_extract.h"

namespace linesurf::ooc::detail {

json argumentsJson(const OocNormalsOptions& o, const TileExtraction* extraction) {
  const GeometryOptions& g = o.geometry;
  return json{{"extract", extraction ? extraction->arguments() : json(nullptr)},
              {"k", g.k},
              {"orientation_penalty_bits", floatBits(g.orientationPenalty)},
              {"orient", g.orientNormals},
              {"orient_side", int(g.orient)},
              {"viewpoint_bits", {floatBits(g.viewpoint.x()), floatBits(g.viewpoint.y()), floatBits(g.viewpoint.z())}},
              {"recompute", g.recomputeNormals},
              {"memory_bytes", o.memoryBytes},
              {"curvature", g.curvature && (!extraction || extraction->usesCurvature())},
              {"curvature_fit", int(g.curvatureFit)},
              {"min_tiles", o.minTiles}};
}

json identityJson(const fs::path& in, const FileIdentity& id) {
  return json{{"path", fs::absolute(in).lexically_normal().string()},
              {"size", id.size},
              {"mtime_ns", id.mtimeNs},
              {"hash", fmt::format("{:016x}", id.hash)}};
}

namespace {

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
  std::vector<float> rad, att;
  const size_t na = r.attrFloats();
  while (reader.read(pos, nrm, chunk, &rad, &att) > 0) {
    for (size_t i = 0; i < pos.size(); ++i, ++index) {
      const size_t d = r.denseOf.at(g.tileOf(pos[i]));
      std::string& b = buf[d];
      putRaw(b, index);
      b.append(reinterpret_cast<const char*>(pos[i].data()), 12);
      if (r.normalsIn) b.append(reinterpret_cast<const char*>(nrm[i].data()), 12);
      if (r.radiusIn) putRaw(b, rad[i]);
      if (na) b.append(reinterpret_cast<const char*>(att.data() + i * na), 4 * na);
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
              {"arguments", argumentsJson(r.o, r.extraction)},
              {"points", r.info.count},
              {"normals", r.normalsIn},
              {"radius", r.radiusIn},
              {"colors", r.info.colors},
              {"properties", r.info.properties},
              {"comments", r.info.comments},
              {"bounds_bits", {floatBits(r.bounds.min.x()), floatBits(r.bounds.min.y()), floatBits(r.bounds.min.z()),
                               floatBits(r.bounds.max.x()), floatBits(r.bounds.max.y()), floatBits(r.bounds.max.z())}},
              {"grid", {{"cell_bits", floatBits(r.grid.cell)}, {"dims", r.grid.dims}, {"tile_cells", r.grid.s}, {"tiles", r.grid.tiles}}},
              {"block", kBlock},
              {"tiles", tiles},
              {"partitioned", true}};
}

}  // namespace

void loadManifest(Run& r, const json& m) {
  r.info.count = m.at("points").get<uint64_t>();
  r.normalsIn = m.at("normals").get<bool>();
  r.radiusIn = m.value("radius", false);
  r.info.normals = r.normalsIn;
  r.info.colors = m.value("colors", false);
  r.info.properties = m.value("properties", std::vector<std::string>{});
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

void loadSharedManifest(Run& r, const json& wantInput, const json& wantArgs) {
  // The other ranks take the partition rank 0 has just written (same input, same arguments).
  const fs::path manifestPath = r.dir / "manifest.json";
  json m;
  try {
    std::ifstream f(manifestPath);
    m = json::parse(f);
  } catch (const std::exception&) {
    throwIo(manifestPath.string(), "rank " + std::to_string(r.o.rank) + " cannot read the manifest (is the tile folder shared by all ranks?)");
  }
  if (m.at("input") != wantInput || m.at("arguments") != wantArgs)
    throwIo(manifestPath.string(), "rank " + std::to_string(r.o.rank) + " sees another input or other arguments than rank 0");
  loadManifest(r, m);
}

}  // namespace linesurf::ooc::detail
