// Normalised frames for scale-free geometry and rendering (model_frame.h).
#include "linesurf/io/model_frame.h"

#include <algorithm>
#include <cmath>

namespace linesurf {

ModelFrame normalizingFrame(const Bounds3f& b) {
  ModelFrame f;
  if (b.empty()) return f;
  const Vec3d lo = b.min.cast<double>(), hi = b.max.cast<double>();
  const Vec3d centre = 0.5 * (lo + hi);
  const double radius = 0.5 * (hi - lo).norm();
  const double offset = centre.norm();
  const bool sizeOk = radius >= std::ldexp(1.0, -10) && radius <= std::ldexp(1.0, 20);
  const bool centreOk = offset <= std::ldexp(1.0, 10) * std::max(radius, 1.0);
  if (!(radius > 0) || !std::isfinite(radius) || (sizeOk && centreOk)) return f;
  f.centre = centre;
  f.scale = std::ldexp(1.0, std::ilogb(radius));  // power of two: scaling is exact
  return f;
}

void toFrame(HybridModel& m, const ModelFrame& f) {
  if (f.identity()) return;
  const float inv = float(1.0 / f.scale);
  for (Point& p : m.points) {
    p.position = f.toNormalized(p.position);
    p.radius *= inv;
  }
  for (Segment& s : m.segments) {
    s.p0 = f.toNormalized(s.p0);
    s.p1 = f.toNormalized(s.p1);
    s.radius *= inv;
  }
}

void toFrame(TriangleMesh& m, const ModelFrame& f) {
  if (f.identity()) return;
  for (Vec3f& p : m.positions) p = f.toNormalized(p);
}

}  // namespace linesurf
