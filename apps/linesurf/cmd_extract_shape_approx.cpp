// linesurf extract shape-approx IN -o OUT [--clustering greedy|hierarchical] [--delta-n 0.008]
// [--seed N] [--clusters-out FILE] [--out-of-core]: shape-approximation based line segment extraction,
// thesis §3.2; in tiles streamed from disk when the cloud would not fit --max-mb.
#include <fmt/format.h>

#include <cmath>
#include <map>

#include "command.h"
#include "extract_common.h"
#include "options_bind.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/clustering.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/ooc/ooc_extract.h"
#include "ooc_cli.h"

namespace linesurf::cli {
namespace {

struct ShapeApproxArgs {
  std::string input, output, clustersOut;
  GeometryOptions geometry;  // curvature on: §3.2.4.2 needs minimum-curvature directions
  ShapeApproxOptions extract;
  bool ascii = false;
  OutOfCoreFlags ooc;  // picked by itself when the input would not fit --max-mb
};

std::string histogramText(const ShapeApproxStats& st) {
  std::string hist;
  for (size_t b = 0; b < st.sizeHistogram.size(); ++b)
    hist += fmt::format("{}{}: {}", b ? ", " : "", ShapeApproxStats::kHistogramLabels[b], st.sizeHistogram[b]);
  return hist;
}

void sayCounts(const ShapeApproxStats& st, const ShapeApproxOptions& o, const std::string& output) {
  say(fmt::format("             {} clusters > 100 points hold {} points; {} with segments; {} below {} points; "
                  "{} degenerate; {} took the k_min direction",
                  st.largeClusters, st.largeClusterPoints, st.clustersWithSegments, st.smallClusters, o.minClusterSize,
                  st.degenerateClusters, st.curvatureDirectionUsed));
  say(fmt::format("output       {} points + {} segments -> {}", st.pointsKept, st.segments, output));
  say(fmt::format("replaced     {} points ({:.2f}%), {:.2f} points per segment{}", st.pointsReplaced,
                  100.0 * double(st.pointsReplaced) / double(std::max<size_t>(st.inputPoints, 1)),
                  st.segments ? double(st.pointsReplaced) / double(st.segments) : 0.0,
                  st.degenerateRuns ? fmt::format("; {} degenerate runs kept as points", st.degenerateRuns) : ""));
  say(fmt::format("reduction    {:.2f}% (§7.2.2: 6 floats per point, 9 per segment)", 100.0 * st.dataReduction()));
}

void runOutOfCore(ShapeApproxArgs& a, const std::string& why) {
  Timer total;
  if (a.ascii) throwBadParameter("--ascii", "the out-of-core path writes binary PLY");
  if (!a.clustersOut.empty())
    throwBadParameter("--clusters-out", "is not written out of core (clusters are cut per tile); run in memory for it");
  MpiRun mpi;
  if (mpi.rank != 0) globalOptions().quiet = true;  // rank 0 speaks for the job
  const ooc::OocNormalsOptions o = outOfCoreOptions(a.geometry, a.input, a.output, a.ooc, mpi, why, true);
  ooc::OocShapeApproxReport r;
  mpi.guard([&] { r = ooc::extractShapeApproxOutOfCore(a.input, a.output, o, a.extract); });
  endProgress();
  if (mpi.rank != 0) return;
  const ooc::OocNormalsReport& g = r.geometry;
  const ShapeApproxStats& st = r.stats;
  sayTiles(g, a.input);
  say(fmt::format("clusters     {} (cut at tile borders); sizes {}", st.clusters, histogramText(st)));
  sayCounts(st, a.extract, a.output);
  say(fmt::format("times        bbox {:.3f} s, partition {:.3f} s, geometry tiles {:.3f} s, orientation {:.3f} s, "
                  "shape-approx tiles {:.3f} s, write {:.3f} s, total {:.3f} s",
                  g.tBbox, g.tPartition, g.tTiles, g.tOrient, r.tExtract, r.tWrite, total.seconds()));
}

void run(ShapeApproxArgs& a) {
  Timer total;
  ShapeApproxOptions& o = a.extract;
  validate(o);  // before the (long) geometry stage
  validate(a.geometry);
  checkFiles({a.input}, {{"--output", a.output, {".ply"}}, {"--clusters-out", a.clustersOut, {".ply", ".xyz"}}}, false);
  if (const std::string why = a.ooc.requested(); !why.empty()) {
    runOutOfCore(a, why);
    return;
  }
  {
    // Clustering holds Delaunay lists, curvature and cluster labels besides the normals' data.
    const double need = 1.5 * inMemoryEstimate(a.input, a.geometry.k);
    if (need > memoryBudgetBytes()) {
      runOutOfCore(a, fmt::format("in memory it needs about {:.0f} MiB, more than --max-mb {:g}", need / (1024.0 * 1024.0),
                                  globalOptions().maxMegabytes));
      return;
    }
  }
  CloudWithGeometry in = readCloudWithGeometry(a.input, a.geometry);
  const HybridModel& cloud = in.cloud;
  const PointGeometry& geo = in.geometry;
  o.clustering.progress = progressBar();
  o.progress = progressBar();

  Timer t;
  Clustering clustering = clusterShapeApprox(geo, o);
  const double clusteringSeconds = t.seconds();
  double clustersWriteSeconds = 0;
  if (!a.clustersOut.empty()) {
    t.reset();
    writeExtracted(a.clustersOut, colorByCluster(cloud, geo, clustering), a.ascii);
    clustersWriteSeconds = t.seconds();
  }

  ShapeApproxStats st;
  HybridModel out = extractShapeApprox(cloud, geo, clustering, o, &st);
  t.reset();
  writeExtracted(a.output, out, a.ascii);
  const double writeSeconds = t.seconds();
  endProgress();

  const char* method = o.method == ClusteringMethod::Greedy ? "greedy (§3.2.3.1)" : "hierarchical (§3.2.3.2)";
  say(fmt::format("clustering   {}, delta_n {:.6g} (<= {:.2f} deg between a normal and its cluster's){}", method,
                  o.clustering.deltaN, std::acos(std::max(-1.0, 1.0 - 0.5 * o.clustering.deltaN)) * 180.0 / 3.14159265358979,
                  o.method == ClusteringMethod::Hierarchical
                      ? fmt::format(", seed {}, {} splits, {} growths, {} stopped by the cap of {}", o.clustering.seed,
                                    clustering.splits, clustering.iterations, clustering.capReached, o.clustering.maxIterations)
                      : std::string()));
  say(fmt::format("clusters     {} ({} connected components); sizes {}", st.clusters, clustering.components, histogramText(st)));
  sayCounts(st, o, a.output);
  if (!a.clustersOut.empty()) say(fmt::format("clusters-out {} (points coloured by cluster)", a.clustersOut));
  say(fmt::format("times        read {:.3f} s, geometry {:.3f} s (kNN {:.3f}, normals {:.3f}, orient {:.3f}, "
                  "delaunay {:.3f}, curvature {:.3f}, spacing {:.3f}), clustering {:.3f} s, segments {:.3f} s, "
                  "write {:.3f} s, total {:.3f} s",
                  in.readSeconds, in.geometrySeconds, geo.times.neighbours, geo.times.normals, geo.times.orientation,
                  geo.times.delaunay, geo.times.curvature, geo.times.spacing, clusteringSeconds, st.extractionSeconds,
                  writeSeconds + clustersWriteSeconds, total.seconds()));
}

RegisterCommand reg(32, [](CLI::App& app) {
  CLI::App* extract = extractCommand(app);
  auto a = std::make_shared<ShapeApproxArgs>();
  ShapeApproxOptions& o = a->extract;
  CLI::App* sub = extract->add_subcommand(
      "shape-approx", "Shape-approximation extraction: normal-variation clusters, bunches of parallel segments (thesis §3.2)");
  sub->add_option("IN", a->input, "Input point cloud (.ply, .xyz)")->type_name("FILE")->required();
  sub->add_option("-o,--output", a->output, "Output hybrid model (.ply)")->type_name("FILE")->required();
  sub->add_option("--clusters-out", a->clustersOut, "Also write the cloud coloured by cluster (.ply)")->type_name("FILE");
  bindOptions(sub, o);
  bindGeometryOptions(sub, a->geometry);
  // on here (§3.2.4.2 needs minimum-curvature directions); --no-curvature: from the rectangles only
  bindOptions(sub, a->geometry, {"curvature"});
  sub->add_flag("--ascii", a->ascii, "Write ASCII PLY");
  bindOutOfCoreFlags(sub, a->ooc);
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
