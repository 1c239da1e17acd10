// linesurf normals IN -o OUT [--k 12] [--recompute] [--curvature]: the geometry pipeline of
// thesis §6.1 (neighbours, oriented normals, local Delaunay neighbours, curvature, spacing).
#include <fmt/format.h>

#include "command.h"
#include "options_bind.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

namespace linesurf::cli {
namespace {

struct NormalsArgs {
  std::string in, out;
  GeometryOptions geometry = [] {
    GeometryOptions g;
    g.delaunayNeighbours = g.curvature = false;  // --curvature turns both on
    return g;
  }();
};

void run(const NormalsArgs& args) {
  Timer total;
  validate(args.geometry);  // before reading the cloud
  checkFiles({args.in}, {{"--output", args.out, {".ply", ".xyz"}}});
  HybridModel model = readModel(args.in);
  const double readTime = total.seconds();
  if (model.points.empty()) throw Error(Error::Kind::BadInput, args.in, "", "holds no points");
  checkGeometry(args.in, model.points.size(), args.geometry.k);
  checkModelOutput("--output", args.out, model.points.size(), model.segments.size());
  GeometryOptions o = args.geometry;
  o.delaunayNeighbours = o.curvature;
  o.progress = progressBar();
  const bool hadNormals = model.attributes.normals;
  PointGeometry g = computePointGeometry(model, o);
  endProgress();
  applyGeometry(model, g);
  if (o.curvature) addCurvatureProperties(model, g);
  Timer writeTimer;
  writeModel(args.out, model);
  const double writeTime = writeTimer.seconds();

  const size_t n = g.size();
  say(fmt::format("{}: {} points, k = {}, {} threads", args.in, n, g.k, currentThreadCount()));
  say(fmt::format("normals        {}", hadNormals && !o.recomputeNormals ? "kept from the file" : "estimated by PCA"));
  if (g.orientationComponents > 0)
    say(fmt::format("orientation    {} component(s), {} normals flipped", g.orientationComponents, g.orientationFlips));
  say(fmt::format("average spacing {:.6g}", g.averageSpacing));
  say(fmt::format("degenerate     {} duplicate, {} with < 3 distinct neighbours, {} collinear/flat, {} isolated{}",
                  g.countFlag(kPointDuplicate), g.countFlag(kPointFewNeighbours),
                  g.countFlag(kPointFlatNeighbourhood), g.countFlag(kPointIsolated),
                  o.curvature ? fmt::format(", {} without a Delaunay star", g.countFlag(kPointNoStar)) : ""));
  const auto& t = g.times;
  say(fmt::format("time (s)       read {:.3f}  neighbours {:.3f}  normals {:.3f}  orientation {:.3f}{}  spacing {:.3f}  write {:.3f}  total {:.3f}",
                  readTime, t.neighbours, t.normals, t.orientation,
                  o.curvature ? fmt::format("  delaunay {:.3f}  curvature {:.3f}", t.delaunay, t.curvature) : "",
                  t.spacing, writeTime, total.seconds()));
  say("wrote " + args.out);
}

RegisterCommand reg(20, [](CLI::App& app) {
  auto args = std::make_shared<NormalsArgs>();
  CLI::App* sub = app.add_subcommand("normals", "Estimate oriented normals (and curvature) of a point cloud (thesis §6.1)");
  sub->add_option("IN", args->in, "Input point cloud (.ply, .xyz)")->required();
  sub->add_option("-o,--output", args->out, "Output .ply with normals (and curvature properties)")->required();
  GeometryOptions& o = args->geometry;
  // --curvature also writes vertex properties k_min, k_max, dmin_x, dmin_y, dmin_z
  bindOptions(sub, o, {"k", "recomputeNormals", "orientNormals", "orientationPenalty", "curvature", "curvatureFit"});
  sub->callback([args] { run(*args); });
});

}  // namespace
}  // namespace linesurf::cli
