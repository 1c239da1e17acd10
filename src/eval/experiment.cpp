// The experiment harness of thesis §7 (protocol in docs/experiments.md, figures in
// docs/metrics.md): extraction, rendering from views spread over the sphere, image comparison.
#include "linesurf/eval/experiment.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <system_error>

#include <time.h>

#include "linesurf/core/budget.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/clustering.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_io.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/mesh_render.h"
#include "linesurf/render/renderer.h"
#include "linesurf/view/viewer_page.h"

namespace linesurf {
namespace fs = std::filesystem;

const char* experimentMethodName(ExperimentMethod m) {
  switch (m) {
    case ExperimentMethod::EpsDelta: return "eps-delta";
    case ExperimentMethod::ShapeGreedy: return "shape-greedy";
    case ExperimentMethod::ShapeHierarchical: return "shape-hierarchical";
    case ExperimentMethod::CurvatureLines: return "curvature-lines";
    case ExperimentMethod::Contour: return "contour";
  }
  return "?";
}

ExperimentMethod parseExperimentMethod(const std::string& name) {
  if (name == "eps-delta" || name == "epsdelta") return ExperimentMethod::EpsDelta;
  if (name == "shape-greedy" || name == "greedy") return ExperimentMethod::ShapeGreedy;
  if (name == "shape-hierarchical" || name == "hierarchical") return ExperimentMethod::ShapeHierarchical;
  if (name == "curvature-lines") return ExperimentMethod::CurvatureLines;
  if (name == "contour") return ExperimentMethod::Contour;
  throwBadParameter("methods", "unknown method '" + name +
                                   "' (expected eps-delta, shape-greedy, shape-hierarchical, curvature-lines or contour)");
}

int thesisTableOf(ExperimentMethod m) {
  switch (m) {
    case ExperimentMethod::EpsDelta: return 1;
    case ExperimentMethod::ShapeGreedy: return 2;
    case ExperimentMethod::ShapeHierarchical: return 3;
    case ExperimentMethod::CurvatureLines: return 6;
    case ExperimentMethod::Contour: return 5;
  }
  return 0;
}

std::vector<ExperimentMethod> ExperimentOptions::effectiveMethods() const {
  static const std::vector<ExperimentMethod> all = {ExperimentMethod::EpsDelta, ExperimentMethod::ShapeGreedy,
                                                    ExperimentMethod::ShapeHierarchical, ExperimentMethod::CurvatureLines,
                                                    ExperimentMethod::Contour};
  static const std::vector<ExperimentMethod> thesis = {ExperimentMethod::EpsDelta, ExperimentMethod::ShapeGreedy,
                                                       ExperimentMethod::ShapeHierarchical, ExperimentMethod::Contour};
  if (methods.empty()) return thesis;
  // Keep the canonical order and drop repeats, so the output does not depend on how they were listed.
  std::vector<ExperimentMethod> out;
  for (ExperimentMethod m : all)
    if (std::find(methods.begin(), methods.end(), m) != methods.end()) out.push_back(m);
  return out;
}

void ExperimentOptions::validate() const {
  // Every option of every stage, before any model is read: a bad value would otherwise surface
  // only in the first model that reaches its stage, after minutes of work.
  if (views < 1 || views > 100000) throwBadOption("views", "must be in [1, 100000], got " + std::to_string(views));
  if (meshViews < 1 || meshViews > 100000)
    throwBadOption("meshViews", "must be in [1, 100000], got " + std::to_string(meshViews));
  if (size < 16 || size > 8192) throwBadOption("size", "must be in [16, 8192] pixels, got " + std::to_string(size));
  if (imageViews < 0) throwBadOption("imageViews", "must be >= 0, got " + std::to_string(imageViews));
  if (groundTruthSupersampling < 1 || groundTruthSupersampling > 16)
    throwBadOption("groundTruthSupersampling", "must be in [1, 16]");
  linesurf::validate(render);
  linesurf::validate(geometry);
  linesurf::validate(epsDelta);
  linesurf::validate(shapeApprox);
  linesurf::validate(contour);
  linesurf::validate(curvatureLines);
  if (surfaceError) linesurf::validate(surface);
}

double ExperimentOptions::workingBytes() const {
  // Two renders' buffers alive at once (the reference's result while a candidate renders) and
  // the mesh image's colour, depth and alpha (its supersamples are per tile, not per image).
  return 2.0 * renderViewBytes(size, size, render.layers) + double(size) * size * 48.0;
}

double ExperimentOptions::outputBytes(size_t models) const {
  // Per model: the images of imageViews views (reference, mesh, and per method a candidate and a
  // difference image) plus the structure and cluster pictures; the reports hold about 2 KiB a
  // view and method.
  const double images = double(std::min(imageViews, std::max(views, meshViews))) * 8.0 + 8.0;
  const double report = double(std::max(views, meshViews)) * 4.0 * 2048.0;
  return double(models) * ((outDir.empty() ? 0.0 : images * pngFileBytes(size, size)) + report) + 65536.0;
}

size_t ExperimentResults::failedCount() const {
  return size_t(std::count_if(models.begin(), models.end(), [](const ModelResult& m) { return m.failed; }));
}

namespace {

bool isModelFile(const fs::path& p) {
  std::string ext = p.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".ply" || ext == ".obj" || ext == ".xyz";
}

std::vector<fs::path> listModels(const ExperimentOptions& o) {
  std::error_code ec;
  if (!fs::is_directory(o.dataDir, ec))
    throw Error(Error::Kind::BadInput, o.dataDir.string(), "", "not a folder (expected a folder of .ply/.obj/.xyz models)");
  std::vector<fs::path> files;
  for (fs::directory_iterator it(o.dataDir, ec), end; !ec && it != end; it.increment(ec)) {
    if (!it->is_regular_file(ec) || !isModelFile(it->path())) continue;
    const std::string stem = it->path().stem().string();
    if (!o.only.empty() &&
        std::none_of(o.only.begin(), o.only.end(), [&](const std::string& s) { return stem.find(s) != std::string::npos; }))
      continue;
    files.push_back(it->path());
  }
  if (ec) throw Error(Error::Kind::Io, o.dataDir.string(), "", "cannot list the folder: " + ec.message());
  if (files.empty())
    throw Error(Error::Kind::BadInput, o.dataDir.string(), "",
                o.only.empty() ? "holds no model file (.ply, .obj, .xyz)" : "no model file matches --only");
  std::sort(files.begin(), files.end());
  return files;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

MeanStd meanStd(const std::vector<double>& v) {
  MeanStd r;
  if (v.empty()) return r;
  for (double x : v) r.mean += x;
  r.mean /= double(v.size());
  double s = 0;
  for (double x : v) s += (x - r.mean) * (x - r.mean);
  r.std = v.size() > 1 ? std::sqrt(s / double(v.size() - 1)) : 0.0;
  return r;
}

/// Fills the per-method summaries from its per-view figures.
void summarise(MethodResult& m) {
  std::vector<double> mse, nccm, ssim, mad, sad, tr, tc;
  m.maxAbsDiff = 0;
  m.minNccm = std::numeric_limits<double>::infinity();
  for (const ExperimentView& v : m.views) {
    mse.push_back(v.metrics.mse);
    nccm.push_back(v.metrics.nccm);
    ssim.push_back(v.metrics.ssim);
    mad.push_back(v.metrics.meanAbsDiff);
    sad.push_back(v.metrics.stdAbsDiff);
    tr.push_back(v.referenceSeconds);
    tc.push_back(v.candidateSeconds);
    m.maxAbsDiff = std::max(m.maxAbsDiff, v.metrics.maxAbsDiff);
    m.minNccm = std::min(m.minNccm, v.metrics.nccm);
  }
  if (m.views.empty()) m.minNccm = 0;
  m.mse = meanStd(mse).mean;
  m.nccm = meanStd(nccm).mean;
  m.ssim = meanStd(ssim).mean;
  m.psnr = m.mse > 0 ? 10 * std::log10(1.0 / m.mse) : std::numeric_limits<double>::infinity();
  m.meanAbsDiff = meanStd(mad);
  m.stdAbsDiff = meanStd(sad);
  m.referenceRenderMedian = median(tr);
  m.candidateRenderMedian = median(tc);
  m.speedup = m.referenceRenderMedian > 0 ? 1.0 - m.candidateRenderMedian / m.referenceRenderMedian : 0.0;
  auto med = [&](auto field) {
    std::vector<double> v;
    for (const ExperimentView& x : m.views) v.push_back(double(x.*field));
    return median(v);
  };
  m.referenceWallMedian = med(&ExperimentView::referenceWallSeconds);
  m.candidateWallMedian = med(&ExperimentView::candidateWallSeconds);
  m.referenceFragments = med(&ExperimentView::referenceFragments);
  m.candidateFragments = med(&ExperimentView::candidateFragments);
  m.referencePrepareMedian = med(&ExperimentView::referencePrepareSeconds);
  m.candidatePrepareMedian = med(&ExperimentView::candidatePrepareSeconds);
  m.referenceRasterMedian = med(&ExperimentView::referenceRasterSeconds);
  m.candidateRasterMedian = med(&ExperimentView::candidateRasterSeconds);
}

TruthSummary summariseTruth(const std::vector<ExperimentView>& views, bool candidate) {
  TruthSummary t;
  std::vector<double> mse, ssim, mad;
  uint64_t bad = 0, covered = 0, badOff = 0, inBand = 0;
  t.minSsim = std::numeric_limits<double>::infinity();
  for (const ExperimentView& v : views) {
    const ImageMetrics& m = candidate ? v.candidateVsTruth : v.referenceVsTruth;
    const uint64_t b = candidate ? v.candidateBadPixels : v.referenceBadPixels;
    const uint64_t c = candidate ? v.coveredPixels : v.referenceCoveredPixels;
    mse.push_back(m.mse);
    ssim.push_back(m.ssim);
    mad.push_back(m.meanAbsDiff);
    t.minSsim = std::min(t.minSsim, m.ssim);
    bad += b;
    badOff += candidate ? v.candidateBadOffSilhouettes : v.referenceBadOffSilhouettes;
    covered += c;
    if (candidate) inBand += v.coveredInSilhouetteBand;
    if (c) t.maxBadFraction = std::max(t.maxBadFraction, double(b) / double(c));
  }
  if (views.empty()) t.minSsim = 0;
  const double meanMse = meanStd(mse).mean;
  t.psnr = meanMse > 0 ? 10 * std::log10(1.0 / meanMse) : std::numeric_limits<double>::infinity();
  t.ssim = meanStd(ssim).mean;
  t.meanAbsDiff = meanStd(mad).mean;
  t.badFraction = covered ? double(bad) / double(covered) : 0.0;
  t.badOffSilhouettesFraction = covered ? double(badOff) / double(covered) : 0.0;
  t.silhouetteBandFraction = covered ? double(inBand) / double(covered) : 0.0;
  return t;
}

/// Pixels covered (alpha > 0) in either image, among them those whose 8-bit colours differ by
/// more than 64 grey levels in any channel, and of those the ones outside `band` (the truth's
/// silhouettes, silhouetteBand).
struct BadPixels {
  uint64_t covered = 0, bad = 0, badOffBand = 0, coveredInBand = 0;
};
BadPixels badPixels(const Image& truth, const Image& truthAlpha, const std::vector<uint8_t>& band, const Image& img,
                    const Image& imgAlpha) {
  BadPixels r;
  auto q = [](float v) { return int(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f)); };
  for (size_t i = 0; i < truth.pixels.size(); ++i) {
    if (!(truthAlpha.pixels[i].w() > 0) && !(imgAlpha.pixels[i].w() > 0)) continue;
    ++r.covered;
    r.coveredInBand += band[i];
    for (int c = 0; c < 3; ++c)
      if (std::abs(q(truth.pixels[i][c]) - q(img.pixels[i][c])) > 64) {
        ++r.bad;
        if (!band[i]) ++r.badOffBand;
        break;
      }
  }
  return r;
}

double dataReduction(size_t referencePoints, size_t points, size_t segments) {
  return referencePoints ? 1.0 - (6.0 * double(points) + 9.0 * double(segments)) / (6.0 * double(referencePoints)) : 0.0;
}

/// Progress within one model, mapped onto the whole run.
/// Never goes backwards: library stages that share a range (clustering, then extraction) restart at 0.
struct ModelProgress {
  const ProgressFn* fn;
  std::string name;
  size_t index, count;
  std::shared_ptr<double> last = std::make_shared<double>(0.0);
  void operator()(const std::string& step, double local) const {
    if (!*fn) return;
    const double f = (double(index) + std::clamp(local, 0.0, 1.0)) / double(std::max<size_t>(count, 1));
    *last = std::max(*last, f);
    (*fn)(name + ": " + step, *last);
  }
  /// A ProgressFn for a library stage occupying [lo, hi) of this model's work.
  ProgressFn sub(const std::string& step, double lo, double hi) const {
    if (!*fn) return {};
    ModelProgress self = *this;
    return [self, step, lo, hi](std::string_view, double f) { self(step, lo + (hi - lo) * std::clamp(f, 0.0, 1.0)); };
  }
};

/// One candidate model rendered against the reference.
struct Candidate {
  MethodResult* result;
  std::unique_ptr<HybridModel> model;
  std::unique_ptr<Renderer> renderer;
};

/// CPU time of the whole process (every thread), seconds.
double processCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

std::string viewName(int v) { return fmt::format("view_{:03d}", v); }

/// Renders the reference and every candidate from the views, interleaved per view so that the
/// timings see the same machine state; writes the first imageViews images when outDir is set.
void renderAndCompare(const ExperimentOptions& o, ModelResult& model, const HybridModel& reference,
                      std::vector<Candidate>& candidates, int views, const ModelProgress& progress, double lo,
                      double hi, const TriangleMesh* truthMesh = nullptr) {
  const int size = o.size;
  const BoundingSphere sphere = boundingSphere(reference);
  const std::vector<Camera> cams = Camera::spreadViews(sphere, views, size, size);
  // With a ground truth, every image also gets its coverage (alpha; the colours are unchanged).
  RenderOptions ro = o.render;
  if (truthMesh) ro.alphaBuffer = true;
  Renderer ref(reference, ro);
  for (Candidate& c : candidates) c.renderer = std::make_unique<Renderer>(*c.model, ro);
  std::unique_ptr<MeshRenderer> truth;
  if (truthMesh) {
    MeshRenderOptions mo;
    mo.supersampling = o.groundTruthSupersampling;
    RenderOptions to = ro;
    to.depthBuffer = true;  // for the silhouette band of the > 64 count
    truth = std::make_unique<MeshRenderer>(*truthMesh, to, mo);
  }
  const bool images = !o.outDir.empty();
  const fs::path modelDir = o.outDir / model.name;
  if (images && o.imageViews > 0) {
    // A fresh folder per model: in a transaction it replaces an earlier run's only at commit.
    makeOutputFolder(modelDir, true);
    for (Candidate& c : candidates) makeOutputFolder(modelDir / experimentMethodName(c.result->method));
  }
  for (int v = 0; v < int(cams.size()); ++v) {
    progress(fmt::format("rendering view {}/{}", v + 1, cams.size()), lo + (hi - lo) * double(v) / double(cams.size()));
    Timer tr;
    double cpu0 = processCpuSeconds();
    RenderResult rr = ref.render(cams[size_t(v)]);
    const double refCpu = processCpuSeconds() - cpu0, refWall = tr.seconds();
    const bool keep = images && v < o.imageViews;
    if (keep) {
      const std::string rel = model.name + "/" + viewName(v) + "_points.png";
      writePng(o.outDir / rel, rr.color, false);
      model.referenceImages.push_back(rel);
    }
    std::optional<MeshRenderResult> meshImg;
    std::vector<uint8_t> band;
    if (truth) {
      meshImg = truth->render(cams[size_t(v)]);
      // an inner silhouette: a depth step between neighbours steeper than a surface turned 80 degrees
      // from the camera would make (tan 80 = 5.67 pixel footprints, depth / focal length, per pixel)
      band = silhouetteBand(*meshImg->alpha, *meshImg->depth, 1, 5.67 / double(cams[size_t(v)].focalPixels()));
      if (keep) {
        const std::string rel = model.name + "/" + viewName(v) + "_mesh.png";
        writePng(o.outDir / rel, meshImg->color, false);
        model.truthImages.push_back(rel);
      }
    }
    for (Candidate& c : candidates) {
      Timer tc;
      cpu0 = processCpuSeconds();
      RenderResult rc = c.renderer->render(cams[size_t(v)]);
      ExperimentView ev;
      ev.candidateSeconds = processCpuSeconds() - cpu0;
      ev.candidateWallSeconds = tc.seconds();
      ev.referenceSeconds = refCpu;
      ev.referenceWallSeconds = refWall;
      ev.referenceFragments = rr.stats.fragments;
      ev.candidateFragments = rc.stats.fragments;
      ev.referencePrepareSeconds = rr.stats.prepareSeconds;
      ev.candidatePrepareSeconds = rc.stats.prepareSeconds;
      ev.referenceRasterSeconds = rr.stats.rasterSeconds;
      ev.candidateRasterSeconds = rc.stats.rasterSeconds;
      ev.metrics = compareImages(rr.color, rc.color);
      if (meshImg) {
        ev.hasTruth = true;
        ev.candidateVsTruth = compareImages(meshImg->color, rc.color);
        ev.referenceVsTruth = compareImages(meshImg->color, rr.color);
        const BadPixels bc = badPixels(meshImg->color, *meshImg->alpha, band, rc.color, *rc.alpha);
        const BadPixels br = badPixels(meshImg->color, *meshImg->alpha, band, rr.color, *rr.alpha);
        ev.coveredPixels = bc.covered;
        ev.candidateBadPixels = bc.bad;
        ev.candidateBadOffSilhouettes = bc.badOffBand;
        ev.coveredInSilhouetteBand = bc.coveredInBand;
        ev.referenceCoveredPixels = br.covered;
        ev.referenceBadPixels = br.bad;
        ev.referenceBadOffSilhouettes = br.badOffBand;
      }
      c.result->views.push_back(ev);
      if (keep) {
        const std::string base = model.name + "/" + experimentMethodName(c.result->method) + "/" + viewName(v);
        writePng(o.outDir / (base + ".png"), rc.color, false);
        writePng(o.outDir / (base + "_diff.png"), differenceHeatmap(rr.color, rc.color), false);
        c.result->images.push_back(base + ".png");
        c.result->diffImages.push_back(base + "_diff.png");
      }
    }
  }
  for (Candidate& c : candidates) {
    c.renderer.reset();
    summarise(*c.result);
    if (truth) {
      c.result->hasTruth = true;
      c.result->candidateTruth = summariseTruth(c.result->views, true);
      c.result->referenceTruth = summariseTruth(c.result->views, false);
    }
  }
  // Which primitives are segments: the candidate from the first view, points grey, segments orange.
  if (images && o.imageViews > 0 && !cams.empty())
    for (Candidate& c : candidates) {
      HybridModel painted = *c.model;
      painted.texture.reset();
      painted.attributes.colors = true;
      for (Point& p : painted.points) p.color = Color(0.75f, 0.75f, 0.75f, 1);
      for (Segment& s : painted.segments) s.color = Color(1.0f, 0.45f, 0.1f, 1);
      const std::string rel = model.name + "/" + experimentMethodName(c.result->method) + "/structure.png";
      writePng(o.outDir / rel, renderImage(painted, cams.front(), o.render).color, false);
      c.result->structureImage = rel;
    }
  // Interactive viewer pages (linesurf view) beside the images, linked from the report's rows;
  // a model over the viewer's primitive budget gets no page (and no link), not a failure.
  if (images && o.imageViews > 0) {
    ViewerPageOptions vo;
    vo.render = o.render;
    auto fits = [&](const HybridModel& m) { return m.points.size() + m.segments.size() <= vo.maxPrimitives; };
    vo.name = model.name + " (points)";
    if (fits(reference)) {
      model.referenceViewer = model.name + "/points.html";
      writeViewerPage(o.outDir / model.referenceViewer, reference, vo);
    }
    for (Candidate& c : candidates) {
      if (!fits(*c.model)) continue;
      vo.name = model.name + " (" + experimentMethodName(c.result->method) + ")";
      c.result->viewerPage = model.name + "/" + experimentMethodName(c.result->method) + "/viewer.html";
      writeViewerPage(o.outDir / c.result->viewerPage, *c.model, vo);
    }
  }
}

bool isPointMethod(ExperimentMethod m) { return m != ExperimentMethod::Contour; }

/// The surface error of each candidate against the reference `makeReference` builds; a cloud,
/// mesh or model the surface refuses gets a note, not a failed model (the refusals are
/// BadParameter errors, which would stop the whole run).
void measureSurfaces(const std::function<SurfaceErrorReference()>& makeReference, std::vector<Candidate>& candidates) {
  std::optional<SurfaceErrorReference> reference;
  try {
    reference.emplace(makeReference());
  } catch (const OptionError&) {
    throw;
  } catch (const Error& e) {
    for (Candidate& c : candidates) c.result->notes.push_back(std::string("no surface error: ") + e.what());
    return;
  }
  for (Candidate& c : candidates) {
    Timer t;
    try {
      c.result->surface = reference->measure(*c.model);
    } catch (const OptionError&) {
      throw;
    } catch (const Error& e) {
      c.result->notes.push_back(std::string("no surface error: ") + e.what());
    }
    c.result->surfaceSeconds = t.seconds();
  }
}

void runPointCloud(const ExperimentOptions& o, const fs::path& file, ModelResult& model, const ModelProgress& progress) {
  progress("reading", 0);
  Timer t;
  HybridModel cloud = readModel(file);
  model.loadSeconds = t.seconds();
  cloud.segments.clear();  // a hybrid file is taken as the point cloud of its points
  cloud.segmentProperties.clear();
  cloud.provenance.clear();
  model.inputPoints = cloud.points.size();
  if (cloud.points.size() < 4)
    throwBadInput(file.string(), "", fmt::format("{} points: a point cloud needs at least 4", cloud.points.size()));

  t.reset();
  GeometryOptions go = o.geometry;
  go.delaunayNeighbours = true;  // both extraction methods need stages 3 and 4
  go.curvature = true;
  go.progress = progress.sub("geometry (§6.1)", 0.02, 0.15);
  const PointGeometry geo = computePointGeometry(cloud, go);
  applyGeometry(cloud, geo);  // normals and radii for the point model (the reference)
  model.geometrySeconds = t.seconds();
  model.averageSpacing = geo.averageSpacing;

  std::vector<ExperimentMethod> methods;
  for (ExperimentMethod m : o.effectiveMethods())
    if (isPointMethod(m)) methods.push_back(m);
  model.methods.resize(methods.size());
  std::vector<Candidate> candidates;
  std::vector<std::pair<size_t, HybridModel>> clusterPictures;
  for (size_t i = 0; i < methods.size(); ++i) {
    MethodResult& r = model.methods[i];
    r.method = methods[i];
    r.referencePoints = cloud.points.size();
    const double lo = 0.15 + 0.25 * double(i) / double(methods.size()), hi = 0.15 + 0.25 * double(i + 1) / double(methods.size());
    auto hybrid = std::make_unique<HybridModel>();
    Timer te;
    if (r.method == ExperimentMethod::EpsDelta) {
      EpsDeltaOptions eo = o.epsDelta;
      eo.provenance = false;
      eo.progress = progress.sub("eps-delta extraction (§3.1)", lo, hi);
      EpsDeltaStats st;
      *hybrid = extractEpsDelta(cloud, geo, eo, &st);
      r.notes.push_back(fmt::format("epsilon = {:.4g} (object units), delta = {}", st.epsilon, st.delta));
    } else if (r.method == ExperimentMethod::CurvatureLines) {
      CurvatureLineOptions co = o.curvatureLines;
      co.provenance = false;
      co.progress = progress.sub("curvature-lines extraction (§9.2)", lo, hi);
      CurvatureLineStats st;
      *hybrid = extractCurvatureLines(cloud, geo, co, &st);
      r.notes.push_back(fmt::format("{} chains, mean chain length {:.1f} spacings, mean d_sep {:.2f} spacings; "
                                    "data reduction with shared chain endpoints {:.1f}%",
                                    st.lines, st.meanChainLength() / st.averageSpacing, st.meanSeparation / st.averageSpacing,
                                    100 * st.chainDataReduction()));
    } else {
      ShapeApproxOptions so = o.shapeApprox;
      so.provenance = false;
      so.method = r.method == ExperimentMethod::ShapeGreedy ? ClusteringMethod::Greedy : ClusteringMethod::Hierarchical;
      const double mid = 0.5 * (lo + hi);
      so.clustering.progress = progress.sub(std::string(experimentMethodName(r.method)) + " clustering (§3.2.3)", lo, mid);
      so.progress = progress.sub(std::string(experimentMethodName(r.method)) + " extraction (§3.2.4)", mid, hi);
      const Clustering clustering = clusterShapeApprox(geo, so);
      ShapeApproxStats st;
      *hybrid = extractShapeApprox(cloud, geo, clustering, so, &st);
      r.clusters = clustering.size();
      r.largeClusters = st.largeClusters;
      r.largeClusterPoints = st.largeClusterPoints;
      if (st.degenerateClusters) r.notes.push_back(fmt::format("{} degenerate clusters kept as points", st.degenerateClusters));
      if (!o.outDir.empty() && o.imageViews > 0) clusterPictures.emplace_back(i, colorByCluster(cloud, geo, clustering));
    }
    r.extractSeconds = te.seconds();
    r.points = hybrid->points.size();
    r.segments = hybrid->segments.size();
    r.dataReduction = dataReduction(r.referencePoints, r.points, r.segments);
    candidates.push_back({&r, std::move(hybrid), nullptr});
  }

  if (o.surfaceError) {
    progress("surface error", 0.4);
    measureSurfaces([&] { return SurfaceErrorReference(cloud, o.surface, geo.averageSpacing); }, candidates);
  }
  renderAndCompare(o, model, cloud, candidates, o.views, progress, 0.4, 0.98);

  // Clusters pictures (thesis Figure 22) from the first view, same camera as the comparisons.
  if (!clusterPictures.empty()) {
    const Camera cam = Camera::spreadViews(boundingSphere(cloud), 1, o.size, o.size).front();
    for (auto& [i, picture] : clusterPictures) {
      MethodResult& r = model.methods[i];
      const std::string rel = model.name + "/" + experimentMethodName(r.method) + "/clusters.png";
      makeOutputFolder((o.outDir / rel).parent_path());
      writePng(o.outDir / rel, renderImage(picture, cam, o.render).color, false);
      r.clustersImage = rel;
    }
  }
}

void runMesh(const ExperimentOptions& o, const fs::path& file, ModelResult& model, const ModelProgress& progress) {
  progress("reading", 0);
  Timer t;
  const TriangleMesh mesh = readMesh(file);
  model.loadSeconds = t.seconds();
  model.inputPoints = mesh.positions.size();
  model.faces = mesh.faces.size();
  if (mesh.faces.empty()) throwBadInput(file.string(), "", "the mesh has no faces");

  model.methods.resize(1);
  MethodResult& r = model.methods[0];
  r.method = ExperimentMethod::Contour;
  // The pure line model and the pure point model of Table 5, cut by the same planes.
  ContourOptions co = o.contour;
  co.recordFaces = false;
  co.pointsBelow = 0;
  co.allPoints = false;
  co.progress = progress.sub("contour lines (§3.3)", 0.05, 0.2);
  Timer te;
  ContourStats lineStats;
  auto lines = std::make_unique<HybridModel>(extractContour(mesh, co, &lineStats));
  r.extractSeconds = te.seconds();
  co.allPoints = true;
  co.progress = progress.sub("contour points (§3.3)", 0.2, 0.3);
  ContourStats pointStats;
  const HybridModel points = extractContour(mesh, co, &pointStats);
  r.referencePoints = points.points.size();
  r.points = lines->points.size();
  r.segments = lines->segments.size();
  r.dataReduction = dataReduction(r.referencePoints, r.points, r.segments);
  r.notes.push_back(fmt::format("plane spacing d = {:.4g} (mean edge {:.4g}), radius {:.4g}; {} degenerate faces; points {}",
                                lineStats.spacing, lineStats.meanEdgeLength, lineStats.radius,
                                lineStats.degenerateTriangles,
                                pointMasses(points) ? "weigh the contour length they stand for (masses)" : "are unit splats"));
  std::vector<Candidate> candidates;
  candidates.push_back({&r, std::move(lines), nullptr});
  if (o.surfaceError) {
    progress("surface error", 0.3);
    measureSurfaces([&] { return SurfaceErrorReference(mesh, o.surface); }, candidates);
  }
  renderAndCompare(o, model, points, candidates, o.meshViews, progress, 0.3, 0.98, o.groundTruth ? &mesh : nullptr);
}

}  // namespace

std::vector<std::filesystem::path> experimentModelFiles(const ExperimentOptions& options) { return listModels(options); }

ExperimentResults runExperiment(const ExperimentOptions& options, const ProgressFn& progress) {
  options.validate();
  Timer total;
  ExperimentResults results;
  results.options = options;
  results.options.geometry.progress = {};
  results.options.epsDelta.progress = {};
  results.options.shapeApprox.progress = {};
  results.options.shapeApprox.clustering.progress = {};
  results.options.contour.progress = {};
  results.options.render.progress = {};
  results.threads = currentThreadCount();
  const std::vector<fs::path> files = listModels(options);
  if (!options.outDir.empty()) makeOutputFolder(options.outDir);

  std::vector<ExperimentMethod> methods = options.effectiveMethods();
  const bool anyPointMethod = std::any_of(methods.begin(), methods.end(), isPointMethod);
  const bool meshMethod = std::find(methods.begin(), methods.end(), ExperimentMethod::Contour) != methods.end();

  for (size_t i = 0; i < files.size(); ++i) {
    ModelResult m;
    m.file = files[i].string();
    m.name = files[i].stem().string();
    m.thesisName = thesisModelFor(m.name);
    const ModelProgress mp{&progress, m.name, i, files.size(), std::make_shared<double>(0.0)};
    try {
      m.isMesh = fileHoldsMesh(files[i]);
      if (m.isMesh ? !meshMethod : !anyPointMethod) continue;  // no selected method applies
      if (m.isMesh)
        runMesh(options, files[i], m, mp);
      else
        runPointCloud(options, files[i], m, mp);
    } catch (const Error& e) {
      // An invalid option fails every model: refuse it. An output that cannot be written (a full
      // disk) is no fault of the model and would fail the next one too: stop, writing nothing.
      if (e.kind() == Error::Kind::BadParameter || e.kind() == Error::Kind::Io) throw;
      m.failed = true;
      m.error = e.what();
      m.methods.clear();
    } catch (const std::bad_alloc&) {
      m.failed = true;
      m.error = m.file + ": out of memory";
      m.methods.clear();
    } catch (const std::exception& e) {
      m.failed = true;
      m.error = e.what();
      m.methods.clear();
    }
    mp("done", 1);
    results.models.push_back(std::move(m));
  }
  results.totalSeconds = total.seconds();
  return results;
}

}  // namespace linesurf
