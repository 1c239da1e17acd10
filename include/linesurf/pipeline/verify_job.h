#pragma once
/// `linesurf verify-extraction` as a library call shared by the front ends: the certificate check
/// of an (epsilon, delta) extraction (thesis §3.1.2.1) with the tolerances, k and the normals'
/// origin that `extract eps-delta` recorded in the hybrid's comments, unless given.
#include <optional>
#include <string>

#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"
#include "linesurf/surface/surface_error.h"
#include "linesurf/extract/verify.h"

namespace linesurf {

struct RecordedVerifyOptions {
  std::optional<double> epsilon, delta;  ///< default: as recorded ("eps-delta: epsilon=E delta=D k=K")
  std::optional<int> k;                  ///< neighbours for computed normals, [3, 256]; default: recorded or 12
  /// Also measure the surface error (surface/surface_error.h) of the hybrid against the input: the
  /// two MLS surfaces sampled both ways (a second or two for 100 k points on 2 threads).
  bool surfaceError = true;
  SurfaceErrorOptions surface;
  ProgressFn progress;
};

struct RecordedVerifyResult {
  VerifyReport report;
  double epsilon = 0, delta = 0;  ///< the bounds checked
  int k = 12;
  bool computedNormals = false;   ///< normals recomputed as extraction did (else the input's)
  /// With RecordedVerifyOptions::surfaceError; the input's normals are those checked.
  std::optional<SurfaceError> surface;
};

/// Throws OptionError for bad epsilon/delta/k or surface options and when neither the options nor the hybrid (named
/// `hybridName` in messages) give the tolerances; BadInput as verifyExtraction does.
RecordedVerifyResult verifyAsRecorded(const HybridModel& input, const HybridModel& hybrid, const std::string& hybridName,
                                      const RecordedVerifyOptions& options = {});

}  // namespace linesurf
