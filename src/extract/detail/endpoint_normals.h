#pragma once
// Endpoint normals of smooth line models (Segment::normal0/normal1, beyond the thesis): a
// normal made perpendicular to the segment, on the side of the segment's own normal.
#include "linesurf/core/model.h"

namespace linesurf::detail {

/// `n` minus its component along the segment, normalised and flipped to the side of s.normal;
/// s.normal when that leaves nothing usable.
inline Vec3f perpendicularEndpointNormal(const Segment& s, const Vec3f& n) {
  Vec3d dir = (s.p1 - s.p0).cast<double>();
  const double len = dir.norm();
  if (!(len > 0) || !n.allFinite()) return s.normal;
  dir /= len;
  Vec3d m = n.cast<double>();
  m -= m.dot(dir) * dir;
  if (!(m.norm() > 1e-6)) return s.normal;
  m.normalize();
  if (m.dot(s.normal.cast<double>()) < 0) m = -m;
  return m.cast<float>();
}

/// Fills s.normal0 / s.normal1 from the normals at the segment's ends.
inline void setEndpointNormals(Segment& s, const Vec3f& atP0, const Vec3f& atP1) {
  s.normal0 = perpendicularEndpointNormal(s, atP0);
  s.normal1 = perpendicularEndpointNormal(s, atP1);
}

}  // namespace linesurf::detail
