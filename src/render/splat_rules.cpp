// The screen bounds of a near/far-clipped primitive (splat_rules.h).
#include "splat_rules.h"

namespace linesurf::detail {

bool clippedScreenBounds(const Camera& cam, const Vec3f* poly, int n, float& x0, float& y0, float& x1, float& y1,
                         bool& clipped) {
  // Each plane adds at most one vertex to a convex polygon.
  Vec3f a[18], b[18];
  int na = std::min(n, 16);
  for (int i = 0; i < na; ++i) a[i] = poly[i];
  clipped = false;
  for (int plane = 0; plane < 2; ++plane) {
    // plane 0: d - near >= 0; plane 1: far - d >= 0 (d = -z)
    auto dist = [&](const Vec3f& p) { return plane == 0 ? -p.z() - cam.nearDepth() : cam.farDepth() + p.z(); };
    int nb = 0;
    for (int i = 0; i < na; ++i) {
      const Vec3f& p = a[i];
      const Vec3f& q = a[(i + 1) % na];
      const float dp = dist(p), dq = dist(q);
      if (dp >= 0) b[nb++] = p;
      if ((dp >= 0) != (dq >= 0)) {
        b[nb++] = p + (dp / (dp - dq)) * (q - p);
        clipped = true;
      }
    }
    if (nb == 0) return false;
    na = nb;
    for (int i = 0; i < na; ++i) a[i] = b[i];
  }
  x0 = y0 = INFINITY;
  x1 = y1 = -INFINITY;
  for (int i = 0; i < na; ++i) {
    const Vec3f s = cam.project(a[i]);
    x0 = std::min(x0, s.x());
    x1 = std::max(x1, s.x());
    y0 = std::min(y0, s.y());
    y1 = std::max(y1, s.y());
  }
  return true;
}

}  // namespace linesurf::detail
