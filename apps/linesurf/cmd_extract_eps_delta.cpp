// linesurf extract eps-delta IN -o OUT [--epsilon X | --epsilon-rel R] [--delta D] [--provenance]:
// (epsilon, delta) error-bounded line segment extraction, thesis §3.1.
#include <fmt/format.h>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

namespace linesurf::cli {
namespace {

struct EpsDeltaArgs {
  std::string input, output;
  double epsilon = 0, epsilonRel = 0.05, delta = 0.004;
  int k = 12, minReplaced = 4, maxReplaced = 0;
  bool provenance = false, recomputeNormals = false, ascii = false;
};


void run(const EpsDeltaArgs& a) {
  Timer total, t;
  checkFiles({a.input}, {{"--output", a.output, {".ply"}}});
  HybridModel cloud = readModel(a.input);
  const double readSeconds = t.seconds();
  if (!cloud.segments.empty())
    throwBadInput(a.input, "segments", fmt::format("already holds {} segments; extraction needs a point cloud",
                                                   cloud.segments.size()));
  say(fmt::format("input        {} points ({}), normals {}", cloud.points.size(), a.input,
                  cloud.attributes.normals && !a.recomputeNormals ? "from file" : "computed (PCA, MST-oriented)"));

  t.reset();
  GeometryOptions go;
  go.k = a.k;
  go.recomputeNormals = a.recomputeNormals;
  go.curvature = false;  // §3.1 needs normals, Delaunay neighbours and spacing only
  go.progress = progressBar();
  PointGeometry geo = computePointGeometry(cloud, go);
  const double geometrySeconds = t.seconds();
  for (auto [flag, name] : {std::pair{kPointDuplicate, "duplicate"}, {kPointFewNeighbours, "with few neighbours"},
                            {kPointFlatNeighbourhood, "with collinear neighbourhoods"}, {kPointIsolated, "isolated"}})
    if (size_t c = geo.countFlag(flag)) say(fmt::format("warning      {} points {}", c, name));

  EpsDeltaOptions o;
  o.epsilon = a.epsilon;
  o.epsilonRelative = a.epsilonRel;
  o.delta = a.delta;
  o.minReplaced = a.minReplaced;
  o.maxReplaced = a.maxReplaced;
  o.provenance = a.provenance;
  o.progress = progressBar();
  EpsDeltaStats st;
  HybridModel out = extractEpsDelta(cloud, geo, o, &st);
  // verify-extraction must derive the same normals: tell it how they were obtained.
  out.comments.push_back(fmt::format("eps-delta: normals={}",
                                     cloud.attributes.normals && !a.recomputeNormals ? "file" : "computed"));

  t.reset();
  WriteOptions wo;
  if (a.ascii) wo.encoding = PlyEncoding::Ascii;
  writeModel(a.output, out, wo);
  const double writeSeconds = t.seconds();
  endProgress();

  say(fmt::format("tolerances   epsilon {:.6g}{}  delta {:.6g} ({:.2f} deg)", st.epsilon,
                  a.epsilon > 0 ? std::string() : fmt::format(" ({} x average spacing {:.6g})", a.epsilonRel, geo.averageSpacing),
                  st.delta, std::acos(std::max(-1.0, 1.0 - st.delta)) * 180.0 / 3.14159265358979));
  say(fmt::format("output       {} points + {} segments -> {}", st.keptPoints, st.segments, a.output));
  say(fmt::format("replaced     {} points ({:.2f}%), {:.2f} points per segment", st.replacedPoints,
                  100.0 * st.replacedFraction(), st.segments ? double(st.replacedPoints) / st.segments : 0.0));
  say(fmt::format("reduction    {:.2f}% (§7.2.2: 6 floats per point, 9 per segment)", 100.0 * st.dataReduction()));
  say(fmt::format("candidates   {} seed directions, {} with >= {} points; {} degenerate neighbours",
                  st.seedDirections, st.candidateDirections, a.minReplaced, st.degenerateNeighbours));
  const double meanCandidate = st.candidateDirections ? double(st.candidateMembers) / st.candidateDirections : 0.0;
  if (a.maxReplaced == 0 && meanCandidate > 64)
    say(fmt::format("note         candidates hold {:.0f} points on average: growing them costs O(points x length); "
                    "--max-replaced 32 bounds it", meanCandidate));
  say(fmt::format("times        read {:.3f} s, geometry {:.3f} s (kNN {:.3f}, normals {:.3f}, orient {:.3f}, "
                  "delaunay {:.3f}, spacing {:.3f}), grow {:.3f} s, select {:.3f} s, build {:.3f} s, write {:.3f} s, "
                  "total {:.3f} s",
                  readSeconds, geometrySeconds, geo.times.neighbours, geo.times.normals, geo.times.orientation,
                  geo.times.delaunay, geo.times.spacing, st.growSeconds, st.selectSeconds, st.outputSeconds,
                  writeSeconds, total.seconds()));
}

RegisterCommand reg(31, [](CLI::App& app) {
  auto args = std::make_shared<EpsDeltaArgs>();
  CLI::App* sub = extractCommand(app)->add_subcommand(
      "eps-delta", "(epsilon, delta) error-bounded line segment extraction from a point cloud (thesis §3.1)");
  sub->add_option("IN", args->input, "Input point cloud (.ply, .xyz; a mesh gives its vertices)")->required();
  sub->add_option("-o,--output", args->output, "Output hybrid model (.ply)")->required();
  auto* eps = sub->add_option("--epsilon", args->epsilon, "Distance tolerance, object space")
                  ->check(CLI::PositiveNumber);
  auto* rel = sub->add_option("--epsilon-rel", args->epsilonRel,
                              "Distance tolerance as a fraction of the average neighbour spacing (§7.2)")->capture_default_str()
                  ->check(CLI::PositiveNumber);
  eps->excludes(rel);
  sub->add_option("--delta", args->delta, "Normal tolerance on 1 - n_i.n_j (0.004 ~ 5.13 deg, §7.2)")->capture_default_str()
      ->check(CLI::Range(0.0, 2.0));
  sub->add_option("--min-replaced", args->minReplaced, "Smallest number of points a segment may replace")->capture_default_str()
      ->check(CLI::Range(2, 1 << 30));
  sub->add_option("--max-replaced", args->maxReplaced,
                  "Stop growing a segment at this many points (0 = no limit; bounds time on long regular rows)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  sub->add_option("-k,--neighbours", args->k, "Neighbours per point for normals and spacing (§6.1)")->capture_default_str()
      ->check(CLI::Range(3, 256));
  sub->add_flag("--provenance", args->provenance, "Record the input points each segment replaced (for verify-extraction)");
  sub->add_flag("--recompute-normals", args->recomputeNormals, "Ignore normals in the input and compute them");
  sub->add_flag("--ascii", args->ascii, "Write ASCII PLY");
  sub->callback([args] { run(*args); });
});

}  // namespace
}  // namespace linesurf::cli
