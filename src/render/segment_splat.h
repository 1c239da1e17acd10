#pragma once
/// Object-space EWA segment splats, thesis §5: the pipeline's two stages for line segments.
/// The method (the filter, its three evaluations, shading, the contract) is described in the
/// public header linesurf/render/segment_splat.h; this header is internal to the pipeline
/// (renderer.cpp) and its tests. The evaluations' own state lives in segment_methods.h.
///
/// prepare (one stage per function in segment_splat.cpp):
///  1. stripFrame: culling, model-view transform, the strip's axes (along, across, normal);
///  2. footprint: the resampling covariance along the segment (§5.1.2) in sub-segments, and
///     the footprint box in plane coordinates;
///  3. the method's own data (Reference nodes, Approx quadrilaterals; SegmentExtra);
///  4. screenBounds: frustum test, near/far clipping, pixel bounds, the projected box;
///  5. the per-pixel constants of the SIMD rows (detail::SegmentRaster);
///  6. shading: Gouraud colours, smooth normals.
/// The common case (ScreenSpace, one sub-segment, untextured, colour linear along the segment)
/// allocates nothing and is rasterised by the SIMD rows; everything else keeps its state in
/// PreparedSegment::extra (allocated once per record slot, reused across frames).
#include <cmath>
#include <cstddef>
#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include "detail/splat_rows.h"
#include "point_splat.h"
#include "linesurf/core/model.h"
#include "linesurf/render/segment_splat.h"
#include "linesurf/render/splat_context.h"

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

/// One sub-segment of the ScreenSpace method (detail/splat_rows.h: the SIMD rows evaluate them).
using SegmentPiece = detail::SegmentPiece;

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

namespace segment {
struct WeightTextures;  // §5.2.3.2 tables, segment_methods.cpp
}

/// What the common case does not need, allocated only when a segment needs it.
struct SegmentExtra {
  /// ScreenSpace with K > 1 sub-segments, evenly spaced (piece k covers [k, k+1] /
  /// pieceInvLength); a pixel at a only meets the pieces within pieceMaxReach (the largest reach).
  std::vector<SegmentPiece> pieces;
  float pieceInvLength = 0, pieceMaxReach = 0;
  /// Reference: nodes at spacing nodeStep starting at nodeStep / 2.
  std::vector<SegmentNode> nodes;
  float nodeStep = 0, nodeReach = 0;
  /// Approx: 10 quads (long case) or 8 (short).
  std::vector<SegmentQuad> quads;
  bool longCase = true;
  const segment::WeightTextures* textures = nullptr;
  /// Shading at stations evenly spaced over [0, length] (Gouraud, §6.2.2): the lit colour when
  /// untextured; textured, colour = albedo * diffuse + specular with the albedo from the
  /// texture (§5.2.4: uv interpolated between the endpoints).
  std::vector<Vec3f> diffuse, specular;
  /// untextured: the lit colour of station k, channel c at [c * stations + k], then
  /// detail::kMaxLanes floats of padding (the SIMD rows load whole vectors of a channel)
  std::vector<float> colour;
  int stations = 0;
  bool textured = false;
  Vec2f uv0 = Vec2f::Zero(), uv1 = Vec2f::Zero();

  /// Back to a default-constructed SegmentExtra's state, keeping the vectors' capacity (the
  /// renderer's record slots keep their SegmentExtra from frame to frame: issue 13, i13hot).
  /// Every member above must be reset here.
  void reset() {
    pieces.clear();
    pieceInvLength = pieceMaxReach = 0;
    nodes.clear();
    nodeStep = nodeReach = 0;
    quads.clear();
    longCase = true;
    textures = nullptr;
    diffuse.clear();
    specular.clear();
    colour.clear();
    stations = 0;
    textured = false;
    uv0 = uv1 = Vec2f::Zero();
  }
};

/// Resets a record slot's SegmentExtra (if it has one) for the next segment, keeping the
/// allocation: only a segment that needs it reads it (method, pieceCount, shade say which).
inline void resetExtra(std::unique_ptr<SegmentExtra>& extra) {
  if (extra) extra->reset();
}

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

/// The record is aligned to cache lines and ordered hot first (issue 13, i13hot): what the rows of
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
  /// shade Stations, untextured (issue 13, i13prep2): how many stations' colours stationColour
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

/// Prepare stage for one segment (see linesurf/render/segment_splat.h and splat_context.h): the
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

/// Segment level of detail (beyond the thesis, issue 13; cf. the §5.2.3 approximation). A one-piece
/// ScreenSpace segment's weight is its kernel (covariance M in the strip's plane coordinates (a, b))
/// integrated along it with the linear scale w(tau) = scale0 + slope tau, tau in [0, l]: a box (l)
/// convolved with a Gaussian. When l is short against the kernel (lambda = l sqrt((M^-1)_aa) <=
/// RenderOptions::segmentLod) that is nearly the one Gaussian of the same mass, mean a_m and
/// covariance Sigma = M + var e_a e_a^T (var, a_m: the moments of w over [0, l]): an elliptical
/// object-space point splat in the strip's plane, rasterised by the point rows (4-5x cheaper per
/// fragment and per tile). Its plane coordinates (s, t) = L^T ((a, b) - (a_m, 0)), Sigma^-1 = L L^T
/// (Sherman-Morrison: L^T = [[l00, l00 skew], [0, sqrt(across)]], l00^2 = m00 / (1 + var m00)),
/// weightScale = w's mass / sqrt(1 + var m00), the frame's cutoff; z threshold the mean of the
/// ends', colour attr + (a_m + a) / l dc (Gouraud when the splat is wide, as points are), normal
/// the normalised mean of the endpoint normals. Writes slot 0 of `out` and returns true when the
/// segment qualifies (drawn, ScreenSpace without fallback, one piece, shade Constant / Linear /
/// Smooth, not depth-clipped, lambda <= maxLambda, finite constants); otherwise writes nothing.
bool segmentLodPoint(const PreparedSegment& segment, const FrameContext& frame, float maxLambda, const PointSlots& out);

/// The row spans rasterizeSegment walks for the segment over `rect` (a tile): with tight, those of
/// the polygon around the cutoff region it walks (ScreenSpace), else those of the footprint box.
/// For tests: the tight walk must find every fragment of the box walk.
std::vector<detail::RowSpan> segmentRowSpans(const PreparedSegment& segment, const PixelRect& rect, bool tight);

/// The segment's resampling-filter weight at screen position `pixel` (pixel units; centres at
/// i + 0.5), as rasterizeSegment's scalar path gives it (0 outside the footprint or behind the
/// eye). For tests and error measurements (docs/segment-splatting.md).
float segmentWeightAt(const PreparedSegment& segment, const FrameContext& frame, const Vec2f& pixel);

}  // namespace linesurf
