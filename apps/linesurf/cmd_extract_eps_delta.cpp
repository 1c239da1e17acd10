// linesurf extract eps-delta IN -o OUT [--epsilon X | --epsilon-relative R] [--delta D] [--provenance]:
// (epsilon, delta) error-bounded line segment extraction, thesis §3.1. Options bind straight to
// GeometryOptions and EpsDeltaOptions.
#include <fmt/format.h>

#include <cmath>

#include "command.h"
#include "extract_common.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/geometry/noise.h"
#include "options_bind.h"
#include "linesurf/ooc/ooc_extract.h"
#include "ooc_cli.h"

#include <filesystem>

namespace linesurf::cli {
namespace {

struct EpsDeltaArgs {
  std::string input, output;
  GeometryOptions geometry = [] {
    GeometryOptions g;
    g.curvature = false;  // §3.1 needs normals, Delaunay neighbours and spacing only
    return g;
  }();
  EpsDeltaOptions extract;
  bool ascii = false;
  OutOfCoreFlags ooc;  // picked by itself when the input would not fit --max-mb
};

void runOutOfCore(EpsDeltaArgs& a, const std::string& why) {
  Timer total;
  if (a.ascii) throwBadParameter("--ascii", "the out-of-core path writes binary PLY");
  if (a.extract.epsilonNoise > 0)
    throwBadParameter("--epsilon-noise", "estimates the noise of the whole cloud in memory; out of core, give --epsilon "
                                         "(linesurf info prints the noise of a sample)");
  MpiRun mpi;
  if (mpi.rank != 0) globalOptions().quiet = true;  // rank 0 speaks for the job
  const ooc::OocNormalsOptions o = outOfCoreOptions(a.geometry, a.input, a.output, a.ooc, mpi, why, true);
  ooc::OocEpsDeltaReport r;
  mpi.guard([&] { r = ooc::extractEpsDeltaOutOfCore(a.input, a.output, o, a.extract); });
  endProgress();
  if (mpi.rank != 0) return;
  const ooc::OocNormalsReport& g = r.geometry;
  sayTiles(g, a.input);
  say(fmt::format("tolerances   epsilon {:.6g}{}  delta {:.6g}", r.epsilon,
                  a.extract.epsilon > 0 ? std::string() : fmt::format(" ({} x average spacing {:.6g})", a.extract.epsilonRelative, g.averageSpacing),
                  a.extract.delta));
  say(fmt::format("output       {} points + {} segments -> {}", r.keptPoints, r.segments, a.output));
  say(fmt::format("replaced     {} points ({:.2f}%), {:.2f} points per segment", r.replacedPoints,
                  g.points ? 100.0 * double(r.replacedPoints) / double(g.points) : 0.0,
                  r.segments ? double(r.replacedPoints) / double(r.segments) : 0.0));
  say(fmt::format("times        bbox {:.3f} s, partition {:.3f} s, normals tiles {:.3f} s, orientation {:.3f} s, eps-delta tiles {:.3f} s, "
                  "write {:.3f} s, total {:.3f} s",
                  g.tBbox, g.tPartition, g.tTiles, g.tOrient, r.tExtract, r.tWrite, total.seconds()));
}

void run(EpsDeltaArgs& a) {
  Timer total;
  EpsDeltaOptions& o = a.extract;
  validate(o);  // before the (long) geometry stage
  validate(a.geometry);
  checkFiles({a.input}, {{"--output", a.output, {".ply"}}}, false);
  if (const std::string why = a.ooc.requested(); !why.empty()) {
    runOutOfCore(a, why);
    return;
  }
  {
    // (ε,δ) holds Delaunay lists and candidates besides the normals' data: a quarter more.
    const double need = 1.25 * inMemoryEstimate(a.input, a.geometry.k);
    if (need > memoryBudgetBytes()) {
      runOutOfCore(a, fmt::format("in memory it needs about {:.0f} MiB, more than --max-mb {:g}", need / (1024.0 * 1024.0),
                                  globalOptions().maxMegabytes));
      return;
    }
  }
  CloudWithGeometry in = readCloudWithGeometry(a.input, a.geometry);
  const PointGeometry& geo = in.geometry;
  o.progress = progressBar();
  EpsDeltaStats st;
  HybridModel out = extractEpsDelta(in.cloud, geo, o, &st);
  // verify-extraction must derive the same normals: tell it how they were obtained.
  out.comments.push_back(fmt::format("eps-delta: normals={}", in.normalsFromFile ? "file" : "computed"));

  Timer t;
  writeExtracted(a.output, out, a.ascii);
  const double writeSeconds = t.seconds();
  endProgress();

  say(fmt::format("tolerances   epsilon {:.6g}{}  delta {:.6g} ({:.2f} deg)", st.epsilon,
                  o.epsilon > 0 ? std::string() : fmt::format(" ({} x average spacing {:.6g})", o.epsilonRelative, geo.averageSpacing),
                  st.delta, std::acos(std::max(-1.0, 1.0 - st.delta)) * 180.0 / 3.14159265358979));
  {
    // The noise tells whether the thesis's epsilon can do useful work on this scan.
    const double sigma = o.epsilonNoise > 0 ? st.noiseSigma : estimateNoise(in.cloud).sigma;
    say(fmt::format("noise        sigma {:.6g} ({:.3f} x average spacing){}", sigma,
                    geo.averageSpacing > 0 ? sigma / geo.averageSpacing : 0.0,
                    o.epsilonNoise > 0 ? fmt::format("; epsilon = max({} x spacing, {} x sigma)", o.epsilonRelative, o.epsilonNoise) : ""));
    if (o.epsilon <= 0 && o.epsilonNoise <= 0 && sigma > st.epsilon)
      say("note         the scan's noise exceeds epsilon, so few points lie within it of a segment: --epsilon-noise 2 "
          "sets epsilon to twice the noise");
  }
  say(fmt::format("output       {} points + {} segments -> {}", st.keptPoints, st.segments, a.output));
  say(fmt::format("replaced     {} points ({:.2f}%), {:.2f} points per segment", st.replacedPoints,
                  100.0 * st.replacedFraction(), st.segments ? double(st.replacedPoints) / st.segments : 0.0));
  say(fmt::format("reduction    {:.2f}% (§7.2.2: 6 floats per point, 9 per segment)", 100.0 * st.dataReduction()));
  say(fmt::format("candidates   {} seed directions, {} with >= {} points; {} degenerate neighbours",
                  st.seedDirections, st.candidateDirections, o.minReplaced, st.degenerateNeighbours));
  const double meanCandidate = st.candidateDirections ? double(st.candidateMembers) / st.candidateDirections : 0.0;
  if (o.maxReplaced == 0 && meanCandidate > 64)
    say(fmt::format("note         candidates hold {:.0f} points on average: growing them costs O(points x length); "
                    "--max-replaced 32 bounds it", meanCandidate));
  say(fmt::format("times        read {:.3f} s, geometry {:.3f} s (kNN {:.3f}, normals {:.3f}, orient {:.3f}, "
                  "delaunay {:.3f}, spacing {:.3f}), grow {:.3f} s, select {:.3f} s, build {:.3f} s, write {:.3f} s, "
                  "total {:.3f} s",
                  in.readSeconds, in.geometrySeconds, geo.times.neighbours, geo.times.normals, geo.times.orientation,
                  geo.times.delaunay, geo.times.spacing, st.growSeconds, st.selectSeconds, st.outputSeconds,
                  writeSeconds, total.seconds()));
}

RegisterCommand reg(31, [](CLI::App& app) {
  auto a = std::make_shared<EpsDeltaArgs>();
  EpsDeltaOptions& o = a->extract;
  CLI::App* sub = extractCommand(app)->add_subcommand(
      "eps-delta", "(epsilon, delta) error-bounded line segment extraction from a point cloud (thesis §3.1)");
  sub->add_option("IN", a->input, "Input point cloud (.ply, .xyz; a mesh gives its vertices)")->type_name("FILE")->required();
  sub->add_option("-o,--output", a->output, "Output hybrid model (.ply)")->type_name("FILE")->required();
  const TableBinder b = bindOptions(sub, o);
  b.option("epsilon")->excludes(b.option("epsilonRelative"));
  b.option("epsilon")->excludes(b.option("epsilonNoise"));
  bindGeometryOptions(sub, a->geometry);
  sub->add_flag("--ascii", a->ascii, "Write ASCII PLY");
  bindOutOfCoreFlags(sub, a->ooc);
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
