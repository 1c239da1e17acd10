// linesurf experiment DATA_DIR -o OUT_DIR: the experiments of thesis §7 (Tables 1-5) on every
// model of a folder; writes results.json, results.md, index.html and images.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include "command.h"
#include "options_bind.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/eval/experiment.h"

namespace linesurf::cli {
namespace {

struct ExperimentArgs {
  std::string dataDir, outDir;
  int views = 50, meshViews = 20, size = 512, imageViews = 3, k = 12;
  std::vector<std::string> methods, only;
  double epsilonRelative = 0.05, delta = 0.004;
  float deltaN = 0.008f;
  float contourScale = 1.0f;
  float contourSpacing = 0;
  float contourDiagonalDivisions = ContourOptions{}.diagonalDivisions;
  bool contourVertexNormals = false;
  bool contourPointMasses = ContourOptions{}.pointMasses;
  float contourMergeNormalDeviation = ContourOptions{}.mergeNormalDeviation;
  float contourMergeAngle = ContourOptions{}.mergeAngle;
  float contourMergeStripAngle = ContourOptions{}.mergeStripAngle;
  bool noImages = false;
  float segmentLod = RenderOptions{}.segmentLod;
  float coverageGain = RenderOptions{}.coverageGain;
  float tailCoverage = ExperimentOptions{}.render.tailCoverage;  // the thesis's 0, unlike render's
  float prefilterVariance = RenderOptions{}.prefilterVariance;
  float reconstructionScale = RenderOptions{}.reconstructionScale;
  bool tailLayers = RenderOptions{}.tailLayers;
  int coverageReach = RenderOptions{}.coverageReach;
  bool surfaceError = ExperimentOptions{}.surfaceError;
  SurfaceErrorOptions surface;
};

std::vector<std::string> splitCommas(const std::vector<std::string>& in) {
  std::vector<std::string> out;
  for (const std::string& s : in) {
    std::istringstream is(s);
    std::string tok;
    while (std::getline(is, tok, ','))
      if (!tok.empty()) out.push_back(tok);
  }
  return out;
}

/// The experiment's flag for a field of the stage options it sets (validate() names fields).
std::string experimentFlag(const std::string& field) {
  static const std::map<std::string, std::string> flags = {
      {"epsilonRelative", "--epsilon"},
      {"deltaN", "--delta-n"},
      {"spacingScale", "--contour-scale"},
      {"spacing", "--contour-spacing"},
      {"diagonalDivisions", "--contour-diagonal-divisions"},
      {"mergeNormalDeviation", "--contour-merge-normal-deviation"},
      {"mergeAngle", "--contour-merge-angle"},
      {"mergeStripAngle", "--contour-merge-strip-angle"},
  };
  auto it = flags.find(field);
  return it != flags.end() ? it->second : flagName(field);
}

/// A reason with its `backquoted` fields renamed to the experiment's flags.
std::string renameFields(const std::string& r) {
  std::string out;
  for (size_t i = 0; i < r.size(); ++i) {
    const size_t end = r[i] == '`' ? r.find('`', i + 1) : std::string::npos;
    if (end == std::string::npos) {
      out += r[i];
      continue;
    }
    out += experimentFlag(r.substr(i + 1, end - i - 1));
    i = end;
  }
  return out;
}

std::string pct(double x) { return std::isfinite(x) ? fmt::format("{:.1f}%", 100 * x) : "-"; }

void run(const ExperimentArgs& a) {
  ExperimentOptions o;
  o.dataDir = a.dataDir;
  o.outDir = a.noImages ? std::filesystem::path() : std::filesystem::path(a.outDir);
  o.views = a.views;
  o.meshViews = a.meshViews;
  o.size = a.size;
  o.imageViews = a.imageViews;
  o.only = splitCommas(a.only);
  for (const std::string& m : splitCommas(a.methods)) o.methods.push_back(parseExperimentMethod(m));
  o.geometry.k = a.k;
  o.epsDelta.epsilonRelative = a.epsilonRelative;
  o.epsDelta.delta = a.delta;
  o.shapeApprox.clustering.deltaN = a.deltaN;
  o.contour.spacingScale = a.contourScale;
  o.contour.spacing = a.contourSpacing;
  o.contour.diagonalDivisions = a.contourDiagonalDivisions;
  o.contour.vertexNormals = a.contourVertexNormals;
  o.contour.pointMasses = a.contourPointMasses;
  o.contour.mergeNormalDeviation = a.contourMergeNormalDeviation;
  o.contour.mergeAngle = a.contourMergeAngle;
  o.contour.mergeStripAngle = a.contourMergeStripAngle;
  o.render.segmentLod = a.segmentLod;
  o.render.coverageGain = a.coverageGain;
  o.render.tailCoverage = a.tailCoverage;
  o.render.prefilterVariance = a.prefilterVariance;
  o.render.reconstructionScale = a.reconstructionScale;
  o.render.tailLayers = a.tailLayers;
  o.render.coverageReach = a.coverageReach;
  o.surfaceError = a.surfaceError;
  o.surface = a.surface;

  // Every parameter, the budget and the output folder are checked before any model is read.
  try {
    o.validate();
  } catch (const OptionError& e) {
    throw Error(Error::Kind::BadParameter, experimentFlag(e.field()), "", renameFields(e.reason()));
  }
  const std::filesystem::path out = a.outDir;
  {
    std::error_code ec;
    if (std::filesystem::is_directory(out, ec)) checkFiles({}, {{"--output", (out / "results.json").string(), {}}});
    else if (std::filesystem::exists(std::filesystem::symlink_status(out, ec))) throwIo(a.outDir, "exists and is not a folder");
  }
  const size_t models = experimentModelFiles(o).size();
  checkSize("--size", o.workingBytes(), fmt::format("rendering {}x{} views", o.size, o.size));
  checkSize(o.views >= o.meshViews ? "--views" : "--mesh-views", o.outputBytes(models),
            fmt::format("the images and reports of {} models", models));

  // The run is one transaction: the output folder (when new) or each model's folder and the
  // three reports are built aside and put in place together at the end, so an earlier run's
  // results stay whole until this one is complete.
  makeOutputFolder(out);
  ExperimentResults res = runExperiment(o, progressBar());
  endProgress();
  const size_t failed = res.failedCount();
  if (failed > 0 && failed == res.models.size())  // nothing to report: leave the folder as it was
    throw Error(Error::Kind::BadInput, a.dataDir, "",
                fmt::format("all {} models failed, nothing written; the first: {}", failed,
                            res.models.empty() ? std::string("-") : res.models.front().error));
  writeExperimentJson(res, out / "results.json");
  writeExperimentMarkdown(res, out / "results.md");
  writeExperimentHtml(res, out / "index.html");

  for (const ModelResult& m : res.models) {
    if (m.failed) {
      say(fmt::format("{}: FAILED: {}", m.name, m.error));
      continue;
    }
    say(fmt::format("{} ({}{}{}): {} vertices{}, read {:.2f} s{}", m.name, m.isMesh ? "mesh" : "points",
                    m.thesisName.empty() ? "" : ", thesis: ", m.thesisName, m.inputPoints,
                    m.isMesh ? fmt::format(", {} faces", m.faces) : "", m.loadSeconds,
                    m.isMesh ? "" : fmt::format(", geometry {:.2f} s", m.geometrySeconds)));
    for (const MethodResult& r : m.methods)
      say(fmt::format("  {:<18} {:>8} pts {:>7} segs{} reduction {:>6}  mse {:.4f}  nccm {:.4f}  |A-B| {:.2f} ± {:.2f}"
                      "  render {:.1f} -> {:.1f} ms CPU (speedup {})  extract {:.2f} s",
                      experimentMethodName(r.method), r.points, r.segments,
                      r.clusters ? fmt::format(" {:>6} clusters", r.clusters) : "", pct(r.dataReduction), r.mse,
                      r.nccm, r.meanAbsDiff.mean, r.stdAbsDiff.mean, 1000 * r.referenceRenderMedian,
                      1000 * r.candidateRenderMedian, pct(r.speedup), r.extractSeconds) +
          (r.surface ? fmt::format("  surface RMS {:.3g} / 99% {:.3g} / max {:.3g} eps_ref{}", r.surface->both.rms / r.surface->epsilonRef,
                                   r.surface->both.p99 / r.surface->epsilonRef, r.surface->both.max / r.surface->epsilonRef,
                                   r.surface->failures() ? fmt::format(" ({} failed)", r.surface->failures()) : "")
                     : std::string()));
  }
  say(fmt::format("{} models ({} failed) in {:.1f} s on {} threads; wrote {}, {}, {}", res.models.size(), failed,
                  res.totalSeconds, res.threads, (out / "results.json").string(), (out / "results.md").string(),
                  (out / "index.html").string()));
  if (failed) commitOutputs();  // a batch: keep the results of the models that did run
  if (failed)
    throw Error(Error::Kind::BadInput, a.dataDir, "",
                fmt::format("{} of {} models failed (see above and results.json)", failed, res.models.size()));
}

RegisterCommand reg(70, [](CLI::App& app) {
  auto a = std::make_shared<ExperimentArgs>();
  CLI::App* sub = app.add_subcommand(
      "experiment", "Run the thesis's §7 experiments (Tables 1-5) on every model of a folder: counts, data reduction, "
                    "image quality and render speedup; writes results.json, results.md and index.html");
  sub->add_option("DATA_DIR", a->dataDir, "Folder of models (.ply/.obj/.xyz; a PLY with faces is a mesh)")->type_name("DIR")
      ->required()->check(CLI::ExistingDirectory);
  sub->add_option("-o,--output", a->outDir, "Output folder")->type_name("FILE")->required();
  sub->add_option("--views", a->views, "Views per point cloud, spread over the sphere (thesis: 50)")
      ->capture_default_str()->check(CLI::Range(1, 100000));
  sub->add_option("--mesh-views", a->meshViews, "Views per mesh (thesis: 20)")->capture_default_str()->check(CLI::Range(1, 100000));
  sub->add_option("--size", a->size, "Square image side in pixels (thesis: 512)")->capture_default_str()->check(CLI::Range(16, 8192));
  sub->add_option("--methods", a->methods, "Comma-separated subset of eps-delta, shape-greedy, shape-hierarchical, curvature-lines, contour (default: all but curvature-lines)");
  sub->add_option("--only", a->only, "Only models whose file name contains one of these (comma-separated)");
  sub->add_option("--image-views", a->imageViews, "Views whose images go to the HTML page")->capture_default_str()->check(CLI::Range(0, 100000));
  sub->add_flag("--no-images", a->noImages, "Write no images (numbers only)");
  sub->add_option("--k", a->k, "Neighbours of the §6.1 geometry")->capture_default_str()->check(CLI::Range(3, 200));
  sub->add_option("--epsilon", a->epsilonRelative, "eps-delta: epsilon as a fraction of the average spacing (§7.2: 0.05)")->capture_default_str();
  sub->add_option("--delta", a->delta, "eps-delta: normal tolerance 1 - n.n (§7.2: 0.004)")->capture_default_str();
  sub->add_option("--delta-n", a->deltaN, "shape approximation: normal variation tolerance (§7.2: 0.008)")->capture_default_str();
  sub->add_option("--contour-scale", a->contourScale,
                  "contour: plane spacing d as a multiple of min(mean edge length, diagonal / --contour-diagonal-divisions)")
      ->capture_default_str()->check(CLI::Range(1e-3, 1e3));
  sub->add_option("--contour-diagonal-divisions", a->contourDiagonalDivisions,
                  "contour: default d at most the bounding-box diagonal / N (0 = mean edge only; extract contour "
                  "--diagonal-divisions)")
      ->capture_default_str()->check(CLI::Range(0.0, 1e6));
  sub->add_option("--contour-spacing", a->contourSpacing, "contour: plane spacing d in object units (0 = --contour-scale)")
      ->capture_default_str()->check(CLI::Range(0.0, 1e30));
  sub->add_flag("--contour-vertex-normals", a->contourVertexNormals,
                "contour: normals interpolated from the mesh's vertex normals instead of the triangle's (smooth shading)");
  sub->add_flag("--contour-point-masses,!--no-contour-point-masses", a->contourPointMasses,
                "contour: the point model's points weigh the contour length they stand for (beyond the thesis; default on; "
                "extract contour --no-point-masses)");
  sub->add_option("--contour-merge-normal-deviation", a->contourMergeNormalDeviation,
                  "contour: polyline merging, largest deviation along the normal x d (0: no merging; extract contour "
                  "--merge-normal-deviation)")
      ->capture_default_str();
  sub->add_option("--contour-merge-angle", a->contourMergeAngle,
                  "contour: polyline merging, largest normal angle in degrees (extract contour --merge-angle)")
      ->capture_default_str();
  sub->add_option("--contour-merge-strip-angle", a->contourMergeStripAngle,
                  "contour: polyline merging, largest strip-plane tilt in degrees (extract contour --merge-strip-angle)")
      ->capture_default_str();
  sub->add_option("--segment-lod", a->segmentLod,
                  "Draw segments at most this many kernel sigmas long as one point splat, [0, 4] (render --segment-lod)")
      ->capture_default_str();
  bind(sub, "prefilterVariance", a->prefilterVariance,
       "Screen prefilter variance, pixels^2 in [0, 100] (0 = none; render --prefilter-variance)", "--prefilter");
  bind(sub, "reconstructionScale", a->reconstructionScale,
       "Reconstruction sigma as a fraction of the primitive radius, (0, 4] (render --recon-scale)", "--recon-scale");
  sub->add_flag("--tail-layers,!--no-tail-layers", a->tailLayers, "Tail layers (beyond the thesis; render --tail-layers; default on)");
  sub->add_option("--tail-coverage", a->tailCoverage,
                  "Tail coverage gain, [0, 100] (0 = off, the thesis's setting for Table 5, unlike render's default; render --tail-coverage)")
      ->capture_default_str();
  sub->add_option("--coverage-gain", a->coverageGain,
                  "Coverage alpha gain, [0, 100] (0 = the thesis's normalised alpha; render --coverage-gain)")
      ->capture_default_str();
  sub->add_option("--coverage-reach", a->coverageReach,
                  "Coverage alpha within this many pixels of a silhouette, [0, 16] (0 = everywhere; render "
                  "--coverage-reach)")
      ->capture_default_str();
  sub->add_flag("--surface-error,!--no-surface-error", a->surfaceError,
                "The surface error of every extraction: its MLS surface against the cloud's (contour: against the mesh), "
                "sampled both ways (beyond the thesis; default on)");
  bindOptions(sub, a->surface);
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
