// Writers of the experiment results: results.json, results.md (thesis Tables 1-5 with the
// thesis's figures beside ours) and index.html (images side by side).
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "linesurf/eval/experiment.h"
#include "linesurf/io/atomic_file.h"

namespace linesurf {
namespace {

using nlohmann::json;

json num(double x) { return std::isfinite(x) ? json(x) : json(nullptr); }

json metricsJson(const ImageMetrics& m) {
  return {{"mse", num(m.mse)},           {"psnr", num(m.psnr)},
          {"nccm", num(m.nccm)},         {"ssim", num(m.ssim)},
          {"mean_abs_diff", num(m.meanAbsDiff)}, {"std_abs_diff", num(m.stdAbsDiff)},
          {"max_abs_diff", num(m.maxAbsDiff)},   {"differing_pixels", num(m.differingPixels)}};
}

json methodJson(const MethodResult& r) {
  json views = json::array();
  for (const ExperimentView& v : r.views) {
    json j = metricsJson(v.metrics);
    j["reference_cpu_seconds"] = num(v.referenceSeconds);
    j["candidate_cpu_seconds"] = num(v.candidateSeconds);
    j["reference_wall_seconds"] = num(v.referenceWallSeconds);
    j["candidate_wall_seconds"] = num(v.candidateWallSeconds);
    j["reference_fragments"] = v.referenceFragments;
    j["candidate_fragments"] = v.candidateFragments;
    j["reference_prepare_seconds"] = num(v.referencePrepareSeconds);
    j["candidate_prepare_seconds"] = num(v.candidatePrepareSeconds);
    j["reference_raster_seconds"] = num(v.referenceRasterSeconds);
    j["candidate_raster_seconds"] = num(v.candidateRasterSeconds);
    if (v.hasTruth) {
      j["candidate_vs_mesh"] = metricsJson(v.candidateVsTruth);
      j["reference_vs_mesh"] = metricsJson(v.referenceVsTruth);
      j["candidate_vs_mesh"]["covered_pixels"] = v.coveredPixels;
      j["candidate_vs_mesh"]["pixels_over_64"] = v.candidateBadPixels;
      j["reference_vs_mesh"]["covered_pixels"] = v.referenceCoveredPixels;
      j["reference_vs_mesh"]["pixels_over_64"] = v.referenceBadPixels;
      j["candidate_vs_mesh"]["pixels_over_64_off_silhouettes"] = v.candidateBadOffSilhouettes;
      j["reference_vs_mesh"]["pixels_over_64_off_silhouettes"] = v.referenceBadOffSilhouettes;
    }
    views.push_back(j);
  }
  json j = {{"method", experimentMethodName(r.method)},
            {"thesis_table", thesisTableOf(r.method)},
            {"reference_points", r.referencePoints},
            {"points", r.points},
            {"segments", r.segments},
            {"primitives", r.points + r.segments},
            {"data_reduction", num(r.dataReduction)},
            {"extract_seconds", num(r.extractSeconds)},
            {"mse", num(r.mse)},
            {"psnr", num(r.psnr)},
            {"nccm", num(r.nccm)},
            {"min_nccm", num(r.minNccm)},
            {"ssim", num(r.ssim)},
            {"mean_abs_diff", {{"mean", num(r.meanAbsDiff.mean)}, {"std", num(r.meanAbsDiff.std)}}},
            {"std_abs_diff", {{"mean", num(r.stdAbsDiff.mean)}, {"std", num(r.stdAbsDiff.std)}}},
            {"max_abs_diff", num(r.maxAbsDiff)},
            {"reference_render_median_cpu_seconds", num(r.referenceRenderMedian)},
            {"candidate_render_median_cpu_seconds", num(r.candidateRenderMedian)},
            {"reference_render_median_wall_seconds", num(r.referenceWallMedian)},
            {"candidate_render_median_wall_seconds", num(r.candidateWallMedian)},
            {"speedup", num(r.speedup)},
            {"reference_fragments_median", num(r.referenceFragments)},
            {"candidate_fragments_median", num(r.candidateFragments)},
            {"reference_prepare_median_seconds", num(r.referencePrepareMedian)},
            {"candidate_prepare_median_seconds", num(r.candidatePrepareMedian)},
            {"reference_raster_median_seconds", num(r.referenceRasterMedian)},
            {"candidate_raster_median_seconds", num(r.candidateRasterMedian)},
            {"images", r.images},
            {"diff_images", r.diffImages},
            {"notes", r.notes},
            {"views", views}};
  if (r.method == ExperimentMethod::ShapeGreedy || r.method == ExperimentMethod::ShapeHierarchical) {
    j["clusters"] = r.clusters;
    j["large_clusters"] = r.largeClusters;
    j["large_cluster_points"] = r.largeClusterPoints;
    j["clusters_image"] = r.clustersImage;
  }
  j["structure_image"] = r.structureImage;
  if (r.surface) {
    const SurfaceError& e = *r.surface;
    auto figures = [&](const SurfaceErrorFigures& f) {
      return json{{"samples", f.samples},
                  {"failed_reference", f.failedReference},
                  {"failed_model", f.failedModel},
                  {"rms", num(f.rms)},
                  {"p99", num(f.p99)},
                  {"max", num(f.max)},
                  {"mean", num(f.mean)},
                  {"rms_eps_ref", num(f.rms / e.epsilonRef)},
                  {"p99_eps_ref", num(f.p99 / e.epsilonRef)},
                  {"max_eps_ref", num(f.max / e.epsilonRef)},
                  {"rms_diagonal", num(f.rms / e.diagonal)},
                  {"p99_diagonal", num(f.p99 / e.diagonal)},
                  {"max_diagonal", num(f.max / e.diagonal)}};
    };
    j["surface_error"] = {{"reference", e.meshReference ? "mesh" : "cloud"},
                          {"reference_spacing", num(e.referenceSpacing)},
                          {"eps_ref", num(e.epsilonRef)},
                          {"diagonal", num(e.diagonal)},
                          {"seconds", num(r.surfaceSeconds)},
                          {"both", figures(e.both)},
                          {"from_reference", figures(e.fromReference)},
                          {"from_model", figures(e.fromModel)}};
  }
  if (r.hasTruth) {
    auto truth = [](const TruthSummary& t) {
      return json{{"psnr", num(t.psnr)}, {"ssim", num(t.ssim)}, {"min_ssim", num(t.minSsim)},
                  {"mean_abs_diff", num(t.meanAbsDiff)}, {"fraction_over_64", num(t.badFraction)},
                  {"max_view_fraction_over_64", num(t.maxBadFraction)},
                  {"fraction_over_64_off_silhouettes", num(t.badOffSilhouettesFraction)}};
    };
    j["candidate_vs_mesh"] = truth(r.candidateTruth);
    j["reference_vs_mesh"] = truth(r.referenceTruth);
    j["candidate_vs_mesh"]["silhouette_band_fraction"] = num(r.candidateTruth.silhouetteBandFraction);
  }
  return j;
}

// ---- markdown -------------------------------------------------------------------------------

std::string count(double x) { return x < 0 ? "—" : fmt::format("{:.0f}", x); }
std::string pct(double x) { return std::isfinite(x) ? fmt::format("{:.2f}%", 100 * x) : "—"; }
std::string fixed(double x, int digits) { return std::isfinite(x) && x >= -1e300 ? fmt::format("{:.{}f}", x, digits) : "—"; }
/// "ours / thesis" cell; the thesis half is "—" when it has no figure.
std::string pair(const std::string& ours, const std::string& thesis) { return ours + " / " + thesis; }

/// The surface error cell: RMS / 99th percentile / max in epsilon_ref, and failed projections.
std::string surfaceCell(const MethodResult& r) {
  if (!r.surface) return "—";
  const SurfaceError& e = *r.surface;
  const SurfaceErrorFigures& f = e.both;
  std::string c = fmt::format("{:.3g} / {:.3g} / {:.3g}", f.rms / e.epsilonRef, f.p99 / e.epsilonRef, f.max / e.epsilonRef);
  if (e.failures()) c += fmt::format(" ({} failed)", e.failures());
  return c;
}

const char* kSurfaceNote =
    "Surface error (beyond the thesis): the hybrid's MLS surface against the input cloud's (a contour model's against "
    "its mesh), each sample projected onto both and the distance between the projections taken, sampled both ways "
    "(input points and the model's primitives); RMS / 99th percentile / max in ε_ref = 0.05 × the input's average "
    "spacing (a mesh's mean edge length); failed projections in brackets (surface/surface_error.h).\n\n";

double thesisDataReduction(const ThesisFigures& f) {
  return f.inputPoints > 0 ? 1.0 - (6 * f.points + 9 * f.segments) / (6 * f.inputPoints) : NAN;
}

struct Row {
  const ModelResult* model;
  const MethodResult* method;
  std::optional<ThesisFigures> thesis;
};

std::vector<Row> rowsFor(const ExperimentResults& results, ExperimentMethod m) {
  std::vector<Row> rows;
  for (const ModelResult& model : results.models) {
    if (model.failed) continue;
    for (const MethodResult& r : model.methods)
      if (r.method == m) rows.push_back({&model, &r, thesisFigures(model.thesisName, thesisTableOf(m))});
  }
  return rows;
}

const char* tableCaption(int table) {
  switch (table) {
    case 1: return "Table 1: hybrid point and line segment models from the (ε, δ) error bounded algorithm (§3.1)";
    case 2: return "Table 2: hybrid models from shape approximation with greedy clustering (§3.2.3.1)";
    case 3: return "Table 3: hybrid models from shape approximation with hierarchical distortion minimized clustering (§3.2.3.2)";
    case 5: return "Table 5: pure point and pure line-segment models from contour-plane extraction (§3.3)";
    case 6: return "Lines of curvature traced on the MLS surface (§9.2, the thesis's future work: its cells blank)";
  }
  return "";
}

// Thesis's published averages over all its models (§7.2.2, §7.2.3).
struct PublishedAverages {
  double reduction, speedup;
};
PublishedAverages published(int table) {
  switch (table) {
    case 1: return {0.3403, 0.2696};
    case 2: return {0.4751, 0.3671};
    case 3: return {0.3985, 0.3063};
  }
  return {NAN, NAN};
}

void pointTable(std::string& md, const ExperimentResults& results, ExperimentMethod m) {
  const int table = thesisTableOf(m);
  const std::vector<Row> rows = rowsFor(results, m);
  if (rows.empty()) return;
  md += fmt::format("### {}\n\n", tableCaption(table));
  md += "Each cell: ours / thesis. Our models are often reduced versions of the thesis's (see the data README), so "
        "compare ratios and quality, not counts.\n\n";
  const bool surface = std::any_of(rows.begin(), rows.end(), [](const Row& r) { return r.method->surface.has_value(); });
  if (surface) md += kSurfaceNote;
  md += "| Model | Thesis model | # Points | Hybrid # points | # Line segments | mse | nccm | Speedup | Data reduction | "
        "Extraction (s) |";
  md += surface ? " Surface error (× ε_ref) |\n" : "\n";
  md += surface ? "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n" : "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  double sMse = 0, sNccm = 0, sSpeed = 0, sRed = 0, tMse = 0, tNccm = 0, tSpeed = 0, tRed = 0;
  int nThesis = 0;
  for (const Row& row : rows) {
    const MethodResult& r = *row.method;
    const ThesisFigures* f = row.thesis ? &*row.thesis : nullptr;
    md += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {:.2f} |\n", row.model->name,
                      row.model->thesisName.empty() ? "—" : row.model->thesisName,
                      pair(count(double(r.referencePoints)), f ? count(f->inputPoints) : "—"),
                      pair(count(double(r.points)), f ? count(f->points) : "—"),
                      pair(count(double(r.segments)), f ? count(f->segments) : "—"),
                      pair(fixed(r.mse, 6), f ? fixed(f->mse, 4) : "—"),
                      pair(fixed(r.nccm, 4), f ? fixed(f->nccm, 4) : "—"),
                      pair(pct(r.speedup), f ? pct(f->speedup) : "—"),
                      pair(pct(r.dataReduction), f ? pct(thesisDataReduction(*f)) : "—"), r.extractSeconds);
    if (surface) md.insert(md.size() - 1, " " + surfaceCell(r) + " |");
    sMse += r.mse;
    sNccm += r.nccm;
    sSpeed += r.speedup;
    sRed += r.dataReduction;
    if (f) {
      tMse += f->mse;
      tNccm += f->nccm;
      tSpeed += f->speedup;
      tRed += thesisDataReduction(*f);
      ++nThesis;
    }
  }
  const double n = double(rows.size());
  auto tAvg = [&](double s) { return nThesis ? s / nThesis : NAN; };
  md += fmt::format("| **Average** | (thesis: same models) | | | | {} | {} | {} | {} | |{}\n",
                    pair(fixed(sMse / n, 6), fixed(tAvg(tMse), 4)), pair(fixed(sNccm / n, 4), fixed(tAvg(tNccm), 4)),
                    pair(pct(sSpeed / n), pct(tAvg(tSpeed))), pair(pct(sRed / n), pct(tAvg(tRed))), surface ? " |" : "");
  const PublishedAverages p = published(table);
  if (std::isnan(p.reduction))
    md += "\n";
  else
    md += fmt::format("\nThesis averages over all its ten models: data reduction {}, speedup {}.\n\n", pct(p.reduction),
                      pct(p.speedup));
}

void clusterTable(std::string& md, const ExperimentResults& results) {
  const std::vector<Row> greedy = rowsFor(results, ExperimentMethod::ShapeGreedy);
  const std::vector<Row> hier = rowsFor(results, ExperimentMethod::ShapeHierarchical);
  if (greedy.empty() && hier.empty()) return;
  md += "### Table 4: number of clusters, greedy and hierarchical distortion minimized clustering (§3.2.3, §7.2.1)\n\n";
  md += "Each cell: ours / thesis. Large clusters: clusters of more than 100 points and the points they hold "
        "(§7.2.1 quotes 66 / 13818 greedy and 16 / 2578 hierarchical for the Rocker arm).\n\n";
  md += "| Model | Thesis model | Greedy clusters | Hierarchical clusters | Large clusters greedy | Large clusters "
        "hierarchical |\n|---|---|---:|---:|---:|---:|\n";
  for (const ModelResult& model : results.models) {
    if (model.failed) continue;
    const MethodResult *g = nullptr, *h = nullptr;
    for (const MethodResult& r : model.methods) {
      if (r.method == ExperimentMethod::ShapeGreedy) g = &r;
      if (r.method == ExperimentMethod::ShapeHierarchical) h = &r;
    }
    if (!g && !h) continue;
    auto tg = thesisFigures(model.thesisName, 2), th = thesisFigures(model.thesisName, 3);
    md += fmt::format("| {} | {} | {} | {} | {} | {} |\n", model.name, model.thesisName.empty() ? "—" : model.thesisName,
                      pair(g ? count(double(g->clusters)) : "—", tg ? count(tg->clusters) : "—"),
                      pair(h ? count(double(h->clusters)) : "—", th ? count(th->clusters) : "—"),
                      g ? fmt::format("{} ({} points)", g->largeClusters, g->largeClusterPoints) : "—",
                      h ? fmt::format("{} ({} points)", h->largeClusters, h->largeClusterPoints) : "—");
  }
  md += "\n";
}

void meshTable(std::string& md, const ExperimentResults& results) {
  const std::vector<Row> rows = rowsFor(results, ExperimentMethod::Contour);
  if (rows.empty()) return;
  md += fmt::format("### {}\n\n", tableCaption(5));
  md += "Each cell: ours / thesis. Image differences: mean and standard deviation of |A - B| over the R, G, B composite "
        "in grey levels (0-255), averaged over the views.\n\n";
  const bool surface = std::any_of(rows.begin(), rows.end(), [](const Row& r) { return r.method->surface.has_value(); });
  if (surface) md += kSurfaceNote;
  md += "| Model | Thesis model | # Points | # Line segments | Mean | Standard deviation | Max abs diff | nccm | Speedup | "
        "Extraction (s) |";
  md += surface ? " Surface error (× ε_ref) |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
                : "\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  double sMean = 0, sStd = 0, mMean = 0, mStd = 0, tMean = 0, tStd = 0, tmMean = 0, tmStd = 0;
  int nThesis = 0;
  for (const Row& row : rows) {
    const MethodResult& r = *row.method;
    const ThesisFigures* f = row.thesis ? &*row.thesis : nullptr;
    md += fmt::format("| {} | {} | {} | {} | {} | {} | {:.0f} | {} | {} | {:.2f} |\n", row.model->name,
                      row.model->thesisName.empty() ? "—" : row.model->thesisName,
                      pair(count(double(r.referencePoints)), f ? count(f->points) : "—"),
                      pair(count(double(r.segments)), f ? count(f->segments) : "—"),
                      pair(fixed(r.meanAbsDiff.mean, 2), f ? fixed(f->meanAbsDiff, 2) : "—"),
                      pair(fixed(r.stdAbsDiff.mean, 2), f ? fixed(f->stdAbsDiff, 2) : "—"), r.maxAbsDiff,
                      fixed(r.nccm, 4), pct(r.speedup), r.extractSeconds);
    if (surface) md.insert(md.size() - 1, " " + surfaceCell(r) + " |");
    sMean += r.meanAbsDiff.mean;
    sStd += r.stdAbsDiff.mean;
    mMean = std::max(mMean, r.meanAbsDiff.mean);
    mStd = std::max(mStd, r.stdAbsDiff.mean);
    if (f) {
      tMean += f->meanAbsDiff;
      tStd += f->stdAbsDiff;
      tmMean = std::max(tmMean, f->meanAbsDiff);
      tmStd = std::max(tmStd, f->stdAbsDiff);
      ++nThesis;
    }
  }
  const double n = double(rows.size());
  auto tAvg = [&](double s) { return nThesis ? s / nThesis : NAN; };
  md += fmt::format("| **Average** | (thesis: same models) | | | {} | {} | | | | |{}\n",
                    pair(fixed(sMean / n, 2), fixed(tAvg(tMean), 2)), pair(fixed(sStd / n, 2), fixed(tAvg(tStd), 2)),
                    surface ? " |" : "");
  md += fmt::format("| **Maximum** | (thesis: same models) | | | {} | {} | | | | |{}\n",
                    pair(fixed(mMean, 2), nThesis ? fixed(tmMean, 2) : "—"),
                    pair(fixed(mStd, 2), nThesis ? fixed(tmStd, 2) : "—"), surface ? " |" : "");
  md += "\nThesis over all its nine meshes: average mean 0.13, average standard deviation 2.78; maximum mean 0.31, "
        "maximum standard deviation 4.45.\n\n";
}

// Beyond the thesis (docs/decisions.md "Mesh ground truth and the silhouette band"): both models of
// Table 5 against the mesh rendered itself.
void truthTable(std::string& md, const ExperimentResults& results) {
  const std::vector<Row> rows = rowsFor(results, ExperimentMethod::Contour);
  if (std::none_of(rows.begin(), rows.end(), [](const Row& r) { return r.method->hasTruth; })) return;
  md += "### Against the mesh (ground truth, beyond the thesis)\n\n";
  md += "The mesh rasterised itself (4x4 supersampled, same camera, lighting and background) from the same views. "
        "> 64: pixels whose colour differs from the mesh image by more than 64 grey levels in a channel, as a share of "
        "the pixels covered in either image (pooled over the views; worst view in brackets); off silh.: the part of "
        "them more than 1 pixel from both sides of every silhouette of the mesh image (its outline, and depth steps between neighbouring "
        "pixels steeper than a surface turned 80 degrees from the camera), i.e. not at an edge.\n\n";
  md += "| Model | Lines PSNR (dB) | Lines SSIM (worst view) | Lines > 64 | Lines > 64 off silh. | Points PSNR (dB) | "
        "Points SSIM (worst view) | Points > 64 | Points > 64 off silh. |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Row& row : rows) {
    const MethodResult& r = *row.method;
    if (!r.hasTruth) continue;
    const TruthSummary &c = r.candidateTruth, &p = r.referenceTruth;
    md += fmt::format("| {} | {:.2f} | {:.4f} ({:.4f}) | {} ({}) | {} | {:.2f} | {:.4f} ({:.4f}) | {} ({}) | {} |\n",
                      row.model->name, c.psnr, c.ssim, c.minSsim, pct(c.badFraction), pct(c.maxBadFraction),
                      pct(c.badOffSilhouettesFraction), p.psnr, p.ssim, p.minSsim, pct(p.badFraction),
                      pct(p.maxBadFraction), pct(p.badOffSilhouettesFraction));
  }
  md += "\n";
}

void timingTable(std::string& md, const ExperimentResults& results) {
  md += "### Render times (median over the views, same run, interleaved per view)\n\n";
  md += "Total: process CPU time of one render call (all threads), the basis of the speedup; wall: wall-clock time of "
        "the same calls (depends on the machine's other load).\n";
  md += "Each pair: reference (point model) / candidate (hybrid or line model). Prepare: per-primitive work (culling, "
        "projection, lighting); raster: tiles rasterised and resolved (fill-bound, grows with the fragments).\n\n";
  md += "| Model | Method | Total CPU (ms) | Speedup | Wall (ms) | Primitives | Fragments (k) | Prepare (ms) | Raster (ms) |\n";
  md += "|---|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const ModelResult& model : results.models) {
    if (model.failed) continue;
    for (const MethodResult& r : model.methods)
      md += fmt::format("| {} | {} | {:.1f} / {:.1f} | {} | {:.1f} / {:.1f} | {} / {} | {:.0f} / {:.0f} | {:.1f} / {:.1f} | {:.1f} / {:.1f} |\n",
                        model.name, experimentMethodName(r.method), 1000 * r.referenceRenderMedian,
                        1000 * r.candidateRenderMedian, pct(r.speedup), 1000 * r.referenceWallMedian,
                        1000 * r.candidateWallMedian, r.referencePoints, r.points + r.segments,
                        r.referenceFragments / 1000, r.candidateFragments / 1000, 1000 * r.referencePrepareMedian,
                        1000 * r.candidatePrepareMedian, 1000 * r.referenceRasterMedian, 1000 * r.candidateRasterMedian);
  }
  md += "\n";
}

// ---- html -----------------------------------------------------------------------------------

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

std::string figure(const std::string& src, const std::string& caption) {
  return fmt::format("<figure><img src=\"{}\" loading=\"lazy\"><figcaption>{}</figcaption></figure>", esc(src), esc(caption));
}

}  // namespace

std::string experimentMarkdown(const ExperimentResults& results) {
  const ExperimentOptions& o = results.options;
  std::string md;
  md += fmt::format(
      "Settings: {} views per point cloud, {} per mesh, {}x{} pixels, {} threads; total {:.1f} s; tail coverage {}{}. "
      "Quality and speedup compare each hybrid (or line) model against the point model rendered from the same views. "
      "Definitions: docs/metrics.md; protocol: docs/experiments.md.\n\n",
      o.views, o.meshViews, o.size, o.size, results.threads, results.totalSeconds, o.render.tailCoverage,
      o.render.tailCoverage == 0 ? " (off: the thesis's settings for Table 5; render's default is on)" : "");
  for (ExperimentMethod m : {ExperimentMethod::EpsDelta, ExperimentMethod::ShapeGreedy, ExperimentMethod::ShapeHierarchical,
                             ExperimentMethod::CurvatureLines})
    pointTable(md, results, m);
  clusterTable(md, results);
  meshTable(md, results);
  truthTable(md, results);
  timingTable(md, results);
  const size_t failed = results.failedCount();
  if (failed) {
    md += fmt::format("### Failed models ({})\n\n", failed);
    for (const ModelResult& m : results.models)
      if (m.failed) md += fmt::format("- `{}`: {}\n", m.file, m.error);
    md += "\n";
  }
  return md;
}

void writeExperimentJson(const ExperimentResults& results, const std::filesystem::path& path) {
  const ExperimentOptions& o = results.options;
  json methods = json::array();
  for (ExperimentMethod m : o.effectiveMethods()) methods.push_back(experimentMethodName(m));
  json models = json::array();
  for (const ModelResult& m : results.models) {
    json ms = json::array();
    for (const MethodResult& r : m.methods) ms.push_back(methodJson(r));
    json j = {{"name", m.name},
              {"file", m.file},
              {"thesis_model", m.thesisName},
              {"kind", m.isMesh ? "mesh" : "points"},
              {"failed", m.failed},
              {"input_points", m.inputPoints},
              {"load_seconds", num(m.loadSeconds)},
              {"geometry_seconds", num(m.geometrySeconds)},
              {"reference_images", m.referenceImages},
              {"methods", ms}};
    if (m.failed) j["error"] = m.error;
    if (m.isMesh) j["faces"] = m.faces;
    else j["average_spacing"] = num(m.averageSpacing);
    models.push_back(j);
  }
  json root = {{"options",
                {{"data_dir", o.dataDir.string()},
                 {"views", o.views},
                 {"mesh_views", o.meshViews},
                 {"size", o.size},
                 {"methods", methods},
                 {"k", o.geometry.k},
                 {"epsilon_relative", o.epsDelta.epsilonRelative},
                 {"delta", o.epsDelta.delta},
                 {"delta_n", o.shapeApprox.clustering.deltaN},
                 {"contour_spacing_scale", o.contour.spacingScale},
                 {"contour_diagonal_divisions", o.contour.diagonalDivisions},
                 {"contour_seed", o.contour.seed},
                 {"surface_error", o.surfaceError},
                 {"surface_samples", o.surface.samples},
                 {"surface_support_scale", o.surface.mls.supportScale}}},
               {"threads", results.threads},
               {"total_seconds", num(results.totalSeconds)},
               {"failed", results.failedCount()},
               {"models", models}};
  // File names need not be UTF-8: such bytes become U+FFFD instead of failing the report.
  writeFileAtomically(path, root.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

void writeExperimentMarkdown(const ExperimentResults& results, const std::filesystem::path& path) {
  writeFileAtomically(path, "# linesurf experiment results (thesis §7)\n\n" + experimentMarkdown(results));
}

void writeExperimentHtml(const ExperimentResults& results, const std::filesystem::path& path) {
  std::string h;
  h += "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>linesurf experiment</title>\n<style>"
       "body{font-family:sans-serif;margin:1.5em}table{border-collapse:collapse;margin:.5em 0}"
       "td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}th{background:#eee}"
       "figure{display:inline-block;margin:4px;text-align:center}figure img{width:256px;height:256px;"
       "image-rendering:auto;border:1px solid #ddd}figcaption{font-size:80%}.row{white-space:nowrap;overflow-x:auto}"
       ".failed{color:#b00}</style></head><body>\n";
  const ExperimentOptions& o = results.options;
  h += fmt::format("<h1>linesurf experiment (thesis §7)</h1>\n<p>{} models from <code>{}</code>; {} views per point "
                   "cloud, {} per mesh, {}&times;{} pixels; {} failed. Reference = point model, candidate = hybrid "
                   "(point clouds) or pure line model (meshes); difference heat-map: black = equal, red &rarr; yellow "
                   "&rarr; white at 32 grey levels. Numbers: <a href=\"results.md\">results.md</a>, "
                   "<a href=\"results.json\">results.json</a>.</p>\n",
                   results.models.size(), esc(o.dataDir.string()), o.views, o.meshViews, o.size, o.size,
                   results.failedCount());
  for (const ModelResult& m : results.models) {
    h += fmt::format("<h2 id=\"{0}\">{0}{1}</h2>\n", esc(m.name), m.thesisName.empty() ? "" : " (thesis: " + esc(m.thesisName) + ")");
    if (m.failed) {
      h += fmt::format("<p class=\"failed\">failed: {}</p>\n", esc(m.error));
      continue;
    }
    // 3D: the viewer pages (linesurf view) are separate files, opened only when clicked.
    auto viewerLink = [](const std::string& page, const char* text) {
      return page.empty() ? std::string() : fmt::format("<a href=\"{}\" target=\"_blank\">{}</a>", esc(page), text);
    };
    h += "<table><tr><th>method</th><th>reference points</th><th>points</th><th>segments</th><th>clusters</th>"
         "<th>data reduction</th><th>mse</th><th>nccm</th><th>SSIM</th><th>mean |A-B|</th><th>std |A-B|</th>"
         "<th>speedup</th><th>surface error RMS / 99% / max (&times; &epsilon;<sub>ref</sub>)</th><th>3D viewer</th></tr>\n";
    for (const MethodResult& r : m.methods)
      h += fmt::format("<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{:.6f}</td><td>{:.4f}"
                       "</td><td>{:.4f}</td><td>{:.2f}</td><td>{:.2f}</td><td>{}</td><td>{}</td><td>{}{}{}</td></tr>\n",
                       experimentMethodName(r.method), r.referencePoints, r.points, r.segments,
                       r.clusters ? std::to_string(r.clusters) : "", pct(r.dataReduction), r.mse, r.nccm, r.ssim,
                       r.meanAbsDiff.mean, r.stdAbsDiff.mean, pct(r.speedup), esc(surfaceCell(r)), viewerLink(r.viewerPage, m.isMesh ? "lines" : "hybrid"),
                       r.viewerPage.empty() || m.referenceViewer.empty() ? "" : " &middot; ",
                       viewerLink(m.referenceViewer, "points"));
    h += "</table>\n";
    for (const MethodResult& r : m.methods)
      if (r.hasTruth)
        h += fmt::format("<p>Against the mesh image: lines PSNR {:.2f} dB, SSIM {:.4f}, {} of the covered pixels off by "
                         "&gt; 64 grey levels ({} more than 1 pixel from the mesh's silhouettes); points PSNR {:.2f} dB, "
                         "SSIM {:.4f}, {} ({}).</p>\n",
                         r.candidateTruth.psnr, r.candidateTruth.ssim, pct(r.candidateTruth.badFraction),
                         pct(r.candidateTruth.badOffSilhouettesFraction), r.referenceTruth.psnr, r.referenceTruth.ssim,
                         pct(r.referenceTruth.badFraction), pct(r.referenceTruth.badOffSilhouettesFraction));
    for (const MethodResult& r : m.methods) {
      h += fmt::format("<h3>{}</h3>\n<div class=\"row\">", experimentMethodName(r.method));
      const std::string cand = m.isMesh ? "lines" : "hybrid";
      for (size_t v = 0; v < r.images.size(); ++v) {
        if (v < m.truthImages.size()) h += figure(m.truthImages[v], fmt::format("view {}: mesh (ground truth)", v));
        if (v < m.referenceImages.size()) h += figure(m.referenceImages[v], fmt::format("view {}: points", v));
        h += figure(r.images[v], fmt::format("view {}: {} (nccm {:.4f})", v, cand, r.views[v].metrics.nccm));
        if (v < r.diffImages.size())
          h += figure(r.diffImages[v], fmt::format("view {}: difference (mean {:.2f})", v, r.views[v].metrics.meanAbsDiff));
      }
      if (!r.structureImage.empty())
        h += figure(r.structureImage, fmt::format("{} segments (orange), {} points (grey)", r.segments, r.points));
      if (!r.clustersImage.empty()) h += figure(r.clustersImage, fmt::format("{} clusters", r.clusters));
      h += "</div>\n";
    }
  }
  h += "</body></html>\n";
  writeFileAtomically(path, h);
}

}  // namespace linesurf
