#pragma once
// SIMD evaluation of splat weights over a block of pixels (Google Highway, runtime dispatch: the
// best target the CPU runs among those compiled, AVX-512 / AVX2 / SSE4 / SSSE3 / portable
// scalar; the library itself is built for generic x86-64). splat_rows.cpp.
#include <cstdint>

#include "splat_math.h"

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

/// Pixels are visited in blocks of at most this many; output arrays hold kBlock + kMaxLanes floats.
inline constexpr int kBlock = 256;
inline constexpr int kMaxLanes = 16;

/// Weights and depths of the pixels k0 .. k0 + n - 1 (row-major) of the rectangle of `width`
/// pixels starting at (x0, y0); weight 0 outside the splat. n <= kBlock. With s and t non-null,
/// also the plane coordinates (for Gouraud colours).
void pointWeights(const PointRaster& p, int x0, int y0, int width, int k0, int n, float* weight, float* depth,
                  float* s = nullptr, float* t = nullptr);

/// Per-pixel constants of one ScreenSpace segment splat of a single sub-segment (§5, the
/// closed form of segment_splat.cpp): the ray through (px, py) meets the strip's plane at depth
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

/// As pointWeights for one segment; also the along-axis parameter u = clamp(a / length, 0, 1)
/// and the z threshold of each pixel.
void segmentWeights(const SegmentRaster& s, int x0, int y0, int width, int k0, int n, float* weight, float* depth,
                    float* u, float* zThreshold);

/// Name of the target the functions above dispatch to (Highway's TargetName).
const char* simdTargetName();

}  // namespace linesurf::detail
