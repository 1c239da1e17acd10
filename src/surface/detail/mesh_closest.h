#pragma once
// The closest point on a triangle mesh (CGAL's AABB tree, in its own translation unit so that
// CGAL's headers and flags stay out of the rest of the library).
#include <memory>

#include "linesurf/core/model.h"

namespace linesurf::detail {

class MeshClosestPoint {
 public:
  /// Faces whose three corners are not distinct points are left out (they hold no area).
  explicit MeshClosestPoint(const TriangleMesh& mesh);
  ~MeshClosestPoint();
  /// The point of the mesh nearest to x. Safe to call from many threads at once.
  Vec3d closest(const Vec3d& x) const;
  size_t triangles() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace linesurf::detail
