#pragma once
// The three evaluations of the segment filter (thesis §5; linesurf/render/segment_splat.h) and
// the resampling covariance they share (§5.1.2): ScreenSpace (erf closed form per sub-segment),
// Reference (quadrature) and Approx (§5.2.3, the thesis's weight-texture quadrilaterals).
// Internal to segment_splat.cpp (segment_methods.cpp).
#include <vector>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "segment_splat.h"

namespace linesurf::segment {

using Mat2d = Eigen::Matrix2d;
using Vec2dd = Eigen::Vector2d;

/// Object-space resampling covariance M = sigma_r^2 I + V_h J^-1 J^-T of the point p (camera
/// space) of a strip with unit axes e (a, along) and s (b, across), in (a, b) coordinates,
/// eigenvalues clamped to [sigma_r^2, (kMaxStretch sigma_r)^2] as for point splats. J is the
/// Jacobian of the perspective projection restricted to the strip's plane at p (§5.1.2, RPZ02).
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

/// Approx (§5.2.3.1): the 10 (long) or 8 (short) quadrilaterals of a segment of length L with
/// endpoint covariances M0, M1; false when the construction is unsound (the caller falls back
/// to ScreenSpace). On success also the footprint box of the quads.
bool buildApprox(const Mat2d& M0, const Mat2d& M1, double L, double R, double h, SegmentExtra& x, double& aMin,
                 double& aMax, double& bMax);
float approxWeight(const SegmentExtra& x, float a, float b);

}  // namespace linesurf::segment
