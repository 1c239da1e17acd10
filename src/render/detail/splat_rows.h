#pragma once
// SIMD evaluation of splat weights over a block of pixels (Google Highway, runtime dispatch: the
// best target the CPU runs among those compiled, AVX-512 / AVX2 / SSE4 / SSSE3 / portable
// scalar; the library itself is built for generic x86-64). splat_rows.cpp.
#include <cmath>
#include <cstdint>
#include <vector>

#include "splat_math.h"
#include "linesurf/render/z3_buffer.h"

namespace linesurf::detail {

struct SilhouettePixel;  // coverage.h

/// Per-pixel constants of one object-space EWA point splat (§4.2.2). Along the ray through the
/// pixel centre (px, py) the splat's tangent plane is hit at depth depthNum / N with plane
/// coordinates (s, t) = (S, T) / N (N, S, T affine in the pixel, N < 0 in front); the weight is
/// exp(-q/2) * weightScale with q = s^2 + t^2 <= cutoffQ.
struct PointRaster {
  Affine2 N, S, T;
  float depthNum = 0, cutoffQ = 0, weightScale = 0;
  float nearD = 0, farD = 0;  ///< depth range kept when clipDepth
  bool clipDepth = false;
};

/// Pixels are visited in blocks of at most kBlock; a block's fragments are returned packed.
inline constexpr int kBlock = 256;
inline constexpr int kMaxLanes = 16;

/// The fragments of one block of pixels, packed (only pixels inside the splat, in pixel order):
/// pixel centre, weight > 0, depth, and per kind two more values (points: plane coordinates s, t
/// for Gouraud colours; segments: along-axis parameter u in [0, 1] and z threshold).
struct FragmentBlock {
  alignas(64) float x[kBlock + kMaxLanes], y[kBlock + kMaxLanes], weight[kBlock + kMaxLanes], depth[kBlock + kMaxLanes];
  alignas(64) float p[kBlock + kMaxLanes], q[kBlock + kMaxLanes];
};

/// Fragments of the pixels k0 .. k0 + n - 1 (row-major) of the rectangle of `width` pixels
/// starting at (x0, y0), n <= kBlock: returns how many of them lie inside the splat. p, q (s, t)
/// are filled only when withPlaneCoords.
int pointFragments(const PointRaster& p, int x0, int y0, int width, int k0, int n, bool withPlaneCoords,
                   FragmentBlock& out);

/// The blended attributes of one point splat's fragments (PreparedPoint): attr[Z3Tile::kAttrs],
/// with the colour replaced per fragment by the bilinear Gouraud colour C0 + Cs s + Ct t + Cst s t
/// (3 floats each) when gouraud.
struct PointShade {
  const float* attr = nullptr;
  float zThreshold = 0;
  bool gouraud = false;
  const float *C0 = nullptr, *Cs = nullptr, *Ct = nullptr, *Cst = nullptr;
};

/// Rasterises one point splat over the pixels of `r` (inside tile.rect()) straight into the Z^3
/// tile, row by row: weights, depths and colours of a row's pixels in SIMD, and the Z^3 fast path
/// in SIMD too (a pixel without a layer opens one; a pixel with one layer the fragment lies within
/// the z threshold of merges), the other fragments through Z3Tile::insert. The same layers as
/// inserting the fragments of pointFragments one by one (up to float rounding); returns how many
/// fragments (weight > 0) it inserted.
uint64_t pointRowsZ3(const PointRaster& p, const PointShade& shade, const PixelRect& r, Z3Tile& tile);

/// The resolve of one row of a Z^3 tile without deferred shading (renderer stage 3), in SIMD:
/// of the pixels x0 .. x0 + n - 1 of row y, the first `returned` ones (whole vectors) that hold
/// exactly one layer get Z3Tile::resolve's colour composited over the background bg (r, g, b, a)
/// the way the renderer does, written to out (straight RGBA, 4 floats per pixel from x0); the
/// other pixels before `returned` (empty, or several layers) get bg itself, the pixels from
/// `returned` on are left to the caller. out is only written (it may be uninitialised). `others`:
/// whether any of the pixels before `returned` holds several layers. frontZ (coverage at
/// silhouettes only, src/render/coverage.h): the front depths of the pixels before `returned`
/// (+inf where empty) go to frontZ[0 ..], the one-layer pixels are written with an opaque front
/// layer, and those partly covered are appended to cands with their coverage result.
int resolveSingleLayerRow(Z3Tile& tile, int y, int x0, int n, const float* bg, float* out, bool& others,
                          float* frontZ = nullptr, std::vector<SilhouettePixel>* cands = nullptr);

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

/// A sub-segment's weight scale is linear along it, scale0 + slope tau for tau in [0, len] (§5.2:
/// 1 / (h sqrt(det M)) at its ends). Where it changes by at most kFlatScale of scale0 over the
/// sub-segment, the kernels take it constant at its mean (beyond the thesis, issue 13): the slope
/// term's two extra exps per pixel go (all but ~1% of a contour model's segments), the weights
/// move by at most kFlatScale / 2 and the blended colours (normalised weighted averages) by far
/// less. The SIMD kernel, the scalar closed form and their tests all evaluate this.
inline constexpr float kFlatScale = 1e-2f;
struct PieceScale {
  float scale0 = 0, slope = 0;
};
inline PieceScale pieceScale(float scale0, float slope, float len) {
  if (std::abs(slope * len) <= kFlatScale * scale0) return {scale0 + 0.5f * (slope * len), 0.0f};
  return {scale0, slope};
}

/// Per-pixel constants of one ScreenSpace segment splat (§5, the closed form of
/// segment_methods.cpp): the ray through (px, py) meets the strip's plane at depth depthNum / N
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

/// The rows' spans over r (at most r.height()) of the pixels where the segment can have a
/// fragment (beyond the thesis): a pixel's ray meets the strip's plane (N < 0) at (a, b) in the
/// union over the sub-segments k of [a0_k, a1_k] x {0} + {v : v^T M_k^-1 v < R^2} (the capsule
/// of the cutoff); its support lines in eight directions (the footprint box's sides and its
/// corners cut along the ellipse's diagonals) are, multiplied by N, half-planes of the screen.
/// Every bound is pushed `slack` pixel outward against rounding. Returns how many spans (empty
/// rows left out), or -1 for degenerate constants (walk the footprint box instead).
int segmentSpans(const SegmentRaster& s, const PixelRect& r, float slack, RowSpan* out);

/// segmentSpans for n one-piece segments at once (pieceCount == 1; SIMD lanes = segments):
/// segment i's spans over rects[i] (at most stride rows) go to out + i * stride, counts[i] their
/// number, or -1 for degenerate constants; with widest (and pixels), widest[i] the widest of
/// segment i's spans and pixels[i] their pixels (SegmentRowsItem).
void segmentSpansBatch(const SegmentRaster* const* segs, const PixelRect* rects, int n, float slack, RowSpan* out,
                       int stride, int* counts, int* widest = nullptr, int* pixels = nullptr);

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
/// once (beyond the thesis: issue 13, a short segment's fixed cost). Returns the fragments inserted.
uint64_t segmentRowsRunZ3(const SegmentRowsItem* items, int n, Z3Tile& tile);

/// A prepared point splat's hot record (PreparedPoint, point_splat.h; 64 bytes): PointRaster
/// without the frame's constants, the z threshold and the colour.
struct PointHot {
  Affine2 N, S, T;
  float depthNum = 0;
  /// PointRaster::weightScale, with the sign bit set for PointRaster::clipDepth
  float weightScaleSigned = 0;
  float zThreshold = 0;
  /// the blended colour and alpha (Z3Tile::Attr kR .. kA; kW is 1)
  float color[4] = {};
};
/// A point splat spanning at most this many pixels each way is lit once (flat); a wider one is
/// Gouraud-shaded when lighting is not deferred (point_splat.h).
inline constexpr int kPointFlatShadeSpan = 6;
/// Tail layers (Z3Tile::setTailLayers, RenderOptions::tailLayers): a fragment is a tail where its
/// ray meets the primitive's plane outside this many times its own disc (a point: radius cutoff
/// sigma_r) or strip (a segment: half-width cutoff sigma_r). 1.5, not 1: a grazing surface whose
/// discs leave pixel centres uncovered keeps its fragments (measured, docs/decisions.md).
inline constexpr float kTailDisc = 1.5f;

/// The frame's constants of the point rows (PointRaster's cutoffQ, nearD, farD).
struct PointRowsFrame {
  float cutoffQ = 0, nearD = 0, farD = 0;
  float noDisc[4] = {};  ///< a tail form that never holds (PointTail's default)
};

/// The per-slot arrays of the prepared points: hot records, bounds, normals (3 floats every
/// normalStride), Gouraud colours (C0, Cs, Ct, Cst: 12 floats every gouraudStride; null when
/// lighting is deferred: no splat is Gouraud-shaded).
struct PointRunSlots {
  const PointHot* hot = nullptr;
  const PixelRect* bounds = nullptr;
  const float* normals = nullptr;
  const float* gouraud = nullptr;
  size_t normalStride = 0, gouraudStride = 0;
  /// the points' tail forms (g0, g1, g2: PointCold::disc) every discStride floats; null: no tail
  /// test (Z3Tile::setTailLayers)
  const float* disc = nullptr;
  size_t discStride = 0;
};

/// pointRowsZ3 for the splats in slots refs[0 .. n) in turn (each one's bounds touch the tile),
/// with one dispatch for them all; a splat is Gouraud-shaded when slots.gouraud and its bounds
/// span more than kPointFlatShadeSpan pixels either way. Returns how many fragments it inserted.
uint64_t pointRunZ3(const PointRowsFrame& frame, const PointRunSlots& slots, const uint32_t* refs, int n, Z3Tile& tile);

/// Name of the target the functions above dispatch to (Highway's TargetName).
const char* simdTargetName();

}  // namespace linesurf::detail

namespace linesurf::detail {

/// Per-frame constants of the SIMD point set-up (pointSetup).
struct PointSetupFrame {
  float rot[9] = {}, trans[3] = {};  ///< world -> camera (row-major rotation)
  float eye[3] = {};                 ///< the eye in world space (the early back-face test)
  float f = 1, cx = 0, cy = 0, nearD = 0, farD = 0;
  int width = 0, height = 0;         ///< the viewport, pixels
  float prefilter = 0, reconstructionScale = 0, cutoff = 0, cutoffQ = 0;
  bool backfaceCulling = true;
  bool light = false;                ///< compute the Phong factors (flat shading)
  float lightDir[3] = {}, ambient = 0, diffuse = 0, specular = 0, shininess = 1;
  bool shadingNormals = false;       ///< light with PointSetupBatch::snx.. (issue 14), not the plane normal
};

/// SoA input and output of a batch of at most kSetupBatch points.
inline constexpr int kSetupBatch = 64;
struct PointSetupBatch {
  int lane[kSetupBatch];  ///< the point's place in its batch of the model (not read by pointSetup)
  // input
  alignas(64) float px[kSetupBatch], py[kSetupBatch], pz[kSetupBatch], nx[kSetupBatch], ny[kSetupBatch],
      nz[kSetupBatch], radius[kSetupBatch];
  /// shading normals, world space (read only with PointSetupFrame::shadingNormals)
  alignas(64) float snx[kSetupBatch], sny[kSetupBatch], snz[kSetupBatch];
  // output: 0 = set up here; 1 = culled (back-facing); 2 = needs the exact scalar path; 3 = set
  // up here, bounds cut by the viewport (Clipped); 4 = outside the viewport
  alignas(64) float status[kSetupBatch];
  alignas(64) float Nx[kSetupBatch], Ny[kSetupBatch], N0[kSetupBatch], Sx[kSetupBatch], Sy[kSetupBatch],
      S0[kSetupBatch], Tx[kSetupBatch], Ty[kSetupBatch], T0[kSetupBatch];
  alignas(64) float depthNum[kSetupBatch], weightScale[kSetupBatch], depthExtent[kSetupBatch];
  /// the disc's tail form (PointCold::disc): g0, g1, g2
  alignas(64) float disc0[kSetupBatch], disc1[kSetupBatch], disc2[kSetupBatch];
  /// pixel bounds (pixelBounds: centres inside the splat's screen bounds, within the viewport)
  alignas(64) int32_t x0[kSetupBatch], y0[kSetupBatch], x1[kSetupBatch], y1[kSetupBatch];
  /// unit shading normal on the viewer's side (the plane normal, or the shading normal)
  alignas(64) float onx[kSetupBatch], ony[kSetupBatch], onz[kSetupBatch];
  /// Phong (FrameContext::shade without the albedo): ambient + diffuse n.l, and the specular term
  /// at the centre and at the Gouraud corners (s, t) = (-R,-R), (R,-R), (-R,R), (R,R).
  alignas(64) float diffuseFactor[kSetupBatch], specular[5][kSetupBatch];
};

/// Culling, transform, closed-form warp (§4.2.2: V = sigma_r^2 I + V_h J^-1 J^-T, V^-1 = L L^T),
/// plane constants and conic bounds of points 0 .. n-1 of the batch, in SIMD. Lanes that need
/// anything else (degenerate input, no normal, behind the eye, stretched past kMaxStretch,
/// crossing near/far, nearly edge-on) are marked 2 for the scalar path.
void pointSetup(const PointSetupFrame& frame, PointSetupBatch& batch, int n);

}  // namespace linesurf::detail
