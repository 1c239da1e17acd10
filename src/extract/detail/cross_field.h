#pragma once
// The direction field of the curvature-line extraction (thesis §9.2; extract/curvature_lines.h):
// principal directions of the MLS surface smoothed into a 4-symmetric cross field.
#include <cstddef>
#include <vector>

#include "linesurf/core/math.h"
#include "linesurf/core/model.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf {
class MlsSurface;
}

namespace linesurf::detail {

struct CrossField {
  /// One axis of the cross at each point, unit and tangent to `normal`; the others are its
  /// negative and +-normal x axis.
  std::vector<Vec3f> axis;
  std::vector<Vec3f> normal;
  /// |sum of the aligned neighbour crosses| / their count after the last iteration, [0, 1]:
  /// near 1 where the field is smooth, low at its singularities (umbilics of the cross).
  std::vector<float> coherence;
  /// The MLS principal curvatures and minimum-curvature direction at each point (unsmoothed).
  std::vector<float> kMin, kMax;
  std::vector<Vec3f> minDir;
};

/// §9.2 step 1: the MLS curvature at every point, then `iterations` Jacobi steps of
///   z_i <- normalise(dataWeight a_i z_data_i + mean_j z_j->i)
/// with z = exp(4 i theta) in each point's tangent frame (the 4-fold angle makes the cross's four
/// axes one value) and a_i = |k_max - k_min| / (|k_max| + |k_min| + k_0) the anisotropy (k_0 =
/// 0.002 / average spacing: flatter than a radius of 500 spacings counts as flat). Jacobi, one
/// output slot per point: the same field for any thread count.
CrossField computeCrossField(const HybridModel& cloud, const PointGeometry& geometry, const MlsSurface& surface,
                             int iterations, double dataWeight);

/// The axis of the cross (a, n x a, -a, -n x a) nearest to `ref`.
inline Vec3f nearestAxis(const Vec3f& a, const Vec3f& n, const Vec3f& ref) {
  const Vec3f b = n.cross(a);
  const float da = a.dot(ref), db = b.dot(ref);
  if (std::abs(da) >= std::abs(db)) return da >= 0 ? a : Vec3f(-a);
  return db >= 0 ? b : Vec3f(-b);
}

}  // namespace linesurf::detail
