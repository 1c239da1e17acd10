// Coverage constants of the primitives (beyond the thesis, issue 14; see coverage.h).
#include "coverage.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "linesurf/core/parallel.h"

namespace linesurf::detail {

namespace {

bool usable(float r) { return r > 0 && std::isfinite(r); }

// The density is sampled at the centre and on a ring of kRing points at kRingRadius x the radius
// (measured: the centre alone left 14,500 pixels at alpha < 0.5 inside random sphere samples, 6
// renders at gain 2; the least of a ring at 0.9 r 225, at 0.6 r 172).
constexpr int kRing = 8;
constexpr float kRingRadius = 0.6f;

// One primitive's object-space kernel, as the renderer weights it without the prefilter.
struct Kernel {
  Vec3f p0, e, n;      // start (a point's centre), unit direction (segments), unit normal (or zero)
  float length = 0;    // 0 for a point
  float sigma = 0, radius = 0, invRadius = 0;
};

// w(x): a point exp(-d^2 / 2 s^2) / s^2 (d in its plane); a segment (1 / (r s^2)) times the integral
// of exp(-|x - p(t)|^2 / 2 s^2) over its length (in its strip's plane); 0 beyond the cut-off or off
// the sheet.
float weightAt(const Kernel& k, const Vec3f& x, const Vec3f& nx, float cut) {
  const Vec3f d = x - k.p0;
  const float off = k.n.dot(d);
  const float reach = cut * k.sigma;
  if (std::abs(off) > reach || k.n.dot(nx) < 0) return 0;
  const float s2 = k.sigma * k.sigma;
  if (k.length == 0) {
    const float q = (d.squaredNorm() - off * off) / s2;
    return q <= cut * cut ? std::exp(-0.5f * q) / s2 : 0.0f;
  }
  const float a = k.e.dot(d);
  const float b2 = std::max(0.0f, d.squaredNorm() - a * a - off * off);
  if (b2 > reach * reach || a < -reach || a > k.length + reach) return 0;
  const float is = 1.0f / (k.sigma * std::sqrt(2.0f));
  const float along = 0.5f * (std::erf(a * is) - std::erf((a - k.length) * is)) * k.sigma * std::sqrt(2.0f * 3.14159265f);
  return std::exp(-0.5f * b2 / s2) * along * k.invRadius / s2;
}

}  // namespace

std::vector<float> coverageConstants(const HybridModel& model, float reconstructionScale, float cutoff) {
  const size_t np = model.points.size(), ns = model.segments.size(), n = np + ns;
  std::vector<Kernel> ks(n);
  std::vector<Vec3f> centre(n), normal(n);
  std::vector<uint8_t> ok(n, 0);
  float cell = 0;
  for (size_t i = 0; i < np; ++i) {
    const Point& p = model.points[i];
    if (!usable(p.radius) || !p.position.allFinite() || !p.normal.allFinite()) continue;
    Kernel& k = ks[i];
    k.p0 = p.position, k.e = Vec3f::Zero();
    const float nn = p.normal.norm();
    k.n = nn > 0 ? Vec3f(p.normal / nn) : Vec3f::Zero();
    k.sigma = reconstructionScale * p.radius, k.radius = p.radius;
    centre[i] = p.position, normal[i] = k.n, ok[i] = 1;
    cell = std::max(cell, cutoff * k.sigma);
  }
  for (size_t j = 0; j < ns; ++j) {
    const Segment& s = model.segments[j];
    const float l = s.length();
    if (!usable(s.radius) || !(l > 0) || !std::isfinite(l) || !s.normal.allFinite()) continue;
    Kernel& k = ks[np + j];
    k.p0 = s.p0, k.e = (s.p1 - s.p0) / l, k.length = l;
    const float nn = s.normal.norm();
    k.n = nn > 0 ? Vec3f(s.normal / nn) : Vec3f::Zero();
    k.sigma = reconstructionScale * s.radius, k.radius = s.radius, k.invRadius = 1.0f / s.radius;
    centre[np + j] = 0.5f * (s.p0 + s.p1), normal[np + j] = k.n, ok[np + j] = 1;
    cell = std::max(cell, cutoff * k.sigma);
  }
  std::vector<float> c(n, 0.0f);
  if (!(cell > 0)) return c;
  // a hash grid of cells of the largest kernel reach: each kernel in every cell its box touches
  const float inv = 1.0f / cell;
  auto key = [](int64_t x, int64_t y, int64_t z) {
    return (uint64_t(x) * 73856093u) ^ (uint64_t(y) * 19349663u) ^ (uint64_t(z) * 83492791u);
  };
  auto cellOf = [&](float v) { return int64_t(std::floor(v * inv)); };
  std::unordered_map<uint64_t, std::vector<uint32_t>> grid;
  grid.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    if (!ok[i]) continue;
    const Kernel& k = ks[i];
    const Vec3f p1 = k.p0 + k.length * k.e;
    const float r = cutoff * k.sigma;
    const Vec3f lo = k.p0.cwiseMin(p1).array() - r, hi = k.p0.cwiseMax(p1).array() + r;
    for (int64_t x = cellOf(lo.x()); x <= cellOf(hi.x()); ++x)
      for (int64_t y = cellOf(lo.y()); y <= cellOf(hi.y()); ++y)
        for (int64_t z = cellOf(lo.z()); z <= cellOf(hi.z()); ++z) {
          std::vector<uint32_t>& v = grid[key(x, y, z)];
          if (v.empty() || v.back() != uint32_t(i)) v.push_back(uint32_t(i));
        }
  }
  parallelFor(0, n, [&](size_t i) {
    if (!ok[i]) return;
    auto density = [&](const Vec3f& x) {
      const auto it = grid.find(key(cellOf(x.x()), cellOf(x.y()), cellOf(x.z())));
      float sum = 0;
      if (it != grid.end())
        for (uint32_t j : it->second) sum += weightAt(ks[j], x, normal[i], cutoff);
      return sum;
    };
    // the least of the density at the centre and on a ring of kRing points at kRingRadius r in
    // the primitive's plane (across and along a segment's middle): the troughs between samples
    float sum = density(centre[i]);
    const Kernel& k = ks[i];
    const float r = kRingRadius * k.radius;
    Vec3f u = k.length > 0 ? k.e : (std::abs(k.n.x()) < 0.9f ? Vec3f(Vec3f::UnitX().cross(k.n)) : Vec3f(Vec3f::UnitY().cross(k.n)));
    u.normalize();
    const Vec3f v = k.n.cross(u);
    for (int a = 0; a < kRing; ++a) {
      const float t = 2 * 3.14159265f * float(a) / float(kRing);
      sum = std::min(sum, density(centre[i] + r * (std::cos(t) * u + std::sin(t) * v)));
    }
    c[i] = sum > 0 ? 1.0f / sum : 0.0f;
  }, 1024);
  return c;
}

}  // namespace linesurf::detail
