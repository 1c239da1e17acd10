// Building the level-of-detail hierarchy (include/linesurf/lod/lod.h; beyond the thesis: its
// point and segment primitives of §1.2 and §3, drawn by the §6.2 pipeline, grouped in an octree so
// that a frame draws a bounded number of them).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numeric>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/io/las_io.h"
#include "linesurf/lod/lod.h"
#include "lod_build_parts.h"
#include "lod_format.h"

namespace linesurf::lod {
namespace detail {
namespace {

uint64_t spread3(uint32_t v) {  // bit i of v to bit 3 i
  uint64_t x = v & 0x1fffff;
  x = (x | x << 32) & 0x1f00000000ffffULL;
  x = (x | x << 16) & 0x1f0000ff0000ffULL;
  x = (x | x << 8) & 0x100f00f00f00f00fULL;
  x = (x | x << 4) & 0x10c30c30c30c30c3ULL;
  x = (x | x << 2) & 0x1249249249249249ULL;
  return x;
}

}  // namespace

uint64_t mortonKey(const Vec3f& p, const Vec3f& rootMin, float side) {
  uint64_t m = 0;
  for (int k = 0; k < 3; ++k) {
    double f = (double(p[k]) - rootMin[k]) / side * double(1 << kMaxLevel);
    uint32_t q = std::isfinite(f) ? uint32_t(std::clamp(f, 0.0, double((1 << kMaxLevel) - 1))) : 0;
    m |= spread3(q) << k;
  }
  return m;
}

std::pair<Vec3f, float> rootCube(Bounds3f kb) {
  if (kb.empty()) kb.extend(Vec3f::Zero());
  float side = kb.diagonal().maxCoeff();
  side = side > 0 ? side * (1 + 1e-5f) : 1.0f;
  return {kb.min, side};
}

BNode childCube(const BNode& nd, uint32_t o) {
  BNode c;
  c.level = nd.level + 1, c.side = 0.5f * nd.side;
  c.cubeMin = nd.cubeMin + c.side * Vec3f(float(o & 1), float((o >> 1) & 1), float((o >> 2) & 1));
  return c;
}

void splitBreadthFirst(std::vector<BNode>& nodes, size_t from, const std::vector<std::pair<uint64_t, uint32_t>>& keys,
                       int leafSize) {
  for (size_t i = from; i < nodes.size(); ++i) {
    BNode nd = nodes[i];
    if (nd.end - nd.begin <= size_t(leafSize) || nd.level >= kMaxLevel) {
      nodes[i].leaf = true;
      continue;
    }
    const int shift = 3 * (kMaxLevel - 1 - nd.level);
    nodes[i].firstChild = uint32_t(nodes.size());
    size_t b = nd.begin;
    for (uint32_t o = 0; o < 8 && b < nd.end; ++o) {
      size_t e = b;
      while (e < nd.end && ((keys[e].first >> shift) & 7) == o) ++e;
      if (e == b) continue;
      BNode c = childCube(nd, o);
      c.begin = b, c.end = e;
      nodes.push_back(c);
      ++nodes[i].childCount;
      b = e;
    }
  }
}


void extendPoint(Bounds3f& b, const Vec3f& p, float r) {
  if (!p.allFinite()) return;
  b.extend(p - Vec3f::Constant(r));
  b.extend(p + Vec3f::Constant(r));
}

// An inner node's representatives from its children's primitives: segments at least the node's
// spacing h long are kept whole; shorter ones become points; the points of each grid cell merge
// into one splat at their area-weighted centroid whose radius covers every member's disc and
// whose mass keeps the area they stood for (a point of mass m and radius r stands for m r^2; a
// segment of length l for l r + r^2), so the blend weighs coarse and fine splats alike.
NodeData mergeChildren(const std::vector<const NodeData*>& children, const Vec3f& cubeMin, float side, int grid,
                       bool shading) {
  struct Cand {
    uint32_t cell, order;
    Vec3f p, n, sn;
    Color c;
    float r, area;
  };
  const float h = side / float(grid);
  NodeData out;
  std::vector<Cand> cand;
  auto cellOf = [&](const Vec3f& p) {
    uint32_t id = 0, mul = 1;
    for (int k = 0; k < 3; ++k) {
      float f = (p[k] - cubeMin[k]) / h;
      int c = std::isfinite(f) ? int(std::floor(f)) : 0;
      c = std::clamp(c, 0, grid - 1);
      id += uint32_t(c) * mul;
      mul *= uint32_t(grid);
    }
    return id;
  };
  for (const NodeData* ch : children) {
    for (size_t i = 0; i < ch->points.size(); ++i) {
      const Point& pt = ch->points[i];
      const float m = ch->masses[i];
      cand.push_back({cellOf(pt.position), uint32_t(cand.size()), pt.position, pt.normal,
                      shading ? ch->shadingNormals[i] : pt.normal, pt.color, pt.radius, m * pt.radius * pt.radius});
    }
    for (const Segment& s : ch->segments) {
      const float len = s.length();
      if (len >= h) {
        out.segments.push_back(s);
        out.segmentIndex.push_back(kNoIndex);
        continue;
      }
      const Vec3f mid = 0.5f * (s.p0 + s.p1);
      Vec3f sn = s.normal;
      if (shading) {
        Vec3f e = s.normal0 + s.normal1;
        if (e.norm() > 1e-6f) sn = e.normalized();
      }
      cand.push_back({cellOf(mid), uint32_t(cand.size()), mid, s.normal, sn, s.color, 0.5f * len + s.radius,
                      len * s.radius + s.radius * s.radius});
    }
  }
  std::sort(cand.begin(), cand.end(),
            [](const Cand& a, const Cand& b) { return a.cell != b.cell ? a.cell < b.cell : a.order < b.order; });
  for (size_t b = 0; b < cand.size();) {
    size_t e = b;
    double wsum = 0;
    while (e < cand.size() && cand[e].cell == cand[b].cell) wsum += cand[e].area, ++e;
    const bool uniform = !(wsum > 0);
    Vec3d p = Vec3d::Zero(), n = Vec3d::Zero(), sn = Vec3d::Zero();
    Eigen::Vector4d c = Eigen::Vector4d::Zero();
    double w = 0;
    size_t heaviest = b;
    for (size_t i = b; i < e; ++i) {
      const double wi = uniform ? 1.0 : cand[i].area;
      p += wi * cand[i].p.cast<double>();
      n += wi * cand[i].n.cast<double>();
      sn += wi * cand[i].sn.cast<double>();
      c += wi * cand[i].c.cast<double>();
      w += wi;
      if (cand[i].area > cand[heaviest].area) heaviest = i;
    }
    Point rep;
    rep.position = (p / w).cast<float>();
    rep.normal = n.norm() > 1e-6 * w ? Vec3f(n.normalized().cast<float>()) : cand[heaviest].n;
    rep.color = (c / w).cast<float>();
    float R = 0;
    for (size_t i = b; i < e; ++i) R = std::max(R, (cand[i].p - rep.position).norm() + cand[i].r);
    if (!(R > 0)) R = 0.5f * h;
    rep.radius = R;
    const float mass = uniform ? 1.0f : float(wsum / (double(R) * R));
    out.points.push_back(rep);
    out.masses.push_back(std::clamp(mass, 1e-6f, kMaxPointMass));
    out.pointIndex.push_back(kNoIndex);
    if (shading)
      out.shadingNormals.push_back(sn.norm() > 1e-6 * w ? Vec3f(sn.normalized().cast<float>()) : cand[heaviest].sn);
    b = e;
  }
  return out;
}

std::string blockHeader(uint32_t node, uint32_t points, uint32_t segments) {
  using namespace format;
  std::string out;
  put(out, kBlockMagic, 8);
  put(out, uint64_t(0));  // hierarchy id, patched once every block is known
  put(out, node);
  put(out, points);
  put(out, segments);
  put(out, uint32_t(0));
  return out;
}

std::string serializeBlock(const NodeData& d, uint32_t node, bool shading) {
  using namespace format;
  std::string out = blockHeader(node, uint32_t(d.points.size()), uint32_t(d.segments.size()));
  out.reserve(kBlockHeaderBytes + kPointBytes * d.points.size() + kSegmentBytes * d.segments.size());
  for (size_t i = 0; i < d.points.size(); ++i)
    putPoint(out, d.points[i], shading ? d.shadingNormals[i] : Vec3f(Vec3f::Zero()), d.masses[i], d.pointIndex[i]);
  for (size_t i = 0; i < d.segments.size(); ++i) putSegment(out, d.segments[i], d.segmentIndex[i]);
  return out;
}

Bounds3f contentBounds(const NodeData& d) {
  Bounds3f b;
  for (const Point& p : d.points) extendPoint(b, p.position, p.radius);
  for (const Segment& s : d.segments) extendPoint(b, s.p0, s.radius), extendPoint(b, s.p1, s.radius);
  return b;
}

Bounds3f unite(Bounds3f a, const Bounds3f& b) {
  if (!b.empty()) a.extend(b.min), a.extend(b.max);
  return a;
}

HeaderJson headerJson(const HeaderFacts& f, const BuildOptions& options, const std::string& path) {
  {  // nothing is written that the readers refuse (a model far from its rendering frame)
    LodHeader h;
    h.frame = f.frame, h.sphere = f.sphere, h.maxRadius = f.maxRadius;
    h.points = f.points, h.segments = f.segments, h.options = options;
    try {
      validateHeader(h, "");
    } catch (const Error& e) {
      throwBadInput(path, "", "cannot be stored as a hierarchy: " + e.reason());
    }
  }
  const Attributes& a = f.attributes;
  const std::string placeholder(16, '0');
  const Vec3f& c = f.sphere.center;
  nlohmann::json j = {
      {"format", "linesurf-lod"},
      {"version", format::kVersion},
      {"hierarchy", placeholder},
      {"points", f.points},
      {"segments", f.segments},
      {"nodes", f.nodes},
      {"depth", f.depth},
      {"leafSize", options.leafSize},
      {"grid", options.grid},
      {"frame", {{"centre", {f.frame.centre.x(), f.frame.centre.y(), f.frame.centre.z()}}, {"scale", f.frame.scale}}},
      {"sphere", {{"center", {c.x(), c.y(), c.z()}}, {"radius", f.sphere.radius}}},
      {"maxRadius", f.maxRadius},
      {"attributes",
       {{"normals", a.normals}, {"colors", a.colors}, {"radii", a.radii}, {"texcoords", a.texcoords},
        {"endpointNormals", a.endpointNormals}, {"shadingNormals", f.shading}}},
      {"pointMasses", f.masses},
      {"recordBytes", {{"node", format::kRecordBytes}, {"point", format::kPointBytes}, {"segment", format::kSegmentBytes},
                       {"blockHeader", format::kBlockHeaderBytes}}},
  };
  // Optional, so a model without one gives the bytes it always gave.
  if (!f.upAxis.empty()) j["upAxis"] = f.upAxis;
  HeaderJson hj;
  hj.json = j.dump();
  while ((format::kPreambleBytes + hj.json.size()) % 8) hj.json.push_back(' ');
  hj.idAt = format::kPreambleBytes + hj.json.find(placeholder);
  return hj;
}

uint64_t hierarchyId(std::vector<uint64_t> sums, const BuildOptions& options) {
  sums.push_back(uint64_t(options.leafSize));
  sums.push_back(uint64_t(options.grid));
  return lodChecksum(sums.data(), sums.size() * 8) | 1;  // never 0
}

std::string headerBytes(const HeaderJson& hj, uint64_t id, const std::vector<BNode>& nodes,
                        const std::vector<uint64_t>& offsets, const std::vector<uint64_t>& sizes,
                        const std::vector<uint64_t>& sums, const std::vector<uint32_t>& nPoints,
                        const std::vector<uint32_t>& nSegments) {
  const uint32_t count = uint32_t(nodes.size());
  std::string head;
  format::put(head, format::kMagic, 8);
  format::put(head, format::kVersion);
  format::put(head, uint32_t(hj.json.size()));
  format::put(head, id);
  format::put(head, uint64_t(count));
  head += hj.json;
  const std::string hex = fmt::format("{:016x}", id);
  std::memcpy(head.data() + hj.idAt, hex.data(), 16);
  for (uint32_t i = 0; i < count; ++i) {
    const BNode& n = nodes[i];
    using format::put;
    put(head, id);
    put(head, offsets[i]);
    put(head, sizes[i]);
    put(head, sums[i]);
    format::putVec(head, n.cubeMin);
    put(head, n.side);
    Bounds3f b = n.bounds;
    if (b.empty()) b.extend(n.cubeMin);
    format::putVec(head, b.min);
    format::putVec(head, b.max);
    put(head, nPoints[i]);
    put(head, nSegments[i]);
    put(head, n.firstChild);
    put(head, n.childCount);
    put(head, uint8_t(n.level));
    put(head, uint8_t(n.leaf));
    put(head, uint8_t(0));
  }
  format::put(head, lodChecksum(head.data(), head.size()));
  return head;
}

}  // namespace detail

using namespace detail;

void validate(const BuildOptions& o) {
  if (o.leafSize < 16 || o.leafSize > (1 << 20))
    throwBadOption("leafSize", fmt::format("must be in [16, 1048576], got {}", o.leafSize));
  if (o.grid < 2 || o.grid > 256) throwBadOption("grid", fmt::format("must be in [2, 256], got {}", o.grid));
}

std::string buildLod(const HybridModel& model, const ModelFrame& frame, const BuildOptions& options,
                     BuildReport* report) {
  validate(options);
  if (model.empty()) throwBadInput("", "", "the model holds no points and no segments");
  const size_t P = model.points.size(), S = model.segments.size(), N = P + S;
  if (N >= kNoIndex) throwBadInput("", "", "more than 2^32 - 2 primitives");
  const bool shading = model.attributes.shadingNormals && model.pointShadingNormals.size() == P;
  const std::vector<float>* masses = pointMasses(model);

  // Keys: a point's position, a segment's midpoint, quantised in the root cube.
  auto keyPos = [&](size_t j) {
    return j < P ? model.points[j].position : Vec3f(0.5f * (model.segments[j - P].p0 + model.segments[j - P].p1));
  };
  Bounds3f kb;
  for (size_t j = 0; j < N; ++j)
    if (keyPos(j).allFinite()) kb.extend(keyPos(j));
  const auto [rootMin, side] = rootCube(kb);
  std::vector<std::pair<uint64_t, uint32_t>> keys(N);
  parallelFor(0, N, [&](size_t j) { keys[j] = {mortonKey(keyPos(j), rootMin, side), uint32_t(j)}; }, 4096);
  std::sort(keys.begin(), keys.end());

  // Topology, breadth first: children contiguous and after their parent.
  std::vector<BNode> nodes;
  nodes.push_back({0, N, 0, rootMin, side});
  splitBreadthFirst(nodes, 0, keys, options.leafSize);
  const uint32_t count = uint32_t(nodes.size());

  int depth = 0;
  for (const BNode& n : nodes) depth = std::max(depth, n.level);

  // The header first: everything in it but the id is known before the blocks.
  const BoundingSphere sphere = boundingSphere(model);
  float maxRadius = 0;
  for (const Point& p : model.points)
    if (std::isfinite(p.radius)) maxRadius = std::max(maxRadius, p.radius);
  for (const Segment& s : model.segments)
    if (std::isfinite(s.radius)) maxRadius = std::max(maxRadius, s.radius);
  HeaderFacts facts;
  facts.points = P, facts.segments = S, facts.nodes = count, facts.depth = depth;
  facts.frame = frame, facts.sphere = sphere, facts.maxRadius = maxRadius;
  facts.attributes = model.attributes, facts.shading = shading, facts.masses = masses != nullptr;
  facts.upAxis = recordedUpAxis(model);
  const HeaderJson hj = headerJson(facts, options, "");
  const uint64_t tableOffset = format::kPreambleBytes + hj.json.size();
  const uint64_t blocksOffset =
      tableOffset + uint64_t(count) * format::kRecordBytes + format::tableTrailerBytes(format::kVersion);

  // Leaf blocks first: their sizes follow from their counts, so each is written in place (in
  // parallel, each into its own range); inner blocks follow as they are made, deepest level
  // first. The output buffer is the only copy of the hierarchy (bounded memory: model + keys +
  // output + the inner contents of two levels).
  auto blockBytes = [](uint64_t pts, uint64_t segs) {
    return format::kBlockHeaderBytes + format::kPointBytes * pts + format::kSegmentBytes * segs;
  };
  std::vector<uint64_t> offsets(count), sizes(count);
  std::vector<uint32_t> nPoints(count), nSegments(count);
  uint64_t leafEnd = blocksOffset, leafBytes = 0;
  for (uint32_t i = 0; i < count; ++i) {
    if (!nodes[i].leaf) continue;
    uint64_t pts = 0;
    for (size_t k = nodes[i].begin; k < nodes[i].end; ++k) pts += keys[k].second < P;
    nPoints[i] = uint32_t(pts), nSegments[i] = uint32_t(nodes[i].end - nodes[i].begin - pts);
    offsets[i] = leafEnd;
    sizes[i] = blockBytes(nPoints[i], nSegments[i]);
    leafEnd += sizes[i];
    leafBytes += sizes[i];
  }
  std::string out;
  out.reserve(leafEnd + leafBytes + (1 << 16));  // inner nodes: under the leaves' size in practice
  out.resize(leafEnd);
  auto leafData = [&](const BNode& nd) {
    NodeData d;
    std::vector<uint32_t> idx;
    idx.reserve(nd.end - nd.begin);
    for (size_t k = nd.begin; k < nd.end; ++k) idx.push_back(keys[k].second);
    std::sort(idx.begin(), idx.end());  // model order: every leaf drawn is today's model
    for (uint32_t k : idx) {
      if (k < P) {
        d.points.push_back(model.points[k]);
        d.masses.push_back(masses ? (*masses)[k] : 1.0f);
        d.pointIndex.push_back(k);
        if (shading) d.shadingNormals.push_back(model.pointShadingNormals[k]);
      } else {
        d.segments.push_back(model.segments[k - P]);
        d.segmentIndex.push_back(uint32_t(k - P));
      }
    }
    return d;
  };
  std::vector<uint32_t> leafIds;
  for (uint32_t i = 0; i < count; ++i)
    if (nodes[i].leaf) leafIds.push_back(i);
  parallelFor(0, leafIds.size(), [&](size_t k) {
    const uint32_t i = leafIds[k];
    const NodeData d = leafData(nodes[i]);
    nodes[i].bounds = contentBounds(d);
    const std::string b = serializeBlock(d, i, shading);
    std::memcpy(out.data() + offsets[i], b.data(), b.size());
  }, 1);

  std::vector<NodeData> data(count);  // inner nodes' contents, until their parent is made
  std::vector<std::string> blocks(count);
  std::vector<std::vector<uint32_t>> byLevel(depth + 1);
  for (uint32_t i = 0; i < count; ++i)
    if (!nodes[i].leaf) byLevel[nodes[i].level].push_back(i);
  uint64_t reps = 0;
  for (int level = depth; level >= 0; --level) {
    const auto& ids = byLevel[level];
    parallelFor(0, ids.size(), [&](size_t k) {
      const uint32_t i = ids[k];
      BNode& nd = nodes[i];
      std::vector<NodeData> leafChildren;
      leafChildren.reserve(nd.childCount);
      std::vector<const NodeData*> ch;
      Bounds3f b;
      for (uint32_t c = nd.firstChild; c < nd.firstChild + nd.childCount; ++c) {
        if (nodes[c].leaf) {
          leafChildren.push_back(leafData(nodes[c]));
          ch.push_back(&leafChildren.back());
        } else {
          ch.push_back(&data[c]);
        }
        b = unite(b, nodes[c].bounds);
      }
      NodeData d = mergeChildren(ch, nd.cubeMin, nd.side, options.grid, shading);
      nd.bounds = unite(b, contentBounds(d));
      blocks[i] = serializeBlock(d, i, shading);
      data[i] = std::move(d);
    }, 1);
    for (uint32_t i : ids) {
      reps += data[i].points.size() + data[i].segments.size();
      nPoints[i] = uint32_t(data[i].points.size()), nSegments[i] = uint32_t(data[i].segments.size());
      offsets[i] = out.size();
      sizes[i] = blocks[i].size();
      out += blocks[i];
      std::string().swap(blocks[i]);
      for (uint32_t c = nodes[i].firstChild; c < nodes[i].firstChild + nodes[i].childCount; ++c) data[c] = {};
    }
  }

  // The hierarchy's id: a hash of every block (id field still zero) and the build parameters.
  std::vector<uint64_t> sums(count);
  parallelFor(0, count, [&](size_t i) { sums[i] = lodChecksum(out.data() + offsets[i], sizes[i]); }, 1);
  const uint64_t id = hierarchyId(sums, options);
  parallelFor(0, count, [&](size_t i) {
    std::memcpy(out.data() + offsets[i] + 8, &id, 8);
    sums[i] = lodChecksum(out.data() + offsets[i], sizes[i]);
  }, 1);
  const std::string head = headerBytes(hj, id, nodes, offsets, sizes, sums, nPoints, nSegments);
  if (head.size() != blocksOffset) throw std::logic_error("lod: header size");
  std::memcpy(out.data(), head.data(), head.size());
  if (report) {
    report->primitives = N;
    report->representatives = reps;
    report->nodes = count;
    report->leaves = uint32_t(leafIds.size());
    report->depth = uint32_t(depth);
    report->bytes = out.size();
    report->hierarchyId = id;
  }
  return out;
}

}  // namespace linesurf::lod
