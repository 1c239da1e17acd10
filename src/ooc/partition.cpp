// The partition stage of the out-of-core pipeline (see partition.h): the input's bounding box and
// a 64^3 histogram size the tiles, then one pass bins the points into one cell file per tile, and
// a tile over the budget is re-gridded over its own points (beyond the thesis) until each fits; the
// manifest records what the folder was built from, so that a later run reuses it or clears it.
#include "ooc/partition.h"

#include <fmt/format.h>

#include <algorithm>
#include <cstring>
#include <fstream>

#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "ooc/memory_budget.h"
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

/// Chooses the tile size of g from its fine histogram: the largest tiles that fit the per-tile
/// point budget (with the halo's share) and give at least minTiles non-empty tiles, else the
/// finest (one fine cell a tile). Returns the non-empty tiles' point counts.
std::map<uint32_t, uint64_t> chooseTiles(Grid& g, const std::vector<uint64_t>& hist, double tilePoints, int minTiles) {
  const int longest = *std::max_element(g.dims.begin(), g.dims.end());
  std::map<uint32_t, uint64_t> counts;
  // Tile sizes from the number of tiles along the longest axis (1, 2, 3, ...): even tiles, not a
  // large one beside slivers.
  int previous = 0;
  for (int along = 1; along <= longest; ++along) {
    const int s = (longest + along - 1) / along;
    if (s == previous) continue;
    previous = s;
    g.s = s;
    for (int a = 0; a < 3; ++a) g.tiles[size_t(a)] = (g.dims[size_t(a)] + s - 1) / s;
    counts.clear();
    for (int z = 0; z < g.dims[2]; ++z)
      for (int y = 0; y < g.dims[1]; ++y)
        for (int x = 0; x < g.dims[0]; ++x) {
          const uint64_t c = hist[(size_t(z) * size_t(g.dims[1]) + size_t(y)) * size_t(g.dims[0]) + size_t(x)];
          if (c) counts[g.tileOfFine(x, y, z)] += c;
        }
    uint64_t most = 0;
    for (auto& [t, c] : counts) most = std::max(most, c);
    const bool fits = double(most) * kHaloShare <= tilePoints;
    const bool enough = minTiles <= 0 || counts.size() >= size_t(minTiles);
    if ((fits && enough) || s == 1) break;
  }
  return counts;
}

/// A grid over a box: kFineCells fine cells along its longest side.
Grid gridOver(const Bounds3f& bb) {
  Grid g;
  g.lo = bb.min;
  const Vec3f ext = bb.diagonal();
  const float longest = ext.maxCoeff();
  g.cell = longest > 0 ? longest / float(kFineCells) : 1.0f;
  for (int a = 0; a < 3; ++a) g.dims[size_t(a)] = std::clamp(int(std::ceil(ext[a] / g.cell)), 1, kFineCells);
  return g;
}

/// A tile being built: its points so far, their box, and their count per block of indices.
struct Leaf {
  uint32_t id = 0;
  uint64_t count = 0;
  Bounds3f bounds;
  std::vector<uint32_t> blocks;
  bool cut = false;  ///< refined: its points moved to its children
};

/// Appends cell records to tiles' cell files, buffered per tile and flushed when the buffers
/// reach the I/O budget.
class Binner {
 public:
  Binner(const Run& r, std::vector<Leaf>& leaves) : r_(r), leaves_(leaves) {}
  void add(size_t leaf, const char* record, const Vec3f& p, uint64_t index) {
    std::string& b = buf_[leaf];
    b.append(record, r_.recordBytes());
    Leaf& l = leaves_[leaf];
    ++l.count;
    l.bounds.extend(p);
    ++l.blocks[size_t(index / kBlock)];
    buffered_ += r_.recordBytes();
    if (double(buffered_) > r_.ioBytes) flush();
  }
  void flush() {
    for (auto& [leaf, b] : buf_)
      if (!b.empty()) {
        appendBytes(r_.cellPath(leaves_[leaf].id), b.data(), b.size());
        std::string().swap(b);
      }
    buffered_ = 0;
  }

 private:
  const Run& r_;
  std::vector<Leaf>& leaves_;
  std::map<size_t, std::string> buf_;
  size_t buffered_ = 0;
};

/// Cuts every tile over the budget again: a grid over its own points' box, sized by their
/// histogram as the first grid is, the points moved to the children's cell files in their order;
/// children still over the budget are cut in turn. A tile whose points share one spot is kept.
void refine(Run& r, std::vector<Leaf>& leaves) {
  const size_t rs = r.recordBytes();
  const uint64_t chunk = std::max<uint64_t>(1, uint64_t(r.ioBytes / 2) / rs);
  uint64_t nextId = r.gridTiles();
  for (size_t i = 0; i < leaves.size(); ++i) {  // children are appended, and checked in turn
    if (double(leaves[i].count) * kHaloShare <= r.tilePoints) continue;
    const uint32_t parentId = leaves[i].id;
    const uint64_t n = leaves[i].count;
    Refinement x;
    x.parent = parentId;
    x.grid = gridOver(leaves[i].bounds);
    Grid& g = x.grid;
    if (!(leaves[i].bounds.diagonal().maxCoeff() > 0)) continue;
    const fs::path path = r.cellPath(parentId);
    auto eachRecord = [&](const auto& f) {
      for (uint64_t done = 0; done < n; done += chunk) {
        const uint64_t m = std::min(chunk, n - done);
        const std::string b = readRange(path, done * rs, m * rs);
        for (uint64_t j = 0; j < m; ++j) {
          const char* rec = b.data() + j * rs;
          uint64_t index;
          Vec3f p;
          std::memcpy(&index, rec, 8);
          std::memcpy(p.data(), rec + 8, 12);
          f(rec, p, index);
        }
      }
    };
    std::vector<uint64_t> hist(size_t(g.dims[0]) * size_t(g.dims[1]) * size_t(g.dims[2]), 0);
    eachRecord([&](const char*, const Vec3f& p, uint64_t) { ++hist[g.fineOf(p)]; });
    const std::map<uint32_t, uint64_t> counts = chooseTiles(g, hist, r.tilePoints, 0);
    if (counts.size() < 2 || nextId + x.count() > std::numeric_limits<uint32_t>::max()) continue;
    x.firstId = uint32_t(nextId);
    nextId += x.count();
    std::map<uint32_t, size_t> leafOf;
    for (const auto& [t, c] : counts) {
      leafOf[t] = leaves.size();
      Leaf child;
      child.id = x.firstId + t;
      child.blocks.assign(r.blocks, 0);
      leaves.push_back(std::move(child));
      fs::remove(r.cellPath(x.firstId + t));
    }
    Binner bin(r, leaves);
    eachRecord([&](const char* rec, const Vec3f& p, uint64_t index) { bin.add(leafOf.at(g.tileOf(p)), rec, p, index); });
    bin.flush();
    fs::remove(path);
    leaves[i].cut = true;
    r.refinedOf[parentId] = r.refinements.size();
    r.refinements.push_back(x);
  }
}

void scanAndPartition(Run& r, OocNormalsReport& rep) {
  const ProgressFn& progress = r.o.progress;
  PointReader reader(r.in);
  r.info = reader.info();
  r.normalsIn = r.info.normals;
  r.radiusIn = r.info.radius && r.extracting();
  const uint64_t n = r.info.count;
  const size_t chunk = readChunkPoints(r.o);
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
  g = gridOver(bb);
  // Pass 2: histogram.
  std::vector<uint64_t> hist(size_t(g.dims[0]) * size_t(g.dims[1]) * size_t(g.dims[2]), 0);
  reader.rewind();
  while (reader.read(pos, nrm, chunk) > 0) {
    for (const Vec3f& p : pos) ++hist[g.fineOf(p)];
    reportProgress(progress, "histogram", double(reader.position()) / double(n));
  }
  r.tilePoints = tilePointBudget(r.o, r.extracting(), r.extractionCurvature);
  const std::map<uint32_t, uint64_t> counts = chooseTiles(g, hist, r.tilePoints, r.o.minTiles);
  std::vector<uint64_t>().swap(hist);
  r.blocks = size_t((n + kBlock - 1) / kBlock);
  // Pass 3: binning into the grid's tiles.
  fs::create_directories(r.dir / "cells");
  fs::create_directories(r.dir / "results");
  std::vector<Leaf> leaves;
  std::map<uint32_t, size_t> leafOf;
  for (const auto& [tile, c] : counts) {
    leafOf[tile] = leaves.size();
    Leaf l;
    l.id = tile;
    l.blocks.assign(r.blocks, 0);
    leaves.push_back(std::move(l));
    fs::remove(r.cellPath(tile));
  }
  {
    Binner bin(r, leaves);
    reader.rewind();
    uint64_t index = 0;
    std::vector<float> rad, att;
    const size_t na = r.attrFloats();
    std::string rec;
    while (reader.read(pos, nrm, chunk, &rad, &att) > 0) {
      for (size_t i = 0; i < pos.size(); ++i, ++index) {
        rec.clear();
        putRaw(rec, index);
        rec.append(reinterpret_cast<const char*>(pos[i].data()), 12);
        if (r.normalsIn) rec.append(reinterpret_cast<const char*>(nrm[i].data()), 12);
        if (r.radiusIn) putRaw(rec, rad[i]);
        if (na) rec.append(reinterpret_cast<const char*>(att.data() + i * na), 4 * na);
        bin.add(leafOf.at(g.tileOf(pos[i])), rec.data(), pos[i], index);
      }
      reportProgress(progress, "partition", double(reader.position()) / double(n));
    }
    bin.flush();
  }
  // Tiles over the budget (the points do not fill the box): cut again over their own points.
  refine(r, leaves);
  std::vector<const Leaf*> kept;
  for (const Leaf& l : leaves)
    if (!l.cut) kept.push_back(&l);
  std::sort(kept.begin(), kept.end(), [](const Leaf* a, const Leaf* b) { return a->id < b->id; });
  r.blockCounts.assign(kept.size() * r.blocks, 0);
  for (size_t d = 0; d < kept.size(); ++d) {
    r.tileIds.push_back(kept[d]->id);
    r.tileCounts.push_back(kept[d]->count);
    r.tileBounds.push_back(kept[d]->bounds);
    r.denseOf[kept[d]->id] = d;
    std::copy(kept[d]->blocks.begin(), kept[d]->blocks.end(), r.blockCounts.begin() + std::ptrdiff_t(d * r.blocks));
  }
  rep.tPartition = t.seconds();
}

json boundsBits(const Bounds3f& b) {
  return {floatBits(b.min.x()), floatBits(b.min.y()), floatBits(b.min.z()), floatBits(b.max.x()), floatBits(b.max.y()), floatBits(b.max.z())};
}
Bounds3f bitsBounds(const json& j) {
  const auto v = j.get<std::vector<uint32_t>>();
  if (v.size() != 6) throw std::runtime_error("bounds need 6 values");
  Bounds3f b;
  b.min = Vec3f(bitsFloat(v[0]), bitsFloat(v[1]), bitsFloat(v[2]));
  b.max = Vec3f(bitsFloat(v[3]), bitsFloat(v[4]), bitsFloat(v[5]));
  return b;
}
json gridJson(const Grid& g) {
  return {{"lo_bits", {floatBits(g.lo.x()), floatBits(g.lo.y()), floatBits(g.lo.z())}},
          {"cell_bits", floatBits(g.cell)}, {"dims", g.dims}, {"tile_cells", g.s}, {"tiles", g.tiles}};
}
Grid jsonGrid(const json& j) {
  Grid g;
  const auto lo = j.at("lo_bits").get<std::array<uint32_t, 3>>();
  g.lo = Vec3f(bitsFloat(lo[0]), bitsFloat(lo[1]), bitsFloat(lo[2]));
  g.cell = bitsFloat(j.at("cell_bits").get<uint32_t>());
  g.dims = j.at("dims").get<std::array<int, 3>>();
  g.s = j.at("tile_cells").get<int>();
  g.tiles = j.at("tiles").get<std::array<int, 3>>();
  return g;
}

json manifestJson(const Run& r, const FileIdentity& id) {
  json tiles = json::array();
  for (size_t d = 0; d < r.tileIds.size(); ++d) tiles.push_back({r.tileIds[d], r.tileCounts[d], boundsBits(r.tileBounds[d])});
  json refinements = json::array();
  for (const Refinement& x : r.refinements) refinements.push_back({{"parent", x.parent}, {"first", x.firstId}, {"grid", gridJson(x.grid)}});
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
              {"bounds_bits", boundsBits(r.bounds)},
              {"grid", {{"cell_bits", floatBits(r.grid.cell)}, {"dims", r.grid.dims}, {"tile_cells", r.grid.s}, {"tiles", r.grid.tiles}}},
              {"tile_points", r.tilePoints},
              {"refinements", refinements},
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
  r.bounds = bitsBounds(m.at("bounds_bits"));
  const json& g = m.at("grid");
  r.grid.lo = r.bounds.min;
  r.grid.cell = bitsFloat(g.at("cell_bits").get<uint32_t>());
  r.grid.dims = g.at("dims").get<std::array<int, 3>>();
  r.grid.s = g.at("tile_cells").get<int>();
  r.grid.tiles = g.at("tiles").get<std::array<int, 3>>();
  r.tilePoints = m.at("tile_points").get<double>();
  for (const json& x : m.at("refinements")) {
    r.refinedOf[x.at("parent").get<uint32_t>()] = r.refinements.size();
    r.refinements.push_back({x.at("parent").get<uint32_t>(), x.at("first").get<uint32_t>(), jsonGrid(x.at("grid"))});
  }
  for (const json& t : m.at("tiles")) {
    r.tileIds.push_back(t.at(0).get<uint32_t>());
    r.tileCounts.push_back(t.at(1).get<uint64_t>());
    r.tileBounds.push_back(bitsBounds(t.at(2)));
  }
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
