#pragma once
/// Segment level of detail (RenderOptions::segmentLod; beyond the thesis, built and off by
/// default, see docs/decisions.md, "Segment level of detail"). segment_lod.cpp.
#include "point_splat.h"
#include "segment_splat.h"
#include "splat_context.h"

namespace linesurf {

/// Cf. the §5.2.3 approximation: a one-piece ScreenSpace segment's weight is its kernel (covariance M in the strip's plane coordinates (a, b))
/// integrated along it with the linear scale w(tau) = scale0 + slope tau, tau in [0, l]: a box (l)
/// convolved with a Gaussian. When l is short against the kernel (lambda = l sqrt((M^-1)_aa) <=
/// RenderOptions::segmentLod) that is nearly the one Gaussian of the same mass, mean a_m and
/// covariance Sigma = M + var e_a e_a^T (var, a_m: the moments of w over [0, l]): an elliptical
/// object-space point splat in the strip's plane, rasterised by the point rows (4-5x cheaper per
/// fragment and per tile). Its plane coordinates (s, t) = L^T ((a, b) - (a_m, 0)), Sigma^-1 = L L^T
/// (Sherman-Morrison: L^T = [[l00, l00 skew], [0, sqrt(across)]], l00^2 = m00 / (1 + var m00)),
/// weightScale = w's mass / sqrt(1 + var m00), the frame's cutoff; z threshold the mean of the
/// ends', colour attr + (a_m + a) / l dc (Gouraud when the splat is wide, as points are), normal
/// the normalised mean of the endpoint normals. Writes slot 0 of `out` and returns true when the
/// segment qualifies (drawn, ScreenSpace without fallback, one piece, shade Constant / Linear /
/// Smooth, not depth-clipped, lambda <= maxLambda, finite constants); otherwise writes nothing.
bool segmentLodPoint(const PreparedSegment& segment, const FrameContext& frame, float maxLambda, const PointSlots& out);

}  // namespace linesurf
