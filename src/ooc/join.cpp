// The join stage of the out-of-core pipeline (see join.h): the tiles' MST orientations (§6.1)
// made to agree through the points they share.
#include "ooc/join.h"

#include <algorithm>
#include <numeric>

#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"

namespace linesurf::ooc::detail {
namespace {

using linesurf::detail::mergeSides;

struct Dsu {
  std::vector<uint32_t> p;
  explicit Dsu(size_t n) : p(n) { std::iota(p.begin(), p.end(), 0u); }
  uint32_t find(uint32_t x) {
    while (p[x] != x) x = p[x] = p[p[x]];
    return x;
  }
};

/// Flip per (tile, component) node so that the tiles agree on their shared points: a maximum
/// spanning forest of the vote graph (weight |agree - disagree|); each connected part then faces
/// the side the in-memory rule chooses for it.
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
    r.decode(readRange(r.cellPath(tile), 0, count * r.recordBytes()), pts, false);
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
  // Each part oriented from its first node, then turned to the side the rule chooses from the
  // sum of its nodes' side summaries (the in-memory rule over the same points, so the same side).
  std::vector<uint8_t> flip(nodes, 0), seen(nodes, 0);
  std::vector<uint32_t> queue;
  std::vector<uint32_t> nodeTile(nodes);
  for (size_t d = 0; d < T; ++d)
    for (uint32_t c = 0; c < views[d].summary.components; ++c) nodeTile[nodeOffset[d] + c] = uint32_t(d);
  for (uint32_t node = 0; node < nodes; ++node) {
    if (dsu.find(node) != node) continue;
    seen[node] = 1;
    queue.assign(1, node);
    for (size_t h = 0; h < queue.size(); ++h) {
      const uint32_t u = queue[h];
      for (auto [v, rel] : forest[u])
        if (!seen[v]) seen[v] = 1, flip[v] = uint8_t(flip[u] ^ uint8_t(rel)), queue.push_back(v);
    }
    SideSummary side;  // the pieces add up in any order
    for (uint32_t v : queue) mergeSides(side, views[nodeTile[v]].sides[v - nodeOffset[nodeTile[v]]], flip[v] != 0);
    if (side.empty()) continue;  // parts made of halo points only are not counted
    ++rep.orientationComponents;
    if (linesurf::detail::flipForSide(side, r.o.geometry.orient))
      for (uint32_t v : queue) flip[v] ^= 1;
  }
  for (uint8_t f : flip) rep.tileFlips += f;
  for (auto& [k, v] : votes) rep.disagreeingVotes += (flip[k.first] ^ flip[k.second]) ? v[0] : v[1];
  return flip;
}

}  // namespace

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
      const TileSummary s = readSummary(p);
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
      const TileSummary s = readSummary(r.resultPath(r.tileIds[d]));
      nodeOffset[d + 1] = nodeOffset[d] + s.components;
    }
    flip.assign(nodeOffset.back(), 0);
  }
  rep.tOrient = t.seconds();
}

}  // namespace linesurf::ooc::detail
