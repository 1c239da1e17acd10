// Building a level-of-detail hierarchy from a model too large to hold (include/linesurf/lod/lod.h,
// buildLodStreaming). The same hierarchy as buildLod, byte for byte, in memory bounded by the
// budget: the model is read in chunks several times; a histogram of Morton cells gives the top of
// the octree, whose subtrees of at most a chunk's worth of primitives are each sorted, split and
// merged on their own from a working file, and the top levels are merged last from the subtree
// roots. Leaf blocks go straight to their place in the output; inner blocks go to a working file
// and are copied behind the leaves in the file's order once all are made.
#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <numeric>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/io/las_io.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/io/model_stream.h"
#include "linesurf/lod/lod.h"
#include "lod_build_parts.h"
#include "lod_format.h"

namespace linesurf::lod {
namespace {
using namespace detail;
namespace fs = std::filesystem;

constexpr int kHistLevel = 7;  // 2^21 cells of the top histogram (16 MiB of 64-bit counts)
constexpr size_t kRowsPerRead = size_t(1) << 19;

// Appends to a working file, buffered; files are opened only to flush, so that any number of
// them can be filled at once.
struct Spool {
  fs::path path;
  std::string buf;
  uint64_t records = 0;
  void flush() {
    if (buf.empty()) return;
    std::FILE* f = std::fopen(path.c_str(), "ab");
    const bool ok = f && std::fwrite(buf.data(), 1, buf.size(), f) == buf.size();
    const int e = errno;
    if (f && std::fclose(f) != 0 && ok) throwIo(path.string(), std::string("write failed: ") + std::strerror(errno));
    if (!ok) throwIo(path.string(), std::string("write failed: ") + std::strerror(e));
    buf.clear();
  }
};

std::string readWhole(const fs::path& path, uint64_t bytes) {
  std::string out(bytes, '\0');
  if (!bytes) return out;
  std::FILE* f = std::fopen(path.c_str(), "rb");
  const bool ok = f && std::fread(out.data(), 1, bytes, f) == bytes;
  if (f) std::fclose(f);
  if (!ok) throwIo(path.string(), "cannot read back a working file");
  return out;
}

// One subtree root of the top tree and what its subtree became.
struct Chunk {
  uint32_t top = 0;  // its node in the top tree
  Spool points, segments;
  std::vector<BNode> local;  // its subtree, breadth first from the root (ranges into its sorted keys)
  std::vector<uint32_t> localPoints, localSegments;  // leaves' counts
  std::vector<uint32_t> globalId;                    // of each local node
};

struct TopNode {
  BNode cube;  // level, cubeMin, side
  uint64_t code = 0, count = 0;
  bool split = false;
  uint32_t firstChild = 0, childCount = 0;
  int32_t chunk = -1;
};

// A chunk's records: the primitives with their keys, sorted as buildLod sorts its keys.
struct ChunkData {
  std::string points, segments;  // block-format records
  // (key, record position: points first, then segments), sorted: within a chunk records are in
  // model order, so this is buildLod's (key, model index) order.
  std::vector<std::pair<uint64_t, uint32_t>> keys;
};

}  // namespace

BuildReport buildLodStreaming(const fs::path& input, const fs::path& output, const BuildOptions& options,
                              const StreamBuildOptions& so) {
  validate(options);
  const std::string name = input.string();
  ModelChunkReader reader(input);
  const uint64_t P = reader.points(), S = reader.segments(), N = P + S;
  if (N == 0) throwBadInput(name, "", "the model holds no points and no segments");
  if (N >= kNoIndex) throwBadInput(name, "", "more than 2^32 - 2 primitives");
  const double budget = std::max(so.memoryBytes, 1.0);
  // Per primitive of a chunk: its record (<= 100 bytes), key (16), a decoded copy of a leaf and
  // the merged levels above it (~120): 256 bytes with margin; a third of the budget.
  const uint64_t chunkLimit = std::max<uint64_t>(uint64_t(options.leafSize), uint64_t(budget / 3 / 256));
  auto progress = [&](std::string_view stage, double f) { reportProgress(so.progress, stage, f); };

  // Pass 1: the raw bounds (the frame), and what `linesurf render` would have to estimate.
  Bounds3f raw, kb, sb;
  float maxRadius = 0, maxPointRadius = 0;
  auto frameStats = [&](const HybridModel& m) {
    // As buildLod takes them: maxRadius over every finite radius; the sphere's box and its
    // fallback radius (boundingSphere) over points with finite positions.
    for (const Point& p : m.points) {
      if (std::isfinite(p.radius)) maxRadius = std::max(maxRadius, p.radius);
      if (!p.position.allFinite()) continue;
      kb.extend(p.position), sb.extend(p.position);
      if (std::isfinite(p.radius)) maxPointRadius = std::max(maxPointRadius, p.radius);
    }
    for (const Segment& s : m.segments) {
      const Vec3f mid = Vec3f(0.5f * (s.p0 + s.p1));
      if (mid.allFinite()) kb.extend(mid);
      if (s.p0.allFinite() && s.p1.allFinite()) sb.extend(s.p0), sb.extend(s.p1);
      if (std::isfinite(s.radius)) maxRadius = std::max(maxRadius, s.radius);
    }
  };
  Attributes attributes;
  bool shading = false, masses = false, first = true, firstPoints = true, pointNormals = true, segmentNormals = true;
  std::string upAxis;
  HybridModel c;
  while (reader.next(c, kRowsPerRead)) {
    progress("reading", double(reader.pointsRead() + reader.segmentsRead()) / double(N) / 3);
    if (first) {
      upAxis = recordedUpAxis(c);
      // All but `normals` follow from the header, which every chunk carries whole; `normals`
      // needs them on every element that has rows (as the whole-file reader decides).
      attributes = c.attributes;
      shading = attributes.shadingNormals && P > 0;
      first = false;
    }
    if (!c.points.empty()) {
      if (firstPoints) masses = pointMasses(c) != nullptr, firstPoints = false;
      pointNormals = pointNormals && c.attributes.normals;
      if (!c.attributes.normals || !c.attributes.radii ||
          std::any_of(c.points.begin(), c.points.end(), [](const Point& p) { return p.radius == 0.0f; }))
        throwBadInput(name, "", "the streamed build needs every point's normal and radius (e.g. the output of "
                                "`linesurf extract`); build it in memory to estimate them");
    }
    if (!c.segments.empty()) {
      segmentNormals = segmentNormals && c.attributes.normals;
      if (std::any_of(c.segments.begin(), c.segments.end(), [](const Segment& s) { return s.radius == 0.0f; }))
        throwBadInput(name, "", "the streamed build needs every segment's radius; build it in memory to estimate them");
    }
    const Bounds3f b = c.bounds();
    if (!b.empty()) raw.extend(b.min), raw.extend(b.max);
    frameStats(c);
  }
  attributes.normals = pointNormals && segmentNormals;
  const ModelFrame frame = normalizingFrame(raw);

  // Pass 2: in the frame, the key bounds (root cube), the sphere's box and the largest radius
  // (gathered in pass 1 already, for a model that needs no frame).
  if (!frame.identity()) {
    kb = sb = Bounds3f();
    maxRadius = maxPointRadius = 0;
    reader.rewind();
    while (reader.next(c, kRowsPerRead)) {
      progress("reading", (1 + double(reader.pointsRead() + reader.segmentsRead()) / double(N)) / 3);
      toFrame(c, frame);
      frameStats(c);
    }
  }
  const auto [rootMin, side] = rootCube(kb);
  BoundingSphere sphere;
  if (!sb.empty()) sphere.center = sb.center();

  // Pass 3: the sphere's radius and the histogram of the primitives over the top cells.
  const int shiftHist = 3 * (kMaxLevel - kHistLevel);
  std::vector<uint64_t> prefix((size_t(1) << (3 * kHistLevel)) + 1, 0);  // counts, then prefix sums
  float r2 = 0;
  reader.rewind();
  while (reader.next(c, kRowsPerRead)) {
    progress("reading", (2 + double(reader.pointsRead() + reader.segmentsRead()) / double(N)) / 3);
    toFrame(c, frame);
    for (const Point& p : c.points) {
      if (p.position.allFinite()) r2 = std::max(r2, (p.position - sphere.center).squaredNorm());
      ++prefix[1 + (mortonKey(p.position, rootMin, side) >> shiftHist)];
    }
    for (const Segment& s : c.segments) {
      if (s.p0.allFinite() && s.p1.allFinite())
        r2 = std::max({r2, (s.p0 - sphere.center).squaredNorm(), (s.p1 - sphere.center).squaredNorm()});
      ++prefix[1 + (mortonKey(Vec3f(0.5f * (s.p0 + s.p1)), rootMin, side) >> shiftHist)];
    }
  }
  if (!sb.empty()) {
    sphere.radius = std::sqrt(r2);
    if (!(sphere.radius > 0)) sphere.radius = maxPointRadius > 0 ? maxPointRadius : 1.0f;
  }
  std::partial_sum(prefix.begin(), prefix.end(), prefix.begin());

  // The top of the octree from the counts, breadth first as buildLod splits it: a node of at
  // most a chunk's worth of primitives (or at the histogram's depth) is a subtree root.
  std::vector<TopNode> top;
  std::vector<Chunk> chunks;
  TemporaryFolder work(so.workDir.empty() ? output.parent_path() : so.workDir);
  {
    TopNode root;
    root.cube.cubeMin = rootMin, root.cube.side = side;
    root.count = N;
    top.push_back(root);
  }
  auto cellRange = [&](int level, uint64_t code) {
    const int s = 3 * (kHistLevel - level);
    return std::pair<uint64_t, uint64_t>{code << s, (code + 1) << s};
  };
  for (size_t i = 0; i < top.size(); ++i) {
    TopNode nd = top[i];
    const bool leaf = nd.count <= uint64_t(options.leafSize) || nd.cube.level >= kMaxLevel;
    if (leaf || nd.count <= chunkLimit || nd.cube.level >= kHistLevel) {
      top[i].chunk = int32_t(chunks.size());
      Chunk ch;
      ch.top = uint32_t(i);
      ch.points.path = work.path() / fmt::format("c{}.p", chunks.size());
      ch.segments.path = work.path() / fmt::format("c{}.s", chunks.size());
      chunks.push_back(std::move(ch));
      continue;
    }
    top[i].split = true;
    top[i].firstChild = uint32_t(top.size());
    for (uint32_t o = 0; o < 8; ++o) {
      const uint64_t code = nd.code * 8 + o;
      const auto [b, e] = cellRange(nd.cube.level + 1, code);
      const uint64_t n = prefix[e] - prefix[b];
      if (!n) continue;
      TopNode child;
      child.cube = childCube(nd.cube, o);
      child.code = code, child.count = n;
      top.push_back(child);
      ++top[i].childCount;
    }
  }
  // Each histogram cell's chunk (the counts are no longer needed).
  std::vector<uint32_t> cellChunk(size_t(1) << (3 * kHistLevel), 0);
  for (const Chunk& ch : chunks) {
    const TopNode& t = top[ch.top];
    const auto [b, e] = cellRange(t.cube.level, t.code);
    std::fill(cellChunk.begin() + ptrdiff_t(b), cellChunk.begin() + ptrdiff_t(e), uint32_t(&ch - chunks.data()));
  }
  std::vector<uint64_t>().swap(prefix);

  // Pass 4: every primitive to its chunk's working file, as the record its leaf will hold.
  reader.rewind();
  const size_t flushAt = std::clamp<size_t>(size_t(budget / 4 / double(std::max<size_t>(chunks.size(), 1))), 4096, 1 << 22);
  uint64_t spooled = 0;
  while (reader.next(c, kRowsPerRead)) {
    const uint64_t firstPoint = reader.pointsRead() - c.points.size(), firstSeg = reader.segmentsRead() - c.segments.size();
    toFrame(c, frame);
    const std::vector<float>* m = pointMasses(c);
    for (size_t i = 0; i < c.points.size(); ++i) {
      const Point& p = c.points[i];
      Chunk& ch = chunks[cellChunk[mortonKey(p.position, rootMin, side) >> shiftHist]];
      format::putPoint(ch.points.buf, p, shading ? c.pointShadingNormals[i] : Vec3f(Vec3f::Zero()), m ? (*m)[i] : 1.0f,
                       uint32_t(firstPoint + i));
      ++ch.points.records;
      if (ch.points.buf.size() >= flushAt) ch.points.flush();
    }
    for (size_t i = 0; i < c.segments.size(); ++i) {
      const Segment& s = c.segments[i];
      Chunk& ch = chunks[cellChunk[mortonKey(Vec3f(0.5f * (s.p0 + s.p1)), rootMin, side) >> shiftHist]];
      format::putSegment(ch.segments.buf, s, uint32_t(firstSeg + i));
      ++ch.segments.records;
      if (ch.segments.buf.size() >= flushAt) ch.segments.flush();
    }
    spooled += c.points.size() + c.segments.size();
    progress("sorting into chunks", double(spooled) / double(N));
  }
  for (Chunk& ch : chunks) ch.points.flush(), ch.segments.flush();
  std::vector<uint32_t>().swap(cellChunk);
  c = HybridModel();

  // A chunk's records and their order by (key, record position): records are in model order
  // within each kind (spooled in reading order, points before segments), so this is buildLod's
  // order by (key, model-wide index). Phase A sorts and saves the order; phase B reads it back.
  auto orderPath = [&](const Chunk& ch) { return fs::path(ch.points.path).replace_extension(".o"); };
  auto loadChunk = [&](Chunk& ch, bool sorted) {
    ChunkData d;
    d.points = readWhole(ch.points.path, ch.points.records * format::kPointBytes);
    d.segments = readWhole(ch.segments.path, ch.segments.records * format::kSegmentBytes);
    const size_t np = ch.points.records, ns = ch.segments.records;
    d.keys.resize(np + ns);
    if (sorted) {
      const std::string o = readWhole(orderPath(ch), (np + ns) * 4);
      for (size_t k = 0; k < np + ns; ++k) d.keys[k] = {0, format::get<uint32_t>(o.data() + 4 * k)};
      return d;
    }
    parallelFor(0, np + ns, [&](size_t k) {
      if (k < np) {
        d.keys[k] = {mortonKey(format::getVec(d.points.data() + k * format::kPointBytes), rootMin, side), uint32_t(k)};
      } else {
        const char* r = d.segments.data() + (k - np) * format::kSegmentBytes;
        const Vec3f p0 = format::getVec(r), p1 = format::getVec(r + 12);
        d.keys[k] = {mortonKey(Vec3f(0.5f * (p0 + p1)), rootMin, side), uint32_t(k)};
      }
    }, 4096);
    std::sort(d.keys.begin(), d.keys.end());
    return d;
  };

  // Phase A: each chunk's subtree topology.
  uint64_t done = 0;
  for (Chunk& ch : chunks) {
    const TopNode& t = top[ch.top];
    const uint64_t n = ch.points.records + ch.segments.records;
    if (n != t.count) throw std::logic_error("lod: chunk count");
    BNode root = t.cube;
    root.begin = 0, root.end = n;
    if (n <= uint64_t(options.leafSize) || root.level >= kMaxLevel) {
      root.leaf = true;
      ch.local = {root};
      ch.localPoints = {uint32_t(ch.points.records)};
      ch.localSegments = {uint32_t(ch.segments.records)};
    } else {
      const ChunkData d = loadChunk(ch, false);
      {
        Spool order{orderPath(ch)};
        for (const auto& kv : d.keys) format::put(order.buf, kv.second);
        order.flush();
      }
      ch.local = {root};
      splitBreadthFirst(ch.local, 0, d.keys, options.leafSize);
      ch.localPoints.assign(ch.local.size(), 0);
      ch.localSegments.assign(ch.local.size(), 0);
      for (size_t i = 0; i < ch.local.size(); ++i)
        if (ch.local[i].leaf) {
          uint32_t pts = 0;
          for (size_t k = ch.local[i].begin; k < ch.local[i].end; ++k) pts += d.keys[k].second < ch.points.records;
          ch.localPoints[i] = pts;
          ch.localSegments[i] = uint32_t(ch.local[i].end - ch.local[i].begin - pts);
        }
    }
    done += n;
    progress("splitting", double(done) / double(N));
  }

  // The whole tree's breadth-first numbering (buildLod's): top nodes, then each subtree inside.
  struct Ref {
    int32_t chunk;   // -1: a split top node
    uint32_t local;  // top node id, or the node within the chunk's subtree
  };
  std::vector<Ref> refs{{top[0].chunk, 0}};  // a chunk root is node 0 of its subtree
  std::vector<BNode> nodes;
  for (size_t i = 0; i < refs.size(); ++i) {
    const Ref r = refs[i];
    BNode g;
    if (r.chunk < 0) {
      const TopNode& t = top[r.local];
      g = t.cube;
      g.firstChild = uint32_t(refs.size());
      g.childCount = uint8_t(t.childCount);
      for (uint32_t k = 0; k < t.childCount; ++k) {
        const uint32_t cl = t.firstChild + k;
        refs.push_back({top[cl].chunk, top[cl].chunk >= 0 ? 0u : cl});
      }
    } else {
      Chunk& ch = chunks[size_t(r.chunk)];
      const BNode& l = ch.local[r.local];
      if (ch.globalId.empty()) ch.globalId.assign(ch.local.size(), 0);
      ch.globalId[r.local] = uint32_t(i);
      g = l;
      g.begin = g.end = 0;
      g.firstChild = l.leaf ? 0 : uint32_t(refs.size());
      for (uint32_t k = 0; k < l.childCount; ++k) refs.push_back({r.chunk, l.firstChild + k});
    }
    nodes.push_back(g);
  }
  const uint32_t count = uint32_t(nodes.size());
  int depth = 0;
  for (const BNode& n : nodes) depth = std::max(depth, n.level);

  HeaderFacts facts;
  facts.points = P, facts.segments = S, facts.nodes = count, facts.depth = depth;
  facts.frame = frame, facts.sphere = sphere, facts.maxRadius = maxRadius;
  facts.attributes = attributes, facts.shading = shading, facts.masses = masses;
  facts.upAxis = upAxis;
  const HeaderJson hj = headerJson(facts, options, name);
  const uint64_t blocksOffset = format::kPreambleBytes + hj.json.size() + uint64_t(count) * format::kRecordBytes +
                                format::tableTrailerBytes(format::kVersion);

  std::vector<uint64_t> offsets(count), sizes(count), sums(count);
  std::vector<uint32_t> nPoints(count), nSegments(count);
  uint64_t leafEnd = blocksOffset;
  for (const Chunk& ch : chunks)
    for (size_t l = 0; l < ch.local.size(); ++l)
      if (ch.local[l].leaf) {
        const uint32_t g = ch.globalId[l];
        nPoints[g] = ch.localPoints[l], nSegments[g] = ch.localSegments[l];
      }
  uint32_t leaves = 0;
  for (uint32_t i = 0; i < count; ++i)
    if (nodes[i].leaf) {
      offsets[i] = leafEnd;
      sizes[i] = format::kBlockHeaderBytes + format::kPointBytes * nPoints[i] + format::kSegmentBytes * nSegments[i];
      leafEnd += sizes[i];
      ++leaves;
    }

  // Phase B: leaves into place, inner blocks of each subtree to the working file, the subtree
  // roots' contents kept for the top levels.
  AtomicFileWriter out(output);
  Spool inner{work.path() / "inner"};
  std::vector<uint64_t> innerAt(count, 0);
  uint64_t innerBytes = 0;
  std::vector<NodeData> rootData(chunks.size());
  uint64_t reps = 0;
  auto keepInner = [&](uint32_t g, const NodeData& d) {
    const std::string b = serializeBlock(d, g, shading);
    sums[g] = lodChecksum(b.data(), b.size());
    innerAt[g] = innerBytes, sizes[g] = b.size();
    nPoints[g] = uint32_t(d.points.size()), nSegments[g] = uint32_t(d.segments.size());
    reps += d.points.size() + d.segments.size();
    innerBytes += b.size();
    inner.buf += b;
    if (inner.buf.size() >= (size_t(16) << 20)) inner.flush();
  };
  done = 0;
  for (size_t ci = 0; ci < chunks.size(); ++ci) {
    Chunk& ch = chunks[ci];
    const ChunkData d = loadChunk(ch, ch.local.size() > 1);
    const size_t np = ch.points.records;
    // The chunk root spans every key; locals' ranges are into d.keys.
    if (ch.local.size() == 1) ch.local[0].begin = 0, ch.local[0].end = d.keys.size();
    auto leafIndices = [&](const BNode& l) {  // its records in model order
      std::vector<uint32_t> idx;
      for (size_t k = l.begin; k < l.end; ++k) idx.push_back(d.keys[k].second);
      std::sort(idx.begin(), idx.end());
      return idx;
    };
    auto leafData = [&](const BNode& l) {
      NodeData nd;
      for (uint32_t k : leafIndices(l)) {
        if (k < np) {
          Point pt;
          Vec3f sn;
          float m;
          uint32_t index;
          format::getPoint(d.points.data() + size_t(k) * format::kPointBytes, pt, sn, m, index);
          nd.points.push_back(pt), nd.masses.push_back(m), nd.pointIndex.push_back(index);
          if (shading) nd.shadingNormals.push_back(sn);
        } else {
          Segment s;
          uint32_t index;
          format::getSegment(d.segments.data() + size_t(k - np) * format::kSegmentBytes, s, index);
          nd.segments.push_back(s), nd.segmentIndex.push_back(index);
        }
      }
      return nd;
    };
    std::vector<uint32_t> leafIds;
    for (uint32_t l = 0; l < ch.local.size(); ++l)
      if (ch.local[l].leaf) leafIds.push_back(l);
    parallelFor(0, leafIds.size(), [&](size_t k) {
      const uint32_t l = leafIds[k], g = ch.globalId[l];
      BNode& lb = ch.local[l];
      std::string b = blockHeader(g, nPoints[g], nSegments[g]);
      b.reserve(sizes[g]);
      Bounds3f bounds;
      for (uint32_t kp : leafIndices(lb)) {
        if (kp < np) {
          const char* r = d.points.data() + size_t(kp) * format::kPointBytes;
          b.append(r, format::kPointBytes);
          extendPoint(bounds, format::getVec(r), format::get<float>(r + 52));
        } else {
          const char* r = d.segments.data() + size_t(kp - np) * format::kSegmentBytes;
          b.append(r, format::kSegmentBytes);
          const float rad = format::get<float>(r + 76);
          extendPoint(bounds, format::getVec(r), rad), extendPoint(bounds, format::getVec(r + 12), rad);
        }
      }
      lb.bounds = bounds;
      nodes[g].bounds = bounds;
      sums[g] = lodChecksum(b.data(), b.size());
      out.writeAt(offsets[g], b.data(), b.size());
    }, 1);
    if (ch.local.size() == 1) {
      rootData[ci] = leafData(ch.local[0]);
    } else {
      // Inner nodes of the subtree, deepest level first (their contents until the parent's made).
      int deepest = 0;
      for (const BNode& l : ch.local) deepest = std::max(deepest, l.level);
      std::vector<NodeData> data(ch.local.size());
      for (int level = deepest; level >= ch.local[0].level; --level) {
        std::vector<uint32_t> ids;
        for (uint32_t l = 0; l < ch.local.size(); ++l)
          if (!ch.local[l].leaf && ch.local[l].level == level) ids.push_back(l);
        parallelFor(0, ids.size(), [&](size_t k) {
          BNode& nd = ch.local[ids[k]];
          std::vector<NodeData> leafChildren;
          leafChildren.reserve(nd.childCount);
          std::vector<const NodeData*> chp;
          Bounds3f b;
          for (uint32_t cl = nd.firstChild; cl < nd.firstChild + nd.childCount; ++cl) {
            if (ch.local[cl].leaf) {
              leafChildren.push_back(leafData(ch.local[cl]));
              chp.push_back(&leafChildren.back());
            } else {
              chp.push_back(&data[cl]);
            }
            b = unite(b, ch.local[cl].bounds);
          }
          NodeData merged = mergeChildren(chp, nd.cubeMin, nd.side, options.grid, shading);
          nd.bounds = unite(b, contentBounds(merged));
          data[ids[k]] = std::move(merged);
        }, 1);
        for (uint32_t l : ids) {
          const uint32_t g = ch.globalId[l];
          nodes[g].bounds = ch.local[l].bounds;
          keepInner(g, data[l]);
          const BNode& nd = ch.local[l];
          for (uint32_t cl = nd.firstChild; cl < nd.firstChild + nd.childCount; ++cl) data[cl] = {};
        }
      }
      rootData[ci] = std::move(data[0]);
    }
    done += d.keys.size();
    progress("building", double(done) / double(N));
  }

  // The top levels, deepest first, from the subtree roots.
  {
    std::vector<NodeData> topData(top.size());
    std::vector<Bounds3f> topBounds(top.size());
    std::vector<uint32_t> topGlobal(top.size(), 0);
    for (uint32_t g = 0; g < count; ++g)
      if (refs[g].chunk < 0) topGlobal[refs[g].local] = g;
    for (const Chunk& ch : chunks) topBounds[ch.top] = ch.local[0].bounds;
    int topDeepest = 0;
    for (const TopNode& t : top)
      if (t.split) topDeepest = std::max(topDeepest, t.cube.level);
    for (int level = topDeepest; level >= 0; --level) {
      std::vector<uint32_t> ids;
      for (uint32_t i = 0; i < top.size(); ++i)
        if (top[i].split && top[i].cube.level == level) ids.push_back(i);
      parallelFor(0, ids.size(), [&](size_t k) {
        const TopNode& t = top[ids[k]];
        std::vector<const NodeData*> chp;
        Bounds3f b;
        for (uint32_t cl = t.firstChild; cl < t.firstChild + t.childCount; ++cl) {
          chp.push_back(top[cl].chunk >= 0 ? &rootData[size_t(top[cl].chunk)] : &topData[cl]);
          b = unite(b, topBounds[cl]);
        }
        NodeData merged = mergeChildren(chp, t.cube.cubeMin, t.cube.side, options.grid, shading);
        topBounds[ids[k]] = unite(b, contentBounds(merged));
        topData[ids[k]] = std::move(merged);
      }, 1);
      for (uint32_t i : ids) {
        const uint32_t g = topGlobal[i];
        nodes[g].bounds = topBounds[i];
        keepInner(g, topData[i]);
        for (uint32_t cl = top[i].firstChild; cl < top[i].firstChild + top[i].childCount; ++cl) {
          topData[cl] = {};
          if (top[cl].chunk >= 0) rootData[size_t(top[cl].chunk)] = {};
        }
      }
    }
  }
  inner.flush();

  // Inner blocks behind the leaves, deepest level first and in node order within a level.
  std::vector<uint32_t> innerOrder;
  for (uint32_t i = 0; i < count; ++i)
    if (!nodes[i].leaf) innerOrder.push_back(i);
  std::stable_sort(innerOrder.begin(), innerOrder.end(),
                   [&](uint32_t a, uint32_t b) { return nodes[a].level > nodes[b].level; });
  {
    std::FILE* f = std::fopen(inner.path.c_str(), "rb");
    if (!f && innerBytes) throwIo(inner.path.string(), "cannot read back a working file");
    uint64_t at = leafEnd;
    std::string b;
    for (uint32_t g : innerOrder) {
      b.resize(sizes[g]);
      if (std::fseek(f, long(innerAt[g]), SEEK_SET) != 0 || std::fread(b.data(), 1, b.size(), f) != b.size()) {
        std::fclose(f);
        throwIo(inner.path.string(), "cannot read back a working file");
      }
      offsets[g] = at;
      out.writeAt(at, b.data(), b.size());
      at += b.size();
    }
    if (f) std::fclose(f);
  }

  // The id from every block, then each block's checksum with it.
  const uint64_t id = hierarchyId(sums, options);
  {
    parallelFor(0, count, [&](size_t i) {
      std::string b(sizes[i], '\0');
      out.readAt(offsets[i], b.data(), b.size());
      std::memcpy(b.data() + 8, &id, 8);
      sums[i] = lodChecksum(b.data(), b.size());
      out.writeAt(offsets[i] + 8, &id, 8);
    }, 1);
  }
  const std::string head = headerBytes(hj, id, nodes, offsets, sizes, sums, nPoints, nSegments);
  if (head.size() != blocksOffset) throw std::logic_error("lod: header size");
  out.writeAt(0, head.data(), head.size());
  out.commit();
  progress("building", 1);

  BuildReport rep;
  rep.primitives = N;
  rep.representatives = reps;
  rep.nodes = count;
  rep.leaves = leaves;
  rep.depth = uint32_t(depth);
  rep.bytes = leafEnd + innerBytes;
  rep.hierarchyId = id;
  rep.chunks = uint32_t(chunks.size());
  return rep;
}

}  // namespace linesurf::lod
