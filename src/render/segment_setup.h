#pragma once
/// The prepare stage of segment splats in batches (beyond the thesis; see docs/decisions.md, "Segment prepare"): the common case
/// of prepareSegment (segment_splat.h: ScreenSpace, untextured, up to kBatchPieces sub-segments,
/// not depth-clipped) in SIMD over a batch of segments, in float
/// (segment_setup.cpp, Highway runtime dispatch). Every lane the SIMD code cannot decide safely
/// (unusual input, near a threshold of a culling or subdivision test, clamped covariance, near
/// grazing, depth-clipped, more than kBatchPieces sub-segments) is prepared by
/// prepareSegment itself, the exact path; the others agree with it up to float rounding
/// (tests/render/segment_prepare_test.cpp).
#include <cstddef>
#include <cstdint>

#include "point_setup.h"
#include "segment_splat.h"

namespace linesurf {

namespace detail {

/// A PreparedSegment as the batches write it (the records stream through memory once per frame): one image per lane of the
/// record's bytes [0, 16 kRecordChunks) in 16-byte chunks (aligned: no store splits a cache line),
/// all written but `extra` (its first 8 bytes: neither read nor written in the common case).
inline constexpr size_t kRecordBegin = 0;
inline constexpr int kRecordChunks =
    int((offsetof(PreparedSegment, screenQuad) + sizeof(PreparedSegment::screenQuad) + 15) / 16);
inline constexpr int kRecordSlots = 4 * kRecordChunks;  ///< 32-bit words
static_assert(offsetof(PreparedSegment, extra) == 0 && sizeof(PreparedSegment::extra) == 8 &&
                  16 * kRecordChunks <= sizeof(PreparedSegment) && alignof(PreparedSegment) % 16 == 0,
              "the record image: `extra` in its first 8 bytes, inside the record");

/// The per-frame image of the fields a common-case segment's record holds for every segment of
/// the frame (method, useSpans, R2, nearD, farD, one piece, weight 1, ...), as 32-bit words.
struct SegmentRecordTemplate {
  uint32_t word[kRecordSlots] = {};
};

inline constexpr int kSegmentBatch = 64;
/// The most ScreenSpace sub-segments a lane of the batches takes (hybrid models' long
/// segments); more go to the exact path.
inline constexpr int kBatchPieces = 8;
/// The fields of a sub-segment (SegmentPiece) as the batches write them, one array each.
enum PieceField { kPieceA0, kPieceA1, kPieceM00, kPieceM01, kPieceM11, kPieceScale0, kPieceScale1, kPieceReach,
                  kPieceSkew, kPieceAcross, kPieceInvM00, kPieceK, kPieceErfScale, kPieceSlope, kPieceFields };

/// Per-frame constants of the segment set-up.
struct SegmentSetupFrame {
  PointSetupFrame view;  ///< the camera, filter and material constants (as points use them)
  bool simd = false;  ///< the frame's options allow the SIMD path (else every segment is scalar)
  float invF = 1;     ///< 1 / focal length
  float reach = 0;    ///< cutoff reconstructionScale kMaxStretch: the widest kernel per unit radius
  bool smoothFrame = false;  ///< the model's segments carry endpoint normals
  /// A chain's shared endpoint (p1 of a lane bit-equal to p0 of the next: curvature lines, contour
  /// lines) goes to camera space once, as the next lane's p0 (segmentToCamera); false: every
  /// endpoint on its own (the same bits either way: the benches' reference)
  bool shareChainEnds = true;
  /// FrameContext::primitiveColor: the segment's colour (modelColors) else defaultColor, its
  /// alpha alphaOverride where that is >= 0
  bool modelColors = true;
  float defaultColor[4] = {1, 1, 1, 1};
  float alphaOverride = -1;
  /// Phong factors in SIMD (FrameContext::shade with its specular table); with light false and
  /// perPixelLighting false the batch calls FrameContext::shade per segment instead.
  bool light = false, perPixelLighting = false;
  const float* specularTable = nullptr;
  float lightColor[3] = {1, 1, 1};  ///< RenderOptions::light.color
  /// FrameContext::zThreshold's rule (splat_rules.h), applied here to vectors of depth extents
  ZThresholdRule z;
  SegmentRecordTemplate record;
};

/// SoA input and output of a batch of at most kSegmentBatch segments.
struct SegmentSetupBatch {
  // input, world space (the model's: endpoints, plane normal, radius, endpoint normals where the
  // frame is smooth); segmentSetup turns them into camera space (Camera::toCamera, rotation(), as
  // they round: the exact path's input) and sets smooth[i] = 1 where the endpoint normals are
  // usable, the plane normal then normal0 + normal1 if it is zero (prepareSegment's stage 1)
  alignas(64) float p0x[kSegmentBatch], p0y[kSegmentBatch], p0z[kSegmentBatch];
  alignas(64) float p1x[kSegmentBatch], p1y[kSegmentBatch], p1z[kSegmentBatch];
  alignas(64) float wx[kSegmentBatch], wy[kSegmentBatch], wz[kSegmentBatch], radius[kSegmentBatch];
  alignas(64) float smooth[kSegmentBatch];
  alignas(64) float m0x[kSegmentBatch], m0y[kSegmentBatch], m0z[kSegmentBatch];
  alignas(64) float m1x[kSegmentBatch], m1y[kSegmentBatch], m1z[kSegmentBatch];
  /// the colour (FrameContext::primitiveColor)
  alignas(64) float cr[kSegmentBatch], cg[kSegmentBatch], cb[kSegmentBatch], ca[kSegmentBatch];
  uint32_t first = 0;  ///< the index of lane 0's segment before segmentCull
  /// segmentCull: the status of each lane [0, n) stage 1 decides as PrimitiveStatus bytes
  /// (Culled, Outside; Drawn for the others, which the exact path or segmentSetup decide), the
  /// lanes it leaves to the exact path as bits (no branch per lane); it moves
  /// the others to lanes [0, m), lane[k] the original lane of lane k
  alignas(64) uint8_t decidedStatus[kSegmentBatch];
  uint64_t exactLanes = 0;
  alignas(64) int32_t lane[kSegmentBatch];
  // output: 0 = drawn; 1 = culled; 2 = needs the exact path; 3 = drawn, bounds cut by the
  // viewport (Clipped); 4 = outside
  alignas(64) float status[kSegmentBatch];
  alignas(64) float Nx[kSegmentBatch], Ny[kSegmentBatch], N0[kSegmentBatch];
  alignas(64) float Ax[kSegmentBatch], Ay[kSegmentBatch], A0[kSegmentBatch];
  alignas(64) float Bx[kSegmentBatch], By[kSegmentBatch], B0[kSegmentBatch];
  alignas(64) float depthNum[kSegmentBatch], a0[kSegmentBatch], b0[kSegmentBatch], length[kSegmentBatch];
  alignas(64) float aMin[kSegmentBatch], aMax[kSegmentBatch], bMax[kSegmentBatch];
  alignas(64) float skew[kSegmentBatch], across[kSegmentBatch], invM00[kSegmentBatch], k[kSegmentBatch],
      erfScale[kSegmentBatch], scale0[kSegmentBatch], slope[kSegmentBatch];
  alignas(64) float qx[4][kSegmentBatch], qy[4][kSegmentBatch];      ///< projected footprint box
  /// ScreenSpace sub-segments (prepareSegment's stage 2): K per lane (1: the
  /// piece above only), K / length, the largest reach, and for K > 1 piece p's field f at
  /// piece[f][p][lane] (piece 0 is also the one above)
  alignas(64) float pieceCount[kSegmentBatch], pieceInvLength[kSegmentBatch], pieceMaxReach[kSegmentBatch];
  alignas(64) float piece[kPieceFields][kBatchPieces][kSegmentBatch];
  alignas(64) int32_t x0[kSegmentBatch], y0[kSegmentBatch], x1[kSegmentBatch], y1[kSegmentBatch];
  /// shading normals at p0 and p1 (unit; the plane normal unless smooth)
  alignas(64) float n0x[kSegmentBatch], n0y[kSegmentBatch], n0z[kSegmentBatch];
  alignas(64) float n1x[kSegmentBatch], n1y[kSegmentBatch], n1z[kSegmentBatch];
  /// Phong at p0 and p1 (light): colour = (albedo diffuse + specular) * light colour
  alignas(64) float diffuse0[kSegmentBatch], specular0[kSegmentBatch], diffuse1[kSegmentBatch],
      specular1[kSegmentBatch];
  alignas(64) float p1cx[kSegmentBatch], p1cy[kSegmentBatch], p1cz[kSegmentBatch];  ///< p1, camera space
  /// the rest of the record's per-lane words: z thresholds, attributes at u = 0 (colour, alpha;
  /// the normal is n0), the colour's change dc and the normal's dn to u = 1, the index, and the
  /// word holding `smooth` and `shade` (the template's with those bytes set)
  alignas(64) float zt0[kSegmentBatch], zt1[kSegmentBatch];  ///< z thresholds at p0, p1
  alignas(64) float tailB[kSegmentBatch];  ///< SegmentRaster's
  alignas(64) float ar[kSegmentBatch], ag[kSegmentBatch], ab[kSegmentBatch], aa[kSegmentBatch];
  alignas(64) float dcx[kSegmentBatch], dcy[kSegmentBatch], dcz[kSegmentBatch];
  alignas(64) float dnx[kSegmentBatch], dny[kSegmentBatch], dnz[kSegmentBatch];
  alignas(64) uint32_t index[kSegmentBatch], flags[kSegmentBatch];
  alignas(64) uint32_t stationCount[kSegmentBatch];  ///< the word holding PreparedSegment::stationCount
  /// Gouraud intervals of a turning smooth lane (shade Stations): > 0, or 0 where lighting is
  /// deferred; -1 for a lane that does not turn
  alignas(64) float stations[kSegmentBatch];
  /// The lit colours of the interior stations (frame.light): lane k drawn with
  /// S = stations[k] >= 2 has station s = 1 .. S - 1 (the shading normal normalize(n0 + u dn) and
  /// the point p0 + u (p1 - p0) at u = s / S, lit as FrameContext::shade with the batch's Phong)
  /// at stationJob[k] + s - 1 of stationR, stationG, stationB; stationJobs of them in all
  alignas(64) int32_t stationJob[kSegmentBatch];
  static constexpr int kStationJobs = kSegmentBatch * (kMaxSegmentPieces - 1) + kMaxLanes;
  alignas(64) float stationR[kStationJobs], stationG[kStationJobs], stationB[kStationJobs];
  int stationJobs = 0;
  /// segmentSetup's bookkeeping of those jobs: per lane its first job within its vector of lanes
  /// and its intervals (-1: none), per vector of lanes its jobs and where they start
  alignas(64) int32_t jobFirst[kSegmentBatch];
  alignas(64) float jobIntervals[kSegmentBatch];
  int32_t groupJobs[kSegmentBatch], groupBase[kSegmentBatch];
  /// the records' images: chunk c of lane j at rec[c][4 j .. 4 j + 4) (segmentRecords)
  alignas(64) float rec[kRecordChunks][4 * kSegmentBatch];
};

/// The batch's input (world space) from segments [0, n), and the prefetches of the input a batch
/// ahead and of the records out[0, n) whose plane faces the eye, with 512-bit vectors (runtime
/// dispatch); false on other targets, where the caller copies lane by lane.
bool segmentLoad(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, const Segment* segments, int n,
                 const PreparedSegment* out);

/// World to camera space of the batch's input in place (Camera::toCamera as it rounds), the smooth
/// flags and the plane normals (runtime dispatch).
void segmentToCamera(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n);

/// Stage 1 (culling) over lanes [0, n) of camera-space input (see docs/decisions.md, "Segment prepare"): the lanes it
/// decides (culled, outside, or for the exact path) get their status in `decidedStatus` and
/// `exactLanes`; the others are compacted to lanes [0, m) (`lane`: their original lanes), m
/// returned, so that segmentSetup runs on full vectors of them (runtime dispatch).
int segmentCull(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n);

/// The SIMD set-up of lanes [0, n) of camera-space input (segmentCull's survivors; runtime
/// dispatch). The index of lane k's segment is first + lane[k]. With frame.light it also lights the
/// interior stations of the drawn lanes with two or more Gouraud intervals (stationJob).
void segmentSetup(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n);

/// The records' images of lanes [0, n) of a batch segmentSetup has set up (rec; runtime dispatch).
void segmentRecords(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n);

}  // namespace detail

/// The per-frame constants of prepareSegments.
detail::SegmentSetupFrame segmentSetupFrame(const FrameContext& frame);

/// prepareSegment for segments[first .. first + count): status[j] for segment first + j, and
/// out[j] as prepareSegment writes it where that status is Drawn or Clipped (but `extra`, which
/// the common case neither reads nor resets); the record of a segment not drawn may be left as it
/// was (not written: culled segments cost no memory writes). Returns how many went through
/// prepareSegment itself (lanes the SIMD code left, or all where the frame is not the common case).
size_t prepareSegments(const Segment* segments, uint32_t first, size_t count, const FrameContext& frame,
                       const detail::SegmentSetupFrame& setup, PreparedSegment* out, PrimitiveStatus* status);

}  // namespace linesurf
