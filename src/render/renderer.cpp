// The splatting pipeline of thesis §6.2 (see renderer.h), one frame from top to bottom: prepare
// in parallel, deterministic binning to screen tiles, per-tile rasterisation into the modified Z^3
// buffer and resolve, then the beyond-thesis coverage passes. The stages: frame.h.
#include "linesurf/render/renderer.h"

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>

#include <fmt/format.h>

#include "frame.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "coverage.h"
#include "simd_rows.h"

namespace linesurf {

/// Per-frame buffers, kept from one frame to the next (frame.h).
struct Renderer::Buffers : detail::FrameBuffers {};

Renderer::Renderer(const HybridModel& model, const RenderOptions& options)
    : model_(model), options_(options), sphere_(boundingSphere(model)), buffers_(std::make_shared<Buffers>()) {
  validate(options_);
  if (const std::vector<float>* m = pointMasses(model_))
    for (size_t i = 0; i < m->size(); ++i)
      if (!validPointMass((*m)[i]))
        throwBadParameter("pointProperties['mass']",
                          fmt::format("point {} has mass {:g}; masses must be in (0, {:g}]", i, (*m)[i], kMaxPointMass));
  if (model_.attributes.colors) {
    for (const Point& p : model_.points) opaqueModel_ = opaqueModel_ && p.color.w() >= 1;
    for (const Segment& s : model_.segments) opaqueModel_ = opaqueModel_ && s.color.w() >= 1;
  }
  if (model_.attributes.texcoords && model_.texture) opaqueModel_ = false;
  if (options_.coverageGain > 0) {
    if (opaqueModel_) {
      // at silhouettes only: the mean density around each primitive, else the least (coverage.h)
      coverage_ = detail::coverageConstants(model_, options_.reconstructionScale, options_.cutoffRadius,
                                            options_.coverageReach == 0);
      for (float c : coverage_) coverageMax_ = std::max(coverageMax_, c);
    }
  } else if (options_.tailCoverage > 0 && options_.tailLayers && opaqueModel_) {
    tailCoverageC_ = detail::medianCoverageConstant(model_, options_.reconstructionScale, options_.cutoffRadius);
  }
}

const char* renderSimdTarget() { return detail::simdTargetName(); }

RenderResult renderImage(const HybridModel& model, const Camera& camera, const RenderOptions& options) {
  return Renderer(model, options).render(camera);
}

RenderResult Renderer::render(const Camera& cam) const { return render(cam, options_.facingCheck); }

RenderResult Renderer::render(const Camera& cam, bool facingCheck) const {
  RenderResult res = renderFrame(cam, options_);
  if (facingCheck && options_.backfaceCulling) measureFacing(cam, res.stats);
  return res;
}

// Which side of the surface the pixels show (render_stats.h, facing*): the view drawn again at a
// reduced resolution with back faces culled and two-sided, depths compared per pixel. A pixel the
// two-sided render covers shows a back face when the culled render leaves it empty or finds its
// nearest surface more than kFacingDepthTolerance x the bounding radius deeper (the front surface
// was culled and a farther one shows through, as inside an object whose normals point in).
void Renderer::measureFacing(const Camera& cam, RenderStats& st) const {
  Timer t;
  const int longest = std::max(cam.width(), cam.height());
  const double scale = std::min(1.0, double(kFacingCheckSide) / double(longest));
  const int w = std::max(1, int(std::lround(cam.width() * scale))), h = std::max(1, int(std::lround(cam.height() * scale)));
  const Camera small = cam.withViewport(w, h);
  RenderOptions o = options_;
  o.facingCheck = false;
  o.depthBuffer = true;
  o.alphaBuffer = o.normalBuffer = false;
  o.progress = nullptr;
  const RenderResult culled = renderFrame(small, o);
  o.backfaceCulling = false;
  const RenderResult twoSided = renderFrame(small, o);
  const float tol = kFacingDepthTolerance * sphere_.radius;
  for (size_t i = 0; i < twoSided.depth->pixels.size(); ++i) {
    const Color& d2 = twoSided.depth->pixels[i];
    if (!(d2.w() > 0)) continue;
    ++st.facingPixels;
    const Color& d1 = culled.depth->pixels[i];
    if (!(d1.w() > 0)) ++st.facingEmptyPixels, ++st.facingBackPixels;
    else if (d1.x() > d2.x() + tol) ++st.facingBackPixels;
  }
  st.facingSeconds += t.seconds();
}

RenderResult Renderer::renderFrame(const Camera& cam, const RenderOptions& opt) const {
  Timer total;
  RenderResult res;
  RenderStats& st = res.stats;
  FrameContext frame =
      FrameContext::make(cam, opt, sphere_, model_.attributes.colors,
                         model_.attributes.texcoords ? model_.texture.get() : nullptr);
  frame.endpointNormals = model_.attributes.endpointNormals;
  if (model_.attributes.shadingNormals && model_.pointShadingNormals.size() == model_.points.size())
    frame.pointShadingNormals = model_.pointShadingNormals.data();
  if (const std::vector<float>* m = pointMasses(model_)) frame.pointMasses = m->data();
  const detail::ModelFacts facts{coverage_.data(), coverageMax_, tailCoverageC_, opaqueModel_};
  std::unique_lock<std::mutex> lock(buffers_->mutex, std::try_to_lock);
  std::unique_ptr<Buffers> own;  // another render() of this Renderer holds the shared buffers
  detail::FrameBuffers& buf = lock.owns_lock() ? *buffers_ : *(own = std::make_unique<Buffers>());
  const detail::FramePlan plan = detail::planFrame(cam, opt, model_.points.size(), model_.segments.size(), facts);

  // 1. prepare (parallel), counting the tile bins; 2. binning
  detail::prepareFrame(plan, frame, model_, facts, buf, st);
  reportProgress(opt.progress, "render", 0.1);
  detail::binFrame(plan, buf, st);

  // 3. rasterise + 4. resolve, tiles in parallel; each tile writes only its own pixels
  Timer t;
  // the colour image is not filled here (4 MB at 512^2, one thread): each tile writes every pixel
  // of its own, the background where nothing was drawn (Color() leaves the pixels uninitialised)
  res.color.width = cam.width(), res.color.height = cam.height();
  res.color.pixels.resize(size_t(cam.width()) * size_t(cam.height()));
  if (opt.depthBuffer) res.depth = Image(cam.width(), cam.height(), Color(0, 0, 0, 0));
  if (opt.alphaBuffer) res.alpha = Image(cam.width(), cam.height(), Color(0, 0, 0, 0));
  if (opt.normalBuffer) res.normal = Image(cam.width(), cam.height(), Color(0, 0, 0, 0));
  const size_t tiles = plan.tiles;
  detail::FrameTargets out{&res.color, res.depth ? &*res.depth : nullptr, res.alpha ? &*res.alpha : nullptr,
                           res.normal ? &*res.normal : nullptr};
  // coverage at silhouettes only: every pixel resolved with its front layer opaque, the partly
  // covered ones kept with their coverage result until every tile's front depths are known
  if (plan.silhouettes) {
    buf.frontZ.resize(res.color.pixels.size());
    out.frontZ = buf.frontZ.data();
    buf.silhouette.resize(std::max(buf.silhouette.size(), tiles));
  }
  if (plan.tailScale > 0) {  // tail coverage: the tail-only pixels, decided after every tile
    buf.covered.resize(res.color.pixels.size());
    out.covered = buf.covered.data();
    buf.tailPixels.resize(std::max(buf.tailPixels.size(), tiles));
  }
  std::vector<detail::TileReport> reports(tiles);
  const size_t batch = 64;
  for (size_t b0 = 0; b0 < tiles; b0 += batch) {
    parallelFor(b0, std::min(tiles, b0 + batch), [&](size_t tile) { reports[tile] = detail::renderTile(tile, plan, frame, buf, out); }, 1);
    reportProgress(opt.progress, "render", 0.1 + 0.9 * double(std::min(tiles, b0 + batch)) / double(tiles));
  }
  std::vector<double> resolveSeconds(tiles);
  for (size_t tile = 0; tile < tiles; ++tile) resolveSeconds[tile] = reports[tile].resolveSeconds;

  // the beyond-thesis passes over the whole frame
  if (plan.silhouettes)
    detail::compositeSilhouettes(buf.silhouette, tiles, out.frontZ, buf.partial, opt.coverageReach, opt.background,
                                 res.color, out.alpha, resolveSeconds.data());
  if (out.covered) detail::compositeTailPixels(buf.tailPixels, tiles, out.covered, opt.background, res.color, out.alpha);

  for (size_t tile = 0; tile < tiles; ++tile) {
    const detail::TileReport& r = reports[tile];
    st.fragmentThreadSeconds += r.rasterSeconds;
    st.resolveThreadSeconds += resolveSeconds[tile];
    st.fragments += r.counters.fragments;
    st.merged += r.counters.merged;
    st.allocated += r.counters.allocated;
    st.occluded += r.counters.occluded;
    st.compressed += r.counters.compressed;
  }
  st.rasterSeconds = t.seconds();
  st.totalSeconds = total.seconds();
  return res;
}

}  // namespace linesurf
