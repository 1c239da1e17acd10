#pragma once
/// The rasteriser extension point of the splatting pipeline (thesis §6.2.2), internal to
/// src/render. The pipeline
/// (renderer.cpp) runs every primitive kind through the same two stages:
///
///  1. prepare (per primitive, in parallel, once per frame): back-face culling, model-view
///     transform, local parameterisation, warping, clipping against the frustum, lighting;
///     produces a Prepared<Kind> whose `bounds` (screen pixels) bins it to screen tiles and a
///     PrimitiveStatus that the pipeline counts. Signature for kind K:
///         PrimitiveStatus prepareK(const K& primitive, uint32_t index, const FrameContext& frame,
///                                  PreparedK& out);
///  2. rasterise (per tile, tiles in parallel, primitives in index order: points first, then
///     segments): scan conversion of the prepared primitive restricted to ctx.rect, producing
///     Fragments that go to ctx.tile.insert(x, y, fragment):
///         void rasterizeK(const PreparedK& prepared, const SplatContext& ctx);
///     A rasteriser only writes into ctx.tile, so the image is the same for any thread count.
///
/// Points: point_splat.h (§4.2.2). Line segments: segment_splat.h (§5).
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "linesurf/core/image.h"
#include "linesurf/core/math.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/render_options.h"
#include "splat_rules.h"
#include "z3_buffer.h"

namespace linesurf {

/// Outcome of the prepare stage for one primitive.
enum class PrimitiveStatus : uint8_t {
  Drawn,       ///< entirely inside the view frustum, will be rasterised
  Clipped,     ///< crosses a frustum plane: rasterised, fragments outside are dropped
  Culled,      ///< back-facing (only with RenderOptions::backfaceCulling)
  Outside,     ///< entirely outside the view frustum
  Degenerate,  ///< zero/NaN radius, normal or length; skipped and counted, never drawn
};

/// Per-frame constants shared by all rasterisers (read-only during the frame).
struct FrameContext {
  const Camera* camera = nullptr;
  const RenderOptions* options = nullptr;
  /// Texture of the model (segment uv, §5.2.4); null when untextured.
  const Image* texture = nullptr;
  /// Bounding sphere of the model (fixed z threshold scale, lighting defaults).
  BoundingSphere sphere;
  /// Unit direction towards the light, camera space.
  Vec3f lightDirCamera = Vec3f(0, 0, 1);
  /// The z threshold of a primitive from its depth extent (RenderOptions::zThresholdMode; the
  /// rule the SIMD set-ups apply too).
  detail::ZThresholdRule zRule;
  /// Normalisation of a unit-variance 2D Gaussian weight is not applied: weights are
  /// exp(-q/2) / (r0 r1) with r0 r1 the object-space standard deviations of the resampling
  /// filter (§5.2.3.3 per-vertex weight scaling); the final Z^3 division normalises.
  /// Gaussian value below which fragments are dropped: exp(-cutoff^2 / 2).
  float cutoffQ = 6.25f;  ///< cutoffRadius^2, compare with the Mahalanobis distance q

  /// camera.frustumPlanes(), computed once per frame.
  std::array<Vec4f, 6> frustum;
  /// false when the model has no colours: every primitive gets options.defaultColor.
  bool modelHasColors = true;
  /// The model's segments carry normal0/normal1 (Attributes::endpointNormals): shading normals
  /// are interpolated along segments (segment_splat.h).
  bool endpointNormals = false;
  /// Per-point shading normals (HybridModel::pointShadingNormals, by point index; null when the
  /// model has none): they light the points, whose own normals stay their planes (smooth contour models).
  const Vec3f* pointShadingNormals = nullptr;
  /// Per-point masses (pointMasses(model), by point index; null: every point weighs 1): a
  /// point's weight scale is multiplied by its mass (docs/decisions.md, "Point masses").
  const float* pointMasses = nullptr;

  const Camera& cam() const { return *camera; }

  /// The albedo (rgb) and alpha a primitive of colour `c` is drawn with: options.defaultColor
  /// when the model has no colours, alpha replaced by options.alphaOverride when that is >= 0.
  Color primitiveColor(const Color& c) const {
    Color out = modelHasColors ? c : options->defaultColor;
    if (options->alphaOverride >= 0) out.w() = options->alphaOverride;
    return out;
  }
  const RenderOptions& opt() const { return *options; }

  /// The z threshold for a primitive whose depth extent over its footprint is `depthExtent`
  /// (depth units): zThresholdOf(options) * depthExtent in PerPrimitive mode, that times the
  /// bounding radius in Fixed mode (zRule).
  float zThreshold(float depthExtent) const { return zRule(depthExtent); }

  /// Phong shading (Material) of `albedo` at a camera-space surface point with camera-space
  /// unit normal facing the viewer (flip it first for two-sided lighting). Returns linear RGB.
  /// The specular power comes from specularPow when make() built it.
  Vec3f shade(const Vec3f& albedo, const Vec3f& normalCamera, const Vec3f& pointCamera) const;
  /// x^shininess on [0, 1] at kSpecularTable + 2 samples, linearly interpolated (error below 1e-4
  /// up to shininess 128; null above, where std::pow is used).
  std::shared_ptr<const std::vector<float>> specularPow;
  static constexpr int kSpecularTable = 4096;

  /// Builds the context for one frame (normalises the light, computes zRule, cutoffQ).
  static FrameContext make(const Camera& camera, const RenderOptions& options, const BoundingSphere& sphere,
                           bool modelHasColors = true, const Image* texture = nullptr);
};

/// What a rasteriser gets for one tile.
struct SplatContext {
  const FrameContext& frame;
  /// The tile's pixels; rasterise only inside it (it is also ctx.tile.rect()).
  PixelRect rect;
  Z3Tile& tile;
};

}  // namespace linesurf
