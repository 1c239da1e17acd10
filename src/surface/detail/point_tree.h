#pragma once
// A kd-tree (nanoflann) over points it owns, as the MLS surface and the curvature lines query
// them: the points by value, no bounding box given (the tree computes it).
#include <nanoflann.hpp>

#include <vector>

#include "linesurf/core/math.h"

namespace linesurf::detail {

struct PointCloud {
  std::vector<Vec3f> pts;
  size_t kdtree_get_point_count() const { return pts.size(); }
  float kdtree_get_pt(size_t i, size_t d) const { return pts[i][int(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};

using PointTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, PointCloud>, PointCloud, 3, uint32_t>;

}  // namespace linesurf::detail
