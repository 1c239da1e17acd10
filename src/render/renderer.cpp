// The splatting pipeline of thesis §6.2 (see renderer.h): prepare in parallel, deterministic
// binning to screen tiles, per-tile rasterisation into the modified Z^3 buffer, resolve.
#include "linesurf/render/renderer.h"

#include <algorithm>
#include <ctime>
#include <memory>

#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "detail/splat_rows.h"
#include "point_splat.h"
#include "linesurf/render/segment_splat.h"
#include "linesurf/render/splat_context.h"

namespace linesurf {

Renderer::Renderer(const HybridModel& model, const RenderOptions& options)
    : model_(model), options_(options), sphere_(boundingSphere(model)) {
  validate(options_);
}

const char* renderSimdTarget() { return detail::simdTargetName(); }

RenderResult renderImage(const HybridModel& model, const Camera& camera, const RenderOptions& options) {
  return Renderer(model, options).render(camera);
}

namespace {

void count(PrimitiveStatus s, uint64_t& drawn, uint64_t& clipped, uint64_t& culled, uint64_t& outside,
           uint64_t& degenerate) {
  switch (s) {
    case PrimitiveStatus::Drawn: ++drawn; break;
    case PrimitiveStatus::Clipped: ++drawn; ++clipped; break;
    case PrimitiveStatus::Culled: ++culled; break;
    case PrimitiveStatus::Outside: ++outside; break;
    case PrimitiveStatus::Degenerate: ++degenerate; break;
  }
}

// CPU time of the calling thread (robust against other processes on a shared machine).
double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

bool visible(PrimitiveStatus s) { return s == PrimitiveStatus::Drawn || s == PrimitiveStatus::Clipped; }

}  // namespace

RenderResult Renderer::render(const Camera& cam) const {
  Timer total;
  RenderResult res;
  RenderStats& st = res.stats;
  const RenderOptions& opt = options_;
  FrameContext frame =
      FrameContext::make(cam, opt, sphere_, model_.attributes.colors,
                         model_.attributes.texcoords ? model_.texture.get() : nullptr);
  frame.endpointNormals = model_.attributes.endpointNormals;

  // 1. prepare (per primitive, parallel, each writes its own slot)
  Timer t;
  const size_t np = model_.points.size(), ns = model_.segments.size();
  std::vector<PreparedPoint> pts(np);
  std::vector<PreparedSegment> segs(ns);
  std::vector<PrimitiveStatus> status(np + ns);
  const detail::PointSetupFrame setup = pointSetupFrame(frame);
  const size_t batches = (np + detail::kSetupBatch - 1) / detail::kSetupBatch;
  parallelFor(0, batches, [&](size_t k) {
    const size_t i = k * detail::kSetupBatch;
    preparePoints(model_.points.data(), uint32_t(i), int(std::min<size_t>(detail::kSetupBatch, np - i)), frame, setup,
                  pts.data() + i, status.data() + i);
  }, 16);
  parallelFor(0, ns, [&](size_t i) { status[np + i] = prepareSegment(model_.segments[i], uint32_t(i), frame, segs[i]); }, 256);
  for (size_t i = 0; i < np; ++i)
    count(status[i], st.pointsDrawn, st.pointsClipped, st.pointsCulled, st.pointsOutside, st.pointsDegenerate);
  for (size_t i = 0; i < ns; ++i)
    count(status[np + i], st.segmentsDrawn, st.segmentsClipped, st.segmentsCulled, st.segmentsOutside,
          st.segmentsDegenerate);
  for (size_t i = 0; i < ns; ++i) st.segmentsFallback += segs[i].fallback;
  st.prepareSeconds = t.seconds();
  reportProgress(opt.progress, "render", 0.1);

  // 2. binning: primitive p (points 0..np-1, then segments) goes to every tile its bounds touch.
  // Chunks of a fixed size (not a function of the thread count) count, then fill, so every
  // tile's list is in primitive order.
  t.reset();
  const int T = opt.tileSize;
  const int tilesX = (cam.width() + T - 1) / T, tilesY = (cam.height() + T - 1) / T;
  const size_t tiles = size_t(tilesX) * size_t(tilesY);
  const size_t total_prims = np + ns;
  const size_t chunkSize = 8192;
  const size_t chunks = (total_prims + chunkSize - 1) / chunkSize;
  auto boundsOf = [&](size_t p) -> const PixelRect& { return p < np ? pts[p].bounds : segs[p - np].bounds; };
  auto forTiles = [&](size_t p, auto&& fn) {
    const PixelRect& b = boundsOf(p);
    if (b.empty()) return;
    int tx0 = b.x0 / T, tx1 = (b.x1 - 1) / T, ty0 = b.y0 / T, ty1 = (b.y1 - 1) / T;
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) fn(size_t(ty) * size_t(tilesX) + size_t(tx));
  };
  std::vector<uint32_t> counts(chunks * tiles, 0);
  parallelFor(0, chunks, [&](size_t c) {
    uint32_t* cnt = counts.data() + c * tiles;
    for (size_t p = c * chunkSize, e = std::min(total_prims, p + chunkSize); p < e; ++p)
      if (visible(status[p])) forTiles(p, [&](size_t tile) { ++cnt[tile]; });
  }, 1);
  // offsets: tile-major, chunk-minor
  std::vector<size_t> tileStart(tiles + 1, 0), offset(chunks * tiles, 0);
  size_t run = 0;
  for (size_t tile = 0; tile < tiles; ++tile) {
    tileStart[tile] = run;
    for (size_t c = 0; c < chunks; ++c) {
      offset[c * tiles + tile] = run;
      run += counts[c * tiles + tile];
    }
  }
  tileStart[tiles] = run;
  std::vector<uint32_t> refs(run);
  parallelFor(0, chunks, [&](size_t c) {
    size_t* off = offset.data() + c * tiles;
    for (size_t p = c * chunkSize, e = std::min(total_prims, p + chunkSize); p < e; ++p)
      if (visible(status[p])) forTiles(p, [&](size_t tile) { refs[off[tile]++] = uint32_t(p); });
  }, 1);
  st.tileBins = run;
  st.binSeconds = t.seconds();

  // 3. rasterise + resolve, tiles in parallel; each tile writes only its own pixels
  t.reset();
  res.color = Image(cam.width(), cam.height(), opt.background);
  if (opt.depthBuffer) res.depth = Image(cam.width(), cam.height(), Color(0, 0, 0, 0));
  if (opt.alphaBuffer) res.alpha = Image(cam.width(), cam.height(), Color(0, 0, 0, 0));
  if (opt.normalBuffer) res.normal = Image(cam.width(), cam.height(), Color(0, 0, 0, 0));
  std::vector<Z3Counters> tileCounters(tiles);
  std::vector<std::pair<double, double>> tileSeconds(tiles);  // rasterise, resolve
  const Color bg = opt.background;
  auto doTile = [&](size_t tile) {
    const int tx = int(tile % size_t(tilesX)), ty = int(tile / size_t(tilesX));
    PixelRect rect{tx * T, ty * T, std::min(cam.width(), (tx + 1) * T), std::min(cam.height(), (ty + 1) * T)};
    thread_local std::unique_ptr<Z3Tile> buffer;
    if (!buffer || buffer->layers() != opt.layers)
      buffer = std::make_unique<Z3Tile>(rect, opt.layers);
    else buffer->reset(rect);
    Z3Tile& z3 = *buffer;
    SplatContext ctx{frame, rect, z3};
    const double t0 = threadCpuSeconds();
    for (size_t k = tileStart[tile]; k < tileStart[tile + 1]; ++k) {
      uint32_t p = refs[k];
      if (p < np) rasterizePoint(pts[p], ctx);
      else rasterizeSegment(segs[p - np], ctx);
    }
    const double t1 = threadCpuSeconds();
    tileSeconds[tile].first = t1 - t0;
    for (int y = rect.y0; y < rect.y1; ++y)
      for (int x = rect.x0; x < rect.x1; ++x) {
        if (z3.layerCount(x, y) == 0) continue;
        // per-pixel lighting is deferred: each layer lit once, with its blended normal, at this
        // pixel's ray and the layer's depth; otherwise the fragments carry Gouraud colours
        const Vec3f ray = cam.rayThrough(float(x) + 0.5f, float(y) + 0.5f);
        const ResolvedPixel px =
            opt.perPixelLighting ? z3.resolve(x, y, [&](const Vec3f& albedo, const Vec3f& n, float depth) {
              const float nn = n.norm();
              return frame.shade(albedo, nn > 0 ? Vec3f(n / nn) : Vec3f(0, 0, 1), depth * ray);
            })
                                 : z3.resolve(x, y);
        const float a = px.color.w();
        Color c = px.color;
        c.head<3>() += (1 - a) * bg.w() * bg.head<3>();
        c.w() = a + (1 - a) * bg.w();
        if (bg.w() > 0 && c.w() > 0 && c.w() < 1) c.head<3>() /= c.w();  // straight colour for PNG
        if (bg.w() == 0 && a > 0) c.head<3>() /= a;
        res.color.at(x, y) = c;
        if (res.depth) res.depth->at(x, y) = Color(px.depth, px.depth, px.depth, 1);
        if (res.alpha) res.alpha->at(x, y) = Color(a, a, a, a);
        if (res.normal)
          res.normal->at(x, y) = Color(0.5f * (px.normal.x() + 1), 0.5f * (px.normal.y() + 1), 0.5f * (px.normal.z() + 1), 1);
      }
    tileCounters[tile] = z3.counters();
    tileSeconds[tile].second = threadCpuSeconds() - t1;
  };
  const size_t batch = 64;
  for (size_t b0 = 0; b0 < tiles; b0 += batch) {
    parallelFor(b0, std::min(tiles, b0 + batch), doTile, 1);
    reportProgress(opt.progress, "render", 0.1 + 0.9 * double(std::min(tiles, b0 + batch)) / double(tiles));
  }
  for (const auto& [raster, resolve] : tileSeconds) {
    st.fragmentThreadSeconds += raster;
    st.resolveThreadSeconds += resolve;
  }
  for (const Z3Counters& c : tileCounters) {
    st.fragments += c.fragments;
    st.merged += c.merged;
    st.allocated += c.allocated;
    st.occluded += c.occluded;
    st.compressed += c.compressed;
  }
  st.rasterSeconds = t.seconds();
  st.totalSeconds = total.seconds();
  return res;
}

}  // namespace linesurf
