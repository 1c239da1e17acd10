// The closest point on a triangle mesh: CGAL's AABB tree over the faces (see detail/mesh_closest.h).
#include "detail/mesh_closest.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

#include <vector>

namespace linesurf::detail {
namespace {

using K = CGAL::Simple_cartesian<double>;
using Triangle = K::Triangle_3;
using Primitive = CGAL::AABB_triangle_primitive<K, std::vector<Triangle>::const_iterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;

K::Point_3 point(const Vec3f& v) { return {double(v.x()), double(v.y()), double(v.z())}; }

}  // namespace

struct MeshClosestPoint::Impl {
  std::vector<Triangle> triangles;
  Tree tree;
};

MeshClosestPoint::MeshClosestPoint(const TriangleMesh& mesh) : impl_(std::make_unique<Impl>()) {
  for (const auto& f : mesh.faces) {
    const Triangle t(point(mesh.positions[f[0]]), point(mesh.positions[f[1]]), point(mesh.positions[f[2]]));
    if (!t.is_degenerate()) impl_->triangles.push_back(t);
  }
  impl_->tree.insert(impl_->triangles.begin(), impl_->triangles.end());
  impl_->tree.build();
  // The distance queries' search tree is built here, once, not lazily by the first of many
  // concurrent queries.
  impl_->tree.accelerate_distance_queries();
  if (!impl_->triangles.empty()) (void)impl_->tree.closest_point(K::Point_3(0, 0, 0));
}

MeshClosestPoint::~MeshClosestPoint() = default;

size_t MeshClosestPoint::triangles() const { return impl_->triangles.size(); }

Vec3d MeshClosestPoint::closest(const Vec3d& x) const {
  const K::Point_3 c = impl_->tree.closest_point(K::Point_3(x.x(), x.y(), x.z()));
  return {c.x(), c.y(), c.z()};
}

}  // namespace linesurf::detail
