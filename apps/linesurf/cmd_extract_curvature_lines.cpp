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
#include "options_bind.h"

namespace linesurf::cli {
namespace {

struct CurvatureLineArgs {
  std::string input, output;
  GeometryOptions geometry = [] {
    GeometryOptions g;
    // The lines need normals, neighbours and spacing; the MLS surface gives the curvature and
    // the cover radius the kept points' radii.
    g.curvature = false;
    g.delaunayNeighbours = false;
    return g;
  }();
  CurvatureLineOptions extract;
  bool ascii = false;
};

void run(CurvatureLineArgs& a) {
  Timer total;
  CurvatureLineOptions& o = a.extract;
  validate(o);  // before the (long) geometry stage
  validate(a.geometry);
  checkFiles({a.input}, {{"--output", a.output, {".ply"}}}, false);
  {
    // The MLS surface, the field and the samples: about three times what the normals hold.
    const double need = 3.0 * inMemoryEstimate(a.input, a.geometry.k);
    if (need > memoryBudgetBytes())
      throwBadParameter("--max-mb", fmt::format("extract curvature-lines runs in memory and needs about {:.0f} MiB for {}; "
                                                "give --max-mb {:.0f} or more",
                                                need / (1024.0 * 1024.0), a.input, std::ceil(need / (1024.0 * 1024.0))));
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
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
