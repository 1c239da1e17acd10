#pragma once
/// The experiments of thesis §7, reproducible on any folder of models.
///
///  - Point clouds (§7.2, Tables 1-4): the §6.1 geometry is computed once; each extraction method
///    (eps-delta §3.1, shape approximation with greedy §3.2.3.1 or hierarchical §3.2.3.2
///    clustering) runs with the §7.2 defaults; the point model and every hybrid model are rendered
///    from the same N views spread over the sphere (Camera::spreadViews, deterministic, no prior
///    knowledge of the model) and compared image by image (eval/image_metrics.h). Counts, the
///    §7.2.2 data-reduction ratio, extraction time, render times and the §7.2.3 speedup are kept.
///  - Meshes (§7.3, Table 5): contour-plane extraction (§3.3) to a pure line-segment model and,
///    with the same planes, to a pure point model (every segment sampled into points); both are
///    rendered from N views (20 in the thesis) and compared by the mean and standard deviation
///    of the absolute differences.
///
/// Definitions of every figure are in docs/metrics.md; the protocol and our choices in
/// docs/experiments.md and docs/decisions.md ("Experiments and metrics (§7)").
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "linesurf/core/progress.h"
#include "linesurf/eval/image_metrics.h"
#include "linesurf/surface/surface_error.h"
#include "linesurf/extract/contour.h"
#include "linesurf/extract/curvature_lines.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/render/render_options.h"

namespace linesurf {

/// The extraction methods of the experiments. All but Contour apply to point clouds, Contour to
/// meshes. CurvatureLines (§9.2, the thesis's future work) runs only when asked for.
enum class ExperimentMethod { EpsDelta, ShapeGreedy, ShapeHierarchical, CurvatureLines, Contour };

/// "eps-delta", "shape-greedy", "shape-hierarchical", "curvature-lines", "contour".
const char* experimentMethodName(ExperimentMethod m);
/// Inverse of experimentMethodName (also accepts "greedy", "hierarchical"); throws
/// linesurf::Error (BadParameter) naming the accepted values otherwise.
ExperimentMethod parseExperimentMethod(const std::string& name);
/// The thesis table a method's results belong to: 1, 2, 3 or 5; 6 for curvature lines, a table in
/// the layout of Tables 1-3 with the thesis's cells blank.
int thesisTableOf(ExperimentMethod m);

struct ExperimentOptions {
  std::filesystem::path dataDir;  ///< folder of models (.ply, .obj, .xyz), not recursive
  /// Where images go (per model: a few point / hybrid / difference images and the clusters
  /// picture). Empty: no images are written (the numbers are the same).
  std::filesystem::path outDir;
  int views = 50;       ///< point-cloud views per model (§7.2: 50), >= 1
  int meshViews = 20;   ///< mesh views per model (§7.3: 20), >= 1
  int size = 512;       ///< square image side in pixels (§7: 512), [16, 8192]
  /// Methods to run; empty = the thesis's four (not curvature lines). Point methods are skipped on
  /// meshes and vice versa.
  std::vector<ExperimentMethod> methods;
  int imageViews = 3;   ///< views whose images are written for the HTML page, >= 0
  /// Only models whose file stem contains one of these substrings; empty = every model.
  std::vector<std::string> only;

  GeometryOptions geometry;       ///< §6.1 stages (k = 12); progress is set by the harness
  EpsDeltaOptions epsDelta;       ///< §7.2 defaults: epsilon = 5% of the average spacing, delta 0.004
  ShapeApproxOptions shapeApprox; ///< §7.2 defaults: delta_n = 0.008; method is set per run
  ContourOptions contour;         ///< §3.3 defaults (d = mean edge length, seed 1)
  CurvatureLineOptions curvatureLines;  ///< §9.2 defaults (epsilon = 5% of the average spacing, delta 0.004)
  /// Renderer defaults, the same for every image, except tail coverage: off (0), the thesis's
  /// setting, since it moves Table 5's line-vs-point comparison (render_options.h).
  RenderOptions render = [] {
    RenderOptions r;
    r.tailCoverage = 0;
    return r;
  }();
  /// Meshes: also render the mesh itself (render/mesh_render.h, the ground truth) from the same
  /// views and compare the line model and the point model with it (beyond the thesis;
  /// docs/decisions.md "Mesh ground truth and the silhouette band").
  bool groundTruth = true;
  int groundTruthSupersampling = 4;  ///< samples per pixel side of the mesh image, [1, 16]
  /// The surface error of every extraction (surface/surface_error.h, beyond the thesis): each
  /// hybrid's MLS surface against the cloud's, each contour model's against its mesh.
  bool surfaceError = true;
  SurfaceErrorOptions surface;

  std::vector<ExperimentMethod> effectiveMethods() const;
  /// Throws OptionError (core/options.h) naming the first absurd field, of this struct or of
  /// any stage's options (render, geometry, epsDelta, shapeApprox, contour).
  void validate() const;
  /// Memory the run holds at once (image buffers of one view), bytes, for a Budget (core/budget.h).
  double workingBytes() const;
  /// Bytes the run writes for `models` models (images and reports), for a Budget.
  double outputBytes(size_t models) const;
};

/// Image comparison and timing of one view.
struct ExperimentView {
  ImageMetrics metrics;          ///< reference (point model) vs. candidate (hybrid / line model)
  /// CPU time of the process (all threads) to render the reference / the candidate: what a
  /// single-core machine like the thesis's would show as wall time, and robust to other load.
  double referenceSeconds = 0, candidateSeconds = 0;
  double referenceWallSeconds = 0, candidateWallSeconds = 0;  ///< wall-clock time of the same calls
  /// Renderer breakdown (RenderStats): fragments generated, per-primitive prepare time and
  /// rasterise + resolve time, for the reference and the candidate.
  uint64_t referenceFragments = 0, candidateFragments = 0;
  double referencePrepareSeconds = 0, candidatePrepareSeconds = 0;
  double referenceRasterSeconds = 0, candidateRasterSeconds = 0;
  /// Meshes with ExperimentOptions::groundTruth: the mesh image (truth) against the candidate
  /// (line model) and the reference (point model), and how many pixels differ from it by more
  /// than 64 grey levels (any channel) among the covered ones (covered in either image).
  bool hasTruth = false;
  ImageMetrics candidateVsTruth, referenceVsTruth;
  uint64_t coveredPixels = 0, candidateBadPixels = 0;          ///< candidate vs truth
  uint64_t referenceCoveredPixels = 0, referenceBadPixels = 0; ///< reference vs truth
  /// Of the pixels over 64, those more than 1 pixel from both sides of every silhouette of the mesh image
  /// (silhouetteBand: its outline and its depth steps steeper than a surface at 80 degrees), i.e. not an edge's anti-aliasing.
  uint64_t candidateBadOffSilhouettes = 0, referenceBadOffSilhouettes = 0;
  uint64_t coveredInSilhouetteBand = 0;  ///< of coveredPixels, those within the band
};

/// Agreement of a model's images with the mesh images over the views (ground truth).
struct TruthSummary {
  double psnr = 0;        ///< 10 log10(1 / mean mse) over the views
  double ssim = 0;        ///< mean over the views
  double minSsim = 0;     ///< worst view
  double meanAbsDiff = 0; ///< mean over the views, grey levels
  /// Pixels differing by > 64 grey levels / covered pixels, pooled over the views; and the worst view.
  double badFraction = 0, maxBadFraction = 0;
  /// The part of badFraction more than 1 pixel from the mesh image's silhouettes (same denominator).
  double badOffSilhouettesFraction = 0;
  /// The candidate's covered pixels that lie within the band (0 for the reference's summary).
  double silhouetteBandFraction = 0;
};

/// Mean and standard deviation of a per-view quantity.
struct MeanStd {
  double mean = 0, std = 0;
};

/// One extraction method on one model.
struct MethodResult {
  ExperimentMethod method = ExperimentMethod::EpsDelta;
  size_t referencePoints = 0;  ///< primitives of the reference: input points (clouds) or the
                               ///< contour point model's points (meshes)
  size_t points = 0;           ///< points of the hybrid / line model
  size_t segments = 0;         ///< segments of the hybrid / line model
  size_t clusters = 0;         ///< shape approximation: clusters (Table 4); else 0
  size_t largeClusters = 0;    ///< shape approximation: clusters of > 100 points (§7.2.1)
  size_t largeClusterPoints = 0;
  double dataReduction = 0;    ///< §7.2.2: 1 - (6 points + 9 segments) / (6 reference points)
  double extractSeconds = 0;   ///< wall time of the extraction (clustering included)

  // Quality: means over the views (docs/metrics.md).
  double mse = 0, nccm = 0, ssim = 0;
  double psnr = 0;             ///< 10 log10(1 / mean mse); +inf when every view is identical
  MeanStd meanAbsDiff;         ///< Table 5 "Mean": per-view mean |A-B| (grey levels), over views
  MeanStd stdAbsDiff;          ///< Table 5 "Standard deviation": per-view std of |A-B|, over views
  double maxAbsDiff = 0;       ///< largest |A-B| of any view
  double minNccm = 0;          ///< worst view

  // Timing (§7.2.3): medians over the views, measured interleaved in the same run.
  double referenceRenderMedian = 0, candidateRenderMedian = 0;  ///< CPU seconds (ExperimentView)
  double referenceWallMedian = 0, candidateWallMedian = 0;      ///< wall seconds
  /// (T_ref - T_hybrid) / T_ref of the medians: the fraction of render time saved (thesis's
  /// "speedup", in percent there). Negative when the hybrid is slower.
  double speedup = 0;
  /// Medians over the views of the RenderStats breakdown (same fields as ExperimentView).
  double referenceFragments = 0, candidateFragments = 0;
  double referencePrepareMedian = 0, candidatePrepareMedian = 0;
  double referenceRasterMedian = 0, candidateRasterMedian = 0;

  std::vector<ExperimentView> views;
  bool hasTruth = false;                ///< meshes: the two summaries below are filled
  TruthSummary candidateTruth;          ///< line model vs the mesh image
  TruthSummary referenceTruth;          ///< point model vs the mesh image
  std::vector<std::string> images;      ///< candidate images, relative to outDir
  std::vector<std::string> diffImages;  ///< difference heat-maps, relative to outDir
  std::string clustersImage;            ///< shape approximation: clusters picture (§3.2.3, Fig. 22)
  /// The candidate from the first view with points grey and segments orange (thesis Figs. 23-26).
  std::string structureImage;
  /// Interactive WebGL viewer page of the candidate (linesurf view), relative to outDir.
  std::string viewerPage;
  std::vector<std::string> notes;       ///< extraction diagnostics worth reading
  /// With ExperimentOptions::surfaceError (empty when off, or when the surface refused the model:
  /// a note says why), and its wall time.
  std::optional<SurfaceError> surface;
  double surfaceSeconds = 0;
};

/// One model of the folder.
struct ModelResult {
  std::string name;        ///< file stem, e.g. "santa_points"
  std::string file;        ///< path as found
  std::string thesisName;  ///< thesis model this file stands for ("" when none)
  bool isMesh = false;
  bool failed = false;
  std::string error;       ///< what() of the failure when failed
  size_t inputPoints = 0;  ///< vertices of the file
  size_t faces = 0;        ///< meshes: faces
  double loadSeconds = 0, geometrySeconds = 0;
  double averageSpacing = 0;       ///< clouds: §6.1 stage 5
  std::vector<std::string> referenceImages;  ///< point-model images, relative to outDir
  std::vector<std::string> truthImages;      ///< meshes: mesh images (ground truth), relative to outDir
  std::string referenceViewer;  ///< viewer page of the point model (linesurf view), relative to outDir
  std::vector<MethodResult> methods;
};

struct ExperimentResults {
  ExperimentOptions options;  ///< as run (progress callbacks dropped)
  std::vector<ModelResult> models;
  double totalSeconds = 0;
  int threads = 0;            ///< worker threads used
  size_t failedCount() const;
};

/// Runs the §7 protocol on every model file of options.dataDir (sorted by name; a .ply with
/// faces or an .obj is a mesh, anything else a point cloud). A model that cannot be read or
/// processed is recorded as failed with its error message and the run continues. Progress goes
/// to `progress` as (stage "MODEL: step", fraction of the whole run). Images go under
/// options.outDir when set. Deterministic except for the timings.
/// Throws linesurf::Error: BadParameter for absurd options (before any model is read), Io when
/// the data folder cannot be listed or holds no model file, or when an output cannot be written
/// (a model whose output fails is not recorded as failed: the run stops). Folders are made with
/// makeOutputFolder (io/atomic_file.h): inside an OutputTransaction each model's folder replaces
/// an earlier run's only when the transaction commits.
ExperimentResults runExperiment(const ExperimentOptions& options, const ProgressFn& progress = {});
/// The model files runExperiment would run, in its order (Io errors as runExperiment's).
std::vector<std::filesystem::path> experimentModelFiles(const ExperimentOptions& options);

/// results.json: options, per model and method every count, metric, timing and per-view figure.
void writeExperimentJson(const ExperimentResults& results, const std::filesystem::path& path);
/// results.md: the thesis's Tables 1-5 with the thesis's figures beside ours.
void writeExperimentMarkdown(const ExperimentResults& results, const std::filesystem::path& path);
/// index.html: per model, a few reference / candidate / difference images side by side and the
/// clusters picture (image paths relative to the page, which belongs in outDir).
void writeExperimentHtml(const ExperimentResults& results, const std::filesystem::path& path);
/// The markdown tables alone (what results.md holds), for docs and the CLI.
std::string experimentMarkdown(const ExperimentResults& results);

/// The thesis's published figures for one model and table (§7.2, §7.3), for side-by-side tables.
struct ThesisFigures {
  std::string model;
  int table = 0;               ///< 1, 2, 3 (points/segments/mse/nccm/speedup) or 5
  double inputPoints = 0;      ///< tables 1-3: # points of the point model; table 5: # points
  double points = 0;           ///< tables 1-3: hybrid # points
  double segments = 0;
  double mse = -1, nccm = -1, speedup = -1;  ///< speedup as a fraction (0.0727 for 7.27%)
  double meanAbsDiff = -1, stdAbsDiff = -1;  ///< table 5
  double clusters = -1;        ///< Table 4 (tables 2 and 3)
};
/// The thesis model a file stem stands for (per the shared data README), or "" when none.
std::string thesisModelFor(const std::string& fileStem);
/// The thesis's figures for `thesisModel` in `table`, if it lists the model.
std::optional<ThesisFigures> thesisFigures(const std::string& thesisModel, int table);

}  // namespace linesurf
