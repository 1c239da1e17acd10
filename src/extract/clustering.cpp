// Normal-variation clustering, thesis §3.2.3 (greedy §3.2.3.1, hierarchical §3.2.3.2).
#include "linesurf/extract/clustering.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <queue>
#include <cstring>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf {
namespace {

constexpr uint32_t kNone = UINT32_MAX;

}  // namespace

void validate(const ClusteringOptions& o) {
  if (!(o.deltaN > 0.0f && o.deltaN < 2.0f))
    throwBadOption("deltaN", "must lie in (0, 2) (got " + std::to_string(o.deltaN) +
                                     "): ||n(C) - n_j||^2 = 2 - 2 cos(angle), and at 2 a member normal may stand "
                                     "at 90 degrees to the cluster normal, folding the projection of §3.2.4.1");
  if (o.maxIterations < 1)
    throwBadOption("maxIterations", "must be >= 1 (got " + std::to_string(o.maxIterations) + ")");
}

namespace {

/// Symmetric neighbour graph in CSR form: local Delaunay neighbours when the geometry has them,
/// else its k nearest neighbours. Self loops, invalid and duplicate entries are dropped.
struct Graph {
  std::vector<uint32_t> offsets, indices;
  std::span<const uint32_t> of(size_t i) const { return {indices.data() + offsets[i], offsets[i + 1] - offsets[i]}; }
};

Graph buildGraph(const PointGeometry& g) {
  const size_t n = g.size();
  const bool delaunay = g.delaunayOffsets.size() == n + 1;
  auto forEachSource = [&](size_t i, auto&& f) {
    if (delaunay) {
      for (uint32_t j : g.delaunayOf(i)) f(j);
    } else if (g.k > 0 && g.neighbours.size() >= (i + 1) * size_t(g.k)) {
      for (int a = 0; a < g.k; ++a) f(g.neighbours[i * g.k + a]);
    }
  };
  std::vector<uint32_t> degree(n + 1, 0);
  for (size_t i = 0; i < n; ++i)
    forEachSource(i, [&](uint32_t j) {
      if (j < n && j != i) ++degree[i], ++degree[j];
    });
  Graph gr;
  gr.offsets.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) gr.offsets[i + 1] = gr.offsets[i] + degree[i];
  std::vector<uint32_t> raw(gr.offsets[n]);
  std::vector<uint32_t> fill(gr.offsets.begin(), gr.offsets.end() - 1);
  for (size_t i = 0; i < n; ++i)
    forEachSource(i, [&](uint32_t j) {
      if (j < n && j != i) raw[fill[i]++] = j, raw[fill[j]++] = uint32_t(i);
    });
  // Sort and deduplicate each row in parallel, then compact.
  std::vector<uint32_t> unique(n, 0);
  parallelFor(0, n, [&](size_t i) {
    auto b = raw.begin() + gr.offsets[i], e = raw.begin() + gr.offsets[i + 1];
    std::sort(b, e);
    unique[i] = uint32_t(std::unique(b, e) - b);
  }, 1024);
  std::vector<uint32_t> offsets(n + 1, 0);
  for (size_t i = 0; i < n; ++i) offsets[i + 1] = offsets[i] + unique[i];
  gr.indices.resize(offsets[n]);
  parallelFor(0, n, [&](size_t i) {
    std::copy_n(raw.begin() + gr.offsets[i], unique[i], gr.indices.begin() + offsets[i]);
  }, 1024);
  gr.offsets = std::move(offsets);
  return gr;
}

/// Unit normals; zero where the geometry's normal is missing or not finite.
std::vector<Vec3f> usableNormals(const PointGeometry& g, size_t& zeroCount) {
  std::vector<Vec3f> n(g.size(), Vec3f::Zero());
  zeroCount = 0;
  for (size_t i = 0; i < g.size(); ++i) {
    const Vec3f& v = g.normals[i];
    float len = v.norm();
    if (std::isfinite(len) && len > 0.5f) n[i] = v / len;
    else ++zeroCount;
  }
  return n;
}

bool valid(const Vec3f& n) { return n.squaredNorm() > 0.0f; }

/// One finished cluster before canonical ordering.
struct RawCluster {
  std::vector<uint32_t> members;  ///< increasing
  Vec3f normal = Vec3f::Zero();
  uint32_t seed = kNone;
};

/// Orders clusters by their smallest member and builds the CSR form and the invariant data.
Clustering finalize(std::vector<RawCluster> raw, const std::vector<Vec3f>& normals, size_t n) {
  std::sort(raw.begin(), raw.end(), [](const RawCluster& a, const RawCluster& b) { return a.members[0] < b.members[0]; });
  Clustering c;
  c.labels.assign(n, kNone);
  c.offsets.reserve(raw.size() + 1);
  c.offsets.push_back(0);
  c.members.reserve(n);
  for (size_t id = 0; id < raw.size(); ++id) {
    const RawCluster& r = raw[id];
    float vmax = 0;
    for (uint32_t p : r.members) {
      c.labels[p] = uint32_t(id);
      c.members.push_back(p);
      vmax = std::max(vmax, (r.normal - normals[p]).squaredNorm());
    }
    c.offsets.push_back(uint32_t(c.members.size()));
    c.seedingNormals.push_back(r.normal);
    c.seeds.push_back(r.seed);
    c.maxVariation.push_back(vmax);
  }
  return c;
}

uint64_t splitmix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// §3.2.3.1 greedy clustering.

Clustering clusterGreedy(const PointGeometry& geometry, const ClusteringOptions& options) {
  validate(options);
  const size_t n = geometry.size();
  size_t zeroNormals = 0;
  const std::vector<Vec3f> normals = usableNormals(geometry, zeroNormals);
  const Graph graph = buildGraph(geometry);

  // Flooding order: increasing surface variation V_s (flattest first), ties by index.
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  if (geometry.surfaceVariation.size() == n) {
    auto key = [&](uint32_t i) {
      float v = geometry.surfaceVariation[i];
      return std::isfinite(v) ? v : std::numeric_limits<float>::infinity();
    };
    std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) { return key(a) < key(b); });
  }

  std::vector<uint32_t> label(n, kNone);
  std::vector<RawCluster> clusters;
  std::vector<uint32_t> queue;
  const float delta = options.deltaN;
  size_t done = 0, nextReport = 0;
  for (uint32_t s : order) {
    if (label[s] != kNone) continue;
    const uint32_t id = uint32_t(clusters.size());
    RawCluster rc;
    rc.seed = s;
    rc.normal = normals[s];
    label[s] = id;
    rc.members.push_back(s);
    if (valid(rc.normal)) {
      queue.assign(1, s);
      for (size_t head = 0; head < queue.size(); ++head)
        for (uint32_t q : graph.of(queue[head])) {
          if (label[q] != kNone || !valid(normals[q])) continue;
          if ((rc.normal - normals[q]).squaredNorm() > delta) continue;  // §3.2.2 tolerance
          label[q] = id;
          rc.members.push_back(q);
          queue.push_back(q);
        }
    }
    std::sort(rc.members.begin(), rc.members.end());
    done += rc.members.size();
    clusters.push_back(std::move(rc));
    if (done >= nextReport) {
      reportProgress(options.progress, "greedy clustering", double(done) / double(std::max<size_t>(n, 1)));
      nextReport = done + n / 100 + 1;
    }
  }
  reportProgress(options.progress, "greedy clustering", 1.0);
  Clustering c = finalize(std::move(clusters), normals, n);
  c.zeroNormals = zeroNormals;
  // Connected components of the usable graph, for the summary.
  {
    std::vector<uint8_t> seen(n, 0);
    std::vector<uint32_t> stack;
    for (size_t i = 0; i < n; ++i) {
      if (seen[i]) continue;
      ++c.components;
      seen[i] = 1;
      if (!valid(normals[i])) continue;
      stack.assign(1, uint32_t(i));
      while (!stack.empty()) {
        uint32_t p = stack.back();
        stack.pop_back();
        for (uint32_t q : graph.of(p))
          if (!seen[q] && valid(normals[q])) seen[q] = 1, stack.push_back(q);
      }
    }
  }
  return c;
}

// ---------------------------------------------------------------------------------------------
// §3.2.3.2 hierarchical distortion-minimised clustering.

namespace {

/// A cluster waiting to be checked (and split if it violates delta_n).
struct Work {
  std::vector<uint32_t> members;  ///< increasing
  Vec3f seedNormal = Vec3f::Zero();  ///< normal its last growth used (zero for a component)
  uint32_t seed = kNone;
};

struct WorkResult {
  bool accepted = false;
  RawCluster cluster;        ///< when accepted
  Work children[2];          ///< when split
  size_t iterations = 0;
  bool capReached = false;
};

struct SplitContext {
  const Graph& graph;
  const std::vector<Vec3f>& normals;
  const std::vector<uint32_t>& workOf;  ///< per point: index of its Work in this level
  const std::vector<uint32_t>& slot;    ///< per point: index inside its Work's members
  float delta;
  int maxIterations;
  uint64_t seed;
  SplitSeeding seeding;
};

/// Min-heap of packed 64-bit keys, 4-ary: shallower than a binary heap and its children share a
/// cache line. Keys are unique (one per point and cluster), so the pop order is exact.
class QuadHeap {
 public:
  bool empty() const { return h_.empty(); }
  void push(uint64_t v) {
    size_t i = h_.size();
    h_.push_back(v);
    while (i > 0) {
      size_t parent = (i - 1) / 4;
      if (h_[parent] <= v) break;
      h_[i] = h_[parent];
      i = parent;
    }
    h_[i] = v;
  }
  uint64_t pop() {
    const uint64_t top = h_[0];
    const uint64_t v = h_.back();
    h_.pop_back();
    const size_t n = h_.size();
    if (n == 0) return top;
    size_t i = 0;
    for (;;) {
      size_t c = 4 * i + 1;
      if (c >= n) break;
      size_t best = c;
      const size_t end = std::min(c + 4, n);
      for (size_t k = c + 1; k < end; ++k)
        if (h_[k] < h_[best]) best = k;
      if (h_[best] >= v) break;
      h_[i] = h_[best];
      i = best;
    }
    h_[i] = v;
    return top;
  }

 private:
  std::vector<uint64_t> h_;
};

/// Average normal of the given members (unit), zero when it cancels out.
Vec3f averageNormal(const std::vector<uint32_t>& members, const std::vector<Vec3f>& normals) {
  Vec3d sum = Vec3d::Zero();
  for (uint32_t p : members) sum += normals[p].cast<double>();
  double len = sum.norm();
  return len > 1e-9 * double(members.size()) ? Vec3f((sum / len).cast<float>()) : Vec3f::Zero();
}

/// Largest ||nc - n_j||^2 and the member closest to nc (ties: smallest index).
std::pair<float, uint32_t> variation(const std::vector<uint32_t>& members, const Vec3f& nc,
                                     const std::vector<Vec3f>& normals) {
  float vmax = 0, vmin = std::numeric_limits<float>::infinity();
  uint32_t closest = members[0];
  for (uint32_t p : members) {
    float v = (nc - normals[p]).squaredNorm();
    vmax = std::max(vmax, v);
    if (v < vmin) vmin = v, closest = p;
  }
  return {vmax, closest};
}

WorkResult processWork(const Work& w, uint32_t workIndex, const SplitContext& ctx) {
  WorkResult res;
  const auto& normals = ctx.normals;
  // Accept when either the normal of its last growth or its average normal meets delta_n.
  Vec3f avg = averageNormal(w.members, normals);
  float bestV = std::numeric_limits<float>::infinity();
  Vec3f bestN = Vec3f::Zero();
  uint32_t bestSeed = w.members[0];
  if (valid(w.seedNormal)) {
    auto [v, closest] = variation(w.members, w.seedNormal, normals);
    bestV = v, bestN = w.seedNormal, bestSeed = w.seed != kNone ? w.seed : closest;
  }
  if (valid(avg)) {
    auto [v, closest] = variation(w.members, avg, normals);
    if (v < bestV) bestV = v, bestN = avg, bestSeed = closest;
  }
  if (bestV <= ctx.delta || w.members.size() < 2) {
    res.accepted = true;
    res.cluster.members = w.members;
    res.cluster.normal = valid(bestN) ? bestN : normals[w.members[0]];
    res.cluster.seed = bestSeed;
    return res;
  }

  // Two-way split (§3.2.3.2). Local indices: position inside w.members.
  const size_t m = w.members.size();
  uint64_t state = splitmix64(ctx.seed ^ splitmix64(uint64_t(w.members[0]) * 0x100000001b3ULL + m));
  auto nextRandom = [&](uint64_t bound) {
    state = splitmix64(state);
    return state % bound;
  };
  uint32_t seeds[2];
  if (ctx.seeding == SplitSeeding::Random) {
    seeds[0] = uint32_t(nextRandom(m));
    seeds[1] = uint32_t(nextRandom(m - 1));
    if (seeds[1] >= seeds[0]) ++seeds[1];
  } else {
    // Normal extremes: from a random member r, t = the member whose normal is farthest from n_r,
    // s = the member farthest from n_t (ties: lowest index). Seeds at the two ends of the normal
    // distribution split the cluster where it bends, not by chance.
    auto farthestFrom = [&](uint32_t from) {
      const Vec3f nf = normals[w.members[from]];
      float best = -1;
      uint32_t arg = from;
      for (size_t i = 0; i < m; ++i) {
        float v = (normals[w.members[i]] - nf).squaredNorm();
        if (v > best) best = v, arg = uint32_t(i);
      }
      return arg;
    };
    seeds[1] = farthestFrom(uint32_t(nextRandom(m)));
    seeds[0] = farthestFrom(seeds[1]);
    if (seeds[0] == seeds[1]) seeds[0] = seeds[1] == 0 ? 1 : 0;  // all normals equal (cannot violate delta_n)
  }
  Vec3f seedN[2] = {normals[w.members[seeds[0]]], normals[w.members[seeds[1]]]};

  // Local copies of the normals and of the graph restricted to the cluster: the growths below
  // then touch only small contiguous arrays.
  std::vector<Vec3f> ln(m);
  std::vector<uint32_t> adjOffsets(m + 1, 0), adj;
  adj.reserve(m * 7);
  for (size_t i = 0; i < m; ++i) {
    ln[i] = normals[w.members[i]];
    for (uint32_t q : ctx.graph.of(w.members[i]))
      if (ctx.workOf[q] == workIndex) adj.push_back(ctx.slot[q]);
    adjOffsets[i + 1] = uint32_t(adj.size());
  }

  std::vector<int8_t> lab(m);
  std::vector<uint8_t> pushed(m);
  // Queue entries packed in one integer: V_n's bits (order-preserving for V_n >= 0), then the local
  // index, then b: the smallest V_n pops first, ties by index and cluster, deterministically.
  QuadHeap pq;
  auto pack = [](float v, uint32_t local, uint32_t b) {
    uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    return (uint64_t(bits) << 32) | (uint64_t(local) << 1) | b;
  };
  auto pushNeighbours = [&](uint32_t local, uint8_t b) {
    for (uint32_t e = adjOffsets[local]; e < adjOffsets[local + 1]; ++e) {
      const uint32_t lq = adj[e];
      if (lab[lq] >= 0 || (pushed[lq] & (1u << b))) continue;
      pushed[lq] |= uint8_t(1u << b);
      pq.push(pack((ln[lq] - seedN[b]).squaredNorm(), lq, b));
    }
  };

  Vec3f usedN[2];
  uint32_t usedSeeds[2];
  for (int iter = 1;; ++iter) {
    ++res.iterations;
    std::fill(lab.begin(), lab.end(), int8_t(-1));
    std::fill(pushed.begin(), pushed.end(), uint8_t(0));
    for (int b = 0; b < 2; ++b) lab[seeds[b]] = int8_t(b);
    for (uint8_t b = 0; b < 2; ++b) pushNeighbours(seeds[b], b);
    while (!pq.empty()) {
      const uint64_t top = pq.pop();
      const uint32_t lq = uint32_t(top & 0xffffffffu) >> 1;
      const uint8_t b = uint8_t(top & 1u);
      if (lab[lq] >= 0) continue;
      lab[lq] = int8_t(b);
      pushNeighbours(lq, b);
    }
    // A work item is connected, so every member is reached; guard anyway.
    for (auto& l : lab)
      if (l < 0) l = 0;
    usedN[0] = seedN[0], usedN[1] = seedN[1];
    usedSeeds[0] = seeds[0], usedSeeds[1] = seeds[1];

    // Reseed from the average normal n'(C_b); new seed: the member closest to it.
    Vec3d sum[2] = {Vec3d::Zero(), Vec3d::Zero()};
    for (size_t i = 0; i < m; ++i) sum[lab[i]] += ln[i].cast<double>();
    uint32_t newSeeds[2] = {seeds[0], seeds[1]};
    Vec3f newN[2] = {seedN[0], seedN[1]};
    float best[2] = {std::numeric_limits<float>::infinity(), std::numeric_limits<float>::infinity()};
    for (int b = 0; b < 2; ++b)
      if (sum[b].norm() > 1e-12) newN[b] = Vec3f(sum[b].normalized().cast<float>());
    for (size_t i = 0; i < m; ++i) {
      int b = lab[i];
      float v = (ln[i] - newN[b]).squaredNorm();
      if (v < best[b]) best[b] = v, newSeeds[b] = uint32_t(i);
    }
    if (newSeeds[0] == seeds[0] && newSeeds[1] == seeds[1]) break;
    if (iter >= ctx.maxIterations) {
      res.capReached = true;
      break;
    }
    seeds[0] = newSeeds[0], seeds[1] = newSeeds[1];
    seedN[0] = newN[0], seedN[1] = newN[1];
  }

  for (int b = 0; b < 2; ++b) {
    res.children[b].seedNormal = usedN[b];
    res.children[b].seed = w.members[usedSeeds[b]];
  }
  for (size_t i = 0; i < m; ++i) res.children[lab[i]].members.push_back(w.members[i]);
  return res;
}

}  // namespace

Clustering clusterHierarchical(const PointGeometry& geometry, const ClusteringOptions& options) {
  validate(options);
  const size_t n = geometry.size();
  size_t zeroNormals = 0;
  const std::vector<Vec3f> normals = usableNormals(geometry, zeroNormals);
  const Graph graph = buildGraph(geometry);

  // Initial clusters: connected components of the graph over points with usable normals.
  std::vector<RawCluster> finished;
  std::vector<Work> level;
  size_t components = 0;
  {
    std::vector<uint8_t> seen(n, 0);
    std::vector<uint32_t> stack;
    for (size_t i = 0; i < n; ++i) {
      if (seen[i]) continue;
      seen[i] = 1;
      ++components;
      if (!valid(normals[i])) {
        RawCluster rc;
        rc.members = {uint32_t(i)};
        rc.seed = uint32_t(i);
        finished.push_back(std::move(rc));
        continue;
      }
      Work w;
      stack.assign(1, uint32_t(i));
      while (!stack.empty()) {
        uint32_t p = stack.back();
        stack.pop_back();
        w.members.push_back(p);
        for (uint32_t q : graph.of(p))
          if (!seen[q] && valid(normals[q])) seen[q] = 1, stack.push_back(q);
      }
      std::sort(w.members.begin(), w.members.end());
      level.push_back(std::move(w));
    }
  }

  // workOf holds ids unique over all levels (levelBase + index), so stale entries of points in
  // clusters accepted earlier never match a current work item.
  std::vector<uint32_t> workOf(n, kNone), slot(n, 0);
  uint32_t levelBase = 0;
  Clustering stats;
  size_t acceptedPoints = 0;
  for (auto& f : finished) acceptedPoints += f.members.size();
  while (!level.empty()) {
    parallelFor(0, level.size(), [&](size_t w) {
      const auto& members = level[w].members;
      for (size_t i = 0; i < members.size(); ++i) workOf[members[i]] = levelBase + uint32_t(w), slot[members[i]] = uint32_t(i);
    }, 16);
    std::vector<WorkResult> results(level.size());
    SplitContext ctx{graph, normals, workOf, slot, options.deltaN, options.maxIterations, options.seed,
                     options.seeding};
    // Large clusters first in each chunk is not needed: grain 1 lets TBB balance uneven splits.
    parallelFor(0, level.size(), [&](size_t w) { results[w] = processWork(level[w], levelBase + uint32_t(w), ctx); }, 1);
    levelBase += uint32_t(level.size());
    std::vector<Work> next;
    for (auto& r : results) {
      stats.iterations += r.iterations;
      if (r.capReached) ++stats.capReached;
      if (r.accepted) {
        acceptedPoints += r.cluster.members.size();
        finished.push_back(std::move(r.cluster));
      } else {
        ++stats.splits;
        next.push_back(std::move(r.children[0]));
        next.push_back(std::move(r.children[1]));
      }
    }
    level = std::move(next);
    reportProgress(options.progress, "hierarchical clustering", double(acceptedPoints) / double(std::max<size_t>(n, 1)));
  }
  reportProgress(options.progress, "hierarchical clustering", 1.0);
  Clustering c = finalize(std::move(finished), normals, n);
  c.splits = stats.splits;
  c.iterations = stats.iterations;
  c.capReached = stats.capReached;
  c.components = components;
  c.zeroNormals = zeroNormals;
  return c;
}

// ---------------------------------------------------------------------------------------------

float clusterMaxVariation(const Clustering& clustering, const PointGeometry& geometry, size_t c) {
  const Vec3f& nc = clustering.seedingNormals[c];
  float vmax = 0;
  for (uint32_t p : clustering.membersOf(c)) {
    Vec3f np = geometry.normals[p];
    float len = np.norm();
    np = std::isfinite(len) && len > 0.5f ? Vec3f(np / len) : Vec3f::Zero();
    vmax = std::max(vmax, (nc - np).squaredNorm());
  }
  return vmax;
}

Color clusterColor(size_t id) {
  // Golden-angle hue steps; saturation and value cycle through three levels.
  const double goldenRatioConjugate = 0.6180339887498949;
  double h = std::fmod(0.11 + double(id) * goldenRatioConjugate, 1.0) * 6.0;
  static const float sat[3] = {0.85f, 0.55f, 0.95f}, val[3] = {0.95f, 0.80f, 0.65f};
  float s = sat[id % 3], v = val[(id / 3) % 3];
  int sector = int(h) % 6;
  float f = float(h - std::floor(h));
  float p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  switch (sector) {
    case 0: return Color(v, t, p, 1);
    case 1: return Color(q, v, p, 1);
    case 2: return Color(p, v, t, 1);
    case 3: return Color(p, q, v, 1);
    case 4: return Color(t, p, v, 1);
    default: return Color(v, p, q, 1);
  }
}

HybridModel colorByCluster(const HybridModel& cloud, const PointGeometry& geometry, const Clustering& clustering) {
  HybridModel out;
  out.points = cloud.points;
  out.pointShadingNormals = cloud.pointShadingNormals;  // with attributes.shadingNormals
  out.attributes = cloud.attributes;
  out.attributes.texcoords = false;
  for (size_t i = 0; i < out.points.size(); ++i) {
    Point& p = out.points[i];
    if (i < geometry.normals.size()) p.normal = geometry.normals[i];
    if (p.radius <= 0 && i < geometry.spacing.size()) p.radius = geometry.spacing[i];
    if (i < clustering.labels.size()) p.color = clusterColor(clustering.labels[i]);
  }
  out.attributes.normals = !geometry.normals.empty() || cloud.attributes.normals;
  out.attributes.colors = true;
  out.attributes.radii = cloud.attributes.radii || !geometry.spacing.empty();
  out.comments = cloud.comments;
  out.comments.push_back("linesurf: points coloured by shape-approximation cluster (" +
                         std::to_string(clustering.size()) + " clusters)");
  return out;
}

}  // namespace linesurf
