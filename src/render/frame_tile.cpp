// Stages 3 and 4 of a frame (frame.h) for one screen tile: its primitives rasterised into the
// modified Z^3 buffer (thesis §6.2.3, z3_buffer.h) in bin order, then its pixels resolved back to
// front over the background. Each tile writes only its own pixels.
#include <algorithm>
#include <cmath>
#include <memory>

#include "cpu_time.h"
#include "frame.h"
#include "resolve.h"

namespace linesurf::detail {

namespace {

// Stage 3 reads each tile's primitives in bin order, which visits their prepared records in index
// order with gaps (cold lines; a segment's record spans several): a batch's successors are
// fetched while it is drawn (see docs/decisions.md, "Segment records").
void prefetchPrimitive(uint32_t ref, size_t pointSlots, size_t lodBase, const PreparedPoint* pts,
                       const PreparedSegment* segs, const PreparedPoint* lodPts) {
  const char* a;
  size_t bytes;
  if (ref < pointSlots) a = reinterpret_cast<const char*>(pts + ref), bytes = sizeof(PreparedPoint);
  else if (ref >= lodBase) a = reinterpret_cast<const char*>(lodPts + (ref - lodBase)), bytes = sizeof(PreparedPoint);
  else a = reinterpret_cast<const char*>(segs + (ref - pointSlots)), bytes = kSegmentHotBytes;  // its hot lines
  for (size_t o = 0; o < bytes; o += 64) __builtin_prefetch(a + o);
}

/// Stage 3: the tile's primitives (bins tileStart[tile] .. tileStart[tile + 1]) into ctx.tile, in
/// bin order: runs of points in one call each, segments in batches of consecutive references.
void rasterizeTile(size_t tile, const FramePlan& plan, const FrameBuffers& buf, const SplatContext& ctx) {
  const uint32_t* const refs = buf.refs.data();
  const size_t pointSlots = plan.pointSlots, lodBase = plan.lodBase;
  const PointSlots pointOut = buf.pointSlots(), lodOut = buf.lodSlots();
  const PreparedSegment* const segs = buf.segs.data();
  const size_t kEnd = buf.tileStart[tile + 1];
  for (size_t k = buf.tileStart[tile]; k < kEnd;) {
    const uint32_t p = refs[k];
    if (p < pointSlots) {  // a run of points: one call (their records fetched ahead there)
      size_t e = k + 1;
      while (e < kEnd && refs[e] < pointSlots) ++e;
      rasterizePoints(pointOut, refs + k, int(e - k), ctx);
      k = e;
      continue;
    }
    if (p >= lodBase) {  // a run of segments drawn as points: their slots in the lod* arrays
      uint32_t lodRefs[256];
      int n = 0;
      for (; k < kEnd && n < 256 && refs[k] >= lodBase; ++k) lodRefs[n++] = uint32_t(refs[k] - lodBase);
      rasterizePoints(lodOut, lodRefs, n, ctx);
      continue;
    }
    // segments in batches of consecutive references (their rows' spans found together), the
    // next batch's records fetched meanwhile
    const PreparedSegment* batch[kRasterBatch];
    int n = 0;
    for (; k < kEnd && n < kRasterBatch && refs[k] >= pointSlots && refs[k] < lodBase; ++k) {
      if (k + kRasterBatch < kEnd)
        prefetchPrimitive(refs[k + kRasterBatch], pointSlots, lodBase, pointOut.hot, segs, buf.lodPts.data());
      batch[n++] = &segs[refs[k] - pointSlots];
    }
    rasterizeSegments(batch, n, ctx);
  }
}

/// Stage 4: the tile's pixels resolved into the targets. Pixels with one layer (nearly all) in
/// SIMD rows (resolve.h) unless lighting is deferred or another buffer is written; the rest pixel
/// by pixel (Z3Tile::resolve). Silhouette coverage keeps the partly covered front layers as
/// candidates (silhouette_coverage.h), tail coverage the tail-only pixels (tail_coverage.h).
void resolveTile(size_t tile, const FramePlan& plan, const FrameContext& frame, FrameBuffers& buf, Z3Tile& z3,
                 const FrameTargets& out) {
  const RenderOptions& opt = frame.opt();
  const Camera& cam = frame.cam();
  const PixelRect rect = z3.rect();
  Image& color = *out.color;
  const Color bg = opt.background;
  const bool simdResolve = !opt.perPixelLighting && !out.depth && !out.alpha && !out.normal;
  const float bgRGBA[4] = {bg.x(), bg.y(), bg.z(), bg.w()};
  const int32_t* layerCounts = z3.counts();
  std::vector<SilhouettePixel>* cands = plan.silhouettes ? &buf.silhouette[tile] : nullptr;
  if (cands) cands->clear();
  std::vector<TailPixel>* tailPx = out.covered ? &buf.tailPixels[tile] : nullptr;
  if (tailPx) tailPx->clear();
  // per-pixel lighting is deferred: each layer lit once, with its blended normal, at the pixel's
  // ray and the layer's depth; otherwise the fragments carry Gouraud colours (keep)
  auto shadeAt = [&](int x, int y) {
    return [&frame, ray = cam.rayThrough(float(x) + 0.5f, float(y) + 0.5f)](const Vec3f& albedo, const Vec3f& n, float depth) {
      const float nn = n.norm();
      return frame.shade(albedo, nn > 0 ? Vec3f(n / nn) : Vec3f(0, 0, 1), depth * ray);
    };
  };
  auto keep = [](const Vec3f& c, const Vec3f&, float) { return c; };
  for (int y = rect.y0; y < rect.y1; ++y) {
    bool others = true;  // pixels with several layers before `done`
    float* rowZ = out.frontZ ? out.frontZ + size_t(y) * size_t(cam.width()) : nullptr;
    const int done = simdResolve ? resolveSingleLayerRow(z3, y, rect.x0, rect.width(), bgRGBA, color.at(rect.x0, y).data(),
                                                         others, rowZ ? rowZ + rect.x0 : nullptr, cands)
                                 : 0;
    const int32_t* rowCounts = layerCounts + z3.index(rect.x0, y);
    for (int x = others ? rect.x0 : rect.x0 + done; x < rect.x1; ++x) {
      const int layers = rowCounts[x - rect.x0];
      if (x - rect.x0 < done && layers <= 1) continue;  // written by the SIMD row
      if (layers == 0) {
        color.at(x, y) = bg;
        if (rowZ) rowZ[x] = INFINITY;
        continue;
      }
      const auto shade = shadeAt(x, y);
      // at silhouettes only: the front layer opaque here, its coverage kept as a candidate
      const bool opaqueFront = rowZ && z3.frontAlpha(x, y) < 1.0f;
      const ResolvedPixel px = opt.perPixelLighting ? z3.resolve(x, y, shade, opaqueFront) : z3.resolve(x, y, keep, opaqueFront);
      if (rowZ) rowZ[x] = px.depth;
      if (opaqueFront) {
        const ResolvedPixel pc = opt.perPixelLighting ? z3.resolve(x, y, shade) : z3.resolve(x, y);
        const Color c = overBackground(pc.color, bg);
        cands->push_back({uint32_t(x), uint32_t(y), z3.frontThreshold(x, y), {c.x(), c.y(), c.z(), c.w()}, pc.color.w()});
      }
      const float a = px.color.w();
      color.at(x, y) = overBackground(px.color, bg);
      if (out.depth) out.depth->at(x, y) = Color(px.depth, px.depth, px.depth, 1);
      if (out.alpha) out.alpha->at(x, y) = Color(a, a, a, a);
      if (out.normal)
        out.normal->at(x, y) = Color(0.5f * (px.normal.x() + 1), 0.5f * (px.normal.y() + 1), 0.5f * (px.normal.z() + 1), 1);
    }
    if (tailPx)
      collectTailPixels(z3, rect, y, rowCounts, out.covered + size_t(y) * size_t(cam.width()) + rect.x0, plan.tailScale,
                        *tailPx);
  }
  if (cands)
    keepSilhouetteCandidates(*cands, rect, out.frontZ, cam.width(), cam.height(), opt.coverageReach, [&](int x, int y) {
      return opt.perPixelLighting ? z3.resolveBehind(x, y, shadeAt(x, y)) : z3.resolveBehind(x, y, keep);
    });
}

}  // namespace

TileReport renderTile(size_t tile, const FramePlan& plan, const FrameContext& frame, FrameBuffers& buf,
                      const FrameTargets& out) {
  const RenderOptions& opt = frame.opt();
  const PixelRect rect = plan.tileRect(tile, frame.cam().width(), frame.cam().height());
  thread_local std::unique_ptr<Z3Tile> buffer;
  if (!buffer || buffer->layers() != opt.layers)
    buffer = std::make_unique<Z3Tile>(rect, opt.layers);
  else buffer->reset(rect);
  Z3Tile& z3 = *buffer;
  z3.setBlendNormals(opt.perPixelLighting || opt.normalBuffer);
  z3.setCoverageScale(plan.coverageScale);
  z3.setCoverageOccludes(!plan.silhouettes);  // at silhouettes only: an opaque frame's layers
  z3.setTailLayers(plan.tailsOn);  // (Z3Tile: an opaque frame)
  const SplatContext ctx{frame, rect, z3};
  TileReport report;
  const double t0 = threadCpuSeconds();
  rasterizeTile(tile, plan, buf, ctx);
  const double t1 = threadCpuSeconds();
  report.rasterSeconds = t1 - t0;
  resolveTile(tile, plan, frame, buf, z3, out);
  report.counters = z3.counters();
  report.resolveSeconds = threadCpuSeconds() - t1;
  return report;
}

}  // namespace linesurf::detail
