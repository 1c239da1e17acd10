#pragma once
/// The prepare stage of point splats in batches (thesis §4.2.2, §6.2): the pipeline's fast path
/// around the SIMD set-up detail::pointSetup (point_setup.cpp). Back-facing points are culled on
/// their world-space position and normal before any other work (only those that are clearly
/// back-facing: the rest meet the exact test of the set-up); the survivors are set up in SIMD,
/// with the lanes it cannot handle passed to the scalar reference preparePoint (point_splat.h);
/// only the visible points are written, densely and in primitive order.
#include <cstdint>

#include "point_splat.h"

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
  bool shadingNormals = false;       ///< light with PointSetupBatch::snx.. (smooth contour models), not the plane normal
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

namespace linesurf {

/// How many points of a batch ended in each PrimitiveStatus (the RenderStats counters).
struct PointSetupCounts {
  uint32_t drawn = 0, clipped = 0, culled = 0, outside = 0, degenerate = 0;
  PointSetupCounts& operator+=(const PointSetupCounts& o) {
    drawn += o.drawn, clipped += o.clipped, culled += o.culled, outside += o.outside, degenerate += o.degenerate;
    return *this;
  }
};

/// The per-frame constants of preparePoints.
detail::PointSetupFrame pointSetupFrame(const FrameContext& frame);

/// Prepares points [first, first + count) of `points` (count <= detail::kSetupBatch): constructs
/// the visible ones (Drawn or Clipped) in slots 0 .. k of `out` (storage for `count` slots, not
/// necessarily constructed: untouched slots stay untouched) in index order and returns k; adds
/// every point's status to `counts`. Same results as preparePoint for each point up to float
/// rounding; out.gouraud[j] is written only when PreparedPoint::gouraud(out.bounds[j], ...).
int preparePoints(const Point* points, uint32_t first, int count, const FrameContext& frame,
                  const detail::PointSetupFrame& setup, const PointSlots& out, PointSetupCounts& counts);

}  // namespace linesurf
