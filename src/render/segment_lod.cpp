// Segment level of detail (beyond the thesis; segment_lod.h): a short segment drawn as one
// elliptical point splat through the point pipeline.
#include "segment_lod.h"

#include <algorithm>
#include <cmath>

namespace linesurf {

bool segmentLodPoint(const PreparedSegment& sp, const FrameContext& frame, float maxLambda, const PointSlots& out) {
  const detail::SegmentRaster& k = sp.raster;
  if (sp.method != SegmentMethod::ScreenSpace || sp.fallback || k.pieceCount != 1 || k.clipDepth || !sp.useSpans ||
      sp.shade == SegmentShade::Stations || !(k.invM00 > 0) || !(k.across > 0) || !(k.length > 0))
    return false;
  // lambda^2 = l^2 m00 = l^2 / invM00
  const float l = k.length, invM00 = k.invM00, across = k.across, skew = k.skew;
  if (!(l * l <= maxLambda * maxLambda * invM00)) return false;
  // mass, mean and variance of the scale w(tau) = scale0 + slope tau over [0, l] (one division):
  // with D = scale0 + slope l / 2, mass = l D, mean = l (scale0 / 2 + slope l / 3) / D,
  // E[tau^2] = l^2 (scale0 / 3 + slope l / 4) / D; the scale may change by at most half along
  const float sl = k.slope * l, D = k.scale0 + 0.5f * sl;
  if (!(k.scale0 > 0) || !(std::abs(sl) <= 0.5f * k.scale0)) return false;
  const float invD = 1 / D, mass = l * D;
  const float um = (0.5f * k.scale0 + sl / 3) * invD;  // the mean along, as a fraction of l
  const float var = l * l * std::max(0.0f, (k.scale0 / 3 + 0.25f * sl) * invD - um * um);
  const float am = um * l;
  // Sigma^-1 = L L^T: l00^2 = m00 / (1 + var m00) = 1 / (invM00 + var), l11^2 = across; the
  // weight scale keeps the mass: mass sqrt(det Sigma^-1 / det M^-1) = mass sqrt(invM00) l00
  const float l00 = 1 / std::sqrt(invM00 + var), l11 = std::sqrt(across);
  // the cutoff ellipse's box in plane coordinates (a in am +- R sqrt(Sigma_aa), Sigma_aa = invM00 +
  // skew^2 / across + var; |b| <= R sqrt(M_bb) = R / l11) inside the segment's footprint box, which
  // lies in front of the eye within near / far (the point rows clip no depth here): then the
  // projected ellipse is bounded and its box bounds it
  const float R2 = frame.cutoffQ;
  const float lo = am - k.aMin, hi = k.aMax - am, tol = 1e-3f * (k.aMax - k.aMin);
  const float reach = std::min(lo, hi) + tol;
  if (!(reach > 0) || R2 * ((invM00 + var) * across + skew * skew) > reach * reach * across ||
      R2 > k.bMax * k.bMax * across * (1 + 2e-5f))
    return false;
  // s N = l00 (A + skew B - (a0 + am + skew b0) N), t N = l11 (B - b0 N), in double: the terms cancel
  const double ca = double(k.a0) + double(am) + double(skew) * double(k.b0);
  auto affine = [](double cA, const detail::Affine2& A, double cB, const detail::Affine2& B, double cN,
                   const detail::Affine2& N) {
    return detail::Affine2{float(cA * A.dx + cB * B.dx + cN * N.dx), float(cA * A.dy + cB * B.dy + cN * N.dy),
                           float(cA * A.c + cB * B.c + cN * N.c)};
  };
  const detail::Affine2 S = affine(l00, k.A, double(l00) * skew, k.B, -double(l00) * ca, k.N);
  const detail::Affine2 T = affine(0, k.A, l11, k.B, -double(l11) * k.b0, k.N);
  double x0, y0, x1, y1;
  if (!detail::conicBounds(S, T, k.N, R2, x0, y0, x1, y1)) return false;
  bool cut = false;
  const PixelRect bounds = detail::pixelBounds(frame.cam(), x0, y0, x1, y1, cut).intersect(sp.bounds);
  if (bounds.empty()) return false;
  PreparedPoint& hot = *new (out.hot) PreparedPoint;
  *new (out.bounds) PixelRect = bounds;
  PointCold& cold = *new (out.cold) PointCold;
  hot.N = k.N, hot.S = S, hot.T = T;
  hot.depthNum = k.depthNum;
  hot.setWeightScale(mass * std::sqrt(invM00) * l00, false);
  hot.zThreshold = 0.5f * (k.zThreshold0 + k.zThreshold1);
  const float* a = sp.attr;
  for (int c = 0; c < 3; ++c) hot.color[c] = a[Z3Tile::kR + c] + um * sp.dc[c];
  hot.color[3] = a[Z3Tile::kA];
  Vec3f n(a[Z3Tile::kNx], a[Z3Tile::kNy], a[Z3Tile::kNz]);
  if (sp.shade == SegmentShade::Smooth) {
    const Vec3f m = sp.n0 + 0.5f * sp.dn;
    if (m.squaredNorm() > 0) n = m.normalized();
  }
  cold.normal[0] = n.x(), cold.normal[1] = n.y(), cold.normal[2] = n.z();
  cold.index = sp.index;
  if (PreparedPoint::gouraud(bounds, frame.opt().perPixelLighting)) {
    // the segment's colour, linear in a: a - am = s / l00 - skew t / l11
    PointGouraud& gr = *new (out.gouraud) PointGouraud;
    gr.C0 = Vec3f(hot.color[0], hot.color[1], hot.color[2]);
    gr.Cs = sp.dc * (1 / (l * l00));
    gr.Ct = sp.dc * (-skew / (l * l11));
    gr.Cst = Vec3f::Zero();
  }
  return true;
}

}  // namespace linesurf
