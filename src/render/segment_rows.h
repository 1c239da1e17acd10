#pragma once
/// The rasterise stage of segment splats in SIMD rows (thesis §5.2, the ScreenSpace closed form of
/// segment_filter.h): the rows' spans of a segment's cutoff region, its kernel per pixel, straight
/// into the Z^3 tile with the tile's fast path in SIMD (segment_rows.cpp, Highway runtime dispatch).
#include <cmath>
#include <cstdint>

#include "simd_rows.h"
#include "splat_rules.h"
#include "z3_buffer.h"

namespace linesurf::detail {

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

/// Per-pixel constants of one ScreenSpace segment splat (§5, the closed form of
/// segment_filter.cpp): the ray through (px, py) meets the strip's plane at depth depthNum / N
/// with plane coordinates a = A / N - a0 (along), b = B / N - b0 (across). The first sub-segment
/// is held here (skew .. slope); with pieceCount > 1 all of them are in pieces[] (evenly spaced,
/// 1 / pieceInvLength long, reaching at most pieceMaxReach beyond their ends).
struct SegmentRaster {
  Affine2 N, A, B;
  float depthNum = 0, a0 = 0, b0 = 0;
  float length = 0, R2 = 0;              ///< segment length, cutoff^2
  float aMin = 0, aMax = 0, bMax = 0;    ///< footprint box in plane coordinates
  float skew = 0, across = 0, invM00 = 0, k = 0, erfScale = 0;  ///< SegmentPiece
  float scale0 = 0, slope = 0;
  float zThreshold0 = 0, zThreshold1 = 0;  ///< z threshold at p0 and p1, linear in u between
  float nearD = 0, farD = 0;
  /// tail layers (Z3Tile::setTailLayers): a fragment is a tail where its plane coordinates lie
  /// outside [-tailB, length + tailB] x [-tailB, tailB], tailB = kTailDisc cutoff sigma_r (the
  /// strip's own half-width, widened as a point's disc is); 0: never
  float tailB = 0;
  bool clipDepth = false;
  int pieceCount = 1;
  const SegmentPiece* pieces = nullptr;  ///< pieceCount > 1: owned by the prepared segment
  float pieceInvLength = 0, pieceMaxReach = 0;
};

/// A run of pixels [x0, x1) of row y.
struct RowSpan {
  int y, x0, x1;
};

/// As pointFragments for one segment, over `count` row spans holding at most kBlock pixels in
/// all; p = the along-axis parameter u = clamp(a / length, 0, 1), q = the z threshold.
int segmentFragments(const SegmentRaster& s, const RowSpan* spans, int count, FragmentBlock& out);

/// The blended attributes of one untextured segment's fragments (PreparedSegment):
/// attr[Z3Tile::kAttrs] at u = 0, the colour attr + u dc, and with smooth the normal
/// normalize(n0 + u dn) (by a series when n0, n1 are unit and at most 0.1 rad apart, dn2 = |dn|^2).
/// dc, n0, dn: 3 floats each (in the prepared record: not copied per tile).
struct SegmentShadeRows {
  const float* attr = nullptr;
  const float *dc = nullptr, *n0 = nullptr, *dn = nullptr;
  float dn2 = 0;
  bool smooth = false;
  /// normalize(n0 + u dn) exactly (the endpoint normals turn by more than 0.1 rad)
  bool exactNormal = false;
  /// stations >= 2: the colour piecewise linear between `stations` evenly spaced stations,
  /// stationColour[c * stations + k] (channel c of station k), instead of attr + u dc
  int stations = 0;
  const float* stationColour = nullptr;
  /// stationColour is readable kMaxLanes floats past its 3 * stations (SegmentExtra::colour's
  /// padding; not the record's own stations): the rows load its channels as whole vectors
  bool stationPadded = false;
};

/// Rasterises one segment over `count` row spans (inside tile.rect()) straight into the Z^3 tile,
/// as pointRowsZ3 does points: the weights of segmentFragments, the SIMD fast path for the
/// common fragments, Z3Tile::insert for the others. Returns how many fragments it inserted.
uint64_t segmentRowsZ3(const SegmentRaster& s, const SegmentShadeRows& shade, const RowSpan* spans, int count,
                       Z3Tile& tile);

/// One segment of segmentRowsRunZ3: its constants, shading and row spans.
struct SegmentRowsItem {
  const SegmentRaster* raster = nullptr;
  SegmentShadeRows shade;
  const RowSpan* spans = nullptr;
  int count = 0;
  /// the widest span and the spans' pixels (segmentSpansBatch's), or pixels < 0: counted by the rows
  int widest = 0, pixels = -1;
};

/// segmentRowsZ3 for items[0 .. n) in turn, with one dispatch and the frame's kernel constants set
/// once (beyond the thesis: a short segment's fixed cost). Returns the fragments inserted.
uint64_t segmentRowsRunZ3(const SegmentRowsItem* items, int n, Z3Tile& tile);

}  // namespace linesurf::detail
