// linesurf extract curvature-lines IN -o OUT [--family min|max|both] [--separation S] [--provenance]:
// lines of curvature traced on the MLS surface and straightened into chains of segments (thesis
// §9.2). Options bind straight to GeometryOptions and CurvatureLineOptions.
#include <fmt/format.h>

#include <cmath>

#include "command.h"
#include "extract_common.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/curvature_lines.h"
#include "ooc_cli.h"
#include "linesurf/ooc/ooc_extract.h"
#include "options_bind.h"

namespace linesurf::cli {
namespace {

struct CurvatureLineArgs {
  std::string input, output;
  GeometryOptions geometry = [] {
    GeometryOptions g;
    // The lines need normals, the local Delaunay stars (the cross field's graph) and spacing; the
    // MLS surface gives the curvature, the cover radius the kept points' radii.
    g.curvature = false;
    return g;
  }();
  CurvatureLineOptions extract;
  bool ascii = false;
  OutOfCoreFlags ooc;  // picked by itself when the input would not fit --max-mb
};

void runOutOfCore(CurvatureLineArgs& a, const std::string& why) {
  Timer total;
  if (a.ascii) throwBadParameter("--ascii", "the out-of-core path writes binary PLY");
  MpiRun mpi;
  if (mpi.rank != 0) globalOptions().quiet = true;  // rank 0 speaks for the job
  const ooc::OocNormalsOptions o = outOfCoreOptions(a.geometry, a.input, a.output, a.ooc, mpi, why, true);
  ooc::OocCurvatureLineReport r;
  mpi.guard([&] { r = ooc::extractCurvatureLinesOutOfCore(a.input, a.output, o, a.extract); });
  endProgress();
  if (mpi.rank != 0) return;
  const ooc::OocNormalsReport& g = r.geometry;
  sayTiles(g, a.input);
  say(fmt::format("tolerances   epsilon {:.6g}  delta {:.6g}", r.epsilon, a.extract.delta));
  say(fmt::format("lines        {} chains ({} closed), mean length {:.2f} spacings; {} shorter than 2 d_sep, {} dropped; "
                  "lines end at tile borders",
                  r.lines, r.closedLines, r.lines && g.averageSpacing > 0 ? r.lineLength / double(r.lines) / g.averageSpacing : 0.0,
                  r.shortLines, r.prunedLines));
  say(fmt::format("output       {} points + {} segments -> {}", r.keptPoints, r.segments, a.output));
  say(fmt::format("replaced     {} points ({:.2f}%)", r.replacedPoints,
                  g.points ? 100.0 * double(r.replacedPoints) / double(g.points) : 0.0));
  CurvatureLineStats counts;  // the §7.2.2 measure over the tiles' counts
  counts.inputPoints = g.points, counts.keptPoints = r.keptPoints, counts.segments = r.segments;
  say(fmt::format("reduction    {:.2f}% (§7.2.2: 6 floats per point, 9 per segment)", 100.0 * counts.dataReduction()));
  say(fmt::format("times        bbox {:.3f} s, partition {:.3f} s, normals tiles {:.3f} s, orientation {:.3f} s, "
                  "curvature-lines tiles {:.3f} s, write {:.3f} s, total {:.3f} s",
                  g.tBbox, g.tPartition, g.tTiles, g.tOrient, r.tExtract, r.tWrite, total.seconds()));
}

void run(CurvatureLineArgs& a) {
  Timer total;
  CurvatureLineOptions& o = a.extract;
  validate(o);  // before the (long) geometry stage
  validate(a.geometry);
  checkFiles({a.input}, {{"--output", a.output, {".ply"}}}, false);
  if (const std::string why = a.ooc.requested(); !why.empty()) {
    runOutOfCore(a, why);
    return;
  }
  {
    // The MLS surface (its own neighbour search), the field and the samples: about twice what
    // the normals hold.
    const double need = 2.0 * inMemoryEstimate(a.input, a.geometry.k);
    if (need > memoryBudgetBytes()) {
      runOutOfCore(a, fmt::format("in memory it needs about {:.0f} MiB, more than --max-mb {:g}", need / (1024.0 * 1024.0),
                                  globalOptions().maxMegabytes));
      return;
    }
  }
  CloudWithGeometry in = readCloudWithGeometry(a.input, a.geometry);
  const PointGeometry& geo = in.geometry;
  o.progress = progressBar();
  CurvatureLineStats st;
  HybridModel out = extractCurvatureLines(in.cloud, geo, o, &st);
  out.comments.push_back(fmt::format("curvature-lines: normals={}", in.normalsFromFile ? "file" : "computed"));
  Timer t;
  writeExtracted(a.output, out, a.ascii);
  const double writeSeconds = t.seconds();
  endProgress();

  say(fmt::format("tolerances   epsilon {:.6g}{}  delta {:.6g} ({:.2f} deg)", st.epsilon,
                  o.epsilon > 0 ? std::string() : fmt::format(" ({} x average spacing {:.6g})", o.epsilonRelative, geo.averageSpacing),
                  st.delta, std::acos(std::max(-1.0, 1.0 - st.delta)) * 180.0 / 3.14159265358979));
  say(fmt::format("lines        {} chains ({} closed), mean length {:.2f} spacings, mean d_sep {:.2f} spacings; "
                  "{} shorter than 2 d_sep, {} dropped",
                  st.lines, st.closedLines, st.meanChainLength() / st.averageSpacing, st.meanSeparation / st.averageSpacing,
                  st.shortLines, st.prunedLines));
  say(fmt::format("ends         {} at another line, {} at singularities, {} at boundaries, {} closed; {} steps, "
                  "{} projection failures",
                  st.stopSeparation, st.stopSingularity, st.stopBoundary, st.stopClosed, st.steps, st.projectionFailures));
  say(fmt::format("output       {} points + {} segments -> {}", st.keptPoints, st.segments, a.output));
  say(fmt::format("replaced     {} points ({:.2f}%), {:.2f} points per segment, {:.2f} segments per chain",
                  st.replacedPoints, st.inputPoints ? 100.0 * double(st.replacedPoints) / double(st.inputPoints) : 0.0,
                  st.segments ? double(st.replacedPoints) / double(st.segments) : 0.0,
                  st.lines ? double(st.segments) / double(st.lines) : 0.0));
  say(fmt::format("reduction    {:.2f}% (§7.2.2: 6 floats per point, 9 per segment); {:.2f}% with shared chain endpoints",
                  100.0 * st.dataReduction(), 100.0 * st.chainDataReduction()));
  say(fmt::format("times        read {:.3f} s, geometry {:.3f} s, field {:.3f} s, trace {:.3f} s, straighten {:.3f} s, "
                  "cover {:.3f} s, write {:.3f} s, total {:.3f} s",
                  in.readSeconds, in.geometrySeconds, st.fieldSeconds, st.traceSeconds, st.straightenSeconds,
                  st.coverSeconds, writeSeconds, total.seconds()));
}

RegisterCommand reg(34, [](CLI::App& app) {
  auto a = std::make_shared<CurvatureLineArgs>();
  CLI::App* sub = extractCommand(app)->add_subcommand(
      "curvature-lines", "Lines of curvature traced on the MLS surface, as chains of segments (thesis §9.2)");
  sub->add_option("IN", a->input, "Input point cloud (.ply, .xyz; a mesh gives its vertices)")->type_name("FILE")->required();
  sub->add_option("-o,--output", a->output, "Output hybrid model (.ply)")->type_name("FILE")->required();
  const TableBinder b = bindOptions(sub, a->extract);
  b.option("epsilon")->excludes(b.option("epsilonRelative"));
  bindGeometryOptions(sub, a->geometry);
  sub->add_flag("--ascii", a->ascii, "Write ASCII PLY");
  bindOutOfCoreFlags(sub, a->ooc);
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
