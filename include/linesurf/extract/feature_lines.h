#pragma once
/// Feature lines of a point cloud (thesis §9.5, future work: "feature and skeleton lines"):
/// its creases as a line model, whose segments the drawings stroke (`render --style lines`).
///
///  1. Normals that stay sharp: every point is projected onto the cloud's robust MLS surface
///     (RIMLS, surface/mls.h), whose normal keeps each side of a crease its own instead of
///     turning across a band of a support's width as PCA and plain MLS normals do.
///  2. Crease samples: for every pair of neighbours within `linkRadius` spacings whose normals
///     differ by more than `angle` degrees, the point nearest their midpoint on the line where
///     their two tangent planes meet (kept when it lies within `linkRadius` spacings of both),
///     with that line's direction. Averaged per cell of one spacing: one sample per cell.
///  3. Chains: samples within `linkRadius` spacings whose directions agree within 30 degrees and
///     lie along each other are linked; the minimum spanning forest of the links is cut at its
///     branch points (a corner where three creases meet) into polylines.
///  4. Segments: each polyline longer than `minLength` spacings is simplified (Douglas-Peucker,
///     `tolerance` spacings) into segments with bit-equal shared endpoints; a segment's normal is
///     the mean of its samples' two plane normals, made perpendicular to it, its radius half a
///     spacing.
/// Deterministic for any thread count (samples in point order, the forest by sorted links).
/// See docs/decisions.md "Feature lines".
#include <cstddef>

#include "linesurf/core/model.h"

namespace linesurf {

struct FeatureLineOptions {
  /// Smallest angle between the normals on the two sides of a crease, degrees, [5, 170].
  double angle = 25;
  /// Neighbours and links within this many median spacings, [1, 8].
  double linkRadius = 2;
  /// Polylines shorter than this many spacings are dropped (noise, corners), [0, 1e6].
  double minLength = 4;
  /// Douglas-Peucker tolerance, spacings, [0, 10].
  double tolerance = 0.25;
  /// Normals from the robust MLS surface (else the model's own), and its support in spacings.
  bool robustNormals = true;
  float supportScale = 3.0f;
};

struct FeatureLineStats {
  size_t points = 0;           ///< input points
  size_t creasePairs = 0;      ///< neighbour pairs across a crease
  size_t samples = 0;          ///< crease samples after the per-cell average
  size_t polylines = 0;        ///< kept polylines
  size_t segments = 0;
  double length = 0;           ///< total length of the segments, object units
  double spacing = 0;          ///< median nearest-neighbour spacing, object units
  double normalSeconds = 0, sampleSeconds = 0, chainSeconds = 0;
};

/// Throws Error(BadParameter) naming the field.
void validate(const FeatureLineOptions& options);

/// The creases of `cloud` (points with normals; segments are ignored) as a line model: segments
/// only, with normals and radii. An empty model when the cloud has no crease. Throws
/// Error(BadParameter) on options or a cloud without normals, with fewer than 8 points, or
/// with a non-finite position ("model").
HybridModel extractFeatureLines(const HybridModel& cloud, const FeatureLineOptions& options = {},
                                FeatureLineStats* stats = nullptr);

}  // namespace linesurf
