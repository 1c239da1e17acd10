// linesurf extract shape-approx IN -o OUT [--clustering greedy|hierarchical] [--delta-n 0.008]
// [--seed N] [--clusters-out FILE]: shape-approximation based line segment extraction, thesis §3.2.
#include <fmt/format.h>

#include <cmath>
#include <map>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/clustering.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

namespace linesurf::cli {
namespace {

struct ShapeApproxArgs {
  std::string input, output, clustersOut;
  ClusteringMethod method = ClusteringMethod::Greedy;
  float deltaN = 0.008f, radiusScale = 1.0f;
  uint64_t seed = 1;
  int maxIterations = 16, k = 12;
  bool provenance = false, recomputeNormals = false, noCurvature = false, ascii = false;
};

void run(const ShapeApproxArgs& a) {
  Timer total, t;
  checkFiles({a.input}, {{"--output", a.output, {".ply"}}, {"--clusters-out", a.clustersOut, {".ply", ".xyz"}}});
  HybridModel cloud = readModel(a.input);
  const double readSeconds = t.seconds();
  if (!cloud.segments.empty())
    throwBadInput(a.input, "segments", fmt::format("already holds {} segments; extraction needs a point cloud",
                                                   cloud.segments.size()));
  if (cloud.points.empty()) throwBadInput(a.input, "vertex", "holds no points");
  say(fmt::format("input        {} points ({}), normals {}", cloud.points.size(), a.input,
                  cloud.attributes.normals && !a.recomputeNormals ? "from file" : "computed (PCA, MST-oriented)"));

  ShapeApproxOptions o;
  o.method = a.method;
  o.clustering.deltaN = a.deltaN;
  o.clustering.seed = a.seed;
  o.clustering.maxIterations = a.maxIterations;
  o.clustering.progress = progressBar();
  o.radiusScale = a.radiusScale;
  o.provenance = a.provenance;
  o.progress = progressBar();
  // Check the options before the (long) geometry stage.
  if (!(a.deltaN > 0 && a.deltaN < 2))
    throwBadParameter("delta-n", fmt::format("must lie in (0, 2) (got {}): ||n(C) - n_j||^2 = 2 - 2 cos(angle)", a.deltaN));

  t.reset();
  GeometryOptions go;
  go.k = a.k;
  go.recomputeNormals = a.recomputeNormals;
  go.curvature = !a.noCurvature;  // §3.2.4.2 needs minimum-curvature directions
  go.progress = progressBar();
  PointGeometry geo = computePointGeometry(cloud, go);
  const double geometrySeconds = t.seconds();
  for (auto [flag, name] : {std::pair{kPointDuplicate, "duplicate"}, {kPointFewNeighbours, "with few neighbours"},
                            {kPointFlatNeighbourhood, "with collinear neighbourhoods"}, {kPointIsolated, "isolated"}})
    if (size_t c = geo.countFlag(flag)) say(fmt::format("warning      {} points {}", c, name));

  t.reset();
  Clustering clustering = clusterShapeApprox(geo, o);
  const double clusteringSeconds = t.seconds();
  double clustersWriteSeconds = 0;
  if (!a.clustersOut.empty()) {
    t.reset();
    WriteOptions wo;
    if (a.ascii) wo.encoding = PlyEncoding::Ascii;
    writeModel(a.clustersOut, colorByCluster(cloud, geo, clustering), wo);
    clustersWriteSeconds = t.seconds();
  }

  ShapeApproxStats st;
  HybridModel out = extractShapeApprox(cloud, geo, clustering, o, &st);
  t.reset();
  WriteOptions wo;
  if (a.ascii) wo.encoding = PlyEncoding::Ascii;
  writeModel(a.output, out, wo);
  const double writeSeconds = t.seconds();
  endProgress();

  const char* method = a.method == ClusteringMethod::Greedy ? "greedy (§3.2.3.1)" : "hierarchical (§3.2.3.2)";
  say(fmt::format("clustering   {}, delta_n {:.6g} (<= {:.2f} deg between a normal and its cluster's){}", method,
                  a.deltaN, std::acos(std::max(-1.0, 1.0 - 0.5 * a.deltaN)) * 180.0 / 3.14159265358979,
                  a.method == ClusteringMethod::Hierarchical
                      ? fmt::format(", seed {}, {} splits, {} growths, {} stopped by the cap of {}", a.seed,
                                    clustering.splits, clustering.iterations, clustering.capReached, a.maxIterations)
                      : std::string()));
  std::string hist;
  for (size_t b = 0; b < st.sizeHistogram.size(); ++b)
    hist += fmt::format("{}{}: {}", b ? ", " : "", ShapeApproxStats::kHistogramLabels[b], st.sizeHistogram[b]);
  say(fmt::format("clusters     {} ({} connected components); sizes {}", st.clusters, clustering.components, hist));
  say(fmt::format("             {} clusters > 100 points hold {} points; {} with segments; {} below {} points; "
                  "{} degenerate; {} took the k_min direction",
                  st.largeClusters, st.largeClusterPoints, st.clustersWithSegments, st.smallClusters, o.minClusterSize,
                  st.degenerateClusters, st.curvatureDirectionUsed));
  say(fmt::format("output       {} points + {} segments -> {}", st.pointsKept, st.segments, a.output));
  say(fmt::format("replaced     {} points ({:.2f}%), {:.2f} points per segment{}", st.pointsReplaced,
                  100.0 * double(st.pointsReplaced) / double(std::max<size_t>(st.inputPoints, 1)),
                  st.segments ? double(st.pointsReplaced) / double(st.segments) : 0.0,
                  st.degenerateRuns ? fmt::format("; {} degenerate runs kept as points", st.degenerateRuns) : ""));
  say(fmt::format("reduction    {:.2f}% (§7.2.2: 6 floats per point, 9 per segment)", 100.0 * st.dataReduction()));
  if (!a.clustersOut.empty()) say(fmt::format("clusters-out {} (points coloured by cluster)", a.clustersOut));
  say(fmt::format("times        read {:.3f} s, geometry {:.3f} s (kNN {:.3f}, normals {:.3f}, orient {:.3f}, "
                  "delaunay {:.3f}, curvature {:.3f}, spacing {:.3f}), clustering {:.3f} s, segments {:.3f} s, "
                  "write {:.3f} s, total {:.3f} s",
                  readSeconds, geometrySeconds, geo.times.neighbours, geo.times.normals, geo.times.orientation,
                  geo.times.delaunay, geo.times.curvature, geo.times.spacing, clusteringSeconds, st.extractionSeconds,
                  writeSeconds + clustersWriteSeconds, total.seconds()));
}

RegisterCommand reg(32, [](CLI::App& app) {
  CLI::App* extract = extractCommand(app);
  auto a = std::make_shared<ShapeApproxArgs>();
  CLI::App* sub = extract->add_subcommand(
      "shape-approx", "Shape-approximation extraction: normal-variation clusters, bunches of parallel segments (thesis §3.2)");
  sub->add_option("IN", a->input, "Input point cloud (.ply, .xyz)")->required();
  sub->add_option("-o,--output", a->output, "Output hybrid model (.ply)")->required();
  std::map<std::string, ClusteringMethod> methods{{"greedy", ClusteringMethod::Greedy},
                                                  {"hierarchical", ClusteringMethod::Hierarchical}};
  sub->add_option("--clustering", a->method, "Clustering algorithm: greedy (§3.2.3.1) or hierarchical (§3.2.3.2)")
      ->transform(CLI::CheckedTransformer(methods, CLI::ignore_case))
      ->default_str("greedy");
  sub->add_option("--delta-n", a->deltaN,
                  "Normal variation tolerance on ||n(C) - n_j||^2, in (0, 2) (0.008 ~ 5.1 deg, §7.2)")
      ->capture_default_str();
  sub->add_option("--seed", a->seed, "Seed of the hierarchical clustering's random seed points")->capture_default_str();
  sub->add_option("--max-iterations", a->maxIterations, "Hierarchical: reseeding iterations per split")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  sub->add_option("--clusters-out", a->clustersOut, "Also write the cloud coloured by cluster (.ply)");
  sub->add_option("--radius-scale", a->radiusScale,
                  "Segment half-width as a multiple of the cluster's spacing across segments (>= 1 renders hole-free)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sub->add_option("-k,--neighbours", a->k, "Neighbours per point for normals and spacing (§6.1)")
      ->check(CLI::Range(3, 256))
      ->capture_default_str();
  sub->add_flag("--no-curvature", a->noCurvature, "Skip curvature: directions come from the rectangles only");
  sub->add_flag("--provenance", a->provenance, "Record the input points each segment replaced");
  sub->add_flag("--recompute-normals", a->recomputeNormals, "Ignore normals in the input and compute them");
  sub->add_flag("--ascii", a->ascii, "Write ASCII PLY");
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
