#pragma once
/// Checks the (epsilon, delta) bound of an extracted hybrid model against its input cloud
/// (thesis §3.1.2.1): for every segment, each replaced point lies within epsilon of the segment
/// and 1 - n_anchor . n_q <= delta, where the anchor is the segment's first provenance index; and
/// every input point is either kept as a point (same position) or replaced by exactly one segment.
/// Needs HybridModel::provenance (extract with --provenance).
#include <cstddef>
#include <string>
#include <vector>

#include "linesurf/core/model.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf {

struct VerifyReport {
  size_t segments = 0;
  size_t replacedPoints = 0;      ///< provenance entries
  size_t keptPoints = 0;          ///< hybrid points matched to an input point
  size_t distanceViolations = 0;  ///< replaced point farther than epsilon from its segment
  size_t normalViolations = 0;    ///< replaced point whose normal deviates more than delta
  size_t badSegments = 0;         ///< empty provenance, non-unit or non-perpendicular normal
  size_t badIndices = 0;          ///< provenance index out of range
  size_t replacedTwice = 0;       ///< input points in more than one segment / also kept
  size_t missing = 0;             ///< input points neither kept nor replaced
  size_t unmatchedPoints = 0;     ///< hybrid points that are no unreplaced input point
  double maxDistance = 0;         ///< largest replaced-point distance to its segment
  double maxNormalDeviation = 0;  ///< largest 1 - n_anchor . n_q
  double epsilon = 0, delta = 0;  ///< the bounds checked (before the rounding tolerance)
  std::vector<std::string> messages;  ///< the first violations, one line each

  bool ok() const {
    return distanceViolations == 0 && normalViolations == 0 && badSegments == 0 && badIndices == 0 &&
           replacedTwice == 0 && missing == 0 && unmatchedPoints == 0;
  }
};

/// Verifies `hybrid` against `input`. Normals: `geometry->normals` when given, else the input's
/// normals; throws linesurf::Error (BadInput) when neither is available or the hybrid has no
/// provenance. Distances are checked against epsilon plus a rounding tolerance of
/// 1e-4 epsilon + 8 float ulps of the model's extent (positions are stored as float).
VerifyReport verifyExtraction(const HybridModel& input, const PointGeometry* geometry, const HybridModel& hybrid,
                              double epsilon, double delta);

}  // namespace linesurf
