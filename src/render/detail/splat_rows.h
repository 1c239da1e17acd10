#pragma once
// SIMD evaluation of splat weights over a block of pixels (Google Highway, runtime dispatch: the
// best target the CPU runs among those compiled, AVX-512 / AVX2 / SSE4 / SSSE3 / portable
// scalar; the library itself is built for generic x86-64). splat_rows.cpp.
#include <cstdint>

#include "splat_math.h"
#include "linesurf/render/z3_buffer.h"

namespace linesurf::detail {

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
/// others (empty, several layers, and the pixels from `returned` on) are left to the caller.
int resolveSingleLayerRow(Z3Tile& tile, int y, int x0, int n, const float* bg, float* out);

/// Per-pixel constants of one ScreenSpace segment splat of a single sub-segment (§5, the
/// closed form of segment_methods.cpp): the ray through (px, py) meets the strip's plane at depth
/// depthNum / N with plane coordinates a = A / N - a0 (along), b = B / N - b0 (across).
struct SegmentRaster {
  Affine2 N, A, B;
  float depthNum = 0, a0 = 0, b0 = 0;
  float length = 0, R2 = 0;              ///< segment length, cutoff^2
  float aMin = 0, aMax = 0, bMax = 0;    ///< footprint box in plane coordinates
  float skew = 0, across = 0, invM00 = 0, k = 0, erfScale = 0;  ///< SegmentPiece
  float scale0 = 0, slope = 0;
  float zThreshold0 = 0, zThreshold1 = 0;  ///< z threshold at p0 and p1, linear in u between
  float nearD = 0, farD = 0;
  bool clipDepth = false;
};

/// A run of pixels [x0, x1) of row y.
struct RowSpan {
  int y, x0, x1;
};

/// As pointFragments for one segment, over `count` row spans holding at most kBlock pixels in
/// all; p = the along-axis parameter u = clamp(a / length, 0, 1), q = the z threshold.
int segmentFragments(const SegmentRaster& s, const RowSpan* spans, int count, FragmentBlock& out);

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
};

/// SoA input and output of a batch of at most kSetupBatch points.
inline constexpr int kSetupBatch = 64;
struct PointSetupBatch {
  int lane[kSetupBatch];  ///< the point's place in its batch of the model (not read by pointSetup)
  // input
  alignas(64) float px[kSetupBatch], py[kSetupBatch], pz[kSetupBatch], nx[kSetupBatch], ny[kSetupBatch],
      nz[kSetupBatch], radius[kSetupBatch];
  // output: 0 = set up here; 1 = culled (back-facing); 2 = needs the exact scalar path; 3 = set
  // up here, bounds cut by the viewport (Clipped); 4 = outside the viewport
  alignas(64) float status[kSetupBatch];
  alignas(64) float Nx[kSetupBatch], Ny[kSetupBatch], N0[kSetupBatch], Sx[kSetupBatch], Sy[kSetupBatch],
      S0[kSetupBatch], Tx[kSetupBatch], Ty[kSetupBatch], T0[kSetupBatch];
  alignas(64) float depthNum[kSetupBatch], weightScale[kSetupBatch], depthExtent[kSetupBatch];
  /// pixel bounds (pixelBounds: centres inside the splat's screen bounds, within the viewport)
  alignas(64) int32_t x0[kSetupBatch], y0[kSetupBatch], x1[kSetupBatch], y1[kSetupBatch];
  alignas(64) float onx[kSetupBatch], ony[kSetupBatch], onz[kSetupBatch];  ///< unit normal facing the viewer
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
