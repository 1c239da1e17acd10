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
/// q <= cutoffRadius^2 exactly as point splats are (point_splat.h: weight exp(-q/2)/(r0 r1)).
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
/// Contract with the pipeline (splat_context.h: the two stages):
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
/// The pipeline's two stages for line segments, internal to src/render (renderer.cpp):
/// prepare (one stage per function in segment_splat.cpp):
///  1. stripFrame: culling, model-view transform, the strip's axes (along, across, normal);
///  2. footprint: the resampling covariance along the segment (§5.1.2, segment_filter.h) in
///     sub-segments, and the footprint box in plane coordinates;
///  3. the method's own data (Reference nodes, Approx quadrilaterals; SegmentExtra,
///     segment_extra.h);
///  4. screenBounds: frustum test, near/far clipping, pixel bounds, the projected box;
///  5. the per-pixel constants of the SIMD rows (detail::SegmentRaster, segment_rows.h);
///  6. shading: Gouraud colours, smooth normals.
/// The common case (ScreenSpace, one sub-segment, untextured, colour linear along the segment)
/// allocates nothing and is rasterised by the SIMD rows; everything else keeps its state in
/// PreparedSegment::extra (allocated once per record slot, reused across frames). The common case
/// is prepared in SIMD batches too: segment_setup.h.
#include <cmath>
#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "linesurf/core/model.h"
#include "point_splat.h"
#include "segment_extra.h"
#include "segment_rows.h"
#include "segment_spans.h"
#include "splat_context.h"

namespace linesurf {

namespace segment {
/// ScreenSpace subdivision: a new sub-segment wherever M changes by more than this (relative
/// Frobenius norm) from one end of the sub-segment to the other.
inline constexpr double kPieceTolerance = 0.04;
/// Segments shorter than this fraction of their nearest depth take M in the middle as the mean of
/// the ends (relative error of the order of its square, 1e-4).
inline constexpr double kShortSegment = 0.01;
/// Smooth segments get one lighting station per this many radians the shading normal turns.
inline constexpr float kStationTurn = 0.1f;
}  // namespace segment

/// How a segment's fragments get their blended attributes (Z3Tile::Attr) from the
/// along-axis parameter u in [0, 1].
enum class SegmentShade : uint8_t {
  Constant,  ///< PreparedSegment::attr for every fragment (deferred lighting, one normal)
  Linear,    ///< colour attr + u dc (Gouraud between the end stations), one normal
  Smooth,    ///< colour attr + u dc, normal normalize(n0 + u dn) (smooth line models, turn <= 0.1 rad)
  Stations,  ///< several stations (SIMD rows, untextured) or a texture (per fragment): SegmentExtra
};

/// The most lighting stations a record holds itself (PreparedSegment::stationColour).
inline constexpr int kInlineStations = 3;

/// The record is aligned to cache lines and ordered hot first (see docs/decisions.md, "Segment records"): what the rows of
/// the common case read (extra, bounds, flags, raster, attr, dc, n0, dn) fills its first
/// kSegmentHotBytes; screenQuad (only the box walk reads it) comes last. Stage 3 prefetches only
/// the hot lines (4 instead of the 5-6 a 280-byte unaligned record spans).
struct alignas(64) PreparedSegment {
  /// null in the common case, or a SegmentExtra kept from an earlier use of the slot: reset by
  /// prepareSegment, left as it was by the SIMD batches (segment_setup.h), so read only where
  /// method, pieceCount or shade say the segment needs it (which sets it up). First, with
  /// the fields below up to `shade`: for a segment it does not draw prepareSegment writes (and
  /// reads) only the record's first cache line.
  std::unique_ptr<SegmentExtra> extra;
  PixelRect bounds;      ///< screen bounding box (clamped to the viewport); bins the segment
  uint32_t index = 0;    ///< index in model.segments
  SegmentMethod method = SegmentMethod::ScreenSpace;  ///< evaluation used (after fallback)
  bool fallback = false; ///< Approx construction failed; drawn with ScreenSpace instead
  bool useSpans = false; ///< screenQuad holds the projected footprint box (not depth-clipped)
  bool smooth = false;   ///< shading normals interpolated between the endpoints
  SegmentShade shade = SegmentShade::Constant;
  /// shade Stations, untextured: how many stations' colours stationColour
  /// holds, 0 for none (lighting deferred); -1: the stations are in extra
  int8_t stationCount = -1;
  /// The strip's plane, footprint box, first sub-segment and z thresholds as per-pixel
  /// constants (what the SIMD rows evaluate; the scalar paths intersect the plane with it too).
  detail::SegmentRaster raster;
  /// Attributes at u = 0 (colour, alpha, 1, normal); the colour's change to u = 1 (Linear,
  /// Smooth) and the smooth normal n0 + u dn (unit at both ends, facing the viewer).
  float attr[Z3Tile::kAttrs] = {};
  Vec3f dc = Vec3f::Zero(), n0 = Vec3f::Zero(), dn = Vec3f::Zero();
  /// The footprint box projected to the screen (pixels): rasterisation visits only each row's
  /// span inside it (the box walk; cold: the common case's tight spans do not read it).
  Vec2f screenQuad[4];
  /// shade Stations with stationCount > 0: channel c of station k at [c * stationCount + k]
  /// (most turning segments need 3 stations: their colours here, no SegmentExtra to touch)
  float stationColour[3 * kInlineStations];

  /// Number of ScreenSpace sub-segments (K > 1: their pieces in extra).
  int pieceCount() const { return raster.pieceCount; }
  float length() const { return raster.length; }
};
/// The record slot's SegmentExtra, allocated on its first use (then kept from frame to frame:
/// resetExtra).
inline SegmentExtra& extraOf(PreparedSegment& out) {
  if (!out.extra) out.extra = std::make_unique<SegmentExtra>();
  return *out.extra;
}

/// Gouraud intervals along a smooth segment whose shading normals turn by `turn` radians (§6.2.2,
/// beyond the thesis: one lighting station per kStationTurn), at least `minIntervals`. Shared by
/// the exact path (prepareSegment, stage 6) and the SIMD batches (prepareSegments), which must agree.
inline int stationIntervals(float turn, int minIntervals) {
  return std::clamp(int(std::ceil(turn / segment::kStationTurn)), minIntervals, kMaxSegmentPieces);
}

/// The slot's SegmentExtra for shade Stations with `intervals` Gouraud intervals (0: lighting
/// deferred, no stations); the untextured colours are sized, not filled.
inline SegmentExtra& stationsExtra(PreparedSegment& out, const Segment& seg, bool textured, int intervals) {
  SegmentExtra& x = extraOf(out);
  out.stationCount = -1;
  x.textured = textured;
  x.uv0 = seg.uv0;
  x.uv1 = seg.uv1;
  x.stations = intervals > 0 ? intervals + 1 : 0;
  if (!textured) x.colour.resize(3 * size_t(x.stations) + detail::kMaxLanes);  // padded: the rows load vectors
  return x;
}

/// Whether an untextured segment with `intervals` Gouraud intervals (0: lighting deferred) keeps
/// its stations in the record (PreparedSegment::stationColour) rather than in extra.
inline bool stationsInline(int intervals) { return intervals == 0 || intervals + 1 == kInlineStations; }

/// Shade Stations of an untextured segment with `intervals` Gouraud intervals (0: lighting
/// deferred): where its colours go (channel c of station k at [c * (intervals + 1) + k]; sized,
/// not filled), in the record when they fit (stationsInline), else in the slot's SegmentExtra.
/// Shared by the exact path and the SIMD batches, which must agree.
inline float* untexturedStations(PreparedSegment& out, const Segment& seg, int intervals) {
  if (stationsInline(intervals)) {
    out.stationCount = int8_t(intervals > 0 ? intervals + 1 : 0);
    return out.stationColour;
  }
  return stationsExtra(out, seg, false, intervals).colour.data();
}

/// The bytes of a PreparedSegment the common case's rows read (its first lines).
inline constexpr size_t kSegmentHotBytes = offsetof(PreparedSegment, screenQuad);
static_assert(kSegmentHotBytes <= 256, "the hot part of a segment record: at most four cache lines");

/// The blended attributes at u = 0 of an unshaded segment: colour (albedo, or the lit colour
/// the caller writes over it), alpha, weight 1 and the shading normal n0; dc cleared. Shared by
/// the exact path (prepareSegment) and the SIMD batches (prepareSegments), which must agree.
inline void setBaseAttributes(PreparedSegment& out, const Color& col, const Vec3f& n0) {
  float* a = out.attr;
  a[Z3Tile::kR] = col.x(), a[Z3Tile::kG] = col.y(), a[Z3Tile::kB] = col.z();
  a[Z3Tile::kA] = std::clamp(col.w(), 0.0f, 1.0f);
  a[Z3Tile::kW] = 1.0f;
  a[Z3Tile::kNx] = n0.x(), a[Z3Tile::kNy] = n0.y(), a[Z3Tile::kNz] = n0.z();
  out.dc = Vec3f::Zero();
}

/// Prepare stage for one segment (see the head of this file and splat_context.h): the
/// exact path, in double. The renderer prepares segments in batches (segment_setup.h: the common
/// case in SIMD, float), which hand every segment they cannot decide safely to this function.
PrimitiveStatus prepareSegment(const Segment& segment, uint32_t index, const FrameContext& frame,
                               PreparedSegment& out);

/// Rasterise stage for one segment on one tile.
void rasterizeSegment(const PreparedSegment& segment, const SplatContext& ctx);

/// Rasterise stage for segments[0 .. n) on one tile, in that order (n <= kRasterBatch): the
/// same as rasterizeSegment one by one, with the rows' spans of the common ones found together
/// (SIMD lanes = segments).
inline constexpr int kRasterBatch = 16;
void rasterizeSegments(const PreparedSegment* const* segments, int n, const SplatContext& ctx);


/// The row spans rasterizeSegment walks for the segment over `rect` (a tile): with tight, those of
/// the polygon around the cutoff region it walks (ScreenSpace), else those of the footprint box.
/// For tests: the tight walk must find every fragment of the box walk.
std::vector<detail::RowSpan> segmentRowSpans(const PreparedSegment& segment, const PixelRect& rect, bool tight);

/// The segment's resampling-filter weight at screen position `pixel` (pixel units; centres at
/// i + 0.5), as rasterizeSegment's scalar path gives it (0 outside the footprint or behind the
/// eye). For tests and error measurements (docs/segment-splatting.md).
float segmentWeightAt(const PreparedSegment& segment, const FrameContext& frame, const Vec2f& pixel);

}  // namespace linesurf
