#pragma once
/// (epsilon, delta) error-bounded line segment extraction, thesis §3.1.
///
/// Turns a point cloud into a hybrid point + line-segment model. Every output segment replaces a
/// set Q of input points such that each q in Q lies within `epsilon` of the segment and its normal
/// deviates from the segment's anchor normal by 1 - n_anchor . n_q <= `delta` (§3.1.2.1).
///
/// Algorithm (§3.1.4, decisions in docs/decisions.md "(ε,δ) extraction (§3.1)"):
///  1. For every anchor p_i and every local Delaunay neighbour p_k with 1 - n_i.n_k <= delta and
///     distance to p_i's tangent plane <= epsilon, a segment L_k(p_i) starts on that plane from
///     p_i towards the projection of p_k (its direction is fixed from then on) and grows: the
///     Delaunay neighbours of the points taken so far are tried in increasing distance to the
///     segment's line; one within epsilon of the line and delta of n_i is taken (extending an end
///     to its projection when it lies beyond), a failing one stops the side it lies on.
///     This stage runs in parallel, one anchor per task, on the full cloud.
///  2. Greedy selection: repeatedly output the anchor whose best direction replaces the most
///     still-available points (ties: smallest anchor index, then smallest neighbour index), remove
///     those points, and stop when no candidate replaces more than `minReplaced - 1` points.
///     A lazy max-heap gives exactly the result of re-evaluating every candidate after each step.
#include <cstddef>
#include <cstdint>
#include <string>

#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf {

/// How candidates are updated after each extracted segment. Both give identical results; Eager
/// is the O(n x segments) reference definition kept for tests.
enum class EpsDeltaUpdate { Lazy, Eager };

struct EpsDeltaOptions {
  /// Distance tolerance epsilon, object space. <= 0 means `epsilonRelative` x the geometry's
  /// average spacing (the §7.2 setting).
  double epsilon = 0;
  /// Used when epsilon <= 0: epsilon = epsilonRelative * PointGeometry::averageSpacing. > 0.
  double epsilonRelative = 0.05;
  /// Used when epsilon <= 0 and this is > 0 (beyond the thesis, for real scans): epsilon =
  /// max(epsilonRelative x spacing, epsilonNoise x the scan's noise sigma along its normals,
  /// estimateNoise of geometry/noise.h), so that a scan noisier than 0.05 x spacing still has
  /// points within epsilon of a segment; the thesis's epsilon where the noise is below it.
  /// [0, 100]; 0 = off (the thesis).
  double epsilonNoise = 0;
  /// Normal tolerance delta on 1 - n_i . n_j, in [0, 2]; 0.004 ~ 5.13 degrees (§7.2).
  double delta = 0.004;
  /// Segments replacing fewer points are rejected ("3 or less" in §3.1.4 -> 4). >= 2.
  int minReplaced = 4;
  /// Growth of one segment stops once it holds this many points; 0 = no limit (§3.1.4 as written).
  /// Computing L_max for every point costs O(n x segment length) time and memory, which is
  /// quadratic on long regular rows (a 300 x 300 grid plane); a limit bounds it. 0 or >= minReplaced.
  int maxReplaced = 0;
  /// Record, per segment, the input indices it replaced (HybridModel::provenance); the anchor
  /// comes first, the rest in increasing position along the segment.
  bool provenance = false;
  /// Smooth line models (beyond the thesis): each segment also carries the normals of the
  /// points at its two ends (Segment::normal0/normal1, made perpendicular to it).
  bool endpointNormals = true;
  EpsDeltaUpdate update = EpsDeltaUpdate::Lazy;
  ProgressFn progress;
};

struct EpsDeltaStats {
  size_t inputPoints = 0;
  size_t keptPoints = 0;       ///< points left as point primitives
  size_t segments = 0;
  size_t replacedPoints = 0;   ///< inputPoints - keptPoints
  size_t seedDirections = 0;   ///< (anchor, neighbour) pairs that started a segment
  size_t candidateDirections = 0;  ///< of those, grown to >= minReplaced points
  size_t candidateMembers = 0;     ///< points held by those candidates (grow-stage work and memory)
  size_t degenerateNeighbours = 0; ///< neighbours whose projection coincides with the anchor
  size_t heapPops = 0, heapReinserts = 0;  ///< lazy greedy phase work
  double epsilon = 0, delta = 0;   ///< the tolerances actually used
  double noiseSigma = 0;           ///< the noise estimate epsilonNoise used (0 when off)
  double growSeconds = 0, selectSeconds = 0, outputSeconds = 0;
  /// §7.2.2 data reduction: 1 - (6 floats per point + 9 per segment) / (6 per input point).
  double dataReduction() const {
    return inputPoints ? 1.0 - (6.0 * keptPoints + 9.0 * segments) / (6.0 * inputPoints) : 0.0;
  }
  double replacedFraction() const { return inputPoints ? double(replacedPoints) / inputPoints : 0.0; }
};

/// Throws OptionError (core/options.h) naming the first bad field; NaN is always rejected.
void validate(const EpsDeltaOptions& options);

/// Extracts the hybrid model. `geometry` must come from computePointGeometry(cloud) with local
/// Delaunay neighbours (stage 3); its normals are the ones the bounds refer to.
///
/// Output: kept points in input order (normals from the geometry; radii from the cloud, or
/// geometry spacing when it has none; colours and extra point properties carried over), then the
/// segments in extraction order. Segment endpoints are the projections of the extreme replaced
/// points onto the segment's line, its normal is the anchor normal made perpendicular to the
/// segment, its colour the mean of the replaced points' colours, its radius the least (from the
/// thinnest member's radius up) at which the strips cover every replaced point's Voronoi cell
/// (local Delaunay star) together with the neighbouring segments, at most
/// max_j (r_j + dist(q_j, segment)) <= max r_j + epsilon, the cover of every replaced disc
/// (§3.1.5's "radius + ε" made tight; docs/decisions.md "Hybrid segment widths").
/// A comment "eps-delta: epsilon=E delta=D k=K" records the tolerances.
/// Deterministic for any thread count. Throws linesurf::Error (BadParameter) for absurd options
/// or geometry that does not match the cloud.
HybridModel extractEpsDelta(const HybridModel& cloud, const PointGeometry& geometry,
                            const EpsDeltaOptions& options = {}, EpsDeltaStats* stats = nullptr);

/// The epsilon extractEpsDelta uses for these options, geometry and cloud (whose noise
/// epsilonNoise reads; `noiseSigma` receives the estimate, 0 when not asked for).
double resolveEpsilon(const EpsDeltaOptions& options, const PointGeometry& geometry, const HybridModel& cloud,
                      double* noiseSigma = nullptr);

}  // namespace linesurf
