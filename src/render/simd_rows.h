#pragma once
/// What the SIMD rows of point splats (point_rows.h, §4.2.2) and segment splats (segment_rows.h,
/// §5.2) share: pixels in blocks, fragments packed per block, and the run-time SIMD target.
/// Google Highway, runtime dispatch: the best target the CPU runs among those compiled,
/// AVX-512 / AVX2 / SSE4 / SSSE3 / portable scalar; the library itself is built for generic
/// x86-64. The rows' common SIMD code: simd_rows-inl.h.

namespace linesurf::detail {

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

/// Name of the target the SIMD rows dispatch to in this process (Highway's TargetName).
const char* simdTargetName();

}  // namespace linesurf::detail
