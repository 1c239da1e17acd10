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
/// tile with its fast path in SIMD too (detail/splat_rows.h, pointRowsZ3).
#include <cstdint>

#include "detail/splat_rows.h"
#include "linesurf/core/model.h"
#include "linesurf/render/splat_context.h"

namespace linesurf {

/// Gouraud colour of a splat wider than PreparedPoint::kFlatShadeSpan: C0 + Cs s + Ct t + Cst s t
/// over the plane coordinates (s, t). Kept out of PreparedPoint (few splats need it).
struct PointGouraud {
  Vec3f C0 = Vec3f::Zero(), Cs = Vec3f::Zero(), Ct = Vec3f::Zero(), Cst = Vec3f::Zero();
};

/// One prepared splat: 128 bytes, two cache lines (prepare writes, and every tile it touches
/// reads, one per visible point).
struct alignas(64) PreparedPoint {
  PixelRect bounds;              ///< screen bounds of the cutoff ellipse (clamped to the viewport)
  detail::PointRaster raster;    ///< per-pixel weight and depth
  float zThreshold = 0;          ///< Z^3 merge tolerance
  /// The blended attributes (Z3Tile::Attr): colour (lit, or the albedo when lighting is
  /// deferred), alpha, 1, camera-space unit normal facing the viewer.
  float attr[Z3Tile::kAttrs] = {};
  uint32_t index = 0;            ///< primitive index in the model
  /// Gouraud-shaded: its colour polynomial (storage of the preparer's); null: attr's colour.
  const PointGouraud* gouraud = nullptr;
  static constexpr int kFlatShadeSpan = 6;
};
static_assert(sizeof(PreparedPoint) == 128);

/// Prepare stage (see splat_context.h); colour through frame.primitiveColor. Radius <= 0 or
/// non-finite, or zero normal: Degenerate. A Gouraud-shaded splat's colour polynomial goes to
/// `gouraud`, and out.gouraud points to it.
PrimitiveStatus preparePoint(const Point& point, uint32_t index, const FrameContext& frame, PreparedPoint& out,
                             PointGouraud& gouraud);

/// Rasterise stage: writes the splat's fragments inside ctx.rect into ctx.tile.
void rasterizePoint(const PreparedPoint& splat, const SplatContext& ctx);

}  // namespace linesurf
