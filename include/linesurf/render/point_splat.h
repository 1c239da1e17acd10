#pragma once
/// Object-space EWA point splats, thesis §4.2.2 and §6.2.2 (after Ren, Pfister, Zwicker 2002).
///
/// prepare: back-face culling; model-view transform; local parameterisation (tangent frame
/// u, v of the point's normal); warping: the screen prefilter (variance V_h) mapped into the
/// tangent plane by the inverse Jacobian J^-1 of the local projection and convolved with the
/// reconstruction Gaussian sigma_r^2 I, giving the object-space resampling filter
/// V = sigma_r^2 I + V_h J^-1 J^-T = Rot(theta) Lambda^2 Rot(theta)^T (§5.2.3.1); its cutoff
/// ellipse is bounded by the quadrilateral  centre +- cutoff r0 e0 +- cutoff r1 e1,
/// projected for the screen bounds; weight scaling 1/(r0 r1) (§5.2.3.3); frustum clipping;
/// lighting (Gouraud at the quad's vertices, or per pixel).
///
/// rasterise: for every pixel centre in the projected quad's bounding box the viewing ray is
/// intersected with the tangent plane (exactly perspective-correct, equivalent to the thesis's
/// perspective-correct interpolation of weight-texture coordinates over the quad); the local
/// coordinates give the Gaussian weight exp(-q/2) / (r0 r1) with q the Mahalanobis distance in
/// V (the thesis reads it from a weight texture; we evaluate it exactly), depth, and the
/// bilinearly interpolated Gouraud colour.
#include <cstdint>

#include "linesurf/core/model.h"
#include "linesurf/render/splat_context.h"

namespace linesurf {

struct PreparedPoint {
  PixelRect bounds;            ///< screen bounding box of the projected cutoff quad (clamped)
  uint32_t index = 0;          ///< primitive index in the model
  Vec3f center = Vec3f::Zero();///< camera space
  Vec3f normal = Vec3f::Zero();///< camera space, unit, facing the viewer
  /// Plane-local axes scaled: a point p on the plane has local coords
  /// (s, t) = (e0.(p - c) / r0, e1.(p - c) / r1); q = s^2 + t^2.
  Vec3f axis0 = Vec3f::Zero(), axis1 = Vec3f::Zero();  ///< e0 / r0, e1 / r1
  float weightScale = 0;       ///< 1 / (r0 r1), object space (§5.2.3.3)
  float zThreshold = 0;        ///< Z^3 merge tolerance
  float alpha = 1;
  Vec3f albedo = Vec3f::Zero();
  /// Gouraud colours at the quad corners (s, t) = (-c,-c), (c,-c), (-c,c), (c,c), c = cutoff;
  /// unused with per-pixel lighting.
  Vec3f cornerColor[4];
  /// The quad spans at most kFlatShadeSpan pixels each way: its vertex colours differ by less
  /// than a grey level, so it is lit once at the centre (cornerColor[0]) and not interpolated.
  bool flat = false;
  static constexpr int kFlatShadeSpan = 6;
  bool clipped = false;        ///< crosses the near/far plane: per-fragment depth test needed
};

/// Prepare stage (see splat_context.h); colour through frame.primitiveColor. Radius <= 0 or
/// non-finite, or zero normal: Degenerate.
PrimitiveStatus preparePoint(const Point& point, uint32_t index, const FrameContext& frame, PreparedPoint& out);

/// Rasterise stage: writes the splat's fragments inside ctx.rect into ctx.tile.
void rasterizePoint(const PreparedPoint& splat, const SplatContext& ctx);

}  // namespace linesurf
