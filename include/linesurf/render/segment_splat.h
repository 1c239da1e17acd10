#pragma once
/// Object-space EWA splatting of line segments, thesis §5 (docs/segment-splatting.md).
///
/// A segment p0-p1 of radius r is the integral of point resampling filters along it (§5.1.1),
/// normalised as the row of points it replaces. Every point of this project carries radius =
/// local sample spacing, so a segment of radius r stands for points at spacing h = r along it:
///
///     w(x) = (1/h) * integral_0^L  exp(-q_t(x)/2) / sqrt(det M(t))  dt,    h = r,
///
/// with M(t) = sigma_r^2 I + V_h J(t)^-1 J(t)^-T the object-space resampling covariance of the
/// point p(t) (Jacobian J(t) recomputed along the segment, §5.1.2), q_t the Mahalanobis distance
/// in M(t) of the pixel's ray/plane intersection from p(t), each point kernel cut off at
/// q <= cutoffRadius^2 exactly as point splats are (src/render/point_splat.h: weight exp(-q/2)/(r0 r1)).
/// A row of points at spacing h and a segment through them therefore give the same weight
/// profile, and points and segments blend into one surface through Z^3.
///
/// Three evaluations (RenderOptions::segmentMethod):
///  - Approx (§5.2.3, the thesis): endpoint resampling ellipses M_k = Rot(theta) Lambda^2
///    Rot(theta)^T, their outer common tangents (points 1-4), the axis line 9-10 meeting the
///    ellipses at 5-8, tangents there (11-18); 10 quadrilaterals (long case) or 8 (short case,
///    split by the line through the ellipses' intersection points), mapped with the weight
///    textures T1 (endpoint portions) and T2 (middle) of §5.2.3.2 and the scaling factor
///    interpolated between points 9 and 10 (§5.2.3.3, Figure 19). Constructions that fail
///    (nested, tiny or wildly eccentric ellipses) fall back to ScreenSpace and are counted
///    (PreparedSegment::fallback).
///  - ScreenSpace (after §9.3, the default): per pixel, the integral along each of up to
///    kMaxPieces sub-segments in closed form (erf), M constant and the weight scale linear per
///    sub-segment; sub-segments where M changes along the segment.
///  - Reference: per pixel, numerical quadrature over t of the exact integrand with M(t)
///    recomputed at every node (midpoint rule, node spacing sigma_r / 32: relative weight error
///    below 2e-3). Slow; for measuring the other two.
///
/// Contract with the pipeline (see splat_context.h for the two stages):
///  - prepareSegment is called once per segment per frame, in parallel, with the segment's
///    index in model.segments. It fills out.bounds (screen pixels, clamped to the viewport,
///    empty when nothing is drawn) and returns the PrimitiveStatus that the pipeline counts.
///    Zero length, zero/NaN radius or non-finite input: Degenerate (a zero-length segment has
///    zero weight). A zero normal is replaced by the strip facing the viewer.
///  - rasterizeSegment is called for every screen tile that out.bounds touches, in segment index
///    order within the tile (after the tile's points); it writes only through
///    ctx.tile.insert(x, y, fragment) for pixels inside ctx.rect. Fragment.zThreshold via
///    frame.zThreshold(depth extent), interpolated along the segment in PerPrimitive mode.
///  - Texture (§5.2.4): uv interpolated between the endpoints and held constant beyond them
///    (the thesis assigns the endpoint's uv to points 1, 4, 5, 9, 11, 18); sampled per pixel.
///  - Lighting: Phong at stations along the segment interpolated along it (Gouraud, §6.2.2), or
///    per pixel with RenderOptions::perPixelLighting (deferred: the fragments carry albedo and
///    normal, lit once per pixel and Z^3 layer at the resolve, renderer.cpp).
///  - Smooth line models (beyond the thesis): when the model has Attributes::endpointNormals
///    (FrameContext::endpointNormals) and both of a segment's normal0/normal1 are usable, the
///    shading normal is interpolated between them along the segment (normalize(lerp(n0, n1, u)),
///    u the along-axis parameter); the strip's plane (weights, depth, culling) still comes from
///    Segment::normal (or from n0 + n1 when that is zero).
#include <cstdint>
#include <vector>

#include "linesurf/core/model.h"
#include "linesurf/render/splat_context.h"

namespace linesurf {

/// One sub-segment of the ScreenSpace method: plane coordinates (a along the segment from p0,
/// b across) with the resampling covariance held constant.
struct SegmentPiece {
  float a0 = 0, a1 = 0;              ///< along-range [a0, a1] of the sub-segment
  float m00 = 1, m01 = 0, m11 = 1;   ///< M^-1 in (a, b)
  float scale0 = 0, scale1 = 0;      ///< weight scale 1 / (h sqrt(det M)) at a0 and a1
  float reach = 0;                   ///< R sqrt(M_aa): how far along a kernel reaches
  // derived once in prepare (the per-pixel closed form needs no division)
  float skew = 0;                    ///< m01 / m00
  float across = 1;                  ///< m11 - m01^2 / m00 = 1 / M_bb
  float invM00 = 1;                  ///< 1 / m00
  float k = 1;                       ///< sqrt(m00 / 2)
  float erfScale = 1;                ///< sqrt(pi) / 2 / k
  float slope = 0;                   ///< (scale1 - scale0) / (a1 - a0), 0 when negligible
};

/// One node of the Reference quadrature.
struct SegmentNode {
  float m00 = 1, m01 = 0, m11 = 1;  ///< M(t)^-1 in (a, b)
  float scale = 0;                  ///< dt / (h sqrt(det M(t)))
};

/// One weight-texture-mapped quadrilateral of the Approx method (§5.2.3.2).
struct SegmentQuad {
  Vec2f corner[4];  ///< plane coordinates (a, b); bilinear order 00, 10, 11, 01 (a cycle)
  Vec2f tex[4];     ///< weight-texture coordinates (x inward from the endpoint, y across)
  float scale[4];   ///< weight scaling factor at the corners (Figure 19)
  bool middle = false;   ///< T2 (middle portion) instead of T1 (endpoint portion)
  float tail = 1e30f;    ///< texture length of the segment: T1(x) - T1(x - tail) (short case)
  Vec2f lo = Vec2f::Zero(), hi = Vec2f::Zero();  ///< bounding box of the corners
};

struct WeightTextures;  // §5.2.3.2 tables, segment_splat.cpp

struct PreparedSegment {
  PixelRect bounds;        ///< screen bounding box (clamped to the viewport); bins the segment
  uint32_t index = 0;      ///< index in model.segments
  // --- implementation ---------------------------------------------------------------------
  SegmentMethod method = SegmentMethod::ScreenSpace;  ///< evaluation used (after fallback)
  bool fallback = false;   ///< Approx construction failed; drawn with ScreenSpace instead
  bool longCase = true;    ///< Approx: 10 quads (long) or 8 (short)
  bool clipped = false;    ///< crosses the near/far plane: per-fragment depth test
  bool textured = false;
  Vec3f origin = Vec3f::Zero();  ///< p0, camera space
  Vec3f along = Vec3f::Zero();   ///< unit (p1 - p0) / L, camera space
  Vec3f across = Vec3f::Zero();  ///< unit along x normal: the b axis, camera space
  Vec3f normal = Vec3f::Zero();  ///< unit, facing the viewer: the strip's plane
  /// Smooth line models (Attributes::endpointNormals): unit shading normals at p0 and p1, camera
  /// space, on the viewer's side; a fragment's normal is normalize(lerp(normal0, normal1, u)) with
  /// u = a / length clamped to [0, 1]. false: every fragment carries `normal`.
  bool smooth = false;
  Vec3f normal0 = Vec3f::Zero(), normal1 = Vec3f::Zero();
  /// The shading normal at along-parameter u in [0, 1] (smooth segments only).
  Vec3f shadingNormal(float u) const {
    const Vec3f m = normal0 + u * (normal1 - normal0);
    const float len = m.norm();
    return len > 0 ? Vec3f(m / len) : normal;
  }
  float length = 0;
  float aMin = 0, aMax = 0, bMax = 0;  ///< plane-coordinate box of the footprint
  /// The footprint box projected to the screen (pixels), a convex quad when not clipped by the
  /// near/far plane: rasterisation visits only each row's span inside it.
  Vec2f screenQuad[4];
  bool useSpans = false;
  float zThreshold0 = 0, zThreshold1 = 0;  ///< at p0 and p1
  float alpha = 1;
  Vec3f albedo = Vec3f::Zero();
  Vec2f uv0 = Vec2f::Zero(), uv1 = Vec2f::Zero();
  /// Lighting stations evenly spaced over [0, length]: colour = albedo * diffuse + specular.
  std::vector<Vec3f> diffuse, specular;
  std::vector<SegmentPiece> pieces;  ///< ScreenSpace
  /// ScreenSpace: pieces are evenly spaced (piece k covers [k, k+1] / pieceInvLength); a pixel at
  /// a only meets the pieces within pieceMaxReach (the largest reach) of it.
  float pieceInvLength = 0, pieceMaxReach = 0;
  std::vector<SegmentNode> nodes;    ///< Reference, spacing nodeStep starting at nodeStep / 2
  float nodeStep = 0, nodeReach = 0;
  std::vector<SegmentQuad> quads;    ///< Approx
  const WeightTextures* textures = nullptr;
};

/// The segment's resampling-filter weight at screen position `pixel` (pixel units; centres at
/// i + 0.5), as rasterizeSegment would give it (0 outside the footprint or behind the eye). For
/// tests and error measurements (docs/segment-splatting.md).
float segmentWeightAt(const PreparedSegment& segment, const FrameContext& frame, const Vec2f& pixel);

/// Largest number of ScreenSpace sub-segments per segment.
inline constexpr int kMaxSegmentPieces = 32;

/// Prepare stage for one segment (see above and splat_context.h).
PrimitiveStatus prepareSegment(const Segment& segment, uint32_t index, const FrameContext& frame,
                               PreparedSegment& out);

/// Rasterise stage for one segment on one tile (see above and splat_context.h).
void rasterizeSegment(const PreparedSegment& segment, const SplatContext& ctx);

/// The weight textures of §5.2.3.2 for cutoff radius R, in this project's weight units
/// (Gaussians without the 1/(2 pi), as point splats): T1(x, y) = integral over t >= 0 of the
/// cut-off unit Gaussian at (x - t, y); T2(y) = the same over all t. x, y in standard deviations.
/// Sampled on kWeightTextureSize x kWeightTextureSize/2 texels over [-R, R] x [0, R], bilinear.
inline constexpr int kWeightTextureSize = 128;
float weightTextureT1(float cutoffRadius, float x, float y);
float weightTextureT2(float cutoffRadius, float y);

}  // namespace linesurf
