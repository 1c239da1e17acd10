// Local Delaunay star of a point on its tangent plane (thesis §6.1.1, stage 3), by inversion:
// a circle through the origin p maps to a line under q -> q/|q|^2, its inside to the half-plane
// away from the origin. So q_j is a Delaunay neighbour of p iff its inverse lies on the convex
// hull of {0} and the inverses, and (p, q_a, q_b) is a Delaunay triangle iff the inverses of q_a
// and q_b are consecutive on that hull. One angular sort and a Graham scan, O(k log k).
#include <algorithm>
#include <cmath>

#include "geometry/detail/local_delaunay.h"

namespace linesurf::detail {
namespace {

// Points on the same ray from p closer than this (sine of the angle) hide one another.
constexpr double kSameRaySine = 1e-7;
// A hull turn counts as convex unless it turns right by more than this (sine of the angle):
// co-circular neighbours (regular grids, float round-off) stay in the star.
constexpr double kTurnSine = 1e-6;
// p lies on the hull of its neighbourhood when an angular gap reaches pi minus about this (rad).
constexpr double kGapTolerance = 1e-6;

/// A monotone substitute for atan2 in [0, 4): cheaper, and exact on axis-aligned directions.
inline double pseudoAngle(double x, double y) {
  const double d = std::abs(x) + std::abs(y);
  if (d == 0) return 0;
  const double p = y / d;
  return x >= 0 ? (y >= 0 ? p : 4 + p) : 2 - p;
}

inline double turnSine(double ax, double ay, double bx, double by, double cx, double cy) {
  const double ux = bx - ax, uy = by - ay, vx = cx - bx, vy = cy - by;
  const double len = std::sqrt((ux * ux + uy * uy) * (vx * vx + vy * vy));
  if (len <= 0) return 0;
  return (ux * vy - uy * vx) / len;
}

}  // namespace

void localDelaunayStar(std::span<const Vec2d> q, double minDist2, LocalStar& star, StarScratch& scratch) {
  star.clear();
  auto& c = scratch.cands;
  c.clear();
  for (size_t j = 0; j < q.size(); ++j) {
    const double r2 = q[j].squaredNorm();
    if (!(r2 > minDist2) || !std::isfinite(r2)) continue;
    c.push_back({pseudoAngle(q[j].x(), q[j].y()), q[j].x() / r2, q[j].y() / r2, r2, int(j)});
  }
  if (c.empty()) return;
  std::sort(c.begin(), c.end(), [](const auto& a, const auto& b) {
    if (a.angle != b.angle) return a.angle < b.angle;
    if (a.r2 != b.r2) return a.r2 < b.r2;
    return a.id < b.id;
  });
  // Keep only the nearest point of each ray: the farther ones are hidden behind it.
  auto sameRay = [&](const StarScratch::Cand& a, const StarScratch::Cand& b) {
    const double cr = a.ux * b.uy - a.uy * b.ux, dt = a.ux * b.ux + a.uy * b.uy;
    return dt > 0 && std::abs(cr) <= kSameRaySine * std::sqrt((a.ux * a.ux + a.uy * a.uy) * (b.ux * b.ux + b.uy * b.uy));
  };
  size_t m = 0;
  for (size_t t = 0; t < c.size(); ++t) {
    if (m > 0 && sameRay(c[m - 1], c[t])) {
      if (c[t].r2 < c[m - 1].r2) c[m - 1] = c[t];
      continue;
    }
    c[m++] = c[t];
  }
  while (m > 1 && sameRay(c[m - 1], c[0])) {  // wrap-around at angle +-pi
    if (c[m - 1].r2 < c[0].r2) c[0] = c[m - 1];
    --m;
  }
  c.resize(m);
  if (m == 1) {
    star.ids.push_back(c[0].id);
    star.areas.push_back(0);
    star.boundary = true;
    return;
  }
  // Largest angular gap (as a pseudo-angle of the turn from one direction to the next): p is on
  // the hull of its neighbourhood when it reaches pi (pseudo-angle 2).
  size_t gapAt = 0;
  double maxGap = -1;
  for (size_t t = 0; t < m; ++t) {
    const auto& a = c[t];
    const auto& b = c[t + 1 < m ? t + 1 : 0];
    const double gap = pseudoAngle(a.ux * b.ux + a.uy * b.uy, a.ux * b.uy - a.uy * b.ux);
    if (gap > maxGap) maxGap = gap, gapAt = t;
  }
  auto& h = scratch.hull;  // indices into c; -1 is the origin
  h.clear();
  auto ux = [&](int i) { return i < 0 ? 0.0 : c[size_t(i)].ux; };
  auto uy = [&](int i) { return i < 0 ? 0.0 : c[size_t(i)].uy; };
  auto push = [&](int i) {
    while (h.size() >= 2) {
      const int a = h[h.size() - 2], b = h.back();
      if (turnSine(ux(a), uy(a), ux(b), uy(b), ux(i), uy(i)) >= -kTurnSine) break;
      h.pop_back();
    }
  };
  star.boundary = maxGap >= 2 - kGapTolerance;
  if (star.boundary) {
    // Origin is a hull vertex: scan from the first point after the gap around to the last.
    h.push_back(-1);
    for (size_t t = 0; t < m; ++t) {
      const int i = int((gapAt + 1 + t) % m);
      push(i);
      h.push_back(i);
    }
    push(-1);
    h.erase(h.begin());
  } else {
    // Origin inside: start at the nearest point (largest inverse), always a hull vertex.
    size_t start = 0;
    for (size_t t = 1; t < m; ++t)
      if (c[t].r2 < c[start].r2) start = t;
    for (size_t t = 0; t < m; ++t) {
      const int i = int((start + t) % m);
      push(i);
      h.push_back(i);
    }
    push(int(start));
  }
  const size_t s = h.size();
  star.ids.resize(s);
  star.areas.assign(s, 0.0);
  for (size_t t = 0; t < s; ++t) star.ids[t] = c[size_t(h[t])].id;
  const size_t tris = star.boundary ? s - 1 : s;
  for (size_t t = 0; t < tris && s >= 2; ++t) {
    const size_t a = t, b = (t + 1) % s;
    const Vec2d& qa = q[size_t(star.ids[a])];
    const Vec2d& qb = q[size_t(star.ids[b])];
    const double area = 0.5 * std::abs(qa.x() * qb.y() - qa.y() * qb.x());
    star.areas[a] += area;
    star.areas[b] += area;
    ++star.triangles;
  }
}

}  // namespace linesurf::detail
