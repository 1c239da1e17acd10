#include "linesurf/core/model.h"

#include <cmath>

namespace linesurf {

Bounds3f HybridModel::bounds() const {
  Bounds3f b;
  for (const Point& p : points) b.extend(p.position);
  for (const Segment& s : segments) {
    b.extend(s.p0);
    b.extend(s.p1);
  }
  return b;
}

Bounds3f TriangleMesh::bounds() const {
  Bounds3f b;
  for (const Vec3f& p : positions) b.extend(p);
  return b;
}

Color Image::sampleBilinear(float u, float v) const {
  if (pixels.empty() || !std::isfinite(u) || !std::isfinite(v)) return Color(1, 1, 1, 1);
  u -= std::floor(u);
  v -= std::floor(v);
  // Texel centres at (i + 0.5) / width; v = 0 is the bottom row.
  float x = u * width - 0.5f, y = (1.0f - v) * height - 0.5f;
  float fx = std::floor(x), fy = std::floor(y);
  float ax = x - fx, ay = y - fy;
  auto wrap = [](long i, int n) { long m = i % n; return int(m < 0 ? m + n : m); };
  int x0 = wrap(long(fx), width), x1 = wrap(long(fx) + 1, width);
  int y0 = wrap(long(fy), height), y1 = wrap(long(fy) + 1, height);
  return (1 - ay) * ((1 - ax) * at(x0, y0) + ax * at(x1, y0)) + ay * ((1 - ax) * at(x0, y1) + ax * at(x1, y1));
}

}  // namespace linesurf
