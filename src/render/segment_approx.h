#pragma once
/// The segment splat approximation of thesis §5.2.3 (RenderOptions::SegmentMethod::Approx): the
/// weight textures T1 (endpoint portions) and T2 (middle) of §5.2.3.2, the 10 (long case) or 8
/// (short case) bounding quadrilaterals of §5.2.3.1 built from the endpoint resampling ellipses
/// (segment_filter.h, §5.1.2), and their weights with the scaling factor interpolated between
/// points 9 and 10 (§5.2.3.3, Figure 19). segment_approx.cpp.
#include "segment_extra.h"
#include "segment_filter.h"

namespace linesurf {

/// The weight textures of §5.2.3.2 for cutoff radius R, in this project's weight units
/// (Gaussians without the 1/(2 pi), as point splats): T1(x, y) = integral over t >= 0 of the
/// cut-off unit Gaussian at (x - t, y); T2(y) = the same over all t. x, y in standard deviations.
/// Sampled on kWeightTextureSize x kWeightTextureSize/2 texels over [-R, R] x [0, R], bilinear.
inline constexpr int kWeightTextureSize = 128;
float weightTextureT1(float cutoffRadius, float x, float y);
float weightTextureT2(float cutoffRadius, float y);

namespace segment {

/// Approx (§5.2.3.1): the 10 (long) or 8 (short) quadrilaterals of a segment of length L with
/// endpoint covariances M0, M1; false when the construction is unsound (the caller falls back
/// to ScreenSpace). On success also the footprint box of the quads.
bool buildApprox(const Mat2d& M0, const Mat2d& M1, double L, double R, double h, SegmentExtra& x, double& aMin,
                 double& aMax, double& bMax);
float approxWeight(const SegmentExtra& x, float a, float b);

}  // namespace segment

}  // namespace linesurf
