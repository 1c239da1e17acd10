#pragma once
/// The rules that every path of the splat pipeline must apply alike: point splats (§4.2.2) and
/// segment splats (§5.2), each with an exact scalar path and a SIMD path (point_setup.cpp,
/// segment_setup.cpp, point_rows.cpp, segment_rows.cpp) that must agree. A rule written here once
/// cannot drift between them: the limits of the resampling filter, the z threshold of a primitive
/// (Z^3, §6.2.3), the tail test's disc, the flat-shading span of a point splat, the flat weight
/// scale of a segment piece, the ray/plane set-up and the screen bounds.
#include <algorithm>
#include <cmath>

#include "linesurf/core/math.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/render_options.h"
#include "pixel_rect.h"

namespace linesurf::detail {

/// Limits that point and segment splats share, so that the primitives of one model are cut and
/// culled alike. Largest stretch of the resampling filter relative to the reconstruction sigma:
/// near edge-on the warped prefilter J^-1 V_h J^-T grows without bound (the plane projects to a
/// line); past this stretch the splat is cut, which costs nothing visible (its screen width
/// stays below a pixel) and keeps the footprint finite.
inline constexpr float kMaxStretch = 24.0f;
/// Primitives seen closer to edge-on than this |cos| (everywhere) are culled: they project to a line.
inline constexpr float kMinFacing = 2e-3f;

/// A point splat spanning at most this many pixels each way is lit once (flat); a wider one is
/// Gouraud-shaded when lighting is not deferred (point_splat.h).
inline constexpr int kPointFlatShadeSpan = 6;
/// Tail layers (Z3Tile::setTailLayers, RenderOptions::tailLayers): a fragment is a tail where its
/// ray meets the primitive's plane outside this many times its own disc (a point: radius cutoff
/// sigma_r) or strip (a segment: half-width cutoff sigma_r). 1.5, not 1: a grazing surface whose
/// discs leave pixel centres uncovered keeps its fragments (measured, docs/decisions.md).
inline constexpr float kTailDisc = 1.5f;

/// The z threshold of a primitive (Z^3 merging, §6.2.3; RenderOptions::zThresholdMode), for the
/// scalar paths (FrameContext::zThreshold) and the SIMD set-ups alike: PerPrimitive, `scale`
/// times the primitive's depth extent over its footprint (depth units); Fixed, the frame's
/// `fixed` = zThreshold times the bounding-sphere radius.
struct ZThresholdRule {
  bool perPrimitive = true;
  float scale = 0;  ///< PerPrimitive: the multiple of the depth extent
  float fixed = 0;  ///< Fixed: the frame's threshold, depth units
  static ZThresholdRule make(const RenderOptions& options, float sphereRadius) {
    const float z = zThresholdOf(options);
    return {options.zThresholdMode == ZThresholdMode::PerPrimitive, z, z * (sphereRadius > 0 ? sphereRadius : 1.0f)};
  }
  float operator()(float depthExtent) const { return perPrimitive ? scale * depthExtent : fixed; }
};

/// A segment sub-segment's weight scale is linear along it, scale0 + slope tau for tau in
/// [0, len] (§5.2: 1 / (h sqrt(det M)) at its ends). Where it changes by at most kFlatScale of
/// scale0 over the sub-segment, the kernels take it constant at its mean (beyond the thesis): the
/// slope term's two extra exps per pixel go (all but ~1% of a contour model's segments), the
/// weights move by at most kFlatScale / 2 and the blended colours (normalised weighted averages)
/// by far less. The SIMD kernel, the scalar closed form and their tests all evaluate this.
inline constexpr float kFlatScale = 1e-2f;
struct PieceScale {
  float scale0 = 0, slope = 0;
};
inline PieceScale pieceScale(float scale0, float slope, float len) {
  if (std::abs(slope * len) <= kFlatScale * scale0) return {scale0 + 0.5f * (slope * len), 0.0f};
  return {scale0, slope};
}

/// An affine function of the pixel position, f(px, py) = dx px + dy py + c.
struct Affine2 {
  float dx = 0, dy = 0, c = 0;
  float at(float px, float py) const { return dx * px + dy * py + c; }
};

/// k . r(px, py) as an affine function of the pixel, where r(px, py) = ((px - cx)/f, -(py - cy)/f, -1)
/// is the camera-space ray through the pixel at depth 1 (Camera::rayThrough). Every rasteriser
/// intersects its primitive's plane with these rays.
inline Affine2 rayDot(const Camera& cam, const Vec3f& k) {
  const float f = cam.focalPixels();
  const Vec2f pp = cam.principalPoint();
  return {k.x() / f, -k.y() / f, -k.x() * pp.x() / f + k.y() * pp.y() / f - k.z()};
}

/// exp(-q/2) for q in [0, 25] (cutoff radius up to 5 sigma), linearly interpolated: the thesis's
/// Gaussian weight texture in one dimension. Relative error below 1e-5.
struct GaussTable {
  static constexpr int kSize = 2048;
  static constexpr float kMaxQ = 25.0f;
  float v[kSize + 2];
  GaussTable() {
    for (int i = 0; i < kSize + 2; ++i) v[i] = std::exp(-0.5f * kMaxQ * float(i) / kSize);
  }
  /// q must lie in [0, kMaxQ].
  float operator()(float q) const {
    const float x = q * (kSize / kMaxQ);
    const int i = int(x);
    return v[i] + (x - float(i)) * (v[i + 1] - v[i]);
  }
};
/// Built at static initialisation, so lookups carry no guard check.
inline const GaussTable kGaussTable;

/// exp(-q/2) with q clamped to the table's range.
inline float gaussHalf(float q) { return kGaussTable(std::clamp(q, 0.0f, GaussTable::kMaxQ)); }

/// Pixels whose centres (i + 0.5) lie in [x0, x1] x [y0, y1], clamped to the view; `cut` tells
/// whether the view clamped them.
inline PixelRect pixelBounds(const Camera& cam, double x0, double y0, double x1, double y1, bool& cut) {
  const double lim = 1e7;
  auto lo = [&](double v) { return int(std::ceil(std::clamp(v, -lim, lim) - 0.5)); };
  auto hi = [&](double v) { return int(std::floor(std::clamp(v, -lim, lim) - 0.5)) + 1; };
  const PixelRect bb{lo(x0), lo(y0), hi(x1), hi(y1)};
  const PixelRect out = bb.intersect(PixelRect{0, 0, cam.width(), cam.height()});
  cut = out.x0 != bb.x0 || out.y0 != bb.y0 || out.x1 != bb.x1 || out.y1 != bb.y1;
  return out;
}

/// Screen bounding box of the conic S^2 + T^2 <= c N^2 (S, T, N affine in the pixel: the
/// projected cutoff ellipse of a splat whose plane coordinates are (S, T) / N); false when it is
/// not a bounded ellipse. Double precision: the coefficients cancel for small splats.
inline bool conicBounds(const Affine2& S, const Affine2& T, const Affine2& N, double c, double& x0, double& y0,
                        double& x1, double& y1) {
  auto dot = [](double a0, double a1, double b0, double b1) { return a0 * b0 + a1 * b1; };
  const double a00 = dot(S.dx, T.dx, S.dx, T.dx) - c * double(N.dx) * N.dx;
  const double a01 = dot(S.dx, T.dx, S.dy, T.dy) - c * double(N.dx) * N.dy;
  const double a11 = dot(S.dy, T.dy, S.dy, T.dy) - c * double(N.dy) * N.dy;
  const double b0 = dot(S.dx, T.dx, S.c, T.c) - c * double(N.dx) * N.c;
  const double b1 = dot(S.dy, T.dy, S.c, T.c) - c * double(N.dy) * N.c;
  const double m = dot(S.c, T.c, S.c, T.c) - c * double(N.c) * N.c;
  const double det = a00 * a11 - a01 * a01;
  if (!(a00 > 0 && det > 0)) return false;
  const double cx = (a01 * b1 - a11 * b0) / det, cy = (a01 * b0 - a00 * b1) / det;
  const double k = -(m + b0 * cx + b1 * cy);  // the ellipse is (p - centre)^T A (p - centre) <= k
  if (!(k > 0)) return false;
  const double hx = std::sqrt(k * a11 / det), hy = std::sqrt(k * a00 / det);
  const double slack = 0.01 + 1e-4 * (hx + hy);  // against the float rounding of the per-pixel test
  x0 = cx - hx - slack, x1 = cx + hx + slack, y0 = cy - hy - slack, y1 = cy + hy + slack;
  return std::isfinite(x0) && std::isfinite(x1) && std::isfinite(y0) && std::isfinite(y1);
}

/// Clips a convex camera-space polygon of n <= 16 vertices against the near and far planes and
/// returns the screen bounding box of what remains; false when nothing remains. `clipped` tells
/// whether a plane cut the polygon.
bool clippedScreenBounds(const Camera& cam, const Vec3f* poly, int n, float& x0, float& y0, float& x1, float& y1,
                         bool& clipped);

}  // namespace linesurf::detail
