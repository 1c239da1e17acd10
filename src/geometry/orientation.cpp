// Stage 2b of the §6.1 geometry (see detail/geometry_stages.h). Parallel over points, each task
// writing its own slots; the forest is unique under a strict edge order, so the orientation is
// the same for any thread count.
#include "geometry/detail/geometry_stages.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>
#include <tuple>

#include "geometry/detail/orientation_side.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf::detail {
namespace {
constexpr uint32_t kNone = PointGeometry::kNoNeighbour;
}  // namespace

// ---------------------------------------------------------------------------------------------
// Stage 2b: consistent orientation by a minimum spanning tree (Hoppe 1992) over the symmetrised
// kNN graph with weights 1 - |n_i . n_j| (+ the penalty of GeometryOptions::orientationPenalty);
// a minimum spanning forest (Borůvka, parallel), propagated from each component's lowest-index
// point and then turned to the side its rule chooses (orientation_side.h; docs/decisions.md).
void orientNormals(const std::vector<Vec3f>& pos, int k, float tangentPenalty, const SideChoice& side, PointGeometry& g,
                   const std::vector<uint8_t>& fixedNormal, std::vector<uint32_t>* componentOut) {
  const size_t n = pos.size();
  // Symmetrised adjacency (CSR): row i = the kNN row of i and every j that lists i, sorted, a
  // mutual pair once. Filled in any order (in parallel with atomic counters, which cost more than
  // they save on one thread): the sort makes the rows deterministic.
  const bool threads = currentThreadCount() > 1;
  auto bump = [threads](uint32_t& c) {
    return threads ? std::atomic_ref<uint32_t>(c).fetch_add(1, std::memory_order_relaxed) : c++;
  };
  auto overPoints = [&](const std::function<void(size_t)>& f) {
    if (threads) {
      parallelFor(0, n, f, 4096);
    } else {
      for (size_t i = 0; i < n; ++i) f(i);
    }
  };
  std::vector<uint32_t> off(n + 1, 0);
  overPoints([&](size_t i) {
    for (int t = 0; t < k; ++t) {
      const uint32_t j = g.neighbours[i * k + t];
      if (j == kNone) break;
      bump(off[i + 1]);
      bump(off[j + 1]);
    }
  });
  for (size_t i = 0; i < n; ++i) off[i + 1] += off[i];
  std::vector<uint32_t> adj(off[n]);
  {
    std::vector<uint32_t> fill(off.begin(), off.end() - 1);
    overPoints([&](size_t i) {
      for (int t = 0; t < k; ++t) {
        const uint32_t j = g.neighbours[i * k + t];
        if (j == kNone) break;
        adj[bump(fill[i])] = j;
        adj[bump(fill[j])] = uint32_t(i);
      }
    });
  }
  std::vector<uint32_t> live(n);  // row i holds adj[off[i], live[i])
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t u = b; u < e; ++u) {
      const auto first = adj.begin() + off[u], last = adj.begin() + off[u + 1];
      std::sort(first, last);
      live[u] = off[u] + uint32_t(std::unique(first, last) - first);
    }
  }, 4096);
  {
    // Packed without the repeats (a third of the entries on scans), before the keys double them.
    std::vector<uint32_t> packedOff(n + 1, 0);
    for (size_t i = 0; i < n; ++i) packedOff[i + 1] = packedOff[i] + (live[i] - off[i]);
    std::vector<uint32_t> packed(packedOff[n]);
    parallelFor(0, n, [&](size_t i) {
      std::copy(adj.begin() + off[i], adj.begin() + live[i], packed.begin() + packedOff[i]);
      live[i] = packedOff[i + 1];
    }, 4096);
    adj.swap(packed);
    off.swap(packedOff);
  }

  // The minimum spanning forest by Borůvka's algorithm, parallel over points. Edges are ordered
  // by (weight, lower index, higher index), a strict total order, so the forest is unique and
  // the same for any thread count (Prim's algorithm finds the same forest wherever no two weights
  // tie, but runs on one thread). Points whose normals are fixed hang
  // from a virtual root, as a Prim search started from all of them at once would have it.
  const float crossPenalty = tangentPenalty;
  // Symmetric by construction: both ends compute the weight from (lo, hi).
  auto weight = [&](uint32_t lo, uint32_t hi) {
    const Vec3f& a = g.normals[lo];
    const Vec3f& b = g.normals[hi];
    float w = 1.0f - std::abs(a.dot(b));
    if (crossPenalty > 0) {
      const Vec3f d = pos[hi] - pos[lo];
      const float l2 = d.squaredNorm();
      if (l2 > 0) w += crossPenalty * std::abs(a.dot(d)) * std::abs(b.dot(d)) / l2;
    }
    return w;
  };
  auto orderedBits = [](float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    if (f != f) return UINT32_MAX - 1;  // NaN (a degenerate normal) last, before "no edge"
    return (u & 0x80000000u) ? ~u : (u | 0x80000000u);
  };
  struct Edge {
    uint32_t w = UINT32_MAX, lo = kNone, hi = kNone;  // w: the weight's bits, ordered as the floats
    bool operator<(const Edge& o) const { return std::tie(w, lo, hi) < std::tie(o.w, o.lo, o.hi); }
  };
  // Each edge's key, computed once: rows keep (neighbour, key) pairs while they shrink.
  std::vector<uint32_t> key(off[n]);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t u = b; u < e; ++u)
      for (uint32_t t = off[u]; t < live[u]; ++t)
        key[t] = orderedBits(weight(std::min(uint32_t(u), adj[t]), std::max(uint32_t(u), adj[t])));
  }, 4096);
  const uint32_t root = uint32_t(n);  // the virtual root of the fixed normals
  const bool anyFixed = std::any_of(fixedNormal.begin(), fixedNormal.end(), [](uint8_t f) { return f != 0; });
  // With fixed normals a component's trees meet only at the virtual root: its rows are needed
  // again to find the components (the rounds reorder a row's entries, never drop them).
  const std::vector<uint32_t> rowEnd = anyFixed ? live : std::vector<uint32_t>();
  std::vector<uint32_t> label(n + 1), parentSet(n + 1);
  for (size_t i = 0; i <= n; ++i) label[i] = fixedNormal.size() > i && fixedNormal[i] ? root : uint32_t(i);
  std::vector<Edge> best(n), setBest(n + 1);
  std::vector<std::pair<uint32_t, uint32_t>> tree;
  tree.reserve(n);
  auto find = [&](uint32_t x) {
    while (parentSet[x] != x) x = parentSet[x] = parentSet[parentSet[x]];
    return x;
  };
  for (;;) {
    // Each point's lightest edge to another set; edges inside its own set leave its row for good.
    parallelForRange(0, n, [&](size_t b, size_t e) {
      for (size_t u = b; u < e; ++u) {
        Edge m;
        const uint32_t lu = label[u];
        uint32_t end = live[u];
        for (uint32_t t = off[u]; t < end;) {
          const uint32_t v = adj[t];
          if (label[v] == lu) {
            --end;
            std::swap(adj[t], adj[end]);
            std::swap(key[t], key[end]);
            continue;
          }
          const Edge c{key[t], std::min(uint32_t(u), v), std::max(uint32_t(u), v)};
          if (c < m) m = c;
          ++t;
        }
        live[u] = end;
        best[u] = m;
      }
    }, 4096);
    // Each set's lightest edge.
    bool any = false;
    for (size_t u = 0; u < n; ++u)
      if (best[u].lo != kNone && best[u] < setBest[label[u]]) setBest[label[u]] = best[u], any = true;
    if (!any) break;
    // Join along them. Under a strict order every chosen edge is a forest edge; an edge chosen by
    // both of its sets is taken once.
    for (size_t i = 0; i <= n; ++i) parentSet[i] = uint32_t(i);
    for (size_t u = 0; u <= n; ++u) {
      if (label[u] != u || setBest[u].lo == kNone) continue;
      const Edge e = setBest[u];
      setBest[u] = Edge();
      const uint32_t a = find(label[e.lo]), c = find(label[e.hi]);
      if (a == c) continue;
      parentSet[std::max(a, c)] = std::min(a, c);
      tree.emplace_back(e.lo, e.hi);
    }
    for (size_t i = 0; i <= n; ++i) parentSet[i] = find(uint32_t(i));
    parallelFor(0, n + 1, [&](size_t u) { label[u] = parentSet[label[u]]; }, 4096);
  }
  std::vector<uint32_t>().swap(key);

  // Connected components: the forest's trees (the virtual root left out; with fixed normals,
  // joined by every edge), numbered in the order of their smallest point, members in index order.
  for (size_t i = 0; i < n; ++i) parentSet[i] = uint32_t(i);
  auto join = [&](uint32_t a, uint32_t c) {
    const uint32_t x = find(a), y = find(c);
    parentSet[std::max(x, y)] = std::min(x, y);
  };
  for (const auto& [a, c] : tree) join(a, c);
  if (anyFixed)
    for (size_t u = 0; u < n; ++u)
      for (uint32_t t = off[u]; t < rowEnd[u]; ++t) join(uint32_t(u), adj[t]);
  std::vector<uint32_t>().swap(adj);
  std::vector<uint32_t> comp(n), compStart(1, 0), order(n);
  {
    std::vector<uint32_t> idOf(n, kNone), count;
    for (size_t i = 0; i < n; ++i) {
      const uint32_t r = find(uint32_t(i));
      if (idOf[r] == kNone) idOf[r] = uint32_t(count.size()), count.push_back(0);
      comp[i] = idOf[r];
      ++count[comp[i]];
    }
    for (uint32_t c : count) compStart.push_back(compStart.back() + c);
    std::vector<uint32_t> at(compStart.begin(), compStart.end() - 1);
    for (size_t i = 0; i < n; ++i) order[at[comp[i]]++] = uint32_t(i);
  }
  g.orientationComponents = compStart.size() - 1;
  if (componentOut) *componentOut = comp;

  // Orientation along the forest from its roots: each component's fixed normals, else its
  // lowest-index point; then the side rule turns the components without fixed normals.
  std::vector<uint32_t> treeOff(n + 1, 0), treeAdj(2 * tree.size());
  for (const auto& [a, c] : tree) ++treeOff[a + 1], ++treeOff[c + 1];
  for (size_t i = 0; i < n; ++i) treeOff[i + 1] += treeOff[i];
  {
    std::vector<uint32_t> at(treeOff.begin(), treeOff.end() - 1);
    for (const auto& [a, c] : tree) treeAdj[at[a]++] = c, treeAdj[at[c]++] = a;
  }
  std::vector<uint8_t> done(n, 0), negated(n, 0), unfixed(compStart.size() - 1, 0);
  std::vector<uint32_t> queue;
  for (size_t c = 0; c + 1 < compStart.size(); ++c) {
    const uint32_t* members = order.data() + compStart[c];
    const size_t size = compStart[c + 1] - compStart[c];
    if (size == 1) g.flags[members[0]] |= kPointIsolated;
    queue.clear();
    for (size_t t = 0; t < size; ++t)
      if (fixedNormal[members[t]]) queue.push_back(members[t]);
    if (queue.empty()) unfixed[c] = 1, queue.push_back(members[0]);
    for (uint32_t u : queue) done[u] = 1;
    for (size_t h = 0; h < queue.size(); ++h) {
      const uint32_t u = queue[h];
      for (uint32_t e = treeOff[u]; e < treeOff[u + 1]; ++e) {
        const uint32_t v = treeAdj[e];
        if (done[v]) continue;
        done[v] = 1;
        if (!fixedNormal[v] && g.normals[v].dot(g.normals[u]) < 0) {
          g.normals[v] = -g.normals[v];
          negated[v] = 1;
        }
        queue.push_back(v);
      }
    }
  }
  if (side.decide) {
    Bounds3f bounds;
    for (const Vec3f& p : pos) bounds.extend(p);
    const std::vector<SideSummary> sides =
        sideSummaries(side.rule, side.viewpoint, SideGrid(bounds), pos, g.normals, comp, compStart.size() - 1);
    std::vector<uint8_t> turn(sides.size(), 0);
    for (size_t c = 0; c < sides.size(); ++c) turn[c] = unfixed[c] && flipForSide(sides[c], side.rule);
    for (size_t i = 0; i < n; ++i)
      if (turn[comp[i]]) g.normals[i] = -g.normals[i], negated[i] ^= 1;
  }
  size_t flips = 0;
  for (uint8_t f : negated) flips += f;
  g.orientationFlips = flips;
}

}  // namespace linesurf::detail
