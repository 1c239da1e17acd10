// Feature lines of a point cloud (thesis §9.5): crease samples where the tangent planes of
// neighbours on the two sides of a crease meet, chained by a minimum spanning forest and
// simplified into segments. See include/linesurf/extract/feature_lines.h.
#include "linesurf/extract/feature_lines.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <tuple>
#include <vector>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/surface/mls.h"
#include "../surface/detail/point_tree.h"

namespace linesurf {
namespace {

constexpr double kDegree = 3.14159265358979323846 / 180.0;
/// Linked samples: directions within 30 degrees, and each lies along the other's direction.
const double kLinkCos = std::cos(30 * kDegree);
/// Side branches of the spanning forest shorter than this many spacings are cut.
constexpr double kSpur = 3;

struct CreaseSample {
  Vec3d position = Vec3d::Zero();
  Vec3d direction = Vec3d::Zero();  ///< unit, along the crease
  Vec3d normal = Vec3d::Zero();     ///< sum of the two sides' unit normals
};

/// The point nearest m on the line where the planes n_i.x = n_i.p_i and n_j.x = n_j.p_j meet.
bool planesMeet(const Vec3d& pi, const Vec3d& ni, const Vec3d& pj, const Vec3d& nj, CreaseSample& out) {
  const Vec3d m = 0.5 * (pi + pj);
  const double g = ni.dot(nj), det = 1 - g * g;
  if (!(det > 1e-3)) return false;  // (anti)parallel planes
  const double ei = ni.dot(pi - m), ej = nj.dot(pj - m);
  const double a = (ei - g * ej) / det, b = (ej - g * ei) / det;
  out.position = m + a * ni + b * nj;
  out.direction = ni.cross(nj).normalized();
  out.normal = ni + nj;
  return true;
}

struct UnionFind {
  std::vector<uint32_t> parent;
  explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
  uint32_t find(uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  }
  bool unite(uint32_t a, uint32_t b) {
    a = find(a), b = find(b);
    if (a == b) return false;
    parent[std::max(a, b)] = std::min(a, b);
    return true;
  }
};

/// Douglas-Peucker over polyline[first..last]: marks the vertices kept.
void simplify(const std::vector<Vec3d>& line, size_t first, size_t last, double tol, std::vector<char>& keep) {
  if (last <= first + 1) return;
  const Vec3d a = line[first], d = line[last] - a;
  const double len2 = d.squaredNorm();
  double worst = -1;
  size_t at = first;
  for (size_t i = first + 1; i < last; ++i) {
    const Vec3d r = line[i] - a;
    const double dist = len2 > 0 ? (r - (r.dot(d) / len2) * d).norm() : r.norm();
    if (dist > worst) worst = dist, at = i;
  }
  if (worst <= tol) return;
  keep[at] = 1;
  simplify(line, first, at, tol, keep);
  simplify(line, at, last, tol, keep);
}

}  // namespace

void validate(const FeatureLineOptions& o) {
  requireRange("angle", o.angle, 5, 170);
  requireRange("linkRadius", o.linkRadius, 1, 8);
  requireRange("minLength", o.minLength, 0, 1e6);
  requireRange("tolerance", o.tolerance, 0, 10);
  requireRange("supportScale", o.supportScale, 1.5, 10);
}

HybridModel extractFeatureLines(const HybridModel& cloud, const FeatureLineOptions& o, FeatureLineStats* statsOut) {
  validate(o);
  const size_t n = cloud.points.size();
  if (!cloud.attributes.normals) throwBadParameter("model", "has no normals (run `linesurf normals` first)");
  if (n < 8) throwBadParameter("model", "has " + std::to_string(n) + " points; feature lines need at least 8");
  for (const Point& p : cloud.points)
    if (!p.position.allFinite()) throwBadParameter("model", "has a point with a non-finite position");
  FeatureLineStats st;
  st.points = n;

  // 1. Spacing and sharp normals.
  Timer t;
  detail::PointCloud pc;
  pc.pts.reserve(n);
  for (const Point& p : cloud.points) pc.pts.push_back(p.position);
  detail::PointTree tree(3, pc, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  std::vector<float> nearest(n);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      std::array<uint32_t, 2> idx{};
      std::array<float, 2> d2{};
      tree.knnSearch(pc.pts[i].data(), 2, idx.data(), d2.data());
      nearest[i] = std::sqrt(d2[1]);
    }
  });
  std::vector<float> sorted = nearest;
  std::nth_element(sorted.begin(), sorted.begin() + long(n / 2), sorted.end());
  const double s = sorted[n / 2];
  st.spacing = s;
  if (!(s > 0)) throwBadParameter("model", "has no spacing (every point coincides with another)");
  std::vector<Vec3d> normal(n);
  for (size_t i = 0; i < n; ++i) normal[i] = cloud.points[i].normal.cast<double>().normalized();
  if (o.robustNormals) {
    MlsOptions mo;
    mo.robust = true;
    mo.supportScale = o.supportScale;
    // Sharper than RIMLS's smoothing default: a 30-degree crease's two sides keep a tenth of each
    // other's weight (0.75 leaves them 60% and the normals blend across the band).
    mo.sigmaNormal = 0.35f;
    HybridModel points;
    points.points = cloud.points;
    points.attributes.normals = true;
    const MlsSurface surface(points, mo);
    parallelForRange(0, n, [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) {
        const MlsProjection p = surface.project(pc.pts[i].cast<double>());
        if (p.converged && p.normal.dot(normal[i]) > 0) normal[i] = p.normal;
      }
    }, 64);
  }
  st.normalSeconds = t.seconds();

  // 2. Crease samples from the pairs across a crease, one slot per point (the order of the points).
  t = Timer();
  const double radius = o.linkRadius * s, cosAngle = std::cos(o.angle * kDegree);
  std::vector<std::vector<CreaseSample>> found(n);
  nanoflann::SearchParams unsorted;
  unsorted.sorted = false;
  parallelForRange(0, n, [&](size_t b, size_t e) {
    std::vector<std::pair<uint32_t, float>> near;
    for (size_t i = b; i < e; ++i) {
      near.clear();
      tree.radiusSearch(pc.pts[i].data(), float(radius * radius), near, unsorted);
      std::sort(near.begin(), near.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
      const Vec3d pi = pc.pts[i].cast<double>();
      for (const auto& r : near) {
        const uint32_t j = r.first;
        if (j <= i || !(normal[i].dot(normal[j]) < cosAngle)) continue;
        CreaseSample c;
        const Vec3d pj = pc.pts[j].cast<double>();
        if (!planesMeet(pi, normal[i], pj, normal[j], c)) continue;
        if ((c.position - pi).norm() > radius || (c.position - pj).norm() > radius) continue;
        found[i].push_back(c);
      }
    }
  }, 128);
  // Averaged per cell of one spacing, directions aligned with the cell's first sample.
  std::vector<std::tuple<std::array<int64_t, 3>, size_t, size_t>> keyed;  // cell, point, index
  for (size_t i = 0; i < n; ++i)
    for (size_t k = 0; k < found[i].size(); ++k) {
      const Vec3d& x = found[i][k].position;
      keyed.emplace_back(std::array<int64_t, 3>{int64_t(std::floor(x.x() / s)), int64_t(std::floor(x.y() / s)),
                                                int64_t(std::floor(x.z() / s))},
                         i, k);
    }
  st.creasePairs = keyed.size();
  std::sort(keyed.begin(), keyed.end());
  std::vector<CreaseSample> samples;
  for (size_t a = 0; a < keyed.size();) {
    size_t b = a;
    CreaseSample sum;
    const Vec3d first = found[std::get<1>(keyed[a])][std::get<2>(keyed[a])].direction;
    while (b < keyed.size() && std::get<0>(keyed[b]) == std::get<0>(keyed[a])) {
      const CreaseSample& c = found[std::get<1>(keyed[b])][std::get<2>(keyed[b])];
      sum.position += c.position;
      sum.direction += c.direction.dot(first) < 0 ? Vec3d(-c.direction) : c.direction;
      sum.normal += c.normal;
      ++b;
    }
    sum.position /= double(b - a);
    if (sum.direction.norm() > 0) {
      sum.direction.normalize();
      samples.push_back(sum);
    }
    a = b;
  }
  st.samples = samples.size();
  st.sampleSeconds = t.seconds();

  // 3. Links along the crease, their minimum spanning forest, polylines between branch points.
  t = Timer();
  HybridModel out;
  out.attributes.normals = true;
  out.attributes.radii = true;
  if (samples.size() >= 2) {
    detail::PointCloud sc;
    for (const CreaseSample& c : samples) sc.pts.push_back(c.position.cast<float>());
    detail::PointTree stree(3, sc, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    stree.buildIndex();
    std::vector<std::tuple<double, uint32_t, uint32_t>> links;
    std::vector<std::pair<uint32_t, float>> near;
    for (uint32_t a = 0; a < samples.size(); ++a) {
      near.clear();
      stree.radiusSearch(sc.pts[a].data(), float(radius * radius), near, unsorted);
      for (const auto& r : near) {
        const uint32_t b = r.first;
        if (b <= a) continue;
        const Vec3d v = samples[b].position - samples[a].position;
        const double len = v.norm();
        if (!(len > 0)) continue;
        if (std::abs(samples[a].direction.dot(samples[b].direction)) < kLinkCos) continue;
        if (std::abs(v.dot(samples[a].direction)) < kLinkCos * len || std::abs(v.dot(samples[b].direction)) < kLinkCos * len)
          continue;
        links.emplace_back(len, a, b);
      }
    }
    std::sort(links.begin(), links.end());
    UnionFind uf(samples.size());
    std::vector<std::vector<uint32_t>> adj(samples.size());
    for (const auto& [len, a, b] : links)
      if (uf.unite(a, b)) adj[a].push_back(b), adj[b].push_back(a);
    // Spurs: the forest of a crease a few samples wide branches off sideways; a leaf's branch
    // shorter than `kSpur` spacings up to the first branch point is cut, until none is left.
    auto erase = [&](uint32_t a, uint32_t b) { adj[a].erase(std::find(adj[a].begin(), adj[a].end(), b)); };
    for (bool cut = true; cut;) {
      cut = false;
      for (uint32_t leaf = 0; leaf < samples.size(); ++leaf) {
        if (adj[leaf].size() != 1) continue;
        std::vector<uint32_t> path{leaf};
        uint32_t prev = leaf, cur = adj[leaf][0];
        double len = (samples[cur].position - samples[leaf].position).norm();
        while (adj[cur].size() == 2) {
          const uint32_t next = adj[cur][0] == prev ? adj[cur][1] : adj[cur][0];
          path.push_back(cur);
          len += (samples[next].position - samples[cur].position).norm();
          prev = cur, cur = next;
        }
        if (adj[cur].size() < 3 || len >= kSpur * s) continue;  // a whole polyline, or a real branch
        path.push_back(cur);
        for (size_t q = 0; q + 1 < path.size(); ++q) erase(path[q], path[q + 1]), erase(path[q + 1], path[q]);
        cut = true;
      }
    }
    for (auto& l : adj) std::sort(l.begin(), l.end());
    // Walk from every end or branch point along each of its edges to the next such point.
    std::vector<std::vector<char>> used(samples.size());
    for (size_t a = 0; a < samples.size(); ++a) used[a].assign(adj[a].size(), 0);
    auto markUsed = [&](uint32_t a, uint32_t b) {
      for (size_t k = 0; k < adj[a].size(); ++k)
        if (adj[a][k] == b) used[a][k] = 1;
    };
    const double minLength = o.minLength * s, tol = o.tolerance * s;
    for (uint32_t start = 0; start < samples.size(); ++start) {
      if (adj[start].size() == 2 || adj[start].empty()) continue;
      for (size_t k = 0; k < adj[start].size(); ++k) {
        if (used[start][k]) continue;
        std::vector<uint32_t> chain{start};
        uint32_t prev = start, cur = adj[start][k];
        markUsed(start, cur), markUsed(cur, start);
        chain.push_back(cur);
        while (adj[cur].size() == 2) {
          const uint32_t next = adj[cur][0] == prev ? adj[cur][1] : adj[cur][0];
          markUsed(cur, next), markUsed(next, cur);
          prev = cur, cur = next;
          chain.push_back(cur);
        }
        std::vector<Vec3d> line;
        double length = 0;
        for (size_t c = 0; c < chain.size(); ++c) {
          line.push_back(samples[chain[c]].position);
          if (c > 0) length += (line[c] - line[c - 1]).norm();
        }
        if (length < minLength) continue;
        std::vector<char> keep(line.size(), 0);
        keep.front() = keep.back() = 1;
        simplify(line, 0, line.size() - 1, tol, keep);
        size_t from = 0;
        for (size_t c = 1; c < line.size(); ++c) {
          if (!keep[c]) continue;
          Segment sg;
          sg.p0 = line[from].cast<float>(), sg.p1 = line[c].cast<float>();
          const Vec3d d = (line[c] - line[from]).normalized();
          Vec3d nrm = Vec3d::Zero();
          for (size_t q = from; q <= c; ++q) nrm += samples[chain[q]].normal;
          nrm -= nrm.dot(d) * d;
          if (!(nrm.norm() > 1e-9)) nrm = d.unitOrthogonal();
          sg.normal = nrm.normalized().cast<float>();
          sg.radius = float(0.5 * s);
          if (sg.length() > 0) out.segments.push_back(sg), st.length += double(sg.length());
          from = c;
        }
        ++st.polylines;
      }
    }
  }
  st.segments = out.segments.size();
  st.chainSeconds = t.seconds();
  if (statsOut) *statsOut = st;
  return out;
}

}  // namespace linesurf
