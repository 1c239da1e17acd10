// linesurf verify-extraction INPUT HYBRID [--epsilon X] [--delta D]: proves the (epsilon, delta)
// bound of an extracted hybrid model (thesis §3.1.2.1). Exit 0 when it holds, 3 when violated.
// Also prints the surface error of the hybrid against the input (surface/surface_error.h; beyond
// the thesis), unless --no-surface-error.
#include <fmt/format.h>

#include <cstdio>
#include <stdexcept>

#include "command.h"
#include "linesurf/core/options.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/pipeline/verify_job.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "options_bind.h"

namespace linesurf::cli {
namespace {

struct VerifyArgs {
  std::string input, hybrid;
  RecordedVerifyOptions verify;
};

void run(VerifyArgs& a) {
  Timer t;
  if (a.verify.surfaceError) validate(a.verify.surface);  // before any file is read
  checkFiles({a.input, a.hybrid}, {});  // reading both fits the budget
  HybridModel input = readModel(a.input);
  HybridModel hybrid = readModel(a.hybrid);
  a.verify.progress = progressBar();
  const RecordedVerifyResult rv = blamingFiles({{"cloud", a.input}, {"model", a.hybrid}},
                                               [&] { return verifyAsRecorded(input, hybrid, a.hybrid, a.verify); });
  const VerifyReport& r = rv.report;
  const double epsilon = rv.epsilon, delta = rv.delta;
  const int k = rv.k;
  const bool computedNormals = rv.computedNormals;
  endProgress();
  say(fmt::format("checked      {} segments replacing {} points, {} kept points, of {} input points", r.segments,
                  r.replacedPoints, r.keptPoints, input.points.size()));
  say(fmt::format("distance     max {:.6g} of epsilon {:.6g} ({:.1f}%)", r.maxDistance, epsilon,
                  epsilon > 0 ? 100 * r.maxDistance / epsilon : 0.0));
  say(fmt::format("normal       max 1-n.n {:.6g} of delta {:.6g}", r.maxNormalDeviation, delta));
  say(fmt::format("normals      {} (k = {}), {:.3f} s", computedNormals ? "computed as extract did" : "from the input file",
                  k, t.seconds()));
  if (rv.surface) {
    const SurfaceError& s = *rv.surface;
    const SurfaceErrorFigures& f = s.both;
    say(fmt::format("surface      error RMS {:.4g}, 99% {:.4g}, max {:.4g} = {:.3g} / {:.3g} / {:.3g} x eps_ref {:.4g} "
                    "(0.05 x spacing) = {:.3g} / {:.3g} / {:.3g} x the diagonal; {} samples both ways, {} projections "
                    "failed (onto the input's surface {}, the hybrid's {})",
                    f.rms, f.p99, f.max, f.rms / s.epsilonRef, f.p99 / s.epsilonRef, f.max / s.epsilonRef, s.epsilonRef,
                    f.rms / s.diagonal, f.p99 / s.diagonal, f.max / s.diagonal, f.samples, s.failures(),
                    f.failedReference, f.failedModel));
  }
  for (const std::string& m : r.messages) std::fprintf(stderr, "%s: %s\n", a.hybrid.c_str(), m.c_str());
  if (!r.ok())
    throw std::runtime_error(fmt::format(
        "{}: (epsilon, delta) bound violated: {} distance, {} normal, {} segment, {} index violations; {} points "
        "replaced twice, {} missing, {} unmatched",
        a.hybrid, r.distanceViolations, r.normalViolations, r.badSegments, r.badIndices, r.replacedTwice, r.missing,
        r.unmatchedPoints));
  say("ok           every replaced point within (epsilon, delta); every input point kept or replaced exactly once");
}

RegisterCommand reg(35, [](CLI::App& app) {
  auto args = std::make_shared<VerifyArgs>();
  CLI::App* sub = app.add_subcommand(
      "verify-extraction", "Prove the (epsilon, delta) bound of an extracted hybrid model (thesis §3.1); needs --provenance");
  sub->add_option("INPUT", args->input, "The point cloud the model was extracted from")->type_name("FILE")->required();
  sub->add_option("HYBRID", args->hybrid, "The hybrid model written by `extract eps-delta --provenance`")->type_name("FILE")->required();
  auto& v = args->verify;
  sub->add_option_function<double>("--epsilon", [&v](double e) { requireRange("epsilon", e, 0, 1e30), v.epsilon = e; },
                                   "Distance tolerance, >= 0 (default: as recorded in HYBRID)");
  sub->add_option_function<double>("--delta", [&v](double d) { requireRange("delta", d, 0, 2), v.delta = d; },
                                   "Normal tolerance in [0, 2] (default: as recorded in HYBRID)");
  sub->add_option_function<int>("-k,--k,--neighbours", [&v](int k) { v.k = k; },
                                "Neighbours for computed normals, [3, 256] (default: as recorded)");
  sub->add_flag("--surface-error,!--no-surface-error", v.surfaceError,
                "Measure the hybrid's MLS surface against the input's, sampled both ways (default on)");
  bindOptions(sub, v.surface);
  sub->callback([args] { run(*args); });
});

}  // namespace
}  // namespace linesurf::cli
