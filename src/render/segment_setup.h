#pragma once
/// The prepare stage of segment splats in batches (beyond the thesis, issue 13): the common case
/// of prepareSegment (segment_splat.h: ScreenSpace, untextured, one sub-segment, not
/// depth-clipped, colour linear along the segment) in SIMD over a batch of segments, in float
/// (segment_setup.cpp, Highway runtime dispatch). Every lane the SIMD code cannot decide safely
/// (unusual input, near a threshold of a culling or subdivision test, clamped covariance, near
/// grazing, depth-clipped, more than one sub-segment) is prepared by
/// prepareSegment itself, the exact path; the others agree with it up to float rounding
/// (tests/render/segment_prepare_test.cpp).
#include <cstdint>

#include "segment_splat.h"

namespace linesurf {

namespace detail {

/// Per-frame constants of the segment set-up.
struct SegmentSetupFrame {
  PointSetupFrame view;  ///< the camera, filter and material constants (as points use them)
  bool simd = false;  ///< the frame's options allow the SIMD path (else every segment is scalar)
  float invF = 1;     ///< 1 / focal length
  float reach = 0;    ///< cutoff reconstructionScale kMaxStretch: the widest kernel per unit radius
  bool smoothFrame = false;  ///< the model's segments carry endpoint normals
  /// Phong factors in SIMD (FrameContext::shade with its specular table); with light false and
  /// perPixelLighting false the batch calls FrameContext::shade per segment instead.
  bool light = false, perPixelLighting = false;
  const float* specularTable = nullptr;
};

inline constexpr int kSegmentBatch = 64;

/// SoA input and output of a batch of at most kSegmentBatch segments.
struct SegmentSetupBatch {
  // input, camera space (Camera::toCamera, rotation()): endpoints, plane normal, radius; endpoint
  // normals where smooth[i] = 1
  alignas(64) float p0x[kSegmentBatch], p0y[kSegmentBatch], p0z[kSegmentBatch];
  alignas(64) float p1x[kSegmentBatch], p1y[kSegmentBatch], p1z[kSegmentBatch];
  alignas(64) float wx[kSegmentBatch], wy[kSegmentBatch], wz[kSegmentBatch], radius[kSegmentBatch];
  alignas(64) float smooth[kSegmentBatch];
  alignas(64) float m0x[kSegmentBatch], m0y[kSegmentBatch], m0z[kSegmentBatch];
  alignas(64) float m1x[kSegmentBatch], m1y[kSegmentBatch], m1z[kSegmentBatch];
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
  alignas(64) float extent0[kSegmentBatch], extent1[kSegmentBatch];  ///< depth extents at p0, p1 (z threshold)
  alignas(64) float qx[4][kSegmentBatch], qy[4][kSegmentBatch];      ///< projected footprint box
  alignas(64) int32_t x0[kSegmentBatch], y0[kSegmentBatch], x1[kSegmentBatch], y1[kSegmentBatch];
  alignas(64) float nx[kSegmentBatch], ny[kSegmentBatch], nz[kSegmentBatch];  ///< plane normal facing the viewer
  /// shading normals at p0 and p1 (unit; the plane normal unless smooth)
  alignas(64) float n0x[kSegmentBatch], n0y[kSegmentBatch], n0z[kSegmentBatch];
  alignas(64) float n1x[kSegmentBatch], n1y[kSegmentBatch], n1z[kSegmentBatch];
  /// Phong at p0 and p1 (light): colour = (albedo diffuse + specular) * light colour
  alignas(64) float diffuse0[kSegmentBatch], specular0[kSegmentBatch], diffuse1[kSegmentBatch],
      specular1[kSegmentBatch];
  alignas(64) float p1cx[kSegmentBatch], p1cy[kSegmentBatch], p1cz[kSegmentBatch];  ///< p1, camera space
};

/// The SIMD set-up of n <= kSegmentBatch segments (runtime dispatch).
void segmentSetup(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n);

}  // namespace detail

/// The per-frame constants of prepareSegments.
detail::SegmentSetupFrame segmentSetupFrame(const FrameContext& frame);

/// prepareSegment for segments[first .. first + count): status[j] for segment first + j, and
/// out[j] as prepareSegment writes it where that status is Drawn or Clipped; the record of a
/// segment not drawn may be left as it was (not read, not written: culled segments cost no
/// memory traffic). Returns how many went through
/// prepareSegment itself (lanes the SIMD code left, or all where the frame is not the common case).
size_t prepareSegments(const Segment* segments, uint32_t first, size_t count, const FrameContext& frame,
                       const detail::SegmentSetupFrame& setup, PreparedSegment* out, PrimitiveStatus* status);

}  // namespace linesurf
