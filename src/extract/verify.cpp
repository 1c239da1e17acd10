// Verification of the (epsilon, delta) bound, thesis §3.1.2.1.
#include "linesurf/extract/verify.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <unordered_map>

#include "linesurf/core/error.h"

namespace linesurf {
namespace {

struct PosKey {
  uint32_t x, y, z;
  bool operator==(const PosKey&) const = default;
};
struct PosHash {
  size_t operator()(const PosKey& k) const {
    uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
    h ^= (k.y + 0x632BE59BD9B4E019ull + (h << 6) + (h >> 2));
    h ^= (k.z + 0x85EBCA77C2B2AE63ull + (h << 6) + (h >> 2));
    return size_t(h);
  }
};
PosKey keyOf(const Vec3f& p) {
  PosKey k;
  // +0.0f folds -0 and 0 into one key.
  float x = p.x() + 0.0f, y = p.y() + 0.0f, z = p.z() + 0.0f;
  std::memcpy(&k.x, &x, 4);
  std::memcpy(&k.y, &y, 4);
  std::memcpy(&k.z, &z, 4);
  return k;
}

double distanceToSegment(const Vec3d& q, const Vec3d& a, const Vec3d& b) {
  Vec3d ab = b - a;
  double len2 = ab.squaredNorm();
  double t = len2 > 0 ? std::clamp((q - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return (q - (a + t * ab)).norm();
}

}  // namespace

VerifyReport verifyExtraction(const HybridModel& input, const PointGeometry* geometry, const HybridModel& hybrid,
                              double epsilon, double delta) {
  if (!(epsilon >= 0) || !std::isfinite(epsilon)) throwBadParameter("epsilon", "must be a finite distance >= 0");
  if (!(delta >= 0) || !std::isfinite(delta)) throwBadParameter("delta", "must be finite and >= 0");
  const size_t n = input.points.size();
  const bool useGeometry = geometry != nullptr;
  if (useGeometry && geometry->normals.size() != n)
    throwBadParameter("geometry", "computed for " + std::to_string(geometry->normals.size()) +
                                      " points, the input has " + std::to_string(n));
  if (!useGeometry && !input.attributes.normals)
    throwBadInput("input", "normals", "the input has no normals and no geometry was given to supply them");
  if (!hybrid.segments.empty() && hybrid.provenance.size() != hybrid.segments.size())
    throwBadInput("hybrid", "provenance",
                  hybrid.provenance.empty()
                      ? "the hybrid model records no provenance; extract it with --provenance"
                      : "provenance lists " + std::to_string(hybrid.provenance.size()) + " segments, the model has " +
                            std::to_string(hybrid.segments.size()));
  auto normalOf = [&](size_t j) -> Vec3f { return useGeometry ? geometry->normals[j] : input.points[j].normal; };

  VerifyReport r;
  r.epsilon = epsilon;
  r.delta = delta;
  r.segments = hybrid.segments.size();
  Bounds3f box = input.bounds();
  float extent = 0;
  if (!box.empty()) extent = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
  const double distTol = epsilon + 1e-4 * epsilon + 8.0 * std::numeric_limits<float>::epsilon() * extent;
  const double normalTol = delta + 1e-6;
  auto note = [&](const std::string& s) {
    if (r.messages.size() < 20) r.messages.push_back(s);
  };
  char buf[256];

  std::vector<uint8_t> uses(n, 0);  // 0 free, 1 replaced, 2 replaced again
  for (size_t s = 0; s < hybrid.segments.size(); ++s) {
    const Segment& seg = hybrid.segments[s];
    const auto& prov = hybrid.provenance[s];
    if (prov.empty()) {
      ++r.badSegments;
      std::snprintf(buf, sizeof buf, "segment %zu: empty provenance", s);
      note(buf);
      continue;
    }
    const uint32_t anchor = prov[0];
    if (anchor >= n) {
      ++r.badIndices;
      std::snprintf(buf, sizeof buf, "segment %zu: anchor index %u out of range (%zu points)", s, anchor, n);
      note(buf);
      continue;
    }
    const Vec3f na = normalOf(anchor);
    const Vec3d a = seg.p0.cast<double>(), b = seg.p1.cast<double>();
    const Vec3d dir = (b - a).normalized();
    const double nlen = seg.normal.cast<double>().norm();
    // The stored normal is perpendicular up to float rounding of the endpoints and the normal.
    const double perpTol = 1e-4 + 16.0 * std::numeric_limits<float>::epsilon() * extent / std::max((b - a).norm(), 1e-300);
    if (!(std::abs(nlen - 1) < 1e-4) || !(std::abs(seg.normal.cast<double>().dot(dir)) < perpTol) ||
        !(1.0 - double(na.dot(seg.normal)) <= 1e-4)) {
      ++r.badSegments;
      std::snprintf(buf, sizeof buf,
                    "segment %zu: normal (length %.6g, cos to segment %.3g) is not the anchor %u's normal made "
                    "perpendicular to the segment",
                    s, nlen, seg.normal.cast<double>().dot(dir), anchor);
      note(buf);
    }
    for (uint32_t j : prov) {
      if (j >= n) {
        ++r.badIndices;
        std::snprintf(buf, sizeof buf, "segment %zu: provenance index %u out of range (%zu points)", s, j, n);
        note(buf);
        continue;
      }
      ++r.replacedPoints;
      if (uses[j]) {
        ++r.replacedTwice;
        std::snprintf(buf, sizeof buf, "point %u: replaced by more than one segment (again by segment %zu)", j, s);
        note(buf);
      }
      uses[j] = std::min(uses[j] + 1, 2);
      const double d = distanceToSegment(input.points[j].position.cast<double>(), a, b);
      r.maxDistance = std::max(r.maxDistance, d);
      if (!(d <= distTol)) {
        ++r.distanceViolations;
        std::snprintf(buf, sizeof buf, "segment %zu: point %u lies %.9g from the segment (epsilon %.9g)", s, j, d,
                      epsilon);
        note(buf);
      }
      const double dev = 1.0 - double(na.dot(normalOf(j)));
      r.maxNormalDeviation = std::max(r.maxNormalDeviation, dev);
      if (!(dev <= normalTol)) {
        ++r.normalViolations;
        std::snprintf(buf, sizeof buf, "segment %zu: point %u normal deviates 1-n.n = %.9g from anchor %u (delta %.9g)",
                      s, j, dev, anchor, delta);
        note(buf);
      }
    }
  }

  // Kept points: match positions (as a multiset) against the input points no segment replaced.
  std::unordered_map<PosKey, uint32_t, PosHash> freePositions;
  freePositions.reserve(n);
  for (size_t j = 0; j < n; ++j)
    if (!uses[j]) ++freePositions[keyOf(input.points[j].position)];
  for (size_t h = 0; h < hybrid.points.size(); ++h) {
    auto it = freePositions.find(keyOf(hybrid.points[h].position));
    if (it == freePositions.end() || it->second == 0) {
      ++r.unmatchedPoints;
      const Vec3f& p = hybrid.points[h].position;
      std::snprintf(buf, sizeof buf, "hybrid point %zu (%.9g %.9g %.9g) is no unreplaced input point", h, p.x(), p.y(),
                    p.z());
      note(buf);
      continue;
    }
    --it->second;
    ++r.keptPoints;
  }
  for (auto& [key, count] : freePositions) r.missing += count;
  if (r.missing) {
    std::snprintf(buf, sizeof buf, "%zu input points are neither kept nor replaced", r.missing);
    note(buf);
  }
  return r;
}

}  // namespace linesurf
