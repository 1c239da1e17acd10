// Minimum-area enclosing rectangle for §3.2.4.2 (rotating calipers, [Tous83]). The only
// translation unit of the shape-approximation method that includes CGAL.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/convex_hull_2.h>
#include <CGAL/min_quadrilateral_2.h>

#include <cmath>
#include <iterator>
#include <vector>

#include "linesurf/extract/shape_approx.h"

namespace linesurf {

Rectangle2 minAreaRectangle(std::span<const Vec2d> points) {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using P = K::Point_2;
  Rectangle2 r;
  if (points.empty()) return r;
  std::vector<P> in;
  in.reserve(points.size());
  for (const Vec2d& p : points) in.emplace_back(p.x(), p.y());
  std::vector<P> hull;
  CGAL::convex_hull_2(in.begin(), in.end(), std::back_inserter(hull));
  auto toEigen = [](const P& p) { return Vec2d(CGAL::to_double(p.x()), CGAL::to_double(p.y())); };

  if (hull.size() < 3) {
    // Coincident or collinear points: a zero-width rectangle along the line through them.
    Vec2d a = toEigen(hull.front()), b = toEigen(hull.back());
    Vec2d d = b - a;
    double len = d.norm();
    r.center = 0.5 * (a + b);
    r.longAxis = len > 0 ? Vec2d(d / len) : Vec2d::UnitX();
    r.longLength = len;
    r.shortLength = 0;
    return r;
  }

  std::vector<P> corners;
  CGAL::min_rectangle_2(hull.begin(), hull.end(), std::back_inserter(corners));
  if (corners.size() != 4) return r;
  Vec2d v[4];
  for (int i = 0; i < 4; ++i) v[i] = toEigen(corners[i]);
  Vec2d e0 = v[1] - v[0], e1 = v[2] - v[1];
  double l0 = e0.norm(), l1 = e1.norm();
  r.center = 0.25 * (v[0] + v[1] + v[2] + v[3]);
  if (l0 >= l1) {
    r.longAxis = l0 > 0 ? Vec2d(e0 / l0) : Vec2d::UnitX();
    r.longLength = l0, r.shortLength = l1;
  } else {
    r.longAxis = e1 / l1;
    r.longLength = l1, r.shortLength = l0;
  }
  // Canonical sign: first non-zero component positive, so the result does not depend on hull order.
  if (r.longAxis.x() < 0 || (r.longAxis.x() == 0 && r.longAxis.y() < 0)) r.longAxis = -r.longAxis;
  return r;
}

}  // namespace linesurf
