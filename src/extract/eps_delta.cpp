// (epsilon, delta) error-bounded line segment extraction, thesis §3.1.4.
// Decisions (eager definition, radius rule, tie-breaks): docs/decisions.md
// "(ε,δ) extraction (§3.1)".
#include "linesurf/extract/eps_delta.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <queue>
#include <utility>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/geometry/noise.h"
#include "detail/endpoint_normals.h"
#include "detail/segment_attributes.h"
#include "detail/segment_width.h"

namespace linesurf {
namespace {

// One grown direction L_k(p_i), stored on the full cloud: the replaced indices sorted by their
// position t along the line (ties by index), with t as float bits right after them.
// Layout in a per-anchor flat array: [k, m, idx_0..idx_{m-1}, tbits_0..tbits_{m-1}].
constexpr size_t kHeader = 2;

struct DirectionView {
  uint32_t k = 0, m = 0;
  const uint32_t* idx = nullptr;
  const uint32_t* tbits = nullptr;
  float t(size_t a) const {
    float f;
    std::memcpy(&f, tbits + a, sizeof f);
    return f;
  }
};

template <class F>
void forEachDirection(const std::vector<uint32_t>& rec, F&& f) {
  size_t pos = 0;
  while (pos < rec.size()) {
    DirectionView v;
    v.k = rec[pos];
    v.m = rec[pos + 1];
    v.idx = rec.data() + pos + kHeader;
    v.tbits = v.idx + v.m;
    f(v);
    pos += kHeader + 2 * size_t(v.m);
  }
}

// Line through the anchor on its tangent plane, towards the projection of p_k (§3.1.4).
struct Line {
  Vec3d origin, dir;
};

bool seedLine(const Vec3d& pi, const Vec3d& ni, const Vec3d& pk, Line& line) {
  Vec3d v = pk - pi;
  Vec3d proj = v - v.dot(ni) * ni;
  double len = proj.norm();
  if (!(len > 1e-12 * std::max(1.0, v.norm()))) return false;
  line.origin = pi;
  line.dir = proj / len;
  return true;
}

inline bool normalOk(const Vec3f& ni, const Vec3f& nj, float delta) { return 1.0f - ni.dot(nj) <= delta; }

// Per-thread scratch for growing one direction.
struct Grower {
  std::vector<uint32_t> stamp;
  uint32_t epoch = 0;
  struct Cand {
    double dist, t;
    uint32_t idx;
  };
  std::vector<Cand> heap;
  std::vector<std::pair<double, uint32_t>> taken;  // (t, index)

  void begin(size_t n) {
    if (stamp.size() < n) stamp.assign(n, 0), epoch = 0;
    if (++epoch == 0) {
      std::fill(stamp.begin(), stamp.end(), 0);
      epoch = 1;
    }
    heap.clear();
    taken.clear();
  }
};

struct CandGreater {  // min-heap on (distance to the line, index)
  bool operator()(const Grower::Cand& a, const Grower::Cand& b) const {
    return a.dist != b.dist ? a.dist > b.dist : a.idx > b.idx;
  }
};

struct Context {
  const HybridModel& cloud;
  const PointGeometry& geo;
  double eps;
  float delta;
  int minReplaced;
  int maxReplaced;
  std::vector<Vec3d> pos;
};

// Grows L_k(p_i) (§3.1.4); fills g.taken sorted by (t, index). Returns false if p_k does not seed.
bool growDirection(const Context& c, uint32_t i, uint32_t k, Grower& g, bool& degenerate) {
  degenerate = false;
  const Vec3f& ni = c.geo.normals[i];
  if (!normalOk(ni, c.geo.normals[k], c.delta)) return false;
  const Vec3d nid = ni.cast<double>();
  const Vec3d& pi = c.pos[i];
  // The seed neighbour must lie within epsilon of p_i's tangent plane (= of the line it defines).
  if (std::abs((c.pos[k] - pi).dot(nid)) > c.eps) return false;
  Line line;
  if (!seedLine(pi, nid, c.pos[k], line)) {
    degenerate = true;
    return false;
  }
  const size_t n = c.pos.size();
  g.begin(n);
  double tmin = 0, tmax = 0;
  bool stopLo = false, stopHi = false;
  auto push = [&](uint32_t j) {
    if (j >= n || g.stamp[j] == g.epoch) return;
    g.stamp[j] = g.epoch;
    Vec3d w = c.pos[j] - line.origin;
    double t = w.dot(line.dir);
    double dist2 = (w - t * line.dir).squaredNorm();
    // A candidate beyond epsilon is never taken, and it is popped only once no candidate within
    // epsilon is left (the heap is ordered by distance), when growth is over anyway: skip it.
    if (dist2 > c.eps * c.eps) return;
    g.heap.push_back({std::sqrt(dist2), t, j});
    std::push_heap(g.heap.begin(), g.heap.end(), CandGreater{});
  };
  auto take = [&](uint32_t j, double t) {
    g.taken.emplace_back(t, j);
    tmin = std::min(tmin, t);
    tmax = std::max(tmax, t);
    for (uint32_t nb : c.geo.delaunayOf(j)) push(nb);
  };
  g.stamp[i] = g.epoch;
  g.stamp[k] = g.epoch;
  take(i, 0.0);
  take(k, (c.pos[k] - pi).dot(line.dir));
  const size_t cap = c.maxReplaced > 0 ? size_t(c.maxReplaced) : SIZE_MAX;
  while (!g.heap.empty() && g.taken.size() < cap) {
    std::pop_heap(g.heap.begin(), g.heap.end(), CandGreater{});
    const Grower::Cand cand = g.heap.back();
    g.heap.pop_back();
    const int side = cand.t < tmin ? -1 : (cand.t > tmax ? 1 : 0);
    if ((side < 0 && stopLo) || (side > 0 && stopHi)) continue;
    if (normalOk(ni, c.geo.normals[cand.idx], c.delta)) {
      take(cand.idx, cand.t);
    } else {
      if (side < 0) stopLo = true;
      if (side > 0) stopHi = true;
      if (stopLo && stopHi) break;
    }
  }
  std::sort(g.taken.begin(), g.taken.end());
  return true;
}

// Best direction of an anchor restricted to the available points (the eager definition).
struct Choice {
  uint32_t count = 0;
  uint32_t k = 0;
  size_t offset = 0;  // of the direction record inside the anchor's array
};

Choice evaluate(const std::vector<uint32_t>& rec, const std::vector<uint8_t>& avail, uint32_t anchor,
                int minReplaced, float minLength) {
  Choice best;
  if (!avail[anchor]) return best;
  size_t pos = 0;
  forEachDirection(rec, [&](const DirectionView& v) {
    uint32_t count = 0;
    float lo = 0, hi = 0;
    for (uint32_t a = 0; a < v.m; ++a) {
      if (!avail[v.idx[a]]) continue;
      if (count == 0) lo = v.t(a);
      hi = v.t(a);
      ++count;
    }
    // Degenerate (zero-length) remainders count as nothing; extents only shrink, so this keeps
    // the count monotone under removals, which the lazy heap relies on.
    if (hi - lo < minLength) count = 0;
    if (count >= uint32_t(minReplaced) && (count > best.count || (count == best.count && v.k < best.k))) {
      best.count = count;
      best.k = v.k;
      best.offset = pos;
    }
    pos += kHeader + 2 * size_t(v.m);
  });
  return best;
}

}  // namespace

void validate(const EpsDeltaOptions& o) {
  if (!(o.epsilon >= 0 && o.epsilon <= 1e30))
    throwBadOption("epsilon", "must be a finite distance in [0, 1e30] (0 = use `epsilonRelative`), got " + numberText(o.epsilon));
  if (o.epsilon == 0 && !(o.epsilonRelative > 0 && o.epsilonRelative <= 1e6))
    throwBadOption("epsilonRelative", "must be a fraction of the average spacing in (0, 1e6], got " + numberText(o.epsilonRelative));
  if (!(o.epsilonNoise >= 0 && o.epsilonNoise <= 100))
    throwBadOption("epsilonNoise", "must be a multiple of the noise in [0, 100] (0 = off), got " + numberText(o.epsilonNoise));
  if (!(o.delta >= 0 && o.delta <= 2))
    throwBadOption("delta", "must lie in [0, 2] (it bounds 1 - n_i.n_j), got " + numberText(o.delta));
  if (o.minReplaced < 2) throwBadOption("minReplaced", "must be >= 2, got " + std::to_string(o.minReplaced));
  if (o.maxReplaced != 0 && o.maxReplaced < o.minReplaced)
    throwBadOption("maxReplaced", "must be 0 (no limit) or >= `minReplaced` (" + std::to_string(o.minReplaced) +
                                          "), got " + std::to_string(o.maxReplaced));
}

double resolveEpsilon(const EpsDeltaOptions& options, const PointGeometry& geometry, const HybridModel& cloud,
                      double* noiseSigma) {
  validate(options);
  if (noiseSigma) *noiseSigma = 0;
  if (options.epsilon > 0) return options.epsilon;
  const double relative = options.epsilonRelative * double(geometry.averageSpacing);
  if (options.epsilonNoise <= 0) return relative;
  const double sigma = estimateNoise(cloud).sigma;
  if (noiseSigma) *noiseSigma = sigma;
  return std::max(relative, options.epsilonNoise * sigma);
}

HybridModel extractEpsDelta(const HybridModel& cloud, const PointGeometry& geometry, const EpsDeltaOptions& options,
                            EpsDeltaStats* statsOut) {
  validate(options);
  const size_t n = cloud.points.size();
  if (n >= UINT32_MAX) throwBadParameter("cloud", "too many points for 32-bit indices");
  if (geometry.size() != n)
    throwBadParameter("geometry", "computed for " + std::to_string(geometry.size()) + " points, the cloud has " +
                                      std::to_string(n));
  if (n > 0 && geometry.delaunayOffsets.size() != n + 1)
    throwBadParameter("geometry", "has no local Delaunay neighbours (GeometryOptions::delaunayNeighbours)");
  EpsDeltaStats stats;
  const double eps = resolveEpsilon(options, geometry, cloud, &stats.noiseSigma);
  stats.inputPoints = n;
  stats.epsilon = eps;
  stats.delta = options.delta;

  Context ctx{cloud, geometry, eps, float(options.delta), options.minReplaced, options.maxReplaced, {}};
  ctx.pos.resize(n);
  Bounds3f box;
  for (size_t i = 0; i < n; ++i) {
    ctx.pos[i] = cloud.points[i].position.cast<double>();
    box.extend(cloud.points[i].position);
  }
  const float minLength = n ? 1e-6f * std::max(box.diagonal().norm(), 1e-30f) : 0.0f;

  // Stage 1 (parallel): every anchor's grown directions with >= minReplaced points.
  Timer timer;
  std::vector<std::vector<uint32_t>> records(n);
  std::vector<uint32_t> seeds(n, 0), degenerate(n, 0);
  const size_t block = 16384;
  for (size_t b0 = 0; b0 < n; b0 += block) {
    const size_t b1 = std::min(n, b0 + block);
    parallelFor(b0, b1, [&](size_t ii) {
      thread_local Grower g;
      thread_local std::vector<uint32_t> rec;  // built here, copied once into the anchor's slot
      rec.clear();
      const uint32_t i = uint32_t(ii);
      auto nbs = geometry.delaunayOf(i);
      for (size_t a = 0; a < nbs.size(); ++a) {
        const uint32_t k = nbs[a];
        if (k >= n || k == i) continue;
        if (std::find(nbs.begin(), nbs.begin() + a, k) != nbs.begin() + a) continue;  // duplicate
        bool degen = false;
        if (!growDirection(ctx, i, k, g, degen)) {
          degenerate[i] += degen;
          continue;
        }
        ++seeds[i];
        if (g.taken.size() < size_t(options.minReplaced)) continue;
        const uint32_t m = uint32_t(g.taken.size());
        rec.push_back(k);
        rec.push_back(m);
        for (auto& [t, j] : g.taken) rec.push_back(j);
        for (auto& [t, j] : g.taken) {
          float f = float(t);
          uint32_t bits;
          std::memcpy(&bits, &f, sizeof bits);
          rec.push_back(bits);
        }
      }
      if (!rec.empty()) records[i].assign(rec.begin(), rec.end());
    }, 64);
    reportProgress(options.progress, "eps-delta: grow segments", double(b1) / double(n));
  }
  for (size_t i = 0; i < n; ++i) {
    stats.seedDirections += seeds[i];
    stats.degenerateNeighbours += degenerate[i];
    forEachDirection(records[i], [&](const DirectionView& v) {
      ++stats.candidateDirections;
      stats.candidateMembers += v.m;
    });
  }
  stats.growSeconds = timer.seconds();

  // Stage 2 (sequential): greedy selection with the heap of L_max(p_i) by count (§3.1.4).
  timer.reset();
  std::vector<uint8_t> avail(n, 1);
  struct Pick {
    uint32_t anchor;
    Choice choice;
  };
  std::vector<Pick> picks;
  auto removePoints = [&](uint32_t anchor, const Choice& ch) {
    forEachDirection(records[anchor], [&](const DirectionView& v) {
      if (v.k != ch.k) return;
      for (uint32_t a = 0; a < v.m; ++a) avail[v.idx[a]] = 0;
    });
  };
  size_t replacedSoFar = 0;
  if (options.update == EpsDeltaUpdate::Lazy) {
    struct Entry {
      uint32_t count, anchor;
    };
    auto less = [](const Entry& a, const Entry& b) {  // max count first, then smallest anchor
      return a.count != b.count ? a.count < b.count : a.anchor > b.anchor;
    };
    std::vector<Entry> init;
    for (uint32_t i = 0; i < n; ++i) {
      Choice ch = evaluate(records[i], avail, i, options.minReplaced, minLength);
      if (ch.count) init.push_back({ch.count, i});
    }
    std::priority_queue<Entry, std::vector<Entry>, decltype(less)> heap(less, std::move(init));
    size_t sinceReport = 0;
    while (!heap.empty()) {
      Entry e = heap.top();
      heap.pop();
      ++stats.heapPops;
      // Counts only decrease as points are removed, so every stored count is an upper bound; a
      // popped entry whose count is still current is the eager maximum.
      Choice ch = evaluate(records[e.anchor], avail, e.anchor, options.minReplaced, minLength);
      if (ch.count == 0) continue;
      if (ch.count < e.count) {
        heap.push({ch.count, e.anchor});
        ++stats.heapReinserts;
        continue;
      }
      // Replaced count is exactly ch.count (all counted points are available).
      removePoints(e.anchor, ch);
      replacedSoFar += ch.count;
      picks.push_back({e.anchor, ch});
      if (++sinceReport == 1024) {
        sinceReport = 0;
        reportProgress(options.progress, "eps-delta: select", double(replacedSoFar) / double(n));
      }
    }
  } else {
    // Reference: re-evaluate every anchor after each extracted segment.
    for (;;) {
      Choice best;
      uint32_t bestAnchor = 0;
      for (uint32_t i = 0; i < n; ++i) {
        Choice ch = evaluate(records[i], avail, i, options.minReplaced, minLength);
        if (ch.count > best.count) best = ch, bestAnchor = i;
      }
      if (best.count == 0) break;
      removePoints(bestAnchor, best);
      picks.push_back({bestAnchor, best});
    }
  }
  reportProgress(options.progress, "eps-delta: select", 1.0);
  stats.selectSeconds = timer.seconds();

  // Stage 3: build the hybrid model. removePoints cleared the availability of exactly the
  // replaced points, but a pick's record holds points other picks took before it, so replay.
  timer.reset();
  HybridModel out;
  out.attributes.normals = true;
  out.attributes.radii = true;
  out.attributes.colors = cloud.attributes.colors;
  out.attributes.endpointNormals = options.endpointNormals;
  out.comments = cloud.comments;
  auto radiusOf = [&](size_t j) -> double {
    if (cloud.attributes.radii && cloud.points[j].radius > 0) return cloud.points[j].radius;
    if (j < geometry.spacing.size() && geometry.spacing[j] > 0) return geometry.spacing[j];
    return geometry.averageSpacing;
  };
  std::fill(avail.begin(), avail.end(), 1);
  out.segments.reserve(picks.size());
  if (options.provenance) out.provenance.reserve(picks.size());
  std::vector<uint32_t> members;
  std::vector<uint32_t> owner(n, detail::kKeptPoint);  // the segment that replaced each point
  for (const Pick& pk : picks) {
    members.clear();
    DirectionView dir;
    forEachDirection(records[pk.anchor], [&](const DirectionView& v) {
      if (v.k == pk.choice.k) dir = v;
    });
    for (uint32_t a = 0; a < dir.m; ++a)
      if (avail[dir.idx[a]]) members.push_back(dir.idx[a]);
    const uint32_t i = pk.anchor;
    const Vec3d nid = geometry.normals[i].cast<double>();
    Line line;
    seedLine(ctx.pos[i], nid, ctx.pos[dir.k], line);
    double tmin = std::numeric_limits<double>::infinity(), tmax = -tmin;
    uint32_t jmin = i, jmax = i;  // the points at the two ends (their normals: smooth line models)
    Eigen::Vector4d colour = Eigen::Vector4d::Zero();
    for (uint32_t j : members) {
      avail[j] = 0;
      Vec3d w = ctx.pos[j] - line.origin;
      double t = w.dot(line.dir);
      if (t < tmin) tmin = t, jmin = j;
      if (t > tmax) tmax = t, jmax = j;
      colour += cloud.points[j].color.cast<double>();
    }
    // A segment stands for a row of points, each covering half a spacing on either side: extend
    // both ends by half the mean spacing along the row so that the rendered segment covers what
    // the row covered (docs/decisions.md). Replaced points only get closer to the segment.
    if (members.size() > 1) {
      const double half = 0.5 * (tmax - tmin) / double(members.size() - 1);
      tmin -= half;
      tmax += half;
    }
    Segment s;
    s.p0 = (line.origin + tmin * line.dir).cast<float>();
    s.p1 = (line.origin + tmax * line.dir).cast<float>();
    // Perpendicular to the stored (float) segment, as the Segment contract says: on very short
    // segments the rounded endpoints tilt the direction noticeably against line.dir.
    Vec3d fdir = (s.p1.cast<double>() - s.p0.cast<double>());
    fdir = fdir.norm() > 0 ? Vec3d(fdir.normalized()) : line.dir;
    Vec3d nn = nid - nid.dot(fdir) * fdir;
    s.normal = nn.normalized().cast<float>();
    if (options.endpointNormals) detail::setEndpointNormals(s, geometry.normals[jmin], geometry.normals[jmax]);
    s.color = cloud.attributes.colors ? Color((colour / double(members.size())).cast<float>()) : Color(1, 1, 1, 1);
    for (uint32_t j : members) owner[j] = uint32_t(out.segments.size());
    out.segments.push_back(s);
    if (options.provenance) {
      std::vector<uint32_t> prov;
      prov.reserve(members.size());
      prov.push_back(i);
      for (uint32_t j : members)
        if (j != i) prov.push_back(j);
      out.provenance.push_back(std::move(prov));
    }
  }
  // Half-widths (§3.1.5 "enlarge the radius by ε", made tight): the strips and the kept discs
  // cover every replaced point's Voronoi cell; docs/decisions.md "Hybrid segment widths".
  {
    std::vector<double> radii(n);
    for (size_t j = 0; j < n; ++j) radii[j] = radiusOf(j);
    detail::setSegmentWidths(out.segments, owner, radii, cloud, geometry);
  }
  detail::setSegmentProperties(out, cloud, owner);
  for (auto& [name, values] : cloud.pointProperties) {
    if (values.size() != n) continue;
    auto& dst = out.pointProperties[name];
    for (size_t j = 0; j < n; ++j)
      if (avail[j]) dst.push_back(values[j]);
  }
  for (size_t j = 0; j < n; ++j) {
    if (!avail[j]) continue;
    Point p = cloud.points[j];
    p.normal = geometry.normals[j];
    p.radius = float(radiusOf(j));
    out.points.push_back(p);
  }
  char buf[160];
  std::snprintf(buf, sizeof buf, "eps-delta: epsilon=%.9g delta=%.9g k=%d", eps, options.delta, geometry.k);
  out.comments.push_back(buf);
  stats.keptPoints = out.points.size();
  stats.segments = out.segments.size();
  stats.replacedPoints = n - stats.keptPoints;
  stats.outputSeconds = timer.seconds();
  if (statsOut) *statsOut = stats;
  return out;
}

}  // namespace linesurf
