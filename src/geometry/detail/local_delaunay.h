#pragma once
// Local Delaunay neighbours of one point on its tangent plane (thesis §6.1.1, stage 3).
// The point p sits at the origin; q holds its projected neighbours relative to p.
#include <cstdint>
#include <span>
#include <vector>

#include "linesurf/core/math.h"

namespace linesurf::detail {

/// The star of p in the local 2D Delaunay triangulation: its neighbours counter-clockwise and,
/// per neighbour, the summed area of the (one or two) star triangles on the edge p-q.
struct LocalStar {
  std::vector<int> ids;        ///< indices into the input q, counter-clockwise
  std::vector<double> areas;   ///< same order; unnormalised
  bool boundary = false;       ///< p lies on the convex hull of its neighbourhood
  int triangles = 0;           ///< number of star triangles
  void clear() { ids.clear(); areas.clear(); boundary = false; triangles = 0; }
};

/// Per-thread scratch of localDelaunayStar.
struct StarScratch {
  struct Cand { double angle, ux, uy, r2; int id; };
  std::vector<Cand> cands;
  std::vector<int> hull;
};

/// Exact-star method: q_j is a Delaunay neighbour of the origin iff its inverse q_j/|q_j|^2 lies
/// on the convex hull of {0} and the inverted points. Co-circular neighbours (a regular grid)
/// are all kept (every point on an empty circle through p), so the result does not depend on
/// the input order. Points closer than sqrt(minDist2) to the origin are ignored.
void localDelaunayStar(std::span<const Vec2d> q, double minDist2, LocalStar& star, StarScratch& scratch);

/// The same star from CGAL::Delaunay_triangulation_2 (one diagonal picked on co-circular sets).
void localDelaunayStarCgal(std::span<const Vec2d> q, double minDist2, LocalStar& star);

}  // namespace linesurf::detail
