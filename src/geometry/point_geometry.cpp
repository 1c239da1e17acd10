// Geometry processing of point clouds, thesis §6.1 (five stages; see point_geometry.h).
// Every stage is parallel over points and each task writes only its own slots, so the result is
// identical for any thread count (the MST orientation's forest is unique under a strict edge order).
#include "linesurf/geometry/point_geometry.h"

#include <nanoflann.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <tuple>

#include "geometry/detail/local_delaunay.h"
#include "geometry/detail/point_geometry_tile.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"

namespace linesurf {
namespace {

constexpr uint32_t kNone = PointGeometry::kNoNeighbour;
constexpr float kInf = std::numeric_limits<float>::infinity();

struct CloudAdaptor {
  const std::vector<Vec3f>* pts;
  size_t kdtree_get_point_count() const { return pts->size(); }
  float kdtree_get_pt(size_t i, size_t d) const { return (*pts)[i][int(d)]; }
  template <class B> bool kdtree_get_bbox(B&) const { return false; }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, CloudAdaptor>, CloudAdaptor, 3, uint32_t>;

/// Runs f(begin, end) over [0, n) in parallel, in ~64 blocks so the caller can report progress.
void forBlocks(size_t n, const ProgressFn& progress, std::string_view stage, size_t grain,
               const std::function<void(size_t, size_t)>& f) {
  const size_t blocks = progress && n > 200000 ? 64 : 1;
  const size_t step = (n + blocks - 1) / std::max<size_t>(blocks, 1);
  for (size_t b = 0; b < n; b += step) {
    parallelForRange(b, std::min(n, b + step), f, grain);
    reportProgress(progress, stage, double(std::min(n, b + step)) / double(n));
  }
}

/// The two unit tangents x, y of §6.1.2: second and third columns of the Householder matrix
/// that maps e_0 to n (so that (n, x, y) is orthonormal).
inline void householderTangents(const Vec3d& n, Vec3d& x, Vec3d& y) {
  // H = I - 2 v v^T / (v^T v), v = e0 - n (or e0 + n for stability, mapping e0 to -n).
  Vec3d v = n;
  const double s = n.x() >= 0 ? 1.0 : -1.0;
  v.x() += s;  // v = n + s e0
  const double vv = v.squaredNorm();
  const Mat3d h = Mat3d::Identity() - (2.0 / vv) * v * v.transpose();
  x = h.col(1);
  y = h.col(2);
}

/// Makes the largest-magnitude component of a direction positive (a canonical sign).
inline Vec3f canonicalDirection(Vec3f d) {
  int i = 0;
  d.cwiseAbs().maxCoeff(&i);
  return d[i] < 0 ? Vec3f(-d) : d;
}

// ---------------------------------------------------------------------------------------------
// Stage 1: exact k nearest neighbours (nanoflann kd-tree).
void computeNeighbours(const std::vector<Vec3f>& pos, const KdTree& tree, int k, PointGeometry& g,
                       std::vector<uint32_t>& orderOut, const ProgressFn& progress) {
  const size_t n = pos.size();
  orderOut.resize(n);
  std::iota(orderOut.begin(), orderOut.end(), 0u);
  g.neighbours.assign(n * size_t(k), kNone);
  g.neighbourDistances.assign(n * size_t(k), kInf);
  if (n < 2) return;
  if (tree.vAcc.size() == n) orderOut.assign(tree.vAcc.begin(), tree.vAcc.end());
  // One result more than needed (self + k + 1) tells whether the k-th place is tied; only then
  // a radius search collects every tied point, so ties are always broken by index.
  const size_t want = std::min(n, size_t(k) + 2);
  // Query in the tree's leaf order: consecutive queries touch the same nodes (cache locality).
  // Each query writes only its own row, so the order does not change the result.
  const std::vector<uint32_t>& order = orderOut;
  forBlocks(n, progress, "neighbours", 512, [&](size_t b, size_t e) {
    std::vector<uint32_t> idx(want);
    std::vector<float> d2(want);
    std::vector<std::pair<float, uint32_t>> row;
    std::vector<std::pair<uint32_t, float>> tied;
    for (size_t o = b; o < e; ++o) {
      const size_t i = order[o];
      nanoflann::KNNResultSet<float, uint32_t> rs(want);
      rs.init(idx.data(), d2.data());
      const float* query = pos[i].data();
      tree.findNeighbors(rs, query, nanoflann::SearchParams());
      row.clear();
      for (size_t t = 0; t < rs.size(); ++t) row.emplace_back(d2[t], idx[t]);
      // Sorted by distance already: order equal distances by index (insertion sort, ~free).
      for (size_t a = 1; a < row.size(); ++a)
        for (size_t c = a; c > 0 && row[c] < row[c - 1]; --c) std::swap(row[c], row[c - 1]);
      if (row.size() == size_t(k) + 2 && row[size_t(k) + 1].first == row[size_t(k)].first) {
        tied.clear();
        tree.radiusSearch(query, std::nextafter(row[size_t(k)].first, kInf), tied, nanoflann::SearchParams(32, 0, false));
        row.clear();
        for (auto& [j, d] : tied) row.emplace_back(d, j);
        std::sort(row.begin(), row.end());
      }
      // Drop the point itself (first among its duplicates by index, not necessarily first).
      for (size_t t = 0; t < row.size(); ++t)
        if (row[t].second == i) {
          row.erase(row.begin() + std::ptrdiff_t(t));
          break;
        }
      const size_t m = std::min(row.size(), size_t(k));
      for (size_t t = 0; t < m; ++t) {
        g.neighbours[i * k + t] = row[t].second;
        g.neighbourDistances[i * k + t] = std::sqrt(row[t].first);
      }
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Stage 2a: PCA normals (Hoppe 1992): covariance of p and its neighbours about their centroid.
void computeNormals(const HybridModel& cloud, const std::vector<Vec3f>& pos, const std::vector<uint32_t>& order, int k, float dupTol, bool keepFileNormals, PointGeometry& g,
                    std::vector<uint8_t>& fixedNormal, const ProgressFn& progress) {
  const size_t n = cloud.points.size();
  g.normals.assign(n, Vec3f(0, 0, 1));
  g.eigenvalues.assign(n, Vec3f::Zero());
  g.surfaceVariation.assign(n, 0.0f);
  fixedNormal.assign(n, 0);
  forBlocks(n, progress, "normals", 256, [&](size_t b, size_t e) {
    for (size_t o = b; o < e; ++o) {
      const size_t i = order[o];
      const Vec3d p = pos[i].cast<double>();
      Vec3d sum = Vec3d::Zero();
      int cnt = 1, distinct = 0;
      for (int t = 0; t < k; ++t) {
        const uint32_t j = g.neighbours[i * k + t];
        if (j == kNone) break;
        sum += pos[j].cast<double>() - p;
        ++cnt;
        if (g.neighbourDistances[i * k + t] > dupTol) ++distinct;
        else g.flags[i] |= kPointDuplicate;
      }
      const Vec3d mean = sum / cnt;  // relative to p
      Mat3d cov = Mat3d::Zero();
      for (int t = 0; t < k; ++t) {
        const uint32_t j = g.neighbours[i * k + t];
        if (j == kNone) break;
        const Vec3d d = pos[j].cast<double>() - p - mean;
        cov += d * d.transpose();
      }
      cov += mean * mean.transpose();  // p itself (at 0 relative to p)
      cov /= cnt;
      Eigen::SelfAdjointEigenSolver<Mat3d> es;
      es.computeDirect(cov);
      Vec3d lambda = es.eigenvalues().cwiseMax(0.0);
      const double total = lambda.sum();
      g.eigenvalues[i] = lambda.cast<float>();
      g.surfaceVariation[i] = total > 0 ? float(lambda[0] / total) : 0.0f;
      if (distinct < 3) g.flags[i] |= kPointFewNeighbours;
      Vec3d nrm(0, 0, 1);
      if (!(lambda[2] > 0) || !std::isfinite(lambda[2])) {
        g.flags[i] |= kPointFlatNeighbourhood;  // all neighbours coincide: nothing to fit
      } else if (lambda[1] <= 1e-6 * lambda[2]) {
        // Collinear neighbourhood: any normal of the line fits; take a deterministic one.
        g.flags[i] |= kPointFlatNeighbourhood;
        const Vec3d dir = es.eigenvectors().col(2).normalized();
        Vec3d axis = Vec3d::Zero();
        int a = 0;
        dir.cwiseAbs().minCoeff(&a);
        axis[a] = 1;
        nrm = dir.cross(axis).normalized();
      } else {
        nrm = es.eigenvectors().col(0).normalized();
      }
      if (!nrm.allFinite()) nrm = Vec3d(0, 0, 1);
      g.normals[i] = nrm.cast<float>();
      if (keepFileNormals) {
        const Vec3f fn = cloud.points[i].normal;
        const float len = fn.norm();
        if (len > 0 && std::isfinite(len)) {
          g.normals[i] = fn / len;
          fixedNormal[i] = 1;
        }
      }
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Stage 2b: consistent orientation by a minimum spanning tree (Hoppe 1992) over the symmetrised
// kNN graph with weights 1 - |n_i . n_j| (+ the penalty of GeometryOptions::orientationPenalty);
// a minimum spanning forest (Borůvka, parallel), oriented from one seed per connected component
// (see docs/decisions.md for the seed rule).
void orientNormals(const std::vector<Vec3f>& pos, int k, float tangentPenalty, PointGeometry& g,
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

  // Orientation along the forest from its roots: each component's fixed normals, else its seed.
  std::vector<uint32_t> treeOff(n + 1, 0), treeAdj(2 * tree.size());
  for (const auto& [a, c] : tree) ++treeOff[a + 1], ++treeOff[c + 1];
  for (size_t i = 0; i < n; ++i) treeOff[i + 1] += treeOff[i];
  {
    std::vector<uint32_t> at(treeOff.begin(), treeOff.end() - 1);
    for (const auto& [a, c] : tree) treeAdj[at[a]++] = c, treeAdj[at[c]++] = a;
  }
  size_t flips = 0;
  std::vector<uint8_t> done(n, 0);
  std::vector<uint32_t> queue;
  for (size_t c = 0; c + 1 < compStart.size(); ++c) {
    const uint32_t* members = order.data() + compStart[c];
    const size_t size = compStart[c + 1] - compStart[c];
    if (size == 1) g.flags[members[0]] |= kPointIsolated;
    queue.clear();
    for (size_t t = 0; t < size; ++t)
      if (fixedNormal[members[t]]) queue.push_back(members[t]);
    if (queue.empty()) {
      // Seed: the points extreme along +z, -z, +x, -x, +y, -y; the first whose normal is within
      // 30 degrees of its direction (else the best aligned) is oriented along that direction.
      // On a closed surface the outward normal at an extreme point along d is d itself.
      static const std::array<Vec3f, 6> dirs = {Vec3f(0, 0, 1), Vec3f(0, 0, -1), Vec3f(1, 0, 0),
                                                Vec3f(-1, 0, 0), Vec3f(0, 1, 0), Vec3f(0, -1, 0)};
      uint32_t seed = members[0];
      Vec3f seedDir = dirs[0];
      float bestAlign = -1;
      for (const Vec3f& d : dirs) {
        uint32_t ext = members[0];
        float most = -kInf;
        for (size_t t = 0; t < size; ++t) {
          const uint32_t u = members[t];
          const float v = pos[u].dot(d);
          if (v > most || (v == most && u < ext)) most = v, ext = u;
        }
        const float align = std::abs(g.normals[ext].dot(d));
        if (align > bestAlign) bestAlign = align, seed = ext, seedDir = d;
        if (align >= 0.866f) break;
      }
      if (g.normals[seed].dot(seedDir) < 0) {
        g.normals[seed] = -g.normals[seed];
        ++flips;
      }
      queue.push_back(seed);
    }
    for (uint32_t u : queue) done[u] = 1;
    for (size_t h = 0; h < queue.size(); ++h) {
      const uint32_t u = queue[h];
      for (uint32_t e = treeOff[u]; e < treeOff[u + 1]; ++e) {
        const uint32_t v = treeAdj[e];
        if (done[v]) continue;
        done[v] = 1;
        if (!fixedNormal[v] && g.normals[v].dot(g.normals[u]) < 0) {
          g.normals[v] = -g.normals[v];
          ++flips;
        }
        queue.push_back(v);
      }
    }
  }
  g.orientationFlips = flips;
}

// ---------------------------------------------------------------------------------------------
// Stages 3 and 4.
// Hole-free radius (beyond the thesis) = this x the farthest vertex of the point's
// Voronoi cell among its nearest neighbours in its tangent plane, i.e. the largest circumradius
// of its closed Delaunay star: the splat's cut-off reaches the cell's vertices at 1.0; 10% covers
// the surface's deviation from the plane, normal error and pixel sampling.
constexpr double kCoverMargin = 1.1;
// The cell of a closed star of the k nearest neighbours contains the true cell (fewer points, a
// larger cell), so its radius is safe. An open (boundary) star leaves its open side out and can
// be 5x too small: 12 directions within a half-plane, 0.6% of the points of a uniformly random
// sampling. So an open star's radius comes from the star of 2k, then 4k nearest neighbours, the
// first that closes; one still open at 4k is a border of the surface and keeps the k-star's
// radius (docs/decisions.md, "Spacing and the cover radius").
constexpr int kCoverGrowth = 4;

/// Largest circumradius of the star triangles (0, q_a, q_b), consecutive counter-clockwise
/// neighbours turning by less than pi: R = |a| |b| |a - b| / (2 |a x b|); a boundary star's open
/// side is left out.
double starCircumradius(std::span<const Vec2d> q, const detail::LocalStar& star) {
  double rmax = 0;
  const size_t s = star.ids.size();
  for (size_t t = 0; t < s && s >= 2; ++t) {
    if (star.boundary && t + 1 == s) break;  // the open side of a boundary star
    const Vec2d a = q[size_t(star.ids[t])], b = q[size_t(star.ids[(t + 1) % s])];
    const double cr = a.x() * b.y() - a.y() * b.x();
    if (!(cr > 0)) continue;
    rmax = std::max(rmax, a.norm() * b.norm() * (a - b).norm() / (2 * cr));
  }
  return rmax;
}

void computeDelaunay(const std::vector<Vec3f>& pos, const KdTree* tree, const std::vector<uint32_t>& order, int k, float dupTol,
                     bool useCgal, PointGeometry& g, const ProgressFn& progress, std::vector<float>* reach) {
  const size_t n = pos.size();
  std::vector<uint32_t> tmpIdx(n * size_t(k), kNone);
  std::vector<float> tmpW(n * size_t(k), 0.0f);
  std::vector<uint32_t> count(n, 0);
  const double minDist2 = double(dupTol) * dupTol;
  const size_t kMax = size_t(k) * kCoverGrowth;
  forBlocks(n, progress, "local Delaunay", 256, [&](size_t b, size_t e) {
    detail::LocalStar star, grown;
    detail::StarScratch scratch;
    std::vector<Vec2d> q(static_cast<size_t>(k)), qg(kMax);
    std::vector<uint32_t> idx(kMax + 1);
    std::vector<float> d2(kMax + 1);
    for (size_t o = b; o < e; ++o) {
      const size_t i = order[o];
      const Vec3d p = pos[i].cast<double>();
      Vec3d x, y;
      householderTangents(g.normals[i].cast<double>(), x, y);
      int m = 0;
      for (; m < k; ++m) {
        const uint32_t j = g.neighbours[i * k + m];
        if (j == kNone) break;
        const Vec3d d = pos[j].cast<double>() - p;
        q[size_t(m)] = Vec2d(d.dot(x), d.dot(y));
      }
      std::span<const Vec2d> qs(q.data(), size_t(m));
      auto build = [&](std::span<const Vec2d> pts, detail::LocalStar& out) {
        if (useCgal) detail::localDelaunayStarCgal(pts, minDist2, out);
        else detail::localDelaunayStar(pts, minDist2, out, scratch);
      };
      build(qs, star);
      double total = 0;
      for (double a : star.areas) total += a;
      const size_t s = star.ids.size();
      for (size_t t = 0; t < s; ++t) {
        tmpIdx[i * k + t] = g.neighbours[i * k + size_t(star.ids[t])];
        tmpW[i * k + t] = total > 0 ? float(star.areas[t] / total) : 0.0f;
      }
      count[i] = uint32_t(s);
      if (star.triangles == 0) g.flags[i] |= kPointNoStar;
      if (g.coverRadius.empty()) continue;
      double rmax = starCircumradius(qs, star);
      // An open star from a full row (m == k; a shorter row lists the cloud): grow it.
      if (tree && m == k && star.boundary) {
        for (size_t want = 2 * size_t(k); want <= kMax && want < n; want *= 2) {
          nanoflann::KNNResultSet<float, uint32_t> rs(want + 1);  // + the point itself
          rs.init(idx.data(), d2.data());
          tree->findNeighbors(rs, pos[i].data(), nanoflann::SearchParams());
          if (reach && rs.size() > 0) (*reach)[i] = std::max((*reach)[i], std::sqrt(d2[rs.size() - 1]));
          size_t mg = 0;
          for (size_t t = 0; t < rs.size() && mg < want; ++t) {
            if (idx[t] == i) continue;
            const Vec3d d = pos[idx[t]].cast<double>() - p;
            qg[mg++] = Vec2d(d.dot(x), d.dot(y));
          }
          const std::span<const Vec2d> qgs(qg.data(), mg);
          build(qgs, grown);
          if (!grown.boundary) {
            rmax = starCircumradius(qgs, grown);
            break;
          }
        }
        // still open with 4k neighbours: a border of the surface, its open side has none; the
        // k-star's radius stays (a wider star only adds long triangles along the border)
      }
      g.coverRadius[i] = float(kCoverMargin * rmax);
    }
  });
  g.delaunayOffsets.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) g.delaunayOffsets[i + 1] = g.delaunayOffsets[i] + count[i];
  g.delaunayIndices.resize(g.delaunayOffsets[n]);
  g.delaunayWeights.resize(g.delaunayOffsets[n]);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      std::copy_n(tmpIdx.begin() + i * k, count[i], g.delaunayIndices.begin() + g.delaunayOffsets[i]);
      std::copy_n(tmpW.begin() + i * k, count[i], g.delaunayWeights.begin() + g.delaunayOffsets[i]);
    }
  }, 4096);
}

/// Taubin 1995 as in thesis §6.1.2: M = sum_j w_j kappa_j T_j T_j^T restricted to the tangent
/// plane; its eigenvalues m1 >= m2 give kappa_max = 3 m1 - m2, kappa_min = 3 m2 - m1. Or, with
/// CurvatureFit::Quadric, the Hessian of a height function fitted to the k nearest neighbours.
void computeCurvature(const std::vector<Vec3f>& pos, const std::vector<uint32_t>& order, CurvatureFit fit, PointGeometry& g, const ProgressFn& progress) {
  const size_t n = pos.size();
  g.kMin.assign(n, 0.0f);
  g.kMax.assign(n, 0.0f);
  g.minCurvatureDir.assign(n, Vec3f::Zero());
  g.maxCurvatureDir.assign(n, Vec3f::Zero());
  forBlocks(n, progress, "curvature", 256, [&](size_t b, size_t e) {
    for (size_t o = b; o < e; ++o) {
      const size_t i = order[o];
      const Vec3d p = pos[i].cast<double>();
      const Vec3d nrm = g.normals[i].cast<double>();
      Vec3d x, y;
      householderTangents(nrm, x, y);
      const auto ids = g.delaunayOf(i);
      const auto ws = g.delaunayWeightsOf(i);
      double m11 = 0, m12 = 0, m22 = 0;  // Taubin's M in the (x, y) basis
      for (size_t t = 0; t < ids.size(); ++t) {
        const Vec3d d = p - pos[ids[t]].cast<double>();  // q_j -> p
        const double d2 = d.squaredNorm();
        double tx = d.dot(x), ty = d.dot(y);
        const double tl = std::sqrt(tx * tx + ty * ty);
        if (!(d2 > 0) || !(tl > 0)) continue;
        tx /= tl, ty /= tl;
        const double kappa = 2.0 * nrm.dot(d) / d2;  // §6.1.2 directional curvature, convex > 0
        const double w = double(ws[t]);
        m11 += w * kappa * tx * tx;
        m12 += w * kappa * tx * ty;
        m22 += w * kappa * ty * ty;
      }
      // Symmetric 2x2 block [s11 s12; s12 s22] whose eigen decomposition gives the directions.
      double s11 = m11, s12 = m12, s22 = m22;
      bool taubin = true;
      if (fit == CurvatureFit::Quadric) {
        // h(u, v) = n.(q - p) = (a u^2 + 2 b u v + c v^2) / 2 + e u + f v, least squares over the
        // kNN row with coordinates scaled by the spacing; convex-positive curvature is -Hessian.
        using Vec5d = Eigen::Matrix<double, 5, 1>;
        Eigen::Matrix<double, 5, 5> ata = Eigen::Matrix<double, 5, 5>::Zero();
        Vec5d atb = Vec5d::Zero();
        double scale = g.spacing.empty() ? 0.0 : double(g.spacing[i]);
        int rows = 0;
        for (int t = 0; t < g.k; ++t) {
          const uint32_t j = g.neighbours[i * size_t(g.k) + t];
          if (j == kNone) break;
          if (scale <= 0) scale = double(g.neighbourDistances[i * size_t(g.k) + t]);
          if (!(scale > 0)) continue;
          const Vec3d d = (pos[j].cast<double>() - p) / scale;
          const double u = d.dot(x), v = d.dot(y), h = d.dot(nrm);
          Vec5d phi;
          phi << 0.5 * u * u, u * v, 0.5 * v * v, u, v;
          ata += phi * phi.transpose();
          atb += h * phi;
          ++rows;
        }
        if (rows >= 5 && scale > 0) {
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 5, 5>> es(ata);
          const auto ev = es.eigenvalues();
          if (ev[0] > 1e-8 * ev[4]) {
            const Vec5d sol = es.eigenvectors() * ((es.eigenvectors().transpose() * atb).cwiseQuotient(ev));
            if (sol.allFinite())
              s11 = -sol[0] / scale, s12 = -sol[1] / scale, s22 = -sol[2] / scale, taubin = false;
          }
        }
      }
      const double half = 0.5 * (s11 - s22), r = std::hypot(half, s12), mid = 0.5 * (s11 + s22);
      const double e1 = mid + r, e2 = mid - r;  // e1 >= e2
      double ux = 1, uy = 0;                    // eigenvector of e1
      if (r > 0) {
        const double theta = 0.5 * std::atan2(s12, half);
        ux = std::cos(theta), uy = std::sin(theta);
      }
      const Vec3d dMax = ux * x + uy * y, dMin = -uy * x + ux * y;
      g.kMax[i] = float(taubin ? 3 * e1 - e2 : e1);  // §6.1.2: kappa_1 = 3 m11 - m22 (diagonalised)
      g.kMin[i] = float(taubin ? 3 * e2 - e1 : e2);
      g.maxCurvatureDir[i] = canonicalDirection(dMax.cast<float>().normalized());
      g.minCurvatureDir[i] = canonicalDirection(dMin.cast<float>().normalized());
    }
  });
}

}  // namespace

size_t PointGeometry::countFlag(PointFlag f) const {
  size_t c = 0;
  for (uint8_t v : flags)
    if (f == kPointOk ? v == 0 : (v & f) != 0) ++c;
  return c;
}

void validate(const GeometryOptions& options) {
  if (options.k < 3) throwBadOption("k", "must be at least 3 (got " + std::to_string(options.k) + ")");
  if (options.k > 256) throwBadOption("k", "must be at most 256 (got " + std::to_string(options.k) + ")");
  requireRange("orientationPenalty", options.orientationPenalty, 0, 1e6);
}

PointGeometry computePointGeometry(const HybridModel& cloud, const GeometryOptions& options) {
  return detail::computePointGeometryTile(cloud, options, -1.0f, nullptr);
}

PointGeometry detail::computePointGeometryTile(const HybridModel& cloud, const GeometryOptions& options, float dupTolOverride,
                                               TileGeometryExtras* extras) {
  validate(options);
  for (size_t i = 0; i < cloud.points.size(); ++i)
    if (!cloud.points[i].position.allFinite())
      throwBadParameter("points", "point " + std::to_string(i) + " has a non-finite position");
  PointGeometry g;
  const int k = options.k;
  g.k = k;
  const size_t n = cloud.points.size();
  g.flags.assign(n, kPointOk);
  const Bounds3f bb = cloud.bounds();
  const float diag = n > 0 ? bb.diagonal().norm() : 0.0f;
  const float dupTol = dupTolOverride >= 0 ? dupTolOverride : 1e-6f * diag;
  const ProgressFn& progress = options.progress;

  Timer timer;
  std::vector<Vec3f> pos(n);
  for (size_t i = 0; i < n; ++i) pos[i] = cloud.points[i].position;
  std::vector<uint32_t> order;
  CloudAdaptor adaptor{&pos};
  KdTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  if (n >= 2) tree.buildIndex();
  computeNeighbours(pos, tree, k, g, order, progress);
  g.times.neighbours = timer.seconds();
  if (extras) {
    // The farthest point any query of point i looked at: its k-th neighbour, widened below by the
    // cover-radius growth (stage 3). A tile reproduces the in-memory result for i when this ball
    // lies inside the tile's halo.
    extras->reach.assign(n, 0.0f);
    for (size_t i = 0; i < n; ++i)
      for (int t = k - 1; t >= 0; --t)
        if (g.neighbours[i * k + t] != kNone) {
          extras->reach[i] = g.neighbourDistances[i * k + t];
          break;
        }
    extras->component.clear();
  }

  timer.reset();
  const bool keepFile = cloud.attributes.normals && !options.recomputeNormals;
  std::vector<uint8_t> fixedNormal;
  computeNormals(cloud, pos, order, k, dupTol, keepFile, g, fixedNormal, progress);
  g.times.normals = timer.seconds();

  timer.reset();
  const bool needOrient = options.orientNormals &&
                          std::any_of(fixedNormal.begin(), fixedNormal.end(), [](uint8_t f) { return f == 0; });
  if (needOrient) {
    reportProgress(progress, "orientation", 0.0);
    orientNormals(pos, k, options.orientationPenalty, g, fixedNormal, extras ? &extras->component : nullptr);
    reportProgress(progress, "orientation", 1.0);
  }
  g.times.orientation = timer.seconds();

  if (options.delaunayNeighbours || options.curvature || options.coverRadius) {
    timer.reset();
    if (options.coverRadius) g.coverRadius.assign(n, 0.0f);
    computeDelaunay(pos, n >= 2 ? &tree : nullptr, order, k, dupTol, options.cgalDelaunay, g, progress,
                    extras ? &extras->reach : nullptr);
    if (!options.delaunayNeighbours && !options.curvature) {  // stage 3 ran only for the radii
      g.delaunayOffsets.clear();
      g.delaunayIndices.clear();
      g.delaunayWeights.clear();
    }
    g.times.delaunay = timer.seconds();
  }
  if (options.curvature) {
    timer.reset();
    computeCurvature(pos, order, options.curvatureFit, g, progress);
    g.times.curvature = timer.seconds();
  }

  // Stage 5: spacing = mean distance to the k nearest neighbours; global = mean over points.
  timer.reset();
  g.spacing.assign(n, 0.0f);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      double s = 0;
      int c = 0;
      for (int t = 0; t < k && g.neighbours[i * k + t] != kNone; ++t) s += g.neighbourDistances[i * k + t], ++c;
      g.spacing[i] = c > 0 ? float(s / c) : 0.0f;
    }
  }, 4096);
  double total = 0;
  size_t counted = 0;
  for (size_t i = 0; i < n; ++i)
    if (g.neighbours.empty() || g.neighbours[i * k] != kNone) total += g.spacing[i], ++counted;
  g.averageSpacing = counted > 0 ? float(total / double(counted)) : 0.0f;
  for (size_t i = 0; i < g.coverRadius.size(); ++i)  // a degenerate star must not blow a disc up
    g.coverRadius[i] = std::min(g.coverRadius[i], 3.0f * (g.spacing[i] > 0 ? g.spacing[i] : g.averageSpacing));
  g.times.spacing = timer.seconds();
  return g;
}

void applyGeometry(HybridModel& cloud, const PointGeometry& geometry) {
  const size_t n = std::min(cloud.points.size(), geometry.size());
  for (size_t i = 0; i < n; ++i) cloud.points[i].normal = geometry.normals[i];
  cloud.attributes.normals = true;
  if (!cloud.attributes.radii && geometry.spacing.size() >= n) {
    // Radius rule (docs/decisions.md): the hole-free cover radius, else the per-point spacing,
    // else the cloud's average.
    const bool cover = geometry.coverRadius.size() >= n;
    for (size_t i = 0; i < n; ++i)
      cloud.points[i].radius = cover && geometry.coverRadius[i] > 0 ? geometry.coverRadius[i]
                               : geometry.spacing[i] > 0            ? geometry.spacing[i]
                                                                    : geometry.averageSpacing;
    cloud.attributes.radii = true;
  }
}

void addCurvatureProperties(HybridModel& cloud, const PointGeometry& geometry) {
  const size_t n = cloud.points.size();
  if (geometry.kMin.size() != n) throwBadParameter("curvature", "geometry has no curvature for this cloud");
  auto& props = cloud.pointProperties;
  props["k_min"] = geometry.kMin;
  props["k_max"] = geometry.kMax;
  std::vector<float> dx(n), dy(n), dz(n);
  for (size_t i = 0; i < n; ++i) {
    dx[i] = geometry.minCurvatureDir[i].x();
    dy[i] = geometry.minCurvatureDir[i].y();
    dz[i] = geometry.minCurvatureDir[i].z();
  }
  props["dmin_x"] = std::move(dx);
  props["dmin_y"] = std::move(dy);
  props["dmin_z"] = std::move(dz);
}

}  // namespace linesurf
