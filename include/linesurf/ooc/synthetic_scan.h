#pragma once
/// A synthetic scan for tests and benchmarks of the out-of-core pipeline: points on a closed
/// surface with detail at several scales (a unit sphere displaced along its normal by six
/// octaves of sinusoids in random directions, each octave half the amplitude and twice the
/// frequency of the one before), sampled uniformly in direction with radial sampling noise.
/// Point i depends only on (seed, i), so any N is generated in chunks with bounded memory and
/// the same points for any thread count.
#include <cstdint>
#include <filesystem>
#include <vector>

#include "linesurf/core/math.h"

namespace linesurf::ooc {

struct SyntheticScanOptions {
  uint64_t count = 1000000;
  uint64_t seed = 1;
  /// Radial sampling noise, as a fraction of the expected point spacing sqrt(4 pi / count).
  double noise = 0.1;
  /// Write 8-bit colour (uchar red green blue, and alpha 255): a smooth field over the sphere's directions
  /// (each channel 0.5 + 0.5 sin(4 d.a + phase) for a fixed direction a per channel, so that
  /// neighbouring points have similar colours and a segment's mean colour is meaningful), plus
  /// a per-point dither of +-8 levels from (seed, i). Point i's colour depends only on (seed, i).
  bool color = false;
};

/// Points [first, first + n) of the scan.
void syntheticScanPoints(const SyntheticScanOptions& o, uint64_t first, size_t n, std::vector<Vec3f>& out);

/// Colours of points [first, first + n) (with or without o.color): red green blue 0..255, 3 a point.
void syntheticScanColors(const SyntheticScanOptions& o, uint64_t first, size_t n, std::vector<uint8_t>& out);

/// Writes the whole scan as binary little-endian PLY (x y z floats, then uchar red green blue
/// alpha with o.color), in chunks of 1 M points.
void writeSyntheticScan(const std::filesystem::path& path, const SyntheticScanOptions& o);

}  // namespace linesurf::ooc
