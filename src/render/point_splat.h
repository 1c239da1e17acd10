#pragma once
/// Object-space EWA point splats, thesis §4.2.2 and §6.2.2 (after Ren, Pfister, Zwicker 2002).
/// Internal to the pipeline (renderer.cpp); the contract is splat_context.h's.
///
/// prepare: back-face culling (before any other work); model-view transform; local
/// parameterisation (tangent frame u, v of the point's normal); warping: the screen prefilter
/// (variance V_h) mapped into the tangent plane by the inverse Jacobian J^-1 of the local
/// projection and convolved with the reconstruction Gaussian sigma_r^2 I, giving the
/// object-space resampling filter V = sigma_r^2 I + V_h J^-1 J^-T (§5.2.3.1); weight scaling
/// 1/sqrt(det V) (§5.2.3.3). Common case in closed form: V^-1 = L L^T (Cholesky) gives the plane
/// axes, and the screen bounds are those of the projected cutoff ellipse (a conic in the pixel
/// plane). Splats stretched past kMaxStretch, behind the eye or crossing the near/far plane take
/// the exact path of the thesis instead: eigen-decomposition Rot(theta) Lambda^2 Rot(theta)^T,
/// bounding quadrilateral centre +- cutoff r0 e0 +- cutoff r1 e1 clipped to the near/far planes.
/// Lighting (§6.2.2): Gouraud, i.e. Phong at the corners of the bounding quadrilateral
/// c +- cutoff B0 +- cutoff B1 (B0, B1 the plane vectors of unit plane coordinates) interpolated
/// bilinearly, or once at the centre when the splat spans at most kFlatShadeSpan pixels each way
/// (the corners then differ by less than a grey level); with RenderOptions::perPixelLighting the
/// fragments carry albedo and normal and are lit once per pixel at the resolve (deferred).
///
/// rasterise: for every pixel centre in the bounds the viewing ray is intersected with the
/// tangent plane (perspective-exact, equivalent to the thesis's perspective-correct weight
/// texture coordinates); the plane coordinates give the weight exp(-q/2) / sqrt(det V), q <=
/// cutoff^2, and the depth. Rows of pixels are evaluated in SIMD and go straight into the Z^3
/// tile with its fast path in SIMD too (point_rows.h, pointRunZ3: a tile's run of splats
/// in one call).
#include <cmath>
#include <cstdint>

#include "linesurf/core/model.h"
#include "point_rows.h"
#include "splat_context.h"

namespace linesurf {

/// Gouraud colour of a splat wider than PreparedPoint::kFlatShadeSpan: C0 + Cs s + Ct t + Cst s t
/// over the plane coordinates (s, t). Kept out of PreparedPoint (few splats need it).
struct PointGouraud {
  Vec3f C0 = Vec3f::Zero(), Cs = Vec3f::Zero(), Ct = Vec3f::Zero(), Cst = Vec3f::Zero();
};

/// One prepared splat's hot record, 64 bytes (one cache line): all that the rows read in the
/// common case (prepare writes one, and every tile it touches reads it, per visible point; the
/// dragon's 206 k of them stream through memory every frame). The rest of a prepared point lies
/// in PointSlots' side arrays under the same slot: its bounds (read by binning and the tile
/// loop), its normal and index (read only when the tile blends normals), its Gouraud colours
/// (only when gouraud(), which follows from the bounds).
/// Fields (detail::PointHot): N, S, T, depthNum (ray/plane constants, detail::PointRaster);
/// weightScaleSigned: 1/sqrt(det V), its sign bit set when the fragments' depths are clipped to
/// [near, far] (the few splats crossing a depth plane); zThreshold: the Z^3 merge tolerance;
/// color: the blended colour (lit, or the albedo when lighting is deferred) and alpha (the
/// normal is PointCold's).
struct alignas(64) PreparedPoint : detail::PointHot {
  static constexpr int kFlatShadeSpan = detail::kPointFlatShadeSpan;
  float weightScale() const { return std::fabs(weightScaleSigned); }
  bool clipDepth() const { return std::signbit(weightScaleSigned); }
  void setWeightScale(float w, bool clip) { weightScaleSigned = clip ? -w : w; }
  /// Gouraud-shaded (PointGouraud beside it) when lighting is not deferred and the splat spans
  /// more than kFlatShadeSpan pixels either way.
  static bool gouraud(const PixelRect& bounds, bool perPixelLighting) {
    return !perPixelLighting && (bounds.width() > kFlatShadeSpan || bounds.height() > kFlatShadeSpan);
  }
};
static_assert(sizeof(PreparedPoint) == 64);

/// The cold part of a prepared point: camera-space unit normal facing the viewer, and the
/// primitive index in the model.
struct PointCold {
  float normal[3] = {};
  uint32_t index = 0;
  /// the tail form of the splat's own disc (beyond the thesis, detail::PointTail; docs/decisions.md, "Tail layers"): a
  /// fragment at plane coordinates (s, t) lies outside kTailDisc times the disc |p - c| <= cutoff
  /// sigma_r where disc[0] s^2 + disc[1] s t + disc[2] t^2 > 1 (disc[3] unused). Zero: never.
  float disc[4] = {};
};

/// Where a prepared point's parts go: slot j of each array (the arrays may be uninitialised
/// storage; prepare constructs what it writes).
struct PointSlots {
  PreparedPoint* hot = nullptr;
  PixelRect* bounds = nullptr;   ///< screen bounds of the cutoff ellipse (clamped to the viewport)
  PointCold* cold = nullptr;
  PointGouraud* gouraud = nullptr;
  PointSlots operator+(size_t k) const { return {hot + k, bounds + k, cold + k, gouraud + k}; }
};

/// Prepare stage (see splat_context.h); colour through frame.primitiveColor. Radius <= 0 or
/// non-finite, or zero normal: Degenerate. Writes slot 0 of `out` (constructs all four parts;
/// the Gouraud colours only when gouraud()).
PrimitiveStatus preparePoint(const Point& point, uint32_t index, const FrameContext& frame, const PointSlots& out);

/// The per-pixel constants of a prepared splat (the frame's cutoff and depth range).
detail::PointRaster pointRaster(const PreparedPoint& splat, const FrameContext& frame);

/// Rasterise stage: writes the fragments of the splats in slots refs[0 .. n) of `slots` (each
/// one's bounds touch ctx.rect) inside ctx.rect into ctx.tile, in that order.
void rasterizePoints(const PointSlots& slots, const uint32_t* refs, int n, const SplatContext& ctx);

}  // namespace linesurf
