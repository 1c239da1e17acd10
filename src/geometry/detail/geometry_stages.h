#pragma once
// The §6.1 stages that live in files of their own (orientation.cpp, curvature.cpp) and the small
// pieces they share with point_geometry.cpp. PointGeometry is declared, not included: the stages'
// files include point_geometry.h, and point_geometry.cpp includes this header, so including it
// here would tie the rooms in a cycle.
#include <algorithm>
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

#include "linesurf/core/math.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/progress.h"

namespace linesurf {
struct PointGeometry;
enum class CurvatureFit;
enum class OrientSide;
}  // namespace linesurf

namespace linesurf::detail {

/// Runs f(begin, end) over [0, n) in parallel, in ~64 blocks so the caller can report progress.
inline void forBlocks(size_t n, const ProgressFn& progress, std::string_view stage, size_t grain,
                      const std::function<void(size_t, size_t)>& f) {
  const size_t blocks = progress && n > 200000 ? 64 : 1;
  const size_t step = (n + blocks - 1) / std::max<size_t>(blocks, 1);
  for (size_t b = 0; b < n; b += step) {
    parallelForRange(b, std::min(n, b + step), f, grain);
    reportProgress(progress, stage, double(std::min(n, b + step)) / double(n));
  }
}

/// The two unit tangents x, y of §6.1.2: second and third columns of the Householder matrix
/// that maps e_0 to n (so that (n, x, y) is orthonormal).
inline void householderTangents(const Vec3d& n, Vec3d& x, Vec3d& y) {
  // H = I - 2 v v^T / (v^T v), v = e0 - n (or e0 + n for stability, mapping e0 to -n).
  Vec3d v = n;
  const double s = n.x() >= 0 ? 1.0 : -1.0;
  v.x() += s;  // v = n + s e0
  const double vv = v.squaredNorm();
  const Mat3d h = Mat3d::Identity() - (2.0 / vv) * v * v.transpose();
  x = h.col(1);
  y = h.col(2);
}

/// Makes the largest-magnitude component of a direction positive (a canonical sign).
inline Vec3f canonicalDirection(Vec3f d) {
  int i = 0;
  d.cwiseAbs().maxCoeff(&i);
  return d[i] < 0 ? Vec3f(-d) : d;
}

// Stage 2b, consistent orientation (orientation.cpp):
/// The side rule of orientNormals; decide = false leaves each component as its lowest-index
/// point's normal has it (a tile of an out-of-core run: its join decides for the whole component).
struct SideChoice {
  OrientSide rule;
  Vec3f viewpoint;
  bool decide = true;
};

/// Orients g.normals by a minimum spanning forest of the symmetrised kNN graph (Hoppe 1992),
/// propagated from each component's lowest-index point, then turns each component without fixed
/// normals to the side `side` chooses (geometry/detail/orientation_side.h); points with
/// fixedNormal[i] keep theirs and orient their components. Sets g.orientationFlips;
/// componentOut (optional) gets each point's component.
void orientNormals(const std::vector<Vec3f>& pos, int k, float tangentPenalty, const SideChoice& side, PointGeometry& g,
                   const std::vector<uint8_t>& fixedNormal, std::vector<uint32_t>* componentOut);

// Stage 4, principal curvatures and directions (curvature.cpp):
/// Taubin 1995 as in thesis §6.1.2: M = sum_j w_j kappa_j T_j T_j^T restricted to the tangent
/// plane; its eigenvalues m1 >= m2 give kappa_max = 3 m1 - m2, kappa_min = 3 m2 - m1. Or, with
/// CurvatureFit::Quadric, the Hessian of a height function fitted to the k nearest neighbours.
void computeCurvature(const std::vector<Vec3f>& pos, const std::vector<uint32_t>& order, CurvatureFit fit, PointGeometry& g,
                      const ProgressFn& progress);

}  // namespace linesurf::detail
