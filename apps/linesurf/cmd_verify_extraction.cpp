// linesurf verify-extraction INPUT HYBRID [--epsilon X] [--delta D]: proves the (epsilon, delta)
// bound of an extracted hybrid model (thesis §3.1.2.1). Exit 0 when it holds, 3 when violated.
#include <fmt/format.h>

#include <cstdio>
#include <stdexcept>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/verify.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

namespace linesurf::cli {
namespace {

struct VerifyArgs {
  std::string input, hybrid;
  double epsilon = -1, delta = -1;
  int k = 0;
};

void run(const VerifyArgs& a) {
  Timer t;
  HybridModel input = readModel(a.input);
  HybridModel hybrid = readModel(a.hybrid);
  // Tolerances and the normals' origin as extract eps-delta recorded them.
  double epsilon = -1, delta = -1;
  int k = 12;
  bool computedNormals = !input.attributes.normals;
  for (const std::string& c : hybrid.comments) {
    double e, d;
    int kk;
    if (std::sscanf(c.c_str(), "eps-delta: epsilon=%lf delta=%lf k=%d", &e, &d, &kk) == 3) {
      epsilon = e, delta = d;
      if (kk >= 3) k = kk;
    }
    if (c == "eps-delta: normals=computed") computedNormals = true;
  }
  if (a.epsilon >= 0) epsilon = a.epsilon;
  if (a.delta >= 0) delta = a.delta;
  if (a.k > 0) k = a.k;
  if (epsilon < 0 || delta < 0)
    throwBadParameter("epsilon", fmt::format("{} records no tolerances (no 'eps-delta: epsilon=...' comment); "
                                             "pass --epsilon and --delta", a.hybrid));
  GeometryOptions go;
  go.k = k;
  go.recomputeNormals = computedNormals;
  go.delaunayNeighbours = false;
  go.curvature = false;
  go.progress = progressBar();
  PointGeometry geo = computePointGeometry(input, go);
  VerifyReport r = verifyExtraction(input, &geo, hybrid, epsilon, delta);
  endProgress();
  say(fmt::format("checked      {} segments replacing {} points, {} kept points, of {} input points", r.segments,
                  r.replacedPoints, r.keptPoints, input.points.size()));
  say(fmt::format("distance     max {:.6g} of epsilon {:.6g} ({:.1f}%)", r.maxDistance, epsilon,
                  epsilon > 0 ? 100 * r.maxDistance / epsilon : 0.0));
  say(fmt::format("normal       max 1-n.n {:.6g} of delta {:.6g}", r.maxNormalDeviation, delta));
  say(fmt::format("normals      {} (k = {}), {:.3f} s", computedNormals ? "computed as extract did" : "from the input file",
                  k, t.seconds()));
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
  sub->add_option("INPUT", args->input, "The point cloud the model was extracted from")->required();
  sub->add_option("HYBRID", args->hybrid, "The hybrid model written by `extract eps-delta --provenance`")->required();
  sub->add_option("--epsilon", args->epsilon, "Distance tolerance (default: as recorded in HYBRID)")
      ->check(CLI::NonNegativeNumber);
  sub->add_option("--delta", args->delta, "Normal tolerance (default: as recorded in HYBRID)")->check(CLI::Range(0.0, 2.0));
  sub->add_option("-k,--neighbours", args->k, "Neighbours for computed normals (default: as recorded)")
      ->check(CLI::Range(3, 256));
  sub->callback([args] { run(*args); });
});

}  // namespace
}  // namespace linesurf::cli
