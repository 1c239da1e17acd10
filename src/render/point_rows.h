#pragma once
/// The rasterise stage of object-space EWA point splats in SIMD rows (thesis §4.2.2): a splat's
/// kernel evaluated per pixel through its tangent plane, straight into the Z^3 tile with the
/// tile's fast path in SIMD too (point_rows.cpp, Highway runtime dispatch).
#include <cstddef>
#include <cstdint>

#include "simd_rows.h"
#include "splat_rules.h"
#include "z3_buffer.h"

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

}  // namespace linesurf::detail
