#pragma once
/// The segment filter of thesis §5.1 (segment_splat.h): the resampling covariance along a segment
/// (§5.1.2), shared by every evaluation, and the two exact evaluations, ScreenSpace (erf closed
/// form per sub-segment, after §9.3; the SIMD rows evaluate the same sum, segment_rows.h) and
/// Reference (quadrature). The thesis's approximation is segment_approx.h (§5.2.3).
/// segment_filter.cpp.
#include <algorithm>
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "segment_extra.h"
#include "splat_rules.h"

namespace linesurf::segment {

using Mat2d = Eigen::Matrix2d;
using Vec2dd = Eigen::Vector2d;

/// A symmetric 2x2 matrix (a b; b c) in the strip's (a, b) coordinates.
struct Sym2 {
  double a = 0, b = 0, c = 0;
};

/// Symmetric 2x2 with eigenvalues clamped to [lo, hi] (the test whether clamping is active needs no
/// square root: M - lo I and hi I - M positive semi-definite).
inline Sym2 clampEigen(const Sym2& M, double lo, double hi) {
  const double a = M.a, b = M.b, c = M.c;
  if (a >= lo && c >= lo && (a - lo) * (c - lo) >= b * b && hi >= a && hi >= c && (hi - a) * (hi - c) >= b * b) return M;
  const double mean = 0.5 * (a + c), diff = 0.5 * (a - c);
  const double rad = std::sqrt(diff * diff + b * b);
  double l0 = mean + rad, l1 = mean - rad;
  if (l0 <= hi && l1 >= lo) return M;
  double e0x = 1, e0y = 0;  // unit eigenvector of l0
  if (rad > 0) {
    if (std::abs(b) > 0) {
      const double len = std::sqrt((l0 - c) * (l0 - c) + b * b);
      e0x = (l0 - c) / len, e0y = b / len;
      if (!std::isfinite(e0x) || !std::isfinite(e0y)) e0x = 1, e0y = 0;
    } else if (a < c) {
      e0x = 0, e0y = 1;
    }
  }
  l0 = std::clamp(l0, lo, hi);
  l1 = std::clamp(l1, lo, hi);
  // l0 e0 e0^T + l1 e1 e1^T with e1 = (-e0y, e0x)
  return {l0 * e0x * e0x + l1 * e0y * e0y, (l0 - l1) * e0x * e0y, l0 * e0y * e0y + l1 * e0x * e0x};
}

/// Object-space resampling covariance M = sigma_r^2 I + V_h J^-1 J^-T of the point p (camera
/// space) of a strip with unit axes e (a, along) and s (b, across), in (a, b) coordinates,
/// eigenvalues clamped to [sigma_r^2, (kMaxStretch sigma_r)^2] as for point splats. J is the
/// Jacobian of the perspective projection restricted to the strip's plane at p (§5.1.2, RPZ02).
/// Behind the eye the prefilter is dropped, as for point splats; where J is singular (edge-on)
/// M is as stretched as allowed. Shared by the exact path (resamplingCovariance) and the common
/// case of segment_splat.cpp.
inline Sym2 covariance(const double* p, const double* e, const double* s, double sigmaR, double Vh, double f) {
  const double s2 = sigmaR * sigmaR;
  const double hi = (detail::kMaxStretch * sigmaR) * (detail::kMaxStretch * sigmaR);
  Sym2 M{s2, 0, s2};
  const double d = -p[2];
  if (d > 0 && Vh > 0) {
    // rows of J: gx = (f/d, 0, f x/d^2), gy = (0, -f/d, -f y/d^2) dotted with e and s
    const double g0 = f / d, gx2 = f * p[0] / (d * d), gy2 = -f * p[1] / (d * d);
    const double j00 = g0 * e[0] + gx2 * e[2], j01 = g0 * s[0] + gx2 * s[2];
    const double j10 = -g0 * e[1] + gy2 * e[2], j11 = -g0 * s[1] + gy2 * s[2];
    const double ja = j00 * j00 + j10 * j10, jb = j00 * j01 + j10 * j11, jc = j01 * j01 + j11 * j11;
    const double det = ja * jc - jb * jb;
    if (!(det > 0 && std::isfinite(det))) return {hi, 0, hi};
    const double v = Vh / det;  // V_h adj(J^T J) / det
    M.a += v * jc, M.b = -v * jb, M.c += v * ja;
  }
  return clampEigen(M, s2, hi);
}

/// The inverse of a 2x2 matrix (adjugate over determinant).
inline Mat2d inverse2(const Mat2d& M) {
  const double det = M.determinant();
  Mat2d inv;
  inv << M(1, 1), -M(0, 1), -M(1, 0), M(0, 0);
  return inv / det;
}

/// covariance() as an Eigen matrix.
Mat2d resamplingCovariance(const Vec3d& p, const Vec3d& e, const Vec3d& s, double sigmaR, double Vh, double f);

/// The ScreenSpace sub-segment [a0, a1] with covariance M (constant over it) and the weight
/// scales at its ends, 1 / (h sqrt(det M)) for the covariances M0, M1 there; R = cutoff radius.
SegmentPiece makePiece(double a0, double a1, const Mat2d& M, const Mat2d& M0, const Mat2d& M1, double h, double R);

/// ScreenSpace weight at plane coordinates (a, b): the cut-off Gaussian integrated along each
/// of the K pieces in closed form (table erf; the SIMD rows evaluate the same sum for K = 1).
float screenSpaceWeight(const SegmentPiece* pieces, int K, float pieceInvLength, float pieceMaxReach, float a,
                        float b, float R2);

/// Reference: quadrature nodes over [0, L] at spacing sigma_r / 32 (at most 2^16), and the
/// weight at (a, b) by the midpoint rule. Returns the box half-extents the nodes reach.
void referenceNodes(double L, double sigmaR, double h, double R, const Vec3d& c0, const Vec3d& e, const Vec3d& s,
                    double Vh, double f, SegmentExtra& x, double& aMin, double& aMax, double& bMax);
float referenceWeight(const SegmentExtra& x, float a, float b, float R2);

}  // namespace linesurf::segment
