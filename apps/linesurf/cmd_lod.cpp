// linesurf lod build MODEL -o MODEL.lod: the level-of-detail hierarchy of a point or hybrid model
// (include/linesurf/lod/lod.h), prepared as `linesurf render` prepares it, so that `linesurf
// render MODEL.lod --budget N` draws at most N splats a view and, with a budget at least the
// model's size, today's picture of the model.
#include <fmt/format.h>

#include <filesystem>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/io/model_io.h"
#include "linesurf/io/model_stream.h"
#include "linesurf/lod/lod.h"
#include "linesurf/pipeline/render_job.h"
#include "drawable_model.h"
#include "ooc_cli.h"
#include "options_bind.h"

namespace linesurf::cli {
namespace {

struct LodArgs {
  std::string model, output, workDir;
  lod::BuildOptions build;
  PrepareOptions prepare;
  bool outOfCore = false;
};

// The model's size in memory as the in-memory build holds it (model, keys, the file's bytes):
// about 260 bytes a primitive; 0 when the header cannot tell (not a binary PLY).
double inMemoryLodEstimate(const std::string& path) {
  try {
    ModelChunkReader r(path);
    return 260.0 * double(r.points() + r.segments());
  } catch (const Error&) {
    return 0;
  }
}

// What either build made: the line both print.
std::string hierarchyLine(const lod::BuildReport& rep) {
  return fmt::format("hierarchy {:016x}: {} nodes ({} leaves), depth {}, {} representatives in the inner nodes ({:.1f}% "
                     "of the model), {:.1f} MB{}",
                     rep.hierarchyId, rep.nodes, rep.leaves, rep.depth, rep.representatives,
                     100.0 * double(rep.representatives) / double(rep.primitives), double(rep.bytes) / 1e6,
                     rep.chunks ? fmt::format(", {} subtrees", rep.chunks) : std::string());
}

void runStreaming(const LodArgs& a, const std::string& why) {
  Timer total;
  lod::StreamBuildOptions so;
  so.memoryBytes = outOfCoreBudgetBytes();
  so.workDir = a.workDir;
  so.progress = withTimeLeft(progressBar());
  say(fmt::format("{}: building out of core ({}), in subtrees sized for --max-mb {:g}", a.model, why,
                  so.memoryBytes / (1024.0 * 1024.0)));
  const lod::BuildReport rep = lod::buildLodStreaming(a.model, a.output, a.build, so);
  endProgress();
  const double seconds = total.seconds();
  say(fmt::format("{}: {} primitives; {} threads", a.model, rep.primitives, currentThreadCount()));
  say(hierarchyLine(rep));
  say(fmt::format("time (s): total {:.3f} ({:.2f} M primitives/s)", seconds,
                  double(rep.primitives) / std::max(seconds, 1e-9) / 1e6));
  say("wrote " + a.output);
}

void run(LodArgs& a) {
  Timer total;
  lod::validate(a.build);
  validate(a.prepare);
  checkFiles({a.model}, {{"--output", a.output, {".lod"}}}, /*inputsHeldWhole=*/false);
  if (!a.workDir.empty()) {  // before the work, not when its first file is written
    std::error_code ec;
    if (!std::filesystem::is_directory(a.workDir, ec))
      throwBadParameter("--work-dir", "'" + a.workDir + "' is not an existing folder");
  }
  if (a.outOfCore || !a.workDir.empty()) {
    runStreaming(a, a.outOfCore ? "--out-of-core" : "--work-dir");
    return;
  }
  if (const double need = inMemoryLodEstimate(a.model); need > memoryBudgetBytes()) {
    runStreaming(a, fmt::format("in memory it needs about {:.0f} MiB, more than --max-mb {:g}", need / (1024.0 * 1024.0),
                                globalOptions().maxMegabytes));
    return;
  }
  checkFiles({a.model}, {}, /*inputsHeldWhole=*/true);
  // The model as `linesurf render` draws it: read, moved into its normalising frame, prepared.
  HybridModel model = fileHoldsMesh(a.model) ? meshVerticesAsPoints(readMesh(a.model)) : readModel(a.model);
  if (model.empty()) throw Error(Error::Kind::BadInput, a.model, "", "the model holds no points and no segments");
  if (model.texture) throw Error(Error::Kind::BadInput, a.model, "", "textured models have no level-of-detail form yet");
  const double readSeconds = total.seconds();
  // The leaves hold the model (64 bytes a point, 100 a segment); inner nodes add at most as much
  // again, under half of it in practice.
  checkSize("--output", 1.5 * (64.0 * double(model.points.size()) + 100.0 * double(model.segments.size())),
            "the hierarchy");
  const ModelFrame frame = normalizingFrame(model.bounds());
  toFrame(model, frame);
  a.prepare.progress = progressBar();
  prepareForRendering(model, a.prepare);
  endProgress();
  Timer build;
  lod::BuildReport rep;
  std::string bytes;
  try {
    bytes = lod::buildLod(model, frame, a.build, &rep);
  } catch (const Error& e) {  // the library's model has no path: name the file
    if (!e.path().empty()) throw;
    throw Error(e.kind(), a.model, e.where(), e.reason());
  }
  const double buildSeconds = build.seconds();
  writeFileAtomically(a.output, bytes);
  say(fmt::format("{}: {} points, {} segments; {} threads", a.model, model.points.size(), model.segments.size(),
                  currentThreadCount()));
  say(hierarchyLine(rep));
  say(fmt::format("time (s): read {:.3f}, build {:.3f} ({:.2f} M primitives/s), total {:.3f}", readSeconds, buildSeconds,
                  double(rep.primitives) / std::max(buildSeconds, 1e-9) / 1e6, total.seconds()));
  say("wrote " + a.output);
}

RegisterCommand reg(42, [](CLI::App& app) {
  auto a = std::make_shared<LodArgs>();
  CLI::App* lodCmd = app.add_subcommand("lod", "Level-of-detail hierarchies of point and hybrid models");
  lodCmd->require_subcommand(1);
  CLI::App* sub = lodCmd->add_subcommand(
      "build", "Build an octree of the model whose inner nodes hold merged splats (render it with --budget)");
  sub->add_option("MODEL", a->model, "Point cloud or hybrid model (.ply, .obj, .xyz)")->type_name("FILE")->required();
  sub->add_option("-o,--output", a->output, "Output hierarchy (.lod)")->type_name("FILE")->required();
  bind(sub, "leafSize", a->build.leafSize, "A node of at most this many primitives is a leaf, [16, 1048576]");
  bind(sub, "grid", a->build.grid, "Inner nodes keep at most one merged splat per cell of a GRID^3 grid, [2, 256]");
  bind(sub, "k", a->prepare.k, "Neighbours for normals/radii of raw scans (§6.1), [3, 256]");
  sub->add_flag("--out-of-core", a->outOfCore,
                "Build from the file in bounded memory (--max-mb; chosen by itself when the model would not fit). "
                "Binary PLY whose points carry normals and radii");
  sub->add_option("--work-dir", a->workDir,
                  "Folder for the out-of-core build's working files (about the model's size; default: the output's)")->type_name("DIR");
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
