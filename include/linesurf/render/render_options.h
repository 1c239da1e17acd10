#pragma once
/// Every parameter of the software splatting pipeline (thesis §4, §5, §6.2), with documented
/// defaults. validate() throws linesurf::Error (BadParameter) for absurd values.
///
/// Filter model (thesis §4.2.2, object-space EWA after Ren, Pfister, Zwicker 2002):
///  - A primitive of object-space radius r carries a reconstruction Gaussian of standard
///    deviation sigma_r = reconstructionScale * r in its tangent plane (for a segment: across
///    the strip, integrated along it, §5).
///  - The screen prefilter is a Gaussian of variance prefilterVariance (pixels^2), warped into
///    object space by the inverse local Jacobian of the projection and convolved with the
///    reconstruction Gaussian: the resampling filter.
///  - The resampling filter is cut off at cutoffRadius standard deviations (its bounding
///    quadrilateral is Rot(theta) * Lambda scaled by the cutoff, §5.2.3.1).
#include <cstdint>
#include <optional>

#include "linesurf/core/math.h"
#include "linesurf/core/progress.h"

namespace linesurf {

/// How two fragments at one pixel are judged to be the same surface (Z^3 merging, §6.2.3).
enum class ZThresholdMode {
  /// The thesis's single threshold for the whole frame: zThreshold * bounding-sphere radius
  /// (depth units). Misbehaves with depth (thesis Figure 20).
  Fixed,
  /// Per primitive, from its own depth extent over its footprint (the delta-z idea of
  /// §6.2.3.2; interpolated along a segment): zThreshold * extent. Default.
  PerPrimitive,
};

/// How a line-segment splat's resampling filter is evaluated (thesis §5.2.3).
enum class SegmentMethod {
  Approx,       ///< §5.2.3: 2-10 weight-texture-mapped bounding quadrilaterals (the thesis)
  ScreenSpace,  ///< exact screen-space integral of the Gaussian along the segment (erf closed form)
  Reference,    ///< numerical quadrature of point splats along the segment (slow, for tests)
};

/// Phong material (thesis §6.2.2 lighting: ambient, diffuse, specular).
/// colour = albedo * (ambient + diffuse * max(0, n.l)) + specular * max(0, n.h)^shininess.
struct Material {
  float ambient = 0.25f;   ///< [0, 1]
  float diffuse = 0.75f;   ///< [0, 1]
  float specular = 0.2f;   ///< [0, 1], white highlight
  float shininess = 24.0f; ///< Phong exponent, > 0
};

/// One directional light.
struct Light {
  /// Direction towards the light, in CAMERA space when headlight is true (default: from above
  /// left, behind the viewer), otherwise in world space. Normalised by the pipeline.
  Vec3f direction = Vec3f(-0.35f, 0.45f, 1.0f);
  Vec3f color = Vec3f(1, 1, 1);
  bool headlight = true;
};

struct RenderOptions {
  // --- filtering (§4.2.2) -------------------------------------------------------------------
  /// Variance of the screen-space Gaussian prefilter, pixels^2. 0 disables the prefilter (plain
  /// object-space splatting, aliases under minification). Default 0.25 px^2 (pbrt's Gaussian
  /// pixel filter, sigma 0.5), not the thesis's identity (Zwicker et al. 2001): 1 paints small
  /// splats' colour ~1 px past every silhouette; 0.25 keeps the hole tests closed with the
  /// geometry stage's regrown open stars and still halves the grazing checkerboard's error against
  /// no prefilter (docs/decisions.md, "Screen prefilter").
  float prefilterVariance = 0.25f;
  /// Cut-off of the resampling Gaussian, in standard deviations; fragments beyond it are not
  /// generated. [1, 5], default 2 (weights below e^-2 = 13.5% of the peak are dropped; 2.5
  /// costs 56% more fragments for no visible change, see docs/rendering.md).
  float cutoffRadius = 2.0f;
  /// sigma_r = reconstructionScale * primitive radius (object space). Default 0.5: the disc of
  /// the primitive's radius is the 2-sigma ellipse of its reconstruction Gaussian. (0, 4].
  float reconstructionScale = 0.5f;

  /// Coverage alpha (beyond the thesis). > 0: a pixel's alpha is the surface's coverage
  /// min(1, g sum_k c_k w_k) (w_k the fragments' resampling weights, c_k the inverse of the model's
  /// least kernel density around primitive k, src/render/coverage.h; g this gain), composited over
  /// what lies behind, instead of the normalised alpha that paints a splat's colour out to its
  /// cut-off: the soft silhouette of a box-filtered mesh instead of a 1-3 pixel fringe. With
  /// coverage everywhere (coverageReach 0) a partly covered layer keeps the layers behind it (Z^3
  /// step b waits for full coverage); at silhouettes only, the frame keeps an opaque frame's layers
  /// and sums what they drop per pixel, and a silhouette pixel's front is composited over that and
  /// its farther neighbour. Only when every primitive is opaque (no alphaOverride < 1, no colour
  /// alpha < 1, no texture); otherwise the thesis's alpha. 0 = off, the default: Table 5 (line vs
  /// point model) gets worse and frames cost 4-28% more at silhouettes only (10-120% everywhere;
  /// docs/decisions.md, "Coverage alpha (opt-in)"); 1.25 measured best
  /// for contour models at silhouettes only (1.5 everywhere). [0, 100].
  float coverageGain = 0.0f;
  /// Where coverage alpha applies (beyond the thesis; docs/decisions.md, "The
  /// silhouette fringe"). > 0: only at silhouettes, i.e. at a pixel whose front layer is partly covered
  /// and that has, within this many pixels (a square of side 2 reach + 1), a pixel showing the
  /// background or a front layer farther than this one's by its z threshold and 2 % of its
  /// depth; every other pixel keeps the normalised (opaque) alpha, so the gaps of an irregular or
  /// sparse sampling inside a surface stay closed. 0: everywhere (the gaps show). [0, 16]; only
  /// with coverageGain > 0.
  int coverageReach = 2;

  // --- visibility and blending (§6.2.3, modified Z^3) -----------------------------------------
  ZThresholdMode zThresholdMode = ZThresholdMode::PerPrimitive;
  /// Fixed: fraction of the bounding-sphere radius. PerPrimitive: multiple of the primitive's
  /// depth extent. >= 0; unset: the mode's default, defaultZThreshold(zThresholdMode) (read it
  /// through zThresholdOf; see docs/rendering.md and the measurement in docs/decisions.md).
  std::optional<float> zThreshold;
  /// Fragment layers per pixel, [1, kMaxLayers]. Default 4 (thesis).
  int layers = 4;
  /// Tail layers (beyond the thesis; docs/decisions.md, "Tail layers"): a
  /// fragment whose ray meets its primitive's plane outside 1.5 times the primitive's own disc
  /// (a point: radius cutoff sigma_r; a segment: its strip) is a prefilter tail, its depth the
  /// plane's extrapolated; it occludes nothing and is not composited in front of another layer,
  /// only over the background (a silhouette's anti-aliasing). Removes most fold speckles (a
  /// grazing splat's tail as the opaque front layer): on the 7 contour meshes Table 5 and the
  /// line and point models against the mesh get better; line frames cost −3 to +10% and point
  /// frames −2 to +3% more (BM_ContourFrame). Only in an opaque frame without coverage alpha and with the ScreenSpace
  /// segment method (the Approx and Reference methods are the thesis's comparison paths: their
  /// frames keep the thesis's Z^3 for points too). On by default.
  bool tailLayers = true;
  /// Tail coverage (beyond the thesis; docs/decisions.md, "Tail coverage"):
  /// with tail layers, a pixel that only tails reached (its centre off every primitive's own disc
  /// or strip by half its size; nothing lies behind such a layer) and that borders an empty pixel
  /// (3 x 3) lies past a silhouette: it is composited over the background with alpha
  /// min(1, g c W) instead of the normalised 1, W its weight sum, c the model's median inverse
  /// kernel density (src/render/coverage.h, over a sample of ~4096 primitives), g this gain. The
  /// fringe of full colour that the prefilter paints past a silhouette fades as a box-filtered
  /// edge does; tail-only pixels that no empty pixel borders (gaps inside a surface) stay opaque.
  /// Lines and points against the mesh improve on all seven contour meshes (lines SSIM 0.957-0.971
  /// -> 0.964-0.993) at no frame cost, so 1 (on, the unbiased gain) is the default: pictures
  /// that look like the surface. Table 5 (line vs point model) gets worse on all seven (the point
  /// models' outline is notched between discs), so `experiment` keeps the thesis's 0 (off) for
  /// its tables. [0, 100]; 0 = off.
  float tailCoverage = 1.0f;
  static constexpr int kMaxLayers = 8;

  // --- shading (§6.2.2) -----------------------------------------------------------------------
  Material material;
  Light light;
  /// false: Gouraud (lit at the quadrilateral's vertices and interpolated, the thesis);
  /// true: lit at every fragment.
  bool perPixelLighting = false;
  /// Albedo of primitives when the model has no colours.
  Color defaultColor = Color(0.78f, 0.78f, 0.80f, 1.0f);
  /// Overrides every primitive's alpha when in [0, 1]; < 0 keeps the model's alpha.
  float alphaOverride = -1.0f;
  /// Shown where nothing is drawn; colour images are composited over it. Default opaque white.
  Color background = Color(1, 1, 1, 1);

  // --- culling ----------------------------------------------------------------------------------
  /// Drop primitives whose normal faces away from the viewer (§6.2.2 back-face culling). When
  /// off, back faces are lit with the flipped normal (two-sided lighting).
  bool backfaceCulling = true;
  /// With culling on, also measure on pixels which side of the surface the view shows
  /// (RenderStats::facing*): two more renders at a reduced resolution (Renderer::kFacingCheckSide),
  /// so that a front end can say when normals facing away leave the picture nearly empty. Off by
  /// default in the library (it costs two prepare passes); the CLI and Python turn it on.
  bool facingCheck = false;

  // --- line segments (§5) -------------------------------------------------------------------
  SegmentMethod segmentMethod = SegmentMethod::ScreenSpace;
  /// Segment level of detail (beyond the thesis; cf. the §5.2.3 approximation): a ScreenSpace
  /// segment whose length is at most segmentLod standard deviations of its resampling kernel
  /// along it (lambda = l sqrt((M^-1)_aa), M the kernel's covariance in the strip's plane) is
  /// drawn as the one elliptical point splat of the same mass, mean and covariance (M + var e_a
  /// e_a^T, the moment-matched Gaussian) through the point pipeline. Untextured one-piece segments
  /// that are not depth-clipped only. [0, 4]; 0 = off (every segment exact), the default: the
  /// ellipse's cutoff region misses the ends of the segment's capsule, which moves Z^3 coverage
  /// (al contour lines at 2: 0.67 grey levels mean difference; docs/segment-splatting.md).
  float segmentLod = 0.0f;

  // --- outputs ------------------------------------------------------------------------------
  bool depthBuffer = false;   ///< RenderResult::depth: nearest surface depth (0 = empty)
  bool alphaBuffer = false;   ///< RenderResult::alpha: coverage alpha before the background
  bool normalBuffer = false;  ///< RenderResult::normal: camera-space normal as (n+1)/2 RGB

  // --- execution ----------------------------------------------------------------------------
  /// Side of the square screen tiles rasterised in parallel, [8, 1024]. The image does not
  /// depend on it nor on the thread count (primitives are drawn in index order in each tile).
  int tileSize = 64;
  ProgressFn progress;  ///< optional, reported per tile batch from the calling thread
};

/// The z threshold a mode uses when RenderOptions::zThreshold is unset: 0.5 of the primitive's
/// depth extent (PerPrimitive), 0.01 of the bounding radius (Fixed, the thesis). See
/// docs/rendering.md.
constexpr float defaultZThreshold(ZThresholdMode mode) { return mode == ZThresholdMode::Fixed ? 0.01f : 0.5f; }

/// The z threshold in force: options.zThreshold, or its mode's default when unset.
inline float zThresholdOf(const RenderOptions& options) {
  return options.zThreshold.value_or(defaultZThreshold(options.zThresholdMode));
}

/// Throws linesurf::Error (BadParameter) naming the first absurd field.
void validate(const RenderOptions& options);

}  // namespace linesurf
