// linesurf clean IN -o OUT: a scanned cloud without its outliers (points off the surface,
// isolated points, floaters; beyond the thesis, see geometry/outliers.h), reported in counts.
#include <fmt/format.h>

#include "command.h"
#include "options_bind.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/geometry/outliers.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

namespace linesurf::cli {
namespace {

struct CleanArgs {
  std::string in, out, outliersOut;
  GeometryOptions geometry = [] {
    GeometryOptions g;
    g.delaunayNeighbours = g.curvature = g.coverRadius = false;
    g.orientNormals = false;  // the tests read unoriented tangent planes
    g.k = kOutlierNeighbours;
    return g;
  }();
  OutlierOptions outliers;
};

void run(const CleanArgs& a) {
  Timer total;
  validate(a.geometry);
  validate(a.outliers);
  checkFiles({a.in}, {{"--output", a.out, {".ply", ".xyz", ".las"}}, {"--outliers-out", a.outliersOut, {".ply", ".xyz", ".las"}}});
  HybridModel model = readModel(a.in);
  const double readTime = total.seconds();
  if (model.points.empty()) throw Error(Error::Kind::BadInput, a.in, "", "holds no points");
  if (!model.segments.empty())
    throw Error(Error::Kind::BadInput, a.in, "", "is a hybrid model: remove outliers from the cloud, before an extraction");
  checkGeometry(a.in, model.points.size(), a.geometry.k);
  checkModelOutput("--output", a.out, model.points.size(), 0);
  GeometryOptions o = a.geometry;
  o.recomputeNormals = true;  // the tests need the neighbourhoods' own planes
  o.progress = progressBar();
  const PointGeometry g = computePointGeometry(model, o);
  endProgress();
  std::vector<Vec3f> pos(model.points.size());
  for (size_t i = 0; i < pos.size(); ++i) pos[i] = model.points[i].position;
  Timer findTimer;
  const OutlierReport r = findOutliers(g, pos, a.outliers);
  const double findTime = findTimer.seconds();
  writeModel(a.out, withoutOutliers(model, r));
  if (!a.outliersOut.empty()) writeModel(a.outliersOut, withoutOutliers(model, r, /*outliers=*/true));
  const size_t n = model.points.size();
  say(fmt::format("{}: {} points, k = {}, {} threads", a.in, n, g.k, currentThreadCount()));
  say(fmt::format("outliers       {} ({:.3f}%): {} off the surface, {} isolated, {} floaters (a point may be more than one)",
                  r.total, 100.0 * double(r.total) / double(n), r.offSurface, r.isolated, r.floaters));
  say(fmt::format("kept           {} points", n - r.total));
  say(fmt::format("time (s)       read {:.3f}  geometry {:.3f}  outliers {:.3f}  total {:.3f}", readTime,
                  g.times.neighbours + g.times.normals + g.times.spacing, findTime, total.seconds()));
  say("wrote " + a.out + (a.outliersOut.empty() ? "" : " and " + a.outliersOut));
}

RegisterCommand reg(22, [](CLI::App& app) {
  auto a = std::make_shared<CleanArgs>();
  CLI::App* sub = app.add_subcommand("clean", "Remove a scan's outliers: points off the surface, isolated points, floaters");
  sub->add_option("IN", a->in, "Input point cloud (.ply, .xyz, .las)")->type_name("FILE")->required();
  sub->add_option("-o,--output", a->out, "The cloud without its outliers (.ply, .xyz, .las)")->type_name("FILE")->required();
  sub->add_option("--outliers-out", a->outliersOut, "Also write the outliers (.ply, .xyz, .las)")->type_name("FILE");
  bindOptions(sub, a->geometry, {"k"});
  sub->add_option("--off-surface", a->outliers.offSurface,
                  "Off the surface: median distance to the neighbours' tangent planes above this x their median spacing, [0.1, 1e6]")
      ->capture_default_str()->type_name("FLOAT");
  sub->add_option("--isolated", a->outliers.isolated, "Isolated: spacing above this x the neighbours' median spacing, [1, 1e6]")
      ->capture_default_str()->type_name("FLOAT");
  sub->add_option("--sparse", a->outliers.sparse,
                  "Floater: spacing above this x the cloud's median spacing, in a neighbourhood that is no surface, [1, 1e6]")
      ->capture_default_str()->type_name("FLOAT");
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
