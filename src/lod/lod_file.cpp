// A level-of-detail hierarchy's file (include/linesurf/lod/lod.h; layout in docs/file-format.md):
// the header and node table read and validated once for every reader, node blocks read and
// checked by byte range, and the blocks' checksum. Nothing here is sized by a count the file has
// not shown it holds: the table by the file's size, a block by its range within the file.
#include <fmt/format.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numeric>

#include "linesurf/core/error.h"
#include "linesurf/core/read_only_file.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/lod/lod.h"
#include "lod_format.h"

namespace linesurf::lod {
namespace {

// What the rendering frame (io/model_frame.h) leaves of any model: a bounding radius within
// [2^-10, 2^20] and a centre within 2^10 max(1, radius) of the origin, or a normalised one near 1
// and 0. The bounds keep a margin over that (the sphere is of positions only, the fallback radius
// of a model in one place is its largest splat) and stay where the camera's float arithmetic
// (squared distances, near/far planes) works.
constexpr double kMinSphereRadius = 0x1p-30, kMaxSphereRadius = 0x1p21, kCentreReach = 0x1p11;
// Coordinates and radii of the table and header beyond the sphere (boxes include splat radii):
// squares stay finite in float.
constexpr double kMaxCoordinate = 0x1p32;

[[noreturn]] void bad(const std::string& path, const std::string& where, const std::string& what) {
  throwBadInput(path, where, what);
}

// JSON numbers read as doubles first: a value outside a float's or an integer's range is refused
// rather than converted (the conversion would be undefined behaviour).
double number(const nlohmann::json& j, const std::string& path, const char* name) {
  if (!j.is_number()) bad(path, "header", fmt::format("{} is not a number", name));
  return j.get<double>();
}
float floatNumber(const nlohmann::json& j, const std::string& path, const char* name) {
  const double v = number(j, path, name);
  if (!(std::abs(v) <= double(FLT_MAX))) bad(path, "header", fmt::format("{} {:g} is not a finite float", name, v));
  return float(v);
}
uint64_t jsonCount(const nlohmann::json& j, const std::string& path, const char* name) {
  if (!j.is_number_unsigned()) bad(path, "header", fmt::format("{} is not a non-negative integer", name));
  return j.get<uint64_t>();
}
Vec3f vec3(const nlohmann::json& j, const std::string& path, const char* name) {
  if (!j.is_array() || j.size() != 3) bad(path, "header", fmt::format("{} is not 3 numbers", name));
  return Vec3f(floatNumber(j[0], path, name), floatNumber(j[1], path, name), floatNumber(j[2], path, name));
}

bool inside(const Vec3f& lo, const Vec3f& hi, const Vec3f& outerLo, const Vec3f& outerHi) {
  return (lo.array() >= outerLo.array()).all() && (hi.array() <= outerHi.array()).all();
}

}  // namespace

void validateHeader(const LodHeader& h, const std::string& path) {
  auto fail = [&](const std::string& what) { bad(path, "header", what); };
  const ModelFrame& f = h.frame;
  int e = 0;
  // normalizingFrame scales by a power of two of a float bounding radius.
  if (!(f.scale >= 0x1p-150 && f.scale <= 0x1p128) || std::frexp(f.scale, &e) != 0.5)
    fail(fmt::format("frame scale {:g} is not a power of two in [2^-150, 2^128]", f.scale));
  if (!(f.centre.cwiseAbs().maxCoeff() <= double(FLT_MAX)))  // NaN fails too
    fail(fmt::format("frame centre ({:g}, {:g}, {:g}) is not a finite float position", f.centre.x(), f.centre.y(),
                     f.centre.z()));
  const BoundingSphere& s = h.sphere;
  if (!(s.radius >= kMinSphereRadius && s.radius <= kMaxSphereRadius))
    fail(fmt::format("sphere radius {:g} is outside [2^-30, 2^21] (a model in its rendering frame has none such)",
                     s.radius));
  const double reach = kCentreReach * std::max(1.0, double(s.radius));
  if (!s.center.allFinite() || !(s.center.cast<double>().norm() <= reach))
    fail(fmt::format("sphere centre ({:g}, {:g}, {:g}) lies more than {:g} from the origin (a model in its rendering "
                     "frame lies within 2^11 max(1, radius))",
                     s.center.x(), s.center.y(), s.center.z(), reach));
  // Object space (what cameras given in object units and reports use) must be floats too.
  if (!(f.centre.norm() + f.scale * (s.center.cast<double>().norm() + s.radius) <= double(FLT_MAX)))
    fail("the frame maps the sphere outside a float's range");
  if (!(h.maxRadius >= 0 && h.maxRadius <= kMaxCoordinate))
    fail(fmt::format("maxRadius {:g} is not in [0, 2^32]", h.maxRadius));
  if (h.points + h.segments == 0 || h.points >= kNoIndex || h.segments >= kNoIndex || h.points + h.segments >= kNoIndex)
    fail(fmt::format("{} points + {} segments: a hierarchy holds 1 to 2^32 - 2 primitives", h.points, h.segments));
  if (h.options.leafSize < 16 || h.options.leafSize > (1 << 20) || h.options.grid < 2 || h.options.grid > 256)
    fail(fmt::format("leaf size {} or grid {} out of range ([16, 1048576], [2, 256])", h.options.leafSize,
                     h.options.grid));
}

void validateHierarchy(const LodHeader& h, const std::vector<NodeInfo>& nodes, uint64_t blocksBegin,
                       const std::string& path) {
  validateHeader(h, path);
  const size_t count = nodes.size();
  if (count == 0 || count > UINT32_MAX) bad(path, "node table", fmt::format("{} nodes", count));
  auto where = [](uint64_t i) { return fmt::format("node {}", i); };
  constexpr uint32_t kNone = UINT32_MAX;
  std::vector<uint32_t> parent(count, kNone);
  uint64_t leafPrimitives = 0;
  for (uint32_t i = 0; i < count; ++i) {
    const NodeInfo& n = nodes[i];
    if (!n.boundsMin.allFinite() || !n.boundsMax.allFinite() || (n.boundsMin.array() > n.boundsMax.array()).any() ||
        !(n.boundsMin.cwiseAbs().maxCoeff() <= kMaxCoordinate && n.boundsMax.cwiseAbs().maxCoeff() <= kMaxCoordinate))
      bad(path, where(i), "invalid bounds in the node table");
    if (!n.cubeMin.allFinite() || !(n.side > 0 && n.side <= 2 * kMaxCoordinate) ||
        !(n.cubeMin.cwiseAbs().maxCoeff() <= kMaxCoordinate))
      bad(path, where(i), "invalid cube in the node table");
    // Children lie after their parent (breadth first), so the links have no cycles.
    if (n.leaf != (n.childCount == 0) || n.childCount > 8 ||
        (!n.leaf && (n.firstChild <= i || uint64_t(n.firstChild) + n.childCount > count)))
      bad(path, where(i), "invalid tree links in the node table");
    if (n.size != format::kBlockHeaderBytes + format::kPointBytes * uint64_t(n.points) +
                      format::kSegmentBytes * uint64_t(n.segments))
      bad(path, where(i), "block size does not match its point and segment counts");
    if (n.offset < blocksBegin || n.offset > UINT64_MAX - n.size)
      bad(path, where(i), fmt::format("its block at byte {} is not among the blocks (they start at {})", n.offset,
                                      blocksBegin));
    if (n.leaf) {
      leafPrimitives += n.count();
      continue;
    }
    uint64_t below = 0;
    for (uint32_t c = n.firstChild; c < n.firstChild + n.childCount; ++c) {
      // Two nodes sharing children (a DAG) would draw those twice or leave holes in a cut.
      if (parent[c] != kNone)
        bad(path, where(c), fmt::format("a child of both node {} and node {} (a node has one parent)", parent[c], i));
      parent[c] = i;
      const NodeInfo& ch = nodes[c];
      if (ch.level != n.level + 1) bad(path, where(c), fmt::format("level {} under node {} of level {}", ch.level, i, n.level));
      // An octant of the parent's cube computed as the writer computes it (the half side is
      // exact, the corner one rounding; deep cubes far from the origin may round onto each other).
      bool cubeOk = ch.side == 0.5f * n.side;
      for (int k = 0; k < 3 && cubeOk; ++k)
        cubeOk = ch.cubeMin[k] == n.cubeMin[k] || ch.cubeMin[k] == n.cubeMin[k] + ch.side;
      if (!cubeOk) bad(path, where(c), fmt::format("its cube is not an octant of node {}'s", i));
      if (!inside(ch.boundsMin, ch.boundsMax, n.boundsMin, n.boundsMax))
        bad(path, where(c), fmt::format("its box reaches outside node {}'s", i));
      below += ch.count();
    }
    // Representatives are merged from the children: never more than they hold.
    if (n.count() > below)
      bad(path, where(i), fmt::format("{} representatives for {} primitives in its children", n.count(), below));
  }
  if (nodes[0].level != 0) bad(path, where(0), "the root is not at level 0");
  for (uint32_t i = 1; i < count; ++i)
    if (parent[i] == kNone) bad(path, where(i), "no node links to it (not part of the tree)");
  if (leafPrimitives != h.points + h.segments)
    bad(path, "node table",
        fmt::format("the leaves hold {} primitives, the header says {}", leafPrimitives, h.points + h.segments));
  // Blocks do not overlap: however the counts lie, the nodes' blocks together are no larger than
  // the byte range they span, and the part within the file is what a reader can be made to hold.
  std::vector<uint32_t> order(count);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return nodes[a].offset != nodes[b].offset ? nodes[a].offset < nodes[b].offset : a < b;
  });
  for (size_t k = 1; k < count; ++k) {
    const NodeInfo &p = nodes[order[k - 1]], &n = nodes[order[k]];
    if (n.offset < p.offset + p.size)
      bad(path, where(order[k]), fmt::format("its block [{}, {}) overlaps node {}'s [{}, {})", n.offset,
                                             n.offset + n.size, order[k - 1], p.offset, p.offset + p.size));
  }
  // The default cameras frame the sphere; it lies in the root's box (positions with their radii).
  const NodeInfo& root = nodes[0];
  const float diagonal = (root.boundsMax - root.boundsMin).norm();
  const Vec3f slack = Vec3f::Constant(1e-5f * std::max(1.0f, diagonal));
  if (!inside(h.sphere.center, h.sphere.center, root.boundsMin - slack, root.boundsMax + slack) ||
      h.sphere.radius > std::max(diagonal, 1.0f) * (1 + 1e-5f) || h.maxRadius > std::max(diagonal, 1.0f) * (1 + 1e-5f))
    bad(path, "header", "the bounding sphere or maxRadius does not fit the root node's box");
}

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
  if (!f.isOpen()) bad(ps, "", "cannot open the file");
  std::error_code ec;
  fileSize_ = std::filesystem::file_size(path, ec);
  if (ec) bad(ps, "", "cannot read the file size");
  char pre[format::kPreambleBytes];
  if (f.read(0, pre, sizeof pre) != sizeof pre || std::memcmp(pre, format::kMagic, 8) != 0)
    bad(ps, "header", "not a linesurf level-of-detail hierarchy (no LINESLOD magic)");
  const uint32_t version = format::get<uint32_t>(pre + 8);
  if (version < format::kOldestVersion || version > format::kVersion)
    bad(ps, "header", fmt::format("version {} (this linesurf reads versions {} to {})", version, format::kOldestVersion,
                                  format::kVersion));
  header_.version = version;
  const uint32_t jsonBytes = format::get<uint32_t>(pre + 12);
  header_.hierarchyId = format::get<uint64_t>(pre + 16);
  const uint64_t count = format::get<uint64_t>(pre + 24);
  const uint64_t tableOffset = format::kPreambleBytes + uint64_t(jsonBytes);
  const uint64_t trailer = format::tableTrailerBytes(version);
  // The JSON and the table are sized by the file before they are read.
  if (count == 0 || count > fileSize_ / format::kRecordBytes ||
      tableOffset + count * format::kRecordBytes + trailer > fileSize_)
    bad(ps, "header", fmt::format("truncated: the header and the table of {} nodes need more than the file's {} bytes",
                                  count, fileSize_));
  const uint64_t tableEnd = tableOffset + count * format::kRecordBytes;
  // Version 2 proves the whole header (preamble, JSON, table) before any of it is believed.
  std::string head(tableEnd + trailer, '\0');
  if (f.read(0, head.data(), head.size()) != head.size()) bad(ps, "header", "cannot read the header and the table");
  if (trailer && lodChecksum(head.data(), tableEnd) != format::get<uint64_t>(head.data() + tableEnd))
    bad(ps, "node table", "checksum mismatch (the header or the node table was changed or damaged)");
  const std::string js = head.substr(format::kPreambleBytes, jsonBytes);
  try {
    const auto j = nlohmann::json::parse(js);
    if (!j.is_object() || j.value("format", "") != "linesurf-lod") bad(ps, "header", "format is not linesurf-lod");
    if (j.at("hierarchy") != fmt::format("{:016x}", header_.hierarchyId))
      bad(ps, "header", "the JSON header names another hierarchy than the preamble");
    if (count != jsonCount(j.at("nodes"), ps, "nodes"))
      bad(ps, "header", "node counts of the preamble and the JSON differ");
    const auto& fr = j.at("frame");
    const auto& c = fr.at("centre");
    if (!c.is_array() || c.size() != 3) bad(ps, "header", "frame centre is not 3 numbers");
    header_.frame.centre = Vec3d(number(c[0], ps, "frame centre"), number(c[1], ps, "frame centre"),
                                 number(c[2], ps, "frame centre"));
    header_.frame.scale = number(fr.at("scale"), ps, "frame scale");
    header_.sphere.center = vec3(j.at("sphere").at("center"), ps, "sphere centre");
    header_.sphere.radius = floatNumber(j.at("sphere").at("radius"), ps, "sphere radius");
    header_.maxRadius = floatNumber(j.at("maxRadius"), ps, "maxRadius");
    if (j.contains("upAxis")) {
      const auto& u = j.at("upAxis");
      if (!u.is_string() || (u != "x" && u != "y" && u != "z")) bad(ps, "header", "upAxis is not \"x\", \"y\" or \"z\"");
      header_.upAxis = u.get<std::string>();
    }
    const auto& a = j.at("attributes");
    header_.attributes.normals = a.at("normals");
    header_.attributes.colors = a.at("colors");
    header_.attributes.radii = a.at("radii");
    header_.attributes.texcoords = a.at("texcoords");
    header_.attributes.endpointNormals = a.at("endpointNormals");
    header_.attributes.shadingNormals = a.at("shadingNormals");
    header_.pointMasses = j.at("pointMasses");
    header_.points = jsonCount(j.at("points"), ps, "points");
    header_.segments = jsonCount(j.at("segments"), ps, "segments");
    header_.options.leafSize = int(std::min<uint64_t>(jsonCount(j.at("leafSize"), ps, "leafSize"), INT32_MAX));
    header_.options.grid = int(std::min<uint64_t>(jsonCount(j.at("grid"), ps, "grid"), INT32_MAX));
  } catch (const nlohmann::json::exception& e) {
    bad(ps, "header", std::string("invalid JSON header: ") + e.what());
  }
  const char* const table = head.data() + tableOffset;
  nodes_.resize(count);
  for (uint64_t i = 0; i < count; ++i) {
    const char* r = table + i * format::kRecordBytes;
    NodeInfo& n = nodes_[i];
    if (format::get<uint64_t>(r) != header_.hierarchyId)
      bad(ps, fmt::format("node {}", i), "its table record belongs to another hierarchy; refused");
    n.offset = format::get<uint64_t>(r + 8);
    n.size = format::get<uint64_t>(r + 16);
    n.checksum = format::get<uint64_t>(r + 24);
    n.cubeMin = format::getVec(r + 32);
    n.side = format::get<float>(r + 44);
    n.boundsMin = format::getVec(r + 48);
    n.boundsMax = format::getVec(r + 60);
    n.points = format::get<uint32_t>(r + 72);
    n.segments = format::get<uint32_t>(r + 76);
    n.firstChild = format::get<uint32_t>(r + 80);
    n.childCount = uint8_t(r[84]);
    n.level = uint8_t(r[85]);
    n.leaf = r[86] != 0;
  }
  validateHierarchy(header_, nodes_, tableEnd + trailer, ps);
}

void LodFile::readBlock(uint32_t i, std::vector<char>& buf) const {
  const std::string ps = path_.string(), where = fmt::format("node {}", i);
  if (i >= nodes_.size()) bad(ps, where, "no such node");
  const NodeInfo& n = nodes_[i];
  if (!inFile(i))
    bad(ps, where, fmt::format("missing or truncated: its block [{}, {}) lies past the file's end ({} bytes)", n.offset,
                               n.offset + n.size, fileSize_));
  if (buf.size() < n.size) buf.resize(n.size);
  ReadOnlyFile f(path_);
  if (!f.isOpen() || f.read(n.offset, buf.data(), n.size) != n.size)
    bad(ps, where, "missing or truncated: its block cannot be read in full");
  const char* p = buf.data();
  if (std::memcmp(p, format::kBlockMagic, 8) != 0) bad(ps, where, "its block is not a node block");
  if (uint64_t id = format::get<uint64_t>(p + 8); id != header_.hierarchyId)
    bad(ps, where, fmt::format("its block belongs to another hierarchy ({:016x}, this one is {:016x}); refused", id,
                               header_.hierarchyId));
  if (format::get<uint32_t>(p + 16) != i || format::get<uint32_t>(p + 20) != n.points ||
      format::get<uint32_t>(p + 24) != n.segments)
    bad(ps, where, "its block holds another node");
  if (lodChecksum(p, n.size) != n.checksum) bad(ps, where, "checksum mismatch (corrupt block)");
  // Indices in range (originals) or none (representatives), masses valid: checked before any
  // index is used to place a primitive.
  const char* q = p + format::kBlockHeaderBytes;
  for (uint32_t k = 0; k < n.points; ++k, q += format::kPointBytes) {
    const uint32_t idx = format::get<uint32_t>(q + 60);
    if (!(n.leaf ? idx < header_.points : idx == kNoIndex) || !validPointMass(format::get<float>(q + 56)))
      bad(ps, where, fmt::format("point {}: invalid index or mass", k));
  }
  for (uint32_t k = 0; k < n.segments; ++k, q += format::kSegmentBytes) {
    const uint32_t idx = format::get<uint32_t>(q + 96);
    if (!(n.leaf ? idx < header_.segments : idx == kNoIndex)) bad(ps, where, fmt::format("segment {}: invalid index", k));
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

uint64_t lodChecksum(const void* data, size_t bytes) {
  // Four independent FNV-1a-like lanes over 64-bit words (a frame checks every block it draws,
  // so the hash runs at memory speed rather than one multiply chain's latency), then combined.
  constexpr uint64_t kBasis = 0xcbf29ce484222325ULL, kPrime = 0x100000001b3ULL;
  const auto* p = static_cast<const unsigned char*>(data);
  uint64_t h[4] = {kBasis, kBasis ^ 1, kBasis ^ 2, kBasis ^ 3};
  auto mix = [](uint64_t x, uint64_t w) {
    x = (x ^ w) * kPrime;
    return x ^ (x >> 29);
  };
  size_t i = 0;
  for (; i + 32 <= bytes; i += 32)
    for (int l = 0; l < 4; ++l) {
      uint64_t w;
      std::memcpy(&w, p + i + 8 * l, 8);
      h[l] = mix(h[l], w);
    }
  for (; i + 8 <= bytes; i += 8) {
    uint64_t w;
    std::memcpy(&w, p + i, 8);
    h[0] = mix(h[0], w);
  }
  for (; i < bytes; ++i) h[1] = mix(h[1], p[i]);
  uint64_t r = kBasis;
  for (uint64_t x : h) r = mix(r, x);
  return mix(r, uint64_t(bytes));
}

}  // namespace linesurf::lod
