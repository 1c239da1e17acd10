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
#include "linesurf/ooc/ooc_normals.h"
#include "ooc_cli.h"

#include <filesystem>

namespace linesurf::cli {
namespace {

struct NormalsArgs {
  std::string in, out;
  GeometryOptions geometry = [] {
    GeometryOptions g;
    g.delaunayNeighbours = g.curvature = false;  // --curvature turns both on
    return g;
  }();
  OutOfCoreFlags ooc;  // picked by itself when the input would not fit --max-mb
};

void runOutOfCore(const NormalsArgs& args, const std::string& why) {
  Timer total;
  MpiRun mpi;
  if (mpi.rank != 0) globalOptions().quiet = true;  // rank 0 speaks for the job
  std::string ext = std::filesystem::path(args.out).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext != ".ply") throwBadParameter("--output", "the out-of-core path writes .ply");
  const ooc::OocNormalsOptions o = outOfCoreOptions(args.geometry, args.in, args.out, args.ooc, mpi, why, false);
  ooc::OocNormalsReport r;
  mpi.guard([&] { r = ooc::computeNormalsOutOfCore(args.in, args.out, o); });
  endProgress();
  if (mpi.rank != 0) return;
  if (r.folderCleared) say("tile folder held another input's or other arguments' tiles: not reused, rebuilt");
  say(fmt::format("{}: {} points, k = {}, {} threads, {} tiles (largest {} points with halo){}", args.in, r.points,
                  args.geometry.k, currentThreadCount(), r.tiles, r.tilePointsMax,
                  r.tilesReused ? fmt::format(", {} reused from an earlier run", r.tilesReused) : ""));
  if (r.tilesRecomputed)
    say(fmt::format("tile folder    {} tile(s) whose working files failed their proof (another tile's or input's, damaged, truncated): recomputed",
                    r.tilesRecomputed));
  say(fmt::format("halo           {} tile(s) widened, {} point(s) whose neighbours reach past the widest halo", r.haloWidenings,
                  r.inexactPoints));
  if (r.orientationComponents > 0)
    say(fmt::format("orientation    {} component(s), {} tile component(s) flipped, {} shared point(s) disagreeing",
                    r.orientationComponents, r.tileFlips, r.disagreeingVotes));
  say(fmt::format("average spacing {:.6g}", r.averageSpacing));
  say(fmt::format("degenerate     {} duplicate, {} with < 3 distinct neighbours, {} collinear/flat, {} isolated", r.duplicate,
                  r.fewNeighbours, r.flat, r.isolated));
  say(fmt::format("time (s)       bbox {:.3f}  partition {:.3f}  tiles {:.3f}  orientation {:.3f}  write {:.3f}  total {:.3f}",
                  r.tBbox, r.tPartition, r.tTiles, r.tOrient, r.tWrite, total.seconds()));
  say("wrote " + args.out);
}

void run(const NormalsArgs& args) {
  Timer total;
  validate(args.geometry);  // before reading the cloud
  // The path is chosen below by its own estimate (in memory or out of core).
  checkFiles({args.in}, {{"--output", args.out, {".ply", ".xyz", ".las"}}}, /*inputsHeldWhole=*/false);
  if (const std::string why = args.ooc.requested(); !why.empty()) {
    runOutOfCore(args, why);
    return;
  }
  {
    // Curvature adds the Delaunay lists and its results (~140 bytes a point).
    const double need = inMemoryEstimate(args.in, args.geometry.k) * (args.geometry.curvature ? 1.4 : 1.0);
    if (need > memoryBudgetBytes()) {
      runOutOfCore(args, fmt::format("in memory it needs about {:.0f} MiB, more than --max-mb {:g}", need / (1024.0 * 1024.0),
                                     globalOptions().maxMegabytes));
      return;
    }
  }
  HybridModel model = readModel(args.in);
  const double readTime = total.seconds();
  if (model.points.empty()) throw Error(Error::Kind::BadInput, args.in, "", "holds no points");
  checkGeometry(args.in, model.points.size(), args.geometry.k);
  checkModelOutput("--output", args.out, model.points.size(), model.segments.size());
  // Refused before the work, in the words `convert` uses, rather than when the file is written.
  std::string outExt = std::filesystem::path(args.out).extension().string();
  for (char& c : outExt) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (outExt == ".las" && !model.segments.empty())
    throwBadParameter(args.out, fmt::format("a LAS file holds points only, and the model has {} line segments (write .ply)",
                                            model.segments.size()));
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
  sub->add_option("IN", args->in, "Input point cloud (.ply, .xyz)")->type_name("FILE")->required();
  sub->add_option("-o,--output", args->out, "Output .ply, .xyz or .las with normals (and curvature properties)")->type_name("FILE")->required();
  GeometryOptions& o = args->geometry;
  // --curvature also writes vertex properties k_min, k_max, dmin_x, dmin_y, dmin_z
  bindOptions(sub, o, {"k", "recomputeNormals", "orientNormals", "orientationPenalty", "orient", "viewpoint", "curvature", "curvatureFit"});
  bindOutOfCoreFlags(sub, args->ooc);
  sub->callback([args] { run(*args); });
});

}  // namespace
}  // namespace linesurf::cli
