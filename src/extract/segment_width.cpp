// Segment half-widths from the replaced points' Voronoi cells (beyond the thesis).
// Decisions: docs/decisions.md "Hybrid segment widths".
#include "detail/segment_width.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "linesurf/geometry/point_geometry.h"

namespace linesurf::detail {
namespace {

struct Capsule {
  Vec3d a, ab;
  double ab2;
  double distance(const Vec3d& p) const {
    const Vec3d w = p - a;
    const double t = ab2 > 0 ? std::clamp(w.dot(ab) / ab2, 0.0, 1.0) : 0.0;
    return (w - t * ab).norm();
  }
};

/// The Voronoi cell of point j in its tangent plane (PointGeometry stage 3): the circumcentres
/// of its star triangles (j, ids[t], ids[t+1]), q_j at the origin, in the world.
struct Cell {
  Vec3d q, x, y;
  std::span<const uint32_t> ids;
  std::vector<Vec2d> centres;  ///< centres[t]: of the triangle (j, ids[t], ids[t+1])
  Vec3d world(const Vec2d& c) const { return q + c.x() * x + c.y() * y; }
};

/// False when j has no closed star: fewer than three neighbours, or consecutive neighbours
/// (listed counter-clockwise about the normal by the geometry stage) that do not all turn the
/// same way (a boundary star's open side, or a degenerate one).
bool voronoiCell(uint32_t j, const HybridModel& cloud, const PointGeometry& g, Cell& cell) {
  if (g.delaunayOffsets.size() != cloud.points.size() + 1 || j >= g.normals.size()) return false;
  cell.ids = g.delaunayOf(j);
  const size_t s = cell.ids.size();
  if (s < 3) return false;
  cell.q = cloud.points[j].position.cast<double>();
  const Vec3d n = g.normals[j].cast<double>();
  if (!(n.squaredNorm() > 0.5)) return false;
  // any orthonormal tangent basis: circumcentres do not depend on it, only the turning sign does
  cell.x = (std::abs(n.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY()).cross(n).normalized();
  cell.y = n.cross(cell.x);
  auto tangent = [&](uint32_t k) {
    const Vec3d d = cloud.points[k].position.cast<double>() - cell.q;
    return Vec2d(d.dot(cell.x), d.dot(cell.y));
  };
  int pos = 0, neg = 0;
  cell.centres.resize(s);
  for (size_t t = 0; t < s; ++t) {
    const Vec2d u = tangent(cell.ids[t]), v = tangent(cell.ids[(t + 1) % s]);
    const double cr = u.x() * v.y() - u.y() * v.x();
    if (cr > 0) ++pos;
    else if (cr < 0) ++neg;
    else return false;
    const double uu = u.squaredNorm(), vv = v.squaredNorm();
    cell.centres[t] = Vec2d((v.y() * uu - u.y() * vv) / (2 * cr), (u.x() * vv - v.x() * uu) / (2 * cr));
    if (!cell.centres[t].allFinite()) return false;
  }
  return pos == 0 || neg == 0;
}

/// Subdivisions of a cell's fan triangle sampled for cover (4: 14 points per triangle; 2 left
/// single pixels open on the random spheres at 1024^2, 6 and 8 changed nothing).
constexpr int kSteps = 4;

}  // namespace

void setSegmentWidths(std::span<Segment> segments, std::span<const uint32_t> owner, std::span<const double> radii,
                      const HybridModel& cloud, const PointGeometry& geometry) {
  const size_t n = owner.size(), ns = segments.size();
  std::vector<Capsule> caps(ns);
  for (size_t s = 0; s < ns; ++s) {
    const Vec3d a = segments[s].p0.cast<double>(), ab = segments[s].p1.cast<double>() - a;
    caps[s] = {a, ab, ab.squaredNorm()};
  }
  // Bounds: reach every member and its thinnest member's radius (lower), cover every member's
  // disc (upper: the rule of before).
  std::vector<double> width(ns, 0.0), upper(ns, 0.0), thinnest(ns, HUGE_VAL);
  for (size_t j = 0; j < n; ++j) {
    const uint32_t s = owner[j];
    if (s == kKeptPoint) continue;
    const double d = caps[s].distance(cloud.points[j].position.cast<double>());
    width[s] = std::max(width[s], d);
    upper[s] = std::max(upper[s], radii[j] + d);
    thinnest[s] = std::min(thinnest[s], radii[j]);
  }
  for (size_t s = 0; s < ns; ++s) width[s] = std::min(upper[s], std::max(width[s], thinnest[s]));
  // Cover each replaced cell, fan triangle by fan triangle (q_j, V_t, V_t+1), at the points of a
  // grid of kSteps subdivisions (q_j itself excepted): each within its margin of the strip of a
  // segment that replaced j or a star neighbour the triangle touches (ids[t], ids[t+1], ids[t+2]).
  // Kept points' discs are not counted on (that left single pixels open on the random spheres).
  Cell cell;
  for (size_t j = 0; j < n; ++j) {
    const uint32_t s = owner[j];
    if (s == kKeptPoint) continue;
    if (!voronoiCell(uint32_t(j), cloud, geometry, cell)) {
      width[s] = upper[s];  // no closed cell: cover the whole disc
      continue;
    }
    const size_t m = cell.ids.size();
    for (size_t t = 0; t < m; ++t) {
      const Vec2d& v0 = cell.centres[t];
      const Vec2d& v1 = cell.centres[(t + 1) % m];
      const double margin = (kCoverMargin - 1.0) * std::max(v0.norm(), v1.norm());
      const uint32_t others[3] = {owner[cell.ids[t]], owner[cell.ids[(t + 1) % m]], owner[cell.ids[(t + 2) % m]]};
      for (int a = 0; a <= kSteps; ++a)
        for (int b = (a == 0 ? 1 : 0); a + b <= kSteps; ++b) {
          const Vec3d p = cell.world((double(a) * v0 + double(b) * v1) / double(kSteps));
          uint32_t best = s;
          double bestGrow = caps[s].distance(p) + margin - width[s];
          bool covered = bestGrow <= 0;
          for (int o = 0; o < 3 && !covered; ++o) {
            const uint32_t k = others[o];
            if (k == kKeptPoint || k == s) continue;
            const double grow = caps[k].distance(p) + margin - width[k];
            if (grow <= 0) covered = true;
            else if (width[k] + grow <= upper[k] && (grow < bestGrow || (grow == bestGrow && k < best))) bestGrow = grow, best = k;
          }
          if (!covered) width[best] = std::min(upper[best], width[best] + bestGrow);
        }
    }
  }
  for (size_t s = 0; s < ns; ++s) segments[s].radius = float(width[s]);
}

}  // namespace linesurf::detail
