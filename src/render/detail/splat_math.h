#pragma once
// Helpers shared by the point (§4.2.2) and segment (§5.2) splat rasterisers.
#include <algorithm>
#include <cmath>

#include "linesurf/core/math.h"
#include "linesurf/render/camera.h"

namespace linesurf::detail {

/// exp(-q/2) for q in [0, 25] (cutoff radius up to 5 sigma), linearly interpolated: the thesis's
/// Gaussian weight texture in one dimension. Relative error below 1e-5.
struct GaussTable {
  static constexpr int kSize = 2048;
  static constexpr float kMaxQ = 25.0f;
  float v[kSize + 2];
  GaussTable() {
    for (int i = 0; i < kSize + 2; ++i) v[i] = std::exp(-0.5f * kMaxQ * float(i) / kSize);
  }
  /// q must lie in [0, kMaxQ].
  float operator()(float q) const {
    const float x = q * (kSize / kMaxQ);
    const int i = int(x);
    return v[i] + (x - float(i)) * (v[i + 1] - v[i]);
  }
};
/// Built at static initialisation, so lookups carry no guard check.
inline const GaussTable kGaussTable;

/// exp(-q/2) with q clamped to the table's range.
inline float gaussHalf(float q) { return kGaussTable(std::clamp(q, 0.0f, GaussTable::kMaxQ)); }

/// Clips a convex camera-space polygon of n <= 16 vertices against the near and far planes and
/// returns the screen bounding box of what remains; false when nothing remains. `clipped` tells
/// whether a plane cut the polygon.
bool clippedScreenBounds(const Camera& cam, const Vec3f* poly, int n, float& x0, float& y0, float& x1, float& y1,
                         bool& clipped);

}  // namespace linesurf::detail
