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
///
/// The pipeline's stages for segments (PreparedSegment, prepareSegment, rasterizeSegment) are
/// internal: src/render/segment_splat.h.
namespace linesurf {

/// Largest number of ScreenSpace sub-segments per segment.
inline constexpr int kMaxSegmentPieces = 32;

/// The weight textures of §5.2.3.2 for cutoff radius R, in this project's weight units
/// (Gaussians without the 1/(2 pi), as point splats): T1(x, y) = integral over t >= 0 of the
/// cut-off unit Gaussian at (x - t, y); T2(y) = the same over all t. x, y in standard deviations.
/// Sampled on kWeightTextureSize x kWeightTextureSize/2 texels over [-R, R] x [0, R], bilinear.
inline constexpr int kWeightTextureSize = 128;
float weightTextureT1(float cutoffRadius, float x, float y);
float weightTextureT2(float cutoffRadius, float y);

}  // namespace linesurf
