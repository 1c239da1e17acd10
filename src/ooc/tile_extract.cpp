// The per-tile extraction stage of the out-of-core pipeline and the hybrid writer (see tile_extract.h).
#include "ooc/tile_extract.h"

#include <algorithm>
#include <stdexcept>

#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "io/detail/ply_format.h"
#include "ooc/tile_geometry.h"

namespace linesurf::ooc::detail {
namespace {

/// Extracts one tile's own points, as a cloud of their own, from the geometry the first pass
/// left, with the join's flips applied. Writes the tile's extraction file: counts, the
/// extraction's counters, kept-per-block counts, kept points, segments with provenance (input
/// indices).
void extractTile(const Run& r, uint32_t tile, double epsilon, const std::vector<size_t>& nodeOffset,
                 const std::vector<uint8_t>& flip, float avg) {
  const size_t na = r.attrFloats(), colorFloats = r.info.colors ? 4 : 0;
  const OwnGeometry og = decodeOwnGeometry(r.ownGeometryPath(tile), na);
  const size_t m = og.size(), d = r.denseOf.at(tile);
  const bool curvature = !og.minDir.empty();
  HybridModel c;
  c.points.resize(m);
  c.attributes.normals = true;
  c.attributes.radii = r.radiusIn;
  c.attributes.colors = r.info.colors;
  // The attributes as readModel gives them: the extraction applies the in-memory rules to them
  // (kept points keep theirs; a segment's colour is its points' mean).
  for (size_t e = 0; e < r.info.properties.size(); ++e) {
    std::vector<float>& v = c.pointProperties[r.info.properties[e]];
    v.resize(m);
    for (size_t j = 0; j < m; ++j) v[j] = og.attrs[j * na + colorFloats + e];
  }
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
    if (colorFloats)
      for (int k = 0; k < 4; ++k) c.points[j].color[k] = og.attrs[j * na + size_t(k)];
  }
  ExtractStats stats{};
  const HybridModel x = r.extraction->extract(c, sg, epsilon, stats);
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
  // The properties, kept points' and segments', in the input's (sorted) order.
  std::vector<const std::vector<float>*> props, segProps;
  for (const std::string& name : r.info.properties) {
    auto it = x.pointProperties.find(name);
    auto st = x.segmentProperties.find(name);
    if (it == x.pointProperties.end() || it->second.size() != x.points.size() || st == x.segmentProperties.end() ||
        st->second.size() != x.segments.size())
      throw std::logic_error("extractTile: the extraction dropped property '" + name + "'");
    props.push_back(&it->second), segProps.push_back(&st->second);
  }
  size_t at = 0;
  for (size_t j = 0; j < m; ++j) {
    if (replaced[j]) continue;
    const Point& p = x.points[at];
    putRaw(b, og.idx[j]), putRaw(b, p.position), putRaw(b, p.normal), putRaw(b, p.radius);
    if (colorFloats) putRaw(b, p.color);
    for (const auto* v : props) putRaw(b, (*v)[at]);
    ++at;
  }
  if (at != x.points.size()) throw std::logic_error("extractTile: kept points do not match the provenance");
  for (size_t sI = 0; sI < x.segments.size(); ++sI) {
    const Segment& sgm = x.segments[sI];
    putRaw(b, sgm.p0), putRaw(b, sgm.p1), putRaw(b, sgm.normal), putRaw(b, sgm.normal0), putRaw(b, sgm.normal1), putRaw(b, sgm.radius);
    if (colorFloats) putRaw(b, sgm.color);
    for (const auto* v : segProps) putRaw(b, (*v)[sI]);
    putRaw(b, uint32_t(x.provenance[sI].size()));
    for (uint32_t j : x.provenance[sI]) putRaw(b, uint32_t(og.idx[j]));
  }
  writeWhole(r.extractPath(tile), sealed(r, Stage::Extraction, tile, std::move(b)));
  // The tile's geometry is spent: free its disk now rather than at the end of the run.
  std::error_code ec;
  fs::remove(r.ownGeometryPath(tile), ec);
}

}  // namespace

void extractTiles(const Run& r, const std::vector<size_t>& nodeOffset, const std::vector<uint8_t>& flip, float avg,
                  ExtractTotals& et) {
  Timer t;
  et.epsilon = r.extraction->epsilon(avg);
  std::vector<uint32_t> todo;
  std::error_code ec;
  for (size_t d = 0; d < r.tileIds.size(); ++d)
    if (int(d % size_t(r.o.ranks)) == r.o.rank && !proven(r, Stage::Extraction, r.tileIds[d], r.extractPath(r.tileIds[d])))
      todo.push_back(r.tileIds[d]);
  forEachTile(r, todo, r.extraction->stage(),
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
  for (std::string& c : r.extraction->comments(et.epsilon, r)) comments.push_back(std::move(c));
  const bool endpointNormals = r.extraction->endpointNormals(), provenance = r.extraction->provenance();
  const bool colors = r.info.colors;
  const size_t na = r.attrFloats(), colorFloats = colors ? 4 : 0, np = r.info.properties.size();
  // The segment element as writePlyModel declares it.
  std::string segHead;
  if (et.segments > 0) {
    segHead = "element segment " + std::to_string(et.segments) + "\n";
    segHead += "property float x0\nproperty float y0\nproperty float z0\nproperty float x1\nproperty float y1\nproperty float z1\n";
    segHead += "property float nx\nproperty float ny\nproperty float nz\n";
    if (colors) segHead += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
    segHead += "property float radius\n";
    if (endpointNormals)
      segHead += "property float nx0\nproperty float ny0\nproperty float nz0\nproperty float nx1\nproperty float ny1\nproperty float nz1\n";
    for (const std::string& name : r.info.properties) segHead += "property float " + name + "\n";
    if (provenance) segHead += "property list uint uint provenance\n";
  }
  PlyPointWriter w(r.out, et.kept, comments, true, true, segHead, r.info.properties, colors);
  const size_t kKeptRecord = 8 + 12 + 12 + 4 + 4 * na;
  std::vector<uint64_t> used(T, 0);
  std::vector<Vec3f> pos, nrm;
  std::vector<float> rad, att;
  std::vector<std::pair<uint64_t, uint32_t>> order;  // (input index, slot) of a block's kept points
  for (size_t blk = 0; blk < r.blocks; ++blk) {
    pos.clear(), nrm.clear(), rad.clear(), att.clear(), order.clear();
    for (size_t d = 0; d < T; ++d) {
      const uint32_t cnt = perBlock[d][blk];
      if (!cnt) continue;
      const std::string rec = readRange(r.extractPath(r.tileIds[d]), headBytes + used[d] * kKeptRecord, uint64_t(cnt) * kKeptRecord);
      const char* q = rec.data();
      for (uint32_t i = 0; i < cnt; ++i) {
        order.emplace_back(getRaw<uint64_t>(q), uint32_t(pos.size()));
        pos.push_back(getRaw<Vec3f>(q)), nrm.push_back(getRaw<Vec3f>(q)), rad.push_back(getRaw<float>(q));
        for (size_t a = 0; a < na; ++a) att.push_back(getRaw<float>(q));
      }
      used[d] += cnt;
    }
    std::sort(order.begin(), order.end());
    std::vector<Vec3f> p2(pos.size()), n2(pos.size());
    std::vector<float> r2(pos.size()), c2(pos.size() * colorFloats), e2(pos.size() * np);
    for (size_t i = 0; i < order.size(); ++i) {
      const size_t k = order[i].second;
      p2[i] = pos[k], n2[i] = nrm[k], r2[i] = rad[k];
      for (size_t a = 0; a < colorFloats; ++a) c2[i * 4 + a] = att[k * na + a];
      for (size_t a = 0; a < np; ++a) e2[i * np + a] = att[k * na + colorFloats + a];
    }
    w.write(p2.data(), n2.data(), r2.data(), p2.size(), np ? e2.data() : nullptr, colors ? c2.data() : nullptr);
    reportProgress(r.o.progress, "write points", double(blk + 1) / double(r.blocks));
  }
  // Segments, tile after tile, streamed in pieces.
  for (size_t d = 0; d < T; ++d) {
    if (!segs[d]) continue;
    const fs::path p = r.extractPath(r.tileIds[d]);
    const uint64_t start = headBytes + kept[d] * kKeptRecord;
    const std::string all = readRange(p, start, fs::file_size(p) - kProofBytes - start);
    const char* q = all.data();
    std::string rows;
    for (uint64_t sI = 0; sI < segs[d]; ++sI) {
      Vec3f v[5];
      for (Vec3f& x : v) x = getRaw<Vec3f>(q);
      const float radius = getRaw<float>(q);
      float colour[4];
      for (size_t a = 0; a < colorFloats; ++a) colour[a] = getRaw<float>(q);
      const char* segProps = q;
      q += 4 * np;
      const uint32_t cnt = getRaw<uint32_t>(q);
      for (int a = 0; a < 3; ++a) putRaw(rows, v[a]);
      if (colors)
        for (float c : colour) putRaw(rows, ply::colorByte(c));
      putRaw(rows, radius);
      if (endpointNormals) putRaw(rows, v[3]), putRaw(rows, v[4]);
      rows.append(segProps, 4 * np);
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

}  // namespace linesurf::ooc::detail
