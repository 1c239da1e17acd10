#pragma once
/// The noise of a scan along its normals (beyond the thesis, whose §7.2 tolerances assume a clean
/// scan: epsilon = 0.05 x spacing lies below a real scanner's noise, and (ε,δ) then replaces few
/// points). Built on the §6.1 neighbourhoods: at sampled points, a height function
/// w = (a u² + 2b uv + c v²)/2 + d u + e v + f is fitted over the k nearest neighbours in the
/// PCA tangent frame, so that curvature is not mistaken for noise, and its residual is the local
/// noise. The neighbourhood grows (24, 48, ... 768 neighbours) until its radius is at least
/// `footprint` times the residual: a noise comparable to the spacing makes a small neighbourhood
/// a ball, whose fit says nothing about the surface. The estimate is the median over the samples
/// (edges, creases and outliers move few of them). See docs/decisions.md "Noise".
#include <cstddef>
#include <span>

#include "linesurf/core/math.h"
#include "linesurf/core/model.h"

namespace linesurf {

struct NoiseOptions {
  /// Points sampled (evenly in index order), [16, 10^7]; at most all points.
  int samples = 2048;
  /// Largest neighbourhood tried, [24, 4096].
  int maxNeighbours = 768;
  /// A neighbourhood is trusted once its radius reaches this many times its residual, [2, 100].
  float footprint = 4.0f;
};

/// Throws Error(BadParameter) naming the field.
void validate(const NoiseOptions& o);

struct NoiseEstimate {
  double sigma = 0;            ///< standard deviation along the normals, object units
  double lowerQuartile = 0;    ///< of the samples' local estimates: the spread over the scan
  double upperQuartile = 0;
  size_t samples = 0;          ///< points sampled
  size_t fitted = 0;           ///< of those, with a well-posed fit
  size_t unresolved = 0;       ///< fitted, but no neighbourhood up to maxNeighbours was wide enough
  double medianNeighbours = 0; ///< neighbourhood size the median sample settled on
};

/// Estimates the noise of a cloud. Deterministic for any thread count. Fewer than 7 points, or
/// samples none of which has a well-posed fit (collinear points), give fitted == 0 and sigma 0.
/// Throws Error(BadParameter) for a non-finite position.
NoiseEstimate estimateNoise(std::span<const Vec3f> positions, const NoiseOptions& options = {});
/// The same over a model's points (its segments are not samples of the scan).
NoiseEstimate estimateNoise(const HybridModel& model, const NoiseOptions& options = {});

}  // namespace linesurf
