// Coverage constants of the primitives (beyond the thesis; see coverage.h).
#include "coverage.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstdint>

#include "splat_rules.h"
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
  float mass = 1;      // a point's mass (pointMasses), as the renderer scales its weight
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
    return q <= cut * cut ? k.mass * std::exp(-0.5f * q) / s2 : 0.0f;
  }
  const float a = k.e.dot(d);
  const float b2 = std::max(0.0f, d.squaredNorm() - a * a - off * off);
  if (b2 > reach * reach || a < -reach || a > k.length + reach) return 0;
  const float is = 1.0f / (k.sigma * std::sqrt(2.0f));
  const float along = 0.5f * (std::erf(a * is) - std::erf((a - k.length) * is)) * k.sigma * std::sqrt(2.0f * float(std::numbers::pi));
  return std::exp(-0.5f * b2 / s2) * along * k.invRadius / s2;
}

}  // namespace

std::vector<float> coverageConstants(const HybridModel& model, float reconstructionScale, float cutoff, bool least,
                                     size_t stride) {
  if (stride == 0) stride = 1;
  const size_t np = model.points.size(), ns = model.segments.size(), n = np + ns;
  std::vector<Kernel> ks(n);
  std::vector<Vec3f> centre(n), normal(n);
  std::vector<uint8_t> ok(n, 0);
  float cell = 0;
  const std::vector<float>* masses = pointMasses(model);
  for (size_t i = 0; i < np; ++i) {
    const Point& p = model.points[i];
    if (!usable(p.radius) || !p.position.allFinite() || !p.normal.allFinite()) continue;
    Kernel& k = ks[i];
    if (masses) k.mass = (*masses)[i];
    k.p0 = p.position, k.e = Vec3f::Zero();
    const float nn = p.normal.norm();
    k.n = nn > 0 ? Vec3f(p.normal / nn) : Vec3f::Zero();
    k.sigma = reconstructionScale * p.radius, k.radius = p.radius;
    centre[i] = p.position, normal[i] = k.n, ok[i] = 1;
    cell = std::max(cell, cutoff * k.sigma + kRingRadius * k.radius);
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
    cell = std::max(cell, cutoff * k.sigma + kRingRadius * k.radius);
  }
  std::vector<float> c(n, 0.0f);
  if (!(cell > 0)) return c;
  // A grid of cells of side c = 2 (largest reach + ring radius): every kernel listed once per piece
  // of at most c / 2 (a point is one piece), in the cell of the piece's middle, as (cell, primitive)
  // pairs in hash buckets, in primitive order (deterministic, no container per cell). A kernel that
  // reaches a primitive's samples then has a piece middle within reach + ring + c / 4 < c of the
  // primitive's centre: in the 27 cells around the centre's.
  cell *= 2;
  const float inv = 1.0f / cell;
  auto key = [](int64_t x, int64_t y, int64_t z) {
    return (uint64_t(x) * 73856093u) ^ (uint64_t(y) * 19349663u) ^ (uint64_t(z) * 83492791u);
  };
  auto cellOf = [&](float v) { return int64_t(std::floor(v * inv)); };
  struct Entry {
    uint64_t key;
    uint32_t index;
  };
  const size_t chunk = 16384, chunks = (n + chunk - 1) / chunk;
  std::vector<std::vector<Entry>> parts(chunks);
  parallelFor(0, chunks, [&](size_t ch) {
    std::vector<Entry>& out = parts[ch];
    for (size_t i = ch * chunk, e = std::min(n, i + chunk); i < e; ++i) {
      if (!ok[i]) continue;
      const Kernel& k = ks[i];
      const int pieces = std::max(1, int(std::ceil(2 * k.length * inv)));
      for (int q = 0; q < pieces; ++q) {
        const Vec3f m = k.p0 + (k.length * (float(q) + 0.5f) / float(pieces)) * k.e;
        out.push_back({key(cellOf(m.x()), cellOf(m.y()), cellOf(m.z())), uint32_t(i)});
      }
    }
  }, 1);
  // buckets by a hash of the cell (a power of two, about 2 per entry), filled in primitive order
  size_t total = 0;
  for (const auto& v : parts) total += v.size();
  size_t buckets = 1024;
  while (buckets < 2 * total) buckets *= 2;
  const uint64_t mask = buckets - 1;
  auto bucketOf = [mask](uint64_t k) { return size_t((k * 0x9E3779B97F4A7C15ull) >> 20 & mask); };
  std::vector<uint32_t> start(buckets + 1, 0);
  for (const auto& v : parts)
    for (const Entry& e : v) ++start[bucketOf(e.key) + 1];
  for (size_t b = 0; b < buckets; ++b) start[b + 1] += start[b];
  std::vector<Entry> grid(total);
  {
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (auto& v : parts) {
      for (const Entry& e : v) grid[fill[bucketOf(e.key)]++] = e;
      std::vector<Entry>().swap(v);
    }
  }
  parallelFor(0, n, [&](size_t i) {
    if (!ok[i] || i % stride != 0) return;
    const Kernel& k = ks[i];
    const float ringR = kRingRadius * k.radius;
    // the kernels that may reach the centre or the ring (distance to the kernel's segment within its
    // reach + the ring's radius), in primitive order
    thread_local std::vector<uint32_t> near;
    near.clear();
    const Vec3f& x = centre[i];
    const int64_t cx = cellOf(x.x()), cy = cellOf(x.y()), cz = cellOf(x.z());
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy)
        for (int64_t dz = -1; dz <= 1; ++dz) {
          const uint64_t kx = key(cx + dx, cy + dy, cz + dz);
          const size_t b = bucketOf(kx);
          for (uint32_t g = start[b]; g < start[b + 1]; ++g) {
            if (grid[g].key != kx) continue;
            const Kernel& kj = ks[grid[g].index];
            const Vec3f d = x - kj.p0;
            const float a = std::clamp(kj.e.dot(d), 0.0f, kj.length);
            const float lim = cutoff * kj.sigma + ringR;
            if ((d - a * kj.e).squaredNorm() <= lim * lim) near.push_back(grid[g].index);
          }
        }
    std::sort(near.begin(), near.end());
    near.erase(std::unique(near.begin(), near.end()), near.end());
    auto density = [&](const Vec3f& p) {
      float sum = 0;
      for (uint32_t j : near) sum += weightAt(ks[j], p, normal[i], cutoff);
      return sum;
    };
    // the least (or the mean) of the density at the centre and on a ring of kRing points at
    // kRingRadius r in the primitive's plane (across and along a segment's middle): the troughs
    // between samples
    float sum = density(x), total = sum;
    Vec3f u = k.length > 0 ? k.e : (std::abs(k.n.x()) < 0.9f ? Vec3f(Vec3f::UnitX().cross(k.n)) : Vec3f(Vec3f::UnitY().cross(k.n)));
    u.normalize();
    const Vec3f v = k.n.cross(u);
    for (int a = 0; a < kRing; ++a) {
      const float t = 2 * float(std::numbers::pi) * float(a) / float(kRing);
      const float at = density(x + ringR * (std::cos(t) * u + std::sin(t) * v));
      sum = std::min(sum, at);
      total += at;
    }
    if (!least) sum = total / float(kRing + 1);
    c[i] = sum > 0 ? 1.0f / sum : 0.0f;
  }, 1024);
  return c;
}

float medianCoverageConstant(const HybridModel& model, float reconstructionScale, float cutoff) {
  const size_t n = model.points.size() + model.segments.size();
  const size_t stride = std::max<size_t>(1, n / 4096);
  std::vector<float> c = coverageConstants(model, reconstructionScale, cutoff, false, stride);
  std::erase_if(c, [](float v) { return !(v > 0) || !std::isfinite(v); });
  if (c.empty()) return 0.0f;
  std::nth_element(c.begin(), c.begin() + ptrdiff_t(c.size() / 2), c.end());
  return c[c.size() / 2];
}

}  // namespace linesurf::detail
