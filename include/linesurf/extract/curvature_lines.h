#pragma once
/// Lines of curvature traced on the MLS surface (thesis §9.2, future work): a fourth extraction.
/// The thesis proposes to reconstruct the surface, trace its lines of curvature and straighten
/// them into chains of connected segments; this is that pipeline over the point-set surface of
/// surface/mls.h:
///
///  1. Direction field: the principal directions of the MLS normal field at every input point,
///     smoothed into a 4-symmetric cross field on the §6.1 neighbour graph (Jacobi iterations of
///     a local average with a data term weighted by the anisotropy |k_max - k_min|), so that it
///     follows the principal directions where the surface is anisotropic and interpolates through
///     umbilic and flat regions.
///  2. Evenly spaced lines (Jobard & Lefer 1997): a first seed per component, further seeds at
///     d_sep on either side of every accepted line; each line is integrated by RK4 in the tangent
///     plane and projected onto the surface at every step, in both directions, until it comes
///     within d_test = 0.5 d_sep of a line of its own direction, meets a singularity of the field
///     (umbilic), leaves the data (boundary) or closes on itself. d_sep is curvature-adaptive: at
///     most `separation` x the average spacing, and narrow enough that the strip of half-width
///     r = widthScale d_sep / 2 deviates from the surface across its width by at most epsilon
///     (k_across r^2 / 2 <= epsilon). Placement is sequential, so the lines are the same for any
///     thread count; the field and the cover test run in parallel, one output slot per point.
///  3. Straightening: each line is cut greedily into the longest chords whose samples lie within
///     epsilon of the chord and whose normals deviate from the chord's by at most delta (§3.1's
///     measures), so consecutive segments of a line share bit-equal endpoints (a chain).
///  4. Cover: an input point within a strip (inside its half-width, within epsilon plus its own
///     distance to the surface of the strip's plane) is replaced by the nearest such strip; every
///     other point is kept as a point primitive.
/// See docs/decisions.md "Curvature lines".
#include <cstddef>
#include <cstdint>

#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf {

/// Which lines of curvature are traced.
enum class CurvatureFamily {
  /// Along the direction of least curvature: the straighter lines, so the longest chords.
  Min,
  /// Along the direction of greatest curvature.
  Max,
  /// Both families (a crossing net: twice the segments; for drawings).
  Both,
};

struct CurvatureLineOptions {
  /// Distance tolerance epsilon, object space; <= 0: epsilonRelative x the average spacing.
  double epsilon = 0;
  /// epsilon = epsilonRelative x the average spacing when epsilon <= 0: the thesis's §7.2 value.
  double epsilonRelative = 0.05;
  /// Normal tolerance on 1 - n_chord . n_sample, [0, 2]; 0.004 ~ 5.13 deg (§7.2).
  double delta = 0.004;
  /// Largest line separation d_sep, in average spacings, [1, 100]: flat regions use it.
  double separation = 4.0;
  /// Smallest line separation, in average spacings, [0.25, separation]: below it a strip would
  /// replace fewer points than a segment costs, and the epsilon bound is left to the kept points.
  double minSeparation = 1.0;
  /// Strip half-width = widthScale x d_sep / 2, [1, 3]: adjacent strips overlap by 25% so their
  /// splats blend without a seam.
  double widthScale = 1.25;
  /// Integration step, in average spacings, (0, 4].
  double step = 0.5;
  /// Lines shorter than this many d_sep are dropped (their points stay points), [0, 100]: at 2 no
  /// short line is written (on Igea a quarter of the lines are shorter; dropping them costs 0.8%
  /// of data reduction and no image quality).
  double minLength = 2.0;
  /// Jacobi iterations of the cross-field smoothing, [0, 1000].
  int smoothingIterations = 40;
  /// Weight of the principal direction against the neighbours' average, per unit anisotropy, [0, 1e6].
  double fieldDataWeight = 0.05;
  /// Support of the MLS surface, in spacings (MlsOptions::supportScale), [1.5, 10].
  float supportScale = 3.0f;
  CurvatureFamily family = CurvatureFamily::Min;
  /// Record, per segment, the input points it replaced (HybridModel::provenance).
  bool provenance = false;
  ProgressFn progress;
};

struct CurvatureLineStats {
  size_t inputPoints = 0, keptPoints = 0, replacedPoints = 0;
  size_t segments = 0;
  size_t lines = 0;          ///< chains written
  size_t closedLines = 0;    ///< of those, closed on themselves
  size_t prunedLines = 0;    ///< traced but shorter than minLength d_sep
  size_t shortLines = 0;     ///< written but shorter than 2 d_sep
  double lineLength = 0;     ///< total length of the written chains, object space
  double shortLength = 0;    ///< of that, in chains shorter than 2 d_sep
  size_t steps = 0;          ///< integration steps taken
  size_t projectionFailures = 0;  ///< steps whose projection did not converge (the line stopped)
  /// Why lines stopped (each line has two ends).
  size_t stopSeparation = 0, stopSingularity = 0, stopBoundary = 0, stopClosed = 0, stopLength = 0;
  double epsilon = 0, delta = 0;
  double averageSpacing = 0;
  double meanSeparation = 0;  ///< mean d_sep over the seeds, object space
  double fieldSeconds = 0, traceSeconds = 0, straightenSeconds = 0, coverSeconds = 0;
  /// §7.2.2 data reduction: 1 - (6 floats per point + 9 per segment) / (6 per input point).
  double dataReduction() const {
    return inputPoints ? 1.0 - (6.0 * double(keptPoints) + 9.0 * double(segments)) / (6.0 * double(inputPoints)) : 0.0;
  }
  /// The same with a chain's shared endpoints stored once: a chain of m segments holds m + 1
  /// endpoints (3 floats each) and m x (normal 2 + radius 1) floats.
  double chainDataReduction() const {
    const double floats = 6.0 * double(keptPoints) + 3.0 * double(segments + lines) + 3.0 * double(segments);
    return inputPoints ? 1.0 - floats / (6.0 * double(inputPoints)) : 0.0;
  }
  double meanChainLength() const { return lines ? lineLength / double(lines) : 0.0; }
};

/// Throws OptionError naming the first bad field; NaN is always rejected.
void validate(const CurvatureLineOptions& options);

/// Extracts the hybrid model: kept points in input order (normals from the geometry, radii from
/// the cloud or the geometry's cover radius), then the segments chain by chain, each chain's
/// segments in order along it with bit-equal shared endpoints. Segment normals are the surface
/// normal at the chord's middle made perpendicular to it, endpoint normals the surface normals at
/// its ends, colour the mean of the replaced points' colours. A comment "curvature-lines: ..."
/// records the tolerances. `geometry` must come from computePointGeometry(cloud) (normals,
/// neighbours, spacing, cover radius). A cloud without a surface (too few points, collinear)
/// gives every point kept and no segment. Deterministic for any thread count.
HybridModel extractCurvatureLines(const HybridModel& cloud, const PointGeometry& geometry,
                                  const CurvatureLineOptions& options = {}, CurvatureLineStats* stats = nullptr);

}  // namespace linesurf
