// Reading a level-of-detail hierarchy, choosing its nodes for a view and rendering them with a
// splat budget (include/linesurf/lod/lod.h; the §6.2 pipeline through the public Renderer).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <memory>
#include <queue>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/read_only_file.h"
#include "linesurf/core/timer.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/lod/lod.h"
#include "lod_format.h"

namespace linesurf::lod {
namespace {

Vec3f vec3(const nlohmann::json& j) { return Vec3f(j.at(0).get<float>(), j.at(1).get<float>(), j.at(2).get<float>()); }

}  // namespace

bool isLodFile(const std::filesystem::path& path) {
  // Only a regular file can be a hierarchy: opening a FIFO or a device to sniff its magic would
  // block or read for ever; the model readers report those.
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return false;
  ReadOnlyFile f(path);
  if (!f.isOpen()) return false;
  char m[8];
  return f.read(0, m, 8) == 8 && std::memcmp(m, format::kMagic, 8) == 0;
}

LodFile::LodFile(const std::filesystem::path& path) : path_(path) {
  noteInput(path);
  const std::string ps = path.string();
  ReadOnlyFile f(path);
  if (!f.isOpen()) throwBadInput(ps, "", "cannot open the file");
  std::error_code ec;
  fileSize_ = std::filesystem::file_size(path, ec);
  if (ec) throwBadInput(ps, "", "cannot read the file size");
  char pre[format::kPreambleBytes];
  if (f.read(0, pre, sizeof pre) != sizeof pre || std::memcmp(pre, format::kMagic, 8) != 0)
    throwBadInput(ps, "header", "not a linesurf level-of-detail hierarchy (no LINESLOD magic)");
  if (uint32_t v = format::get<uint32_t>(pre + 8); v != format::kVersion)
    throwBadInput(ps, "header", fmt::format("version {} (this linesurf reads version {})", v, format::kVersion));
  const uint32_t jsonBytes = format::get<uint32_t>(pre + 12);
  header_.hierarchyId = format::get<uint64_t>(pre + 16);
  const uint64_t count = format::get<uint64_t>(pre + 24);
  const uint64_t tableOffset = format::kPreambleBytes + uint64_t(jsonBytes);
  if (count == 0 || count > fileSize_ / format::kRecordBytes || tableOffset + count * format::kRecordBytes > fileSize_)
    throwBadInput(ps, "header", fmt::format("truncated: the header and the table of {} nodes need more than the file's {} bytes",
                                            count, fileSize_));
  std::string js(jsonBytes, '\0');
  f.read(format::kPreambleBytes, js.data(), jsonBytes);
  try {
    const auto j = nlohmann::json::parse(js);
    if (j.at("format") != "linesurf-lod") throwBadInput(ps, "header", "format is not linesurf-lod");
    if (j.at("hierarchy").get<std::string>() != fmt::format("{:016x}", header_.hierarchyId))
      throwBadInput(ps, "header", "the JSON header names another hierarchy than the preamble");
    if (j.at("nodes").get<uint64_t>() != count) throwBadInput(ps, "header", "node counts of the preamble and the JSON differ");
    const auto& fr = j.at("frame");
    header_.frame.centre = Vec3d(fr.at("centre").at(0).get<double>(), fr.at("centre").at(1).get<double>(),
                                 fr.at("centre").at(2).get<double>());
    header_.frame.scale = fr.at("scale").get<double>();
    header_.sphere.center = vec3(j.at("sphere").at("center"));
    header_.sphere.radius = j.at("sphere").at("radius").get<float>();
    header_.maxRadius = j.at("maxRadius").get<float>();
    const auto& a = j.at("attributes");
    header_.attributes.normals = a.at("normals");
    header_.attributes.colors = a.at("colors");
    header_.attributes.radii = a.at("radii");
    header_.attributes.texcoords = a.at("texcoords");
    header_.attributes.endpointNormals = a.at("endpointNormals");
    header_.attributes.shadingNormals = a.at("shadingNormals");
    header_.pointMasses = j.at("pointMasses");
    header_.points = j.at("points");
    header_.segments = j.at("segments");
    header_.options.leafSize = j.at("leafSize");
    header_.options.grid = j.at("grid");
  } catch (const nlohmann::json::exception& e) {
    throwBadInput(ps, "header", std::string("invalid JSON header: ") + e.what());
  }
  std::string table(count * format::kRecordBytes, '\0');
  f.read(tableOffset, table.data(), table.size());
  nodes_.resize(count);
  uint64_t leafPrimitives = 0;
  for (uint64_t i = 0; i < count; ++i) {
    const char* r = table.data() + i * format::kRecordBytes;
    NodeInfo& n = nodes_[i];
    const std::string where = fmt::format("node {}", i);
    if (format::get<uint64_t>(r) != header_.hierarchyId)
      throwBadInput(ps, where, "its table record belongs to another hierarchy; refused");
    n.offset = format::get<uint64_t>(r + 8);
    n.size = format::get<uint64_t>(r + 16);
    n.checksum = format::get<uint64_t>(r + 24);
    n.cubeMin = format::getVec(r + 32);
    n.side = format::get<float>(r + 44);
    n.boundsMin = format::getVec(r + 48);
    n.boundsMax = format::getVec(r + 60);
    if (!n.boundsMin.allFinite() || !n.boundsMax.allFinite() || (n.boundsMin.array() > n.boundsMax.array()).any())
      throwBadInput(ps, where, "invalid bounds in the node table");
    n.points = format::get<uint32_t>(r + 72);
    n.segments = format::get<uint32_t>(r + 76);
    n.firstChild = format::get<uint32_t>(r + 80);
    n.childCount = uint8_t(r[84]);
    n.level = uint8_t(r[85]);
    n.leaf = r[86] != 0;
    // Children lie after their parent (breadth first), so the tree has no cycles.
    if (n.leaf != (n.childCount == 0) || n.childCount > 8 ||
        (!n.leaf && (n.firstChild <= i || uint64_t(n.firstChild) + n.childCount > count)))
      throwBadInput(ps, where, "invalid tree links in the node table");
    if (n.size != format::kBlockHeaderBytes + format::kPointBytes * uint64_t(n.points) +
                      format::kSegmentBytes * uint64_t(n.segments))
      throwBadInput(ps, where, "block size does not match its point and segment counts");
    if (n.leaf) leafPrimitives += n.count();
  }
  if (leafPrimitives != header_.points + header_.segments)
    throwBadInput(ps, "node table", fmt::format("the leaves hold {} primitives, the header says {}", leafPrimitives,
                                                header_.points + header_.segments));
}

void LodFile::readBlock(uint32_t i, std::vector<char>& buf) const {
  const std::string ps = path_.string(), where = fmt::format("node {}", i);
  if (i >= nodes_.size()) throwBadInput(ps, where, "no such node");
  const NodeInfo& n = nodes_[i];
  if (n.offset + n.size > fileSize_)
    throwBadInput(ps, where, fmt::format("missing or truncated: its block [{}, {}) lies past the file's end ({} bytes)",
                                         n.offset, n.offset + n.size, fileSize_));
  if (buf.size() < n.size) buf.resize(n.size);
  ReadOnlyFile f(path_);
  if (!f.isOpen() || f.read(n.offset, buf.data(), n.size) != n.size)
    throwBadInput(ps, where, "missing or truncated: its block cannot be read in full");
  const char* p = buf.data();
  if (std::memcmp(p, format::kBlockMagic, 8) != 0) throwBadInput(ps, where, "its block is not a node block");
  if (uint64_t id = format::get<uint64_t>(p + 8); id != header_.hierarchyId)
    throwBadInput(ps, where, fmt::format("its block belongs to another hierarchy ({:016x}, this one is {:016x}); refused",
                                         id, header_.hierarchyId));
  if (format::get<uint32_t>(p + 16) != i || format::get<uint32_t>(p + 20) != n.points ||
      format::get<uint32_t>(p + 24) != n.segments)
    throwBadInput(ps, where, "its block holds another node");
  if (lodChecksum(p, n.size) != n.checksum) throwBadInput(ps, where, "checksum mismatch (corrupt block)");
  // Indices in range (originals) or none (representatives), masses valid: checked before any
  // index is used to place a primitive.
  const char* q = p + format::kBlockHeaderBytes;
  for (uint32_t k = 0; k < n.points; ++k, q += format::kPointBytes) {
    const uint32_t idx = format::get<uint32_t>(q + 60);
    if (!(n.leaf ? idx < header_.points : idx == kNoIndex) || !validPointMass(format::get<float>(q + 56)))
      throwBadInput(ps, where, fmt::format("point {}: invalid index or mass", k));
  }
  for (uint32_t k = 0; k < n.segments; ++k, q += format::kSegmentBytes) {
    const uint32_t idx = format::get<uint32_t>(q + 96);
    if (!(n.leaf ? idx < header_.segments : idx == kNoIndex))
      throwBadInput(ps, where, fmt::format("segment {}: invalid index", k));
  }
}

NodeData LodFile::readNode(uint32_t i) const {
  std::vector<char> buf;
  readBlock(i, buf);
  const NodeInfo& n = nodes_[i];
  NodeData d;
  const bool shading = header_.attributes.shadingNormals;
  d.points.resize(n.points);
  d.masses.resize(n.points);
  d.pointIndex.resize(n.points);
  if (shading) d.shadingNormals.resize(n.points);
  const char* p = buf.data() + format::kBlockHeaderBytes;
  for (uint32_t k = 0; k < n.points; ++k, p += format::kPointBytes) {
    Vec3f sn;
    format::getPoint(p, d.points[k], sn, d.masses[k], d.pointIndex[k]);
    if (shading) d.shadingNormals[k] = sn;
  }
  d.segments.resize(n.segments);
  d.segmentIndex.resize(n.segments);
  for (uint32_t k = 0; k < n.segments; ++k, p += format::kSegmentBytes) format::getSegment(p, d.segments[k], d.segmentIndex[k]);
  return d;
}

Selection selectNodes(const LodFile& file, const Camera& camera, uint64_t budget) {
  const auto& nodes = file.nodes();
  const LodHeader& h = file.header();
  Selection sel;
  if (budget >= h.points + h.segments) {  // everything: the full model's picture
    for (uint32_t i = 0; i < nodes.size(); ++i)
      if (nodes[i].leaf) sel.nodes.push_back(i), sel.primitives += nodes[i].count();
    return sel;
  }
  const auto planes = camera.frustumPlanes();
  std::vector<char> inCut(nodes.size(), 0);
  auto visible = [&](uint32_t i) {
    const NodeInfo& n = nodes[i];
    const Vec3f c = camera.toCamera(n.boundsMin * 0.5f + n.boundsMax * 0.5f);
    const float r = 0.5f * (n.boundsMax - n.boundsMin).norm();
    for (const Vec4f& pl : planes) {
      const float len = pl.head<3>().norm();
      if (len > 0 && (pl.head<3>().dot(c) + pl.w()) / len < -r) return false;
    }
    return true;
  };
  auto priority = [&](uint32_t i) {
    const NodeInfo& n = nodes[i];
    const Vec3f c = 0.5f * (n.boundsMin + n.boundsMax);
    const float r = 0.5f * (n.boundsMax - n.boundsMin).norm();
    const float d = (c - camera.eye()).norm() - r;
    return r / std::max(d, 1e-6f * std::max(r, 1e-30f));  // projected size, up to the focal length
  };
  using Item = std::pair<float, uint32_t>;
  auto cmp = [](const Item& a, const Item& b) { return a.first != b.first ? a.first < b.first : a.second > b.second; };
  std::priority_queue<Item, std::vector<Item>, decltype(cmp)> queue(cmp);
  inCut[0] = 1;
  uint64_t total = nodes[0].count();
  if (!nodes[0].leaf) queue.push({priority(0), 0});
  while (!queue.empty()) {
    const uint32_t i = queue.top().second;
    queue.pop();
    const NodeInfo& n = nodes[i];
    int64_t cost = -int64_t(n.count());
    for (uint32_t c = n.firstChild; c < n.firstChild + n.childCount; ++c)
      if (visible(c)) cost += int64_t(nodes[c].count());
    if (int64_t(total) + cost > int64_t(budget)) continue;  // stays coarse; smaller nodes may still fit
    total = uint64_t(int64_t(total) + cost);
    inCut[i] = 0;
    for (uint32_t c = n.firstChild; c < n.firstChild + n.childCount; ++c)
      if (visible(c)) {
        inCut[c] = 1;
        if (!nodes[c].leaf) queue.push({priority(c), c});
      }
  }
  for (uint32_t i = 0; i < nodes.size(); ++i)
    if (inCut[i]) sel.nodes.push_back(i);
  sel.primitives = total;
  return sel;
}

Assembled assemble(const LodFile& file, const Selection& selection, float radiusScale) {
  const LodHeader& h = file.header();
  const auto& nodes = file.nodes();
  const size_t n = selection.nodes.size();
  // Where each node's primitives go, from the table's counts: originals first, then the
  // representatives in node order. When every leaf is drawn the originals are placed by their
  // model index, so the model drawn is today's model; otherwise they keep node order
  // (deterministic, and no sort in the frame). Blocks are decoded straight into place.
  uint64_t leafPoints = 0, leafSegments = 0, np = 0, ns = 0;
  bool reps = false;
  for (uint32_t i : selection.nodes) {
    np += nodes[i].points, ns += nodes[i].segments;
    if (nodes[i].leaf) leafPoints += nodes[i].points, leafSegments += nodes[i].segments;
    else reps = true;
  }
  const bool byIndex = leafPoints == h.points && leafSegments == h.segments;
  std::vector<uint64_t> pointAt(n), segmentAt(n);
  uint64_t pl = 0, sl = 0, pr = leafPoints, sr = leafSegments;
  for (size_t k = 0; k < n; ++k) {
    const NodeInfo& nd = nodes[selection.nodes[k]];
    if (nd.leaf) pointAt[k] = pl, segmentAt[k] = sl, pl += nd.points, sl += nd.segments;
    else pointAt[k] = pr, segmentAt[k] = sr, pr += nd.points, sr += nd.segments;
  }
  Assembled out;
  HybridModel& m = out.model;
  m.attributes = h.attributes;
  if (reps) m.attributes.normals = m.attributes.radii = true;
  const bool withMasses = h.pointMasses || reps, shading = h.attributes.shadingNormals;
  m.points.resize(np);
  m.segments.resize(ns);
  std::vector<float> masses(withMasses ? np : 0);
  if (shading) m.pointShadingNormals.resize(np);
  std::vector<std::string> failed(n);
  parallelFor(0, n, [&](size_t k) {
    thread_local std::vector<char> buf;
    const uint32_t i = selection.nodes[k];
    const NodeInfo& nd = nodes[i];
    try {
      file.readBlock(i, buf);
    } catch (const Error& e) {
      failed[k] = e.what();
      return;
    }
    const bool place = nd.leaf && byIndex;
    const char* p = buf.data() + format::kBlockHeaderBytes;
    for (uint32_t j = 0; j < nd.points; ++j, p += format::kPointBytes) {
      Point pt;
      Vec3f sn;
      float mass;
      uint32_t idx;
      format::getPoint(p, pt, sn, mass, idx);
      const uint64_t at = place ? idx : pointAt[k] + j;
      pt.radius *= radiusScale;
      m.points[at] = pt;
      if (withMasses) masses[at] = mass;
      if (shading) m.pointShadingNormals[at] = sn;
    }
    for (uint32_t j = 0; j < nd.segments; ++j, p += format::kSegmentBytes) {
      Segment s;
      uint32_t idx;
      format::getSegment(p, s, idx);
      s.radius *= radiusScale;
      m.segments[place ? idx : segmentAt[k] + j] = s;
    }
  }, 1);
  // Failed nodes leave their places empty: drop them (a failed leaf read by index left the
  // places of its own primitives, known only from its intact neighbours: every place not written).
  bool anyFailed = false;
  for (size_t k = 0; k < n; ++k)
    if (!failed[k].empty()) out.failures.push_back(failed[k]), anyFailed = true;
    else if (!nodes[selection.nodes[k]].leaf) ++out.representativeNodes;
  if (anyFailed) {
    std::vector<char> keepP(np, 0), keepS(ns, 0);
    for (size_t k = 0; k < n; ++k) {
      if (!failed[k].empty()) continue;
      const NodeInfo& nd = nodes[selection.nodes[k]];
      if (nd.leaf && byIndex) {
        const NodeData d = file.readNode(selection.nodes[k]);  // rare path: the indices again
        for (uint32_t idx : d.pointIndex) keepP[idx] = 1;
        for (uint32_t idx : d.segmentIndex) keepS[idx] = 1;
      } else {
        std::fill_n(keepP.begin() + pointAt[k], nd.points, 1);
        std::fill_n(keepS.begin() + segmentAt[k], nd.segments, 1);
      }
    }
    size_t w = 0;
    for (size_t r = 0; r < np; ++r)
      if (keepP[r]) {
        m.points[w] = m.points[r];
        if (withMasses) masses[w] = masses[r];
        if (shading) m.pointShadingNormals[w] = m.pointShadingNormals[r];
        ++w;
      }
    m.points.resize(w);
    if (withMasses) masses.resize(w);
    if (shading) m.pointShadingNormals.resize(w);
    w = 0;
    for (size_t r = 0; r < ns; ++r)
      if (keepS[r]) m.segments[w++] = m.segments[r];
    m.segments.resize(w);
  }
  if (withMasses && !m.points.empty()) m.pointProperties[kPointMassProperty] = std::move(masses);
  return out;
}

LodRenderer::LodRenderer(const LodFile& file, const RenderOptions& options, uint64_t budget, float radiusScale)
    : file_(file), options_(options), budget_(budget), radiusScale_(radiusScale) {
  validate(options_);
}

BoundingSphere LodRenderer::sphere() const {
  BoundingSphere s = file_.header().sphere;
  if (radiusScale_ != 1) s.radius += (radiusScale_ - 1) * file_.header().maxRadius;
  return s;
}

LodFrameResult LodRenderer::render(const Camera& camera) const {
  LodFrameResult r;
  Timer t;
  r.selection = selectNodes(file_, camera, budget_);
  r.selectSeconds = t.seconds();
  Timer tl;
  Assembled a = assemble(file_, r.selection, radiusScale_);
  r.loadSeconds = tl.seconds();
  r.failures = std::move(a.failures);
  if (a.model.empty()) {  // every selected node failed: the background alone
    r.render.color = Image(camera.width(), camera.height(), options_.background);
    return r;
  }
  r.render = Renderer(a.model, options_).render(camera);
  return r;
}

}  // namespace linesurf::lod
