// Synthetic scan (see ooc/synthetic_scan.h).
#include "linesurf/ooc/synthetic_scan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <string>

#include "linesurf/core/parallel.h"
#include "linesurf/ooc/point_stream.h"
#include "ooc/scan_hash.h"

namespace linesurf::ooc {
namespace {

using detail::splitmix;
using detail::unit;

constexpr int kOctaves = 6, kWaves = 3;
struct Wave {
  Vec3d dir;
  double freq, amp, phase;
};

std::array<Wave, kOctaves * kWaves> waves(uint64_t seed) {
  std::array<Wave, kOctaves * kWaves> w{};
  uint64_t s = splitmix(seed ^ 0x5ca1ab1eull);
  for (int o = 0; o < kOctaves; ++o)
    for (int j = 0; j < kWaves; ++j) {
      Wave& v = w[size_t(o * kWaves + j)];
      const double z = 2 * unit(s = splitmix(s)) - 1, phi = 2 * std::numbers::pi * unit(s = splitmix(s));
      const double r = std::sqrt(std::max(0.0, 1 - z * z));
      v.dir = Vec3d(r * std::cos(phi), r * std::sin(phi), z);
      v.freq = 3.0 * double(1 << o);
      v.amp = 0.06 / double(1 << o);
      v.phase = 2 * std::numbers::pi * unit(s = splitmix(s));
    }
  return w;
}

/// The unit direction of point i (uniform over the sphere) from its first two deviates.
Vec3d directionOf(uint64_t h0, uint64_t h1) {
  const double z = 2 * unit(h0) - 1, phi = 2 * std::numbers::pi * unit(h1);
  const double r = std::sqrt(std::max(0.0, 1 - z * z));
  return Vec3d(r * std::cos(phi), r * std::sin(phi), z);
}

uint64_t firstHash(const SyntheticScanOptions& o, uint64_t i) { return splitmix(o.seed * 0x9e3779b97f4a7c15ull + i); }

}  // namespace

void syntheticScanPoints(const SyntheticScanOptions& o, uint64_t first, size_t n, std::vector<Vec3f>& out) {
  const auto w = waves(o.seed);
  const double sigma = o.noise * std::sqrt(4 * std::numbers::pi / double(std::max<uint64_t>(o.count, 1)));
  out.resize(n);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t t = b; t < e; ++t) {
      const uint64_t h0 = firstHash(o, first + t);
      const uint64_t h1 = splitmix(h0), h2 = splitmix(h1), h3 = splitmix(h2);
      const Vec3d d = directionOf(h0, h1);
      double radius = 1.0;
      for (const Wave& v : w) radius += v.amp * std::sin(v.freq * d.dot(v.dir) + v.phase);
      // Box-Muller normal deviate for the radial sampling noise.
      const double g = std::sqrt(-2 * std::log(1 - unit(h2))) * std::cos(2 * std::numbers::pi * unit(h3));
      radius += sigma * g;
      out[t] = (radius * d).cast<float>();
    }
  }, 4096);
}

void syntheticScanColors(const SyntheticScanOptions& o, uint64_t first, size_t n, std::vector<uint8_t>& out) {
  // One fixed direction and phase per channel (from the seed), as the waves are.
  std::array<Vec3d, 3> axis;
  std::array<double, 3> phase{};
  uint64_t s = splitmix(o.seed ^ 0xc0105eedull);
  for (int c = 0; c < 3; ++c) {
    axis[size_t(c)] = directionOf(s = splitmix(s), s = splitmix(s));
    phase[size_t(c)] = 2 * std::numbers::pi * unit(s = splitmix(s));
  }
  out.resize(3 * n);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t t = b; t < e; ++t) {
      const uint64_t h0 = firstHash(o, first + t), h1 = splitmix(h0);
      const Vec3d d = directionOf(h0, h1);
      uint64_t h = splitmix(h1 ^ 0xd17e4ull);  // the dither: deviates of its own
      for (int c = 0; c < 3; ++c) {
        const double v = 255 * (0.5 + 0.5 * std::sin(4 * d.dot(axis[size_t(c)]) + phase[size_t(c)]));
        const double dither = std::floor(17 * unit(h = splitmix(h))) - 8;  // -8..8 levels
        out[3 * t + size_t(c)] = uint8_t(std::clamp(std::lround(v + dither), 0l, 255l));
      }
    }
  }, 4096);
}

void writeSyntheticScan(const std::filesystem::path& path, const SyntheticScanOptions& o) {
  PlyPointWriter writer(path, o.count,
                        {"linesurf synthetic scan: count " + std::to_string(o.count) + " seed " + std::to_string(o.seed) +
                         (o.color ? " colour" : "")},
                        false, false, "", {}, o.color);
  std::vector<Vec3f> pts;
  std::vector<uint8_t> rgb;
  std::vector<float> colors;
  const uint64_t chunk = 1 << 20;
  for (uint64_t b = 0; b < o.count; b += chunk) {
    const size_t n = size_t(std::min(chunk, o.count - b));
    syntheticScanPoints(o, b, n, pts);
    if (o.color) {
      syntheticScanColors(o, b, n, rgb);
      colors.resize(4 * n);
      // k / 255 is the float the writer rounds back to k.
      for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 4; ++c) colors[4 * i + size_t(c)] = c < 3 ? float(rgb[3 * i + size_t(c)]) / 255.0f : 1.0f;
    }
    writer.write(pts.data(), nullptr, nullptr, n, nullptr, o.color ? colors.data() : nullptr);
  }
  writer.finish();
}

}  // namespace linesurf::ooc
