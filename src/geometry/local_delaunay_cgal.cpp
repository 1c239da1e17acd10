// Local Delaunay star by CGAL::Delaunay_triangulation_2 (thesis §6.1.1 uses CGAL for this).
// The only translation unit of the geometry module that includes CGAL.
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <cmath>

#include "geometry/detail/local_delaunay.h"

namespace linesurf::detail {
namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<int, K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb>;
using DT = CGAL::Delaunay_triangulation_2<K, Tds>;
}  // namespace

void localDelaunayStarCgal(std::span<const Vec2d> q, double minDist2, LocalStar& star) {
  star.clear();
  thread_local DT dt;  // reused per thread: clear() keeps nothing but saves re-initialisation
  dt.clear();
  auto origin = dt.insert(K::Point_2(0, 0));
  origin->info() = -1;
  for (size_t j = 0; j < q.size(); ++j) {
    const double r2 = q[j].squaredNorm();
    if (!(r2 > minDist2) || !std::isfinite(r2)) continue;
    const size_t before = dt.number_of_vertices();
    auto v = dt.insert(K::Point_2(q[j].x(), q[j].y()));
    if (dt.number_of_vertices() > before) v->info() = int(j);
  }
  if (dt.number_of_vertices() < 2) return;
  if (dt.dimension() < 2) {
    // Collinear: the neighbours along the line.
    auto vc = dt.incident_vertices(origin), done = vc;
    if (vc != nullptr) do {
        if (!dt.is_infinite(vc)) {
          star.ids.push_back(vc->info());
          star.areas.push_back(0);
        }
      } while (++vc != done);
    star.boundary = true;
    return;
  }
  auto vc = dt.incident_vertices(origin), done = vc;
  do {
    if (dt.is_infinite(vc)) {
      star.boundary = true;
      continue;
    }
    star.ids.push_back(vc->info());
    star.areas.push_back(0);
  } while (++vc != done);
  auto slot = [&](int id) {
    for (size_t t = 0; t < star.ids.size(); ++t)
      if (star.ids[t] == id) return t;
    return size_t(0);
  };
  auto fc = dt.incident_faces(origin), fdone = fc;
  do {
    if (dt.is_infinite(fc)) continue;
    const int i = fc->index(origin);
    auto a = fc->vertex(dt.ccw(i)), b = fc->vertex(dt.cw(i));
    const Vec2d& qa = q[size_t(a->info())];
    const Vec2d& qb = q[size_t(b->info())];
    const double area = 0.5 * std::abs(qa.x() * qb.y() - qa.y() * qb.x());
    star.areas[slot(a->info())] += area;
    star.areas[slot(b->info())] += area;
    ++star.triangles;
  } while (++fc != fdone);
}

}  // namespace linesurf::detail
