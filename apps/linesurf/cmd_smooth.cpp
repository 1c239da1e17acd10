// linesurf smooth IN -o OUT: every point projected onto the MLS surface of the cloud (thesis §9.1;
// surface/mls.h), with the surface's normal and, with --curvature, its principal curvatures.
#include <fmt/format.h>

#include <algorithm>

#include "command.h"
#include "options_bind.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/surface/mls.h"

namespace linesurf::cli {
namespace {

struct SmoothArgs {
  std::string in, out;
  GeometryOptions geometry = [] {
    GeometryOptions g;
    g.delaunayNeighbours = g.curvature = false;
    return g;
  }();
  MlsOptions mls;
  bool curvature = false;
};

void run(const SmoothArgs& a) {
  Timer total;
  validate(a.geometry);
  validate(a.mls);
  checkFiles({a.in}, {{"--output", a.out, {".ply", ".xyz", ".las"}}});
  HybridModel model = readModel(a.in);
  if (model.points.empty()) throw Error(Error::Kind::BadInput, a.in, "", "holds no points");
  if (!model.segments.empty()) throw Error(Error::Kind::BadInput, a.in, "", "is a hybrid model: smooth projects the points of a cloud");
  checkGeometry(a.in, model.points.size(), a.geometry.k);
  checkModelOutput("--output", a.out, model.points.size(), 0);
  GeometryOptions o = a.geometry;
  o.progress = progressBar();
  if (!model.attributes.normals || o.recomputeNormals) applyGeometry(model, computePointGeometry(model, o));
  endProgress();
  const double geometryTime = total.seconds();
  const MlsSurface surface(model, a.mls);
  const size_t n = model.points.size();
  std::vector<MlsProjection> moved(n);
  std::vector<MlsCurvature> bend(a.curvature ? n : 0);
  // In 64 pieces, each parallel inside, so that the bar moves.
  const ProgressFn bar = progressBar();
  const size_t step = (n + 63) / 64;
  for (size_t first = 0; first < n; first += step) {
    parallelForRange(first, std::min(n, first + step), [&](size_t b, size_t e) {
      for (size_t i = b; i < e; ++i) {
        moved[i] = surface.project(model.points[i].position.cast<double>());
        if (a.curvature) bend[i] = surface.curvature(moved[i].point);
      }
    }, 256);
    reportProgress(bar, "projection", double(std::min(n, first + step)) / double(n));
  }
  endProgress();
  size_t converged = 0;
  double shift = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!moved[i].converged) continue;  // a failed projection keeps the point as it was
    ++converged;
    Point& p = model.points[i];
    shift = std::max(shift, (moved[i].point - p.position.cast<double>()).norm());
    p.position = moved[i].point.cast<float>();
    p.normal = moved[i].normal.cast<float>();
  }
  if (a.curvature) {
    auto& props = model.pointProperties;
    for (const char* name : {"k_min", "k_max", "dmin_x", "dmin_y", "dmin_z"}) props[name].assign(n, 0.0f);
    for (size_t i = 0; i < n; ++i) {
      if (!bend[i].valid) continue;
      props["k_min"][i] = float(bend[i].kMin), props["k_max"][i] = float(bend[i].kMax);
      props["dmin_x"][i] = float(bend[i].dirMin.x()), props["dmin_y"][i] = float(bend[i].dirMin.y());
      props["dmin_z"][i] = float(bend[i].dirMin.z());
    }
  }
  writeModel(a.out, model);
  say(fmt::format("{}: {} points, support {} x spacing{}, {} threads", a.in, n, a.mls.supportScale,
                  a.mls.robust ? ", robust (RIMLS)" : "", currentThreadCount()));
  say(fmt::format("projected      {} converged, {} kept where they were; largest move {:.6g}", converged, n - converged, shift));
  say(fmt::format("time (s)       geometry {:.3f}  projection {:.3f}  total {:.3f}", geometryTime, total.seconds() - geometryTime,
                  total.seconds()));
  say("wrote " + a.out);
}

RegisterCommand reg(24, [](CLI::App& app) {
  auto a = std::make_shared<SmoothArgs>();
  CLI::App* sub = app.add_subcommand("smooth", "Project every point onto the cloud's MLS surface (thesis §9.1)");
  sub->add_option("IN", a->in, "Input point cloud (.ply, .xyz; normals computed when it has none)")->type_name("FILE")->required();
  sub->add_option("-o,--output", a->out, "The projected cloud (.ply, .xyz, .las)")->type_name("FILE")->required();
  bindOptions(sub, a->geometry, {"k", "recomputeNormals", "orient", "viewpoint"});
  sub->add_option("--support", a->mls.supportScale, "MLS support radius, in spacings, [1.5, 10]")->capture_default_str()->type_name("FLOAT");
  sub->add_flag("--robust", a->mls.robust, "RIMLS: refit with robust weights, so that creases stay sharp (beyond the thesis)");
  sub->add_flag("--curvature", a->curvature, "Also write the surface's principal curvatures (k_min k_max dmin_x dmin_y dmin_z)");
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
