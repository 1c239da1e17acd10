// Reading a level-of-detail hierarchy, choosing its nodes for a view and rendering them with a
// splat budget (include/linesurf/lod/lod.h; the §6.2 pipeline through the public Renderer).
#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <queue>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/lod/lod.h"
#include "lod_format.h"

namespace linesurf::lod {
namespace {

// A read-only file descriptor read by byte range (pread: safe from several threads).
struct Fd {
  int fd = -1;
  explicit Fd(const std::filesystem::path& p) : fd(::open(p.c_str(), O_RDONLY | O_CLOEXEC)) {}
  ~Fd() {
    if (fd >= 0) ::close(fd);
  }
  Fd(const Fd&) = delete;
  Fd& operator=(const Fd&) = delete;
  // Bytes actually read (fewer at the end of the file).
  size_t read(uint64_t offset, char* out, size_t n) const {
    size_t got = 0;
    while (got < n) {
      ssize_t r = ::pread(fd, out + got, n - got, off_t(offset + got));
      if (r <= 0) break;
      got += size_t(r);
    }
    return got;
  }
};

Vec3f vec3(const nlohmann::json& j) { return Vec3f(j.at(0).get<float>(), j.at(1).get<float>(), j.at(2).get<float>()); }

}  // namespace

bool isLodFile(const std::filesystem::path& path) {
  Fd f(path);
  if (f.fd < 0) return false;
  char m[8];
  return f.read(0, m, 8) == 8 && std::memcmp(m, format::kMagic, 8) == 0;
}

LodFile::LodFile(const std::filesystem::path& path) : path_(path) {
  noteInput(path);
  const std::string ps = path.string();
  Fd f(path);
  if (f.fd < 0) throwBadInput(ps, "", "cannot open the file");
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

NodeData LodFile::readNode(uint32_t i) const {
  const std::string ps = path_.string(), where = fmt::format("node {}", i);
  if (i >= nodes_.size()) throwBadInput(ps, where, "no such node");
  const NodeInfo& n = nodes_[i];
  if (n.offset + n.size > fileSize_)
    throwBadInput(ps, where, fmt::format("missing or truncated: its block [{}, {}) lies past the file's end ({} bytes)",
                                         n.offset, n.offset + n.size, fileSize_));
  std::string buf(n.size, '\0');
  Fd f(path_);
  if (f.fd < 0 || f.read(n.offset, buf.data(), buf.size()) != buf.size())
    throwBadInput(ps, where, "missing or truncated: its block cannot be read in full");
  const char* p = buf.data();
  if (std::memcmp(p, format::kBlockMagic, 8) != 0) throwBadInput(ps, where, "its block is not a node block");
  if (uint64_t id = format::get<uint64_t>(p + 8); id != header_.hierarchyId)
    throwBadInput(ps, where, fmt::format("its block belongs to another hierarchy ({:016x}, this one is {:016x}); refused",
                                         id, header_.hierarchyId));
  if (format::get<uint32_t>(p + 16) != i || format::get<uint32_t>(p + 20) != n.points ||
      format::get<uint32_t>(p + 24) != n.segments)
    throwBadInput(ps, where, "its block holds another node");
  if (lodChecksum(buf.data(), buf.size()) != n.checksum) throwBadInput(ps, where, "checksum mismatch (corrupt block)");
  NodeData d;
  const bool shading = header_.attributes.shadingNormals;
  d.points.resize(n.points);
  d.masses.resize(n.points);
  d.pointIndex.resize(n.points);
  if (shading) d.shadingNormals.resize(n.points);
  p += format::kBlockHeaderBytes;
  for (uint32_t k = 0; k < n.points; ++k, p += format::kPointBytes) {
    Vec3f sn;
    format::getPoint(p, d.points[k], sn, d.masses[k], d.pointIndex[k]);
    if (shading) d.shadingNormals[k] = sn;
    const bool ok = n.leaf ? d.pointIndex[k] < header_.points : d.pointIndex[k] == kNoIndex;
    if (!ok || !validPointMass(d.masses[k])) throwBadInput(ps, where, fmt::format("point {}: invalid index or mass", k));
  }
  d.segments.resize(n.segments);
  d.segmentIndex.resize(n.segments);
  for (uint32_t k = 0; k < n.segments; ++k, p += format::kSegmentBytes) {
    format::getSegment(p, d.segments[k], d.segmentIndex[k]);
    const bool ok = n.leaf ? d.segmentIndex[k] < header_.segments : d.segmentIndex[k] == kNoIndex;
    if (!ok) throwBadInput(ps, where, fmt::format("segment {}: invalid index", k));
  }
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
  std::vector<NodeData> data(n);
  std::vector<std::string> failed(n);
  parallelFor(0, n, [&](size_t k) {
    try {
      data[k] = file.readNode(selection.nodes[k]);
    } catch (const Error& e) {
      failed[k] = e.what();
    }
  }, 1);
  Assembled out;
  for (auto& f : failed)
    if (!f.empty()) out.failures.push_back(f);
  const bool shading = h.attributes.shadingNormals;
  size_t np = 0, ns = 0;
  bool reps = false;
  for (size_t k = 0; k < n; ++k) {
    np += data[k].points.size(), ns += data[k].segments.size();
    if (!nodes[selection.nodes[k]].leaf && failed[k].empty()) reps = true, ++out.representativeNodes;
  }
  HybridModel& m = out.model;
  m.attributes = h.attributes;
  if (reps) m.attributes.normals = m.attributes.radii = true;
  const bool withMasses = h.pointMasses || reps;
  m.points.reserve(np);
  m.segments.reserve(ns);
  std::vector<float> masses;
  if (withMasses) masses.reserve(np);
  if (shading) m.pointShadingNormals.reserve(np);
  // Originals first, merged by their index (each leaf's are sorted), so that every leaf gives
  // the original model in its order; then the representatives in node order.
  auto mergeLeaves = [&](auto indexOf, auto emit, auto sizeOf) {
    using Item = std::pair<uint32_t, std::pair<size_t, size_t>>;  // index, (node slot, position)
    std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
    for (size_t k = 0; k < n; ++k)
      if (nodes[selection.nodes[k]].leaf && sizeOf(data[k]) > 0) q.push({indexOf(data[k], 0), {k, 0}});
    while (!q.empty()) {
      auto [idx, at] = q.top();
      q.pop();
      emit(data[at.first], at.second);
      if (at.second + 1 < sizeOf(data[at.first]))
        q.push({indexOf(data[at.first], at.second + 1), {at.first, at.second + 1}});
    }
  };
  auto emitPoint = [&](const NodeData& d, size_t i) {
    m.points.push_back(d.points[i]);
    if (withMasses) masses.push_back(d.masses[i]);
    if (shading) m.pointShadingNormals.push_back(d.shadingNormals[i]);
  };
  mergeLeaves([](const NodeData& d, size_t i) { return d.pointIndex[i]; }, emitPoint,
              [](const NodeData& d) { return d.points.size(); });
  mergeLeaves([](const NodeData& d, size_t i) { return d.segmentIndex[i]; },
              [&](const NodeData& d, size_t i) { m.segments.push_back(d.segments[i]); },
              [](const NodeData& d) { return d.segments.size(); });
  for (size_t k = 0; k < n; ++k) {
    if (nodes[selection.nodes[k]].leaf) continue;
    for (size_t i = 0; i < data[k].points.size(); ++i) emitPoint(data[k], i);
    m.segments.insert(m.segments.end(), data[k].segments.begin(), data[k].segments.end());
  }
  if (withMasses && !m.points.empty()) m.pointProperties[kPointMassProperty] = std::move(masses);
  if (radiusScale != 1) {
    for (Point& p : m.points) p.radius *= radiusScale;
    for (Segment& s : m.segments) s.radius *= radiusScale;
  }
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
