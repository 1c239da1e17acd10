// Stage 1 of a frame (frame.h): every primitive prepared in parallel and counted per tile (thesis
// §6.2: culling, transform, warping, clipping, lighting; points §4.2.2, segments §5).
#include <algorithm>
#include <atomic>
#include <bit>
#include <cstdint>
#include <mutex>

#include "cpu_time.h"
#include "frame.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"

namespace linesurf::detail {

namespace {

/// What the prepare stage did with a batch of segments (RenderStats' segment counters).
struct SegmentSetupCounts {
  uint64_t drawn = 0;  ///< clipped ones included
  uint64_t clipped = 0, culled = 0, outside = 0, degenerate = 0;
  uint64_t fallback = 0;  ///< Approx construction failed, drawn with ScreenSpace
  uint64_t lod = 0;       ///< drawn as one point splat (RenderOptions::segmentLod)
  SegmentSetupCounts& operator+=(const SegmentSetupCounts& o) {
    drawn += o.drawn, clipped += o.clipped, culled += o.culled, outside += o.outside, degenerate += o.degenerate;
    fallback += o.fallback, lod += o.lod;
    return *this;
  }
};

/// Makes room in `buf` for the frame's slots and clears the per-chunk counts.
void reserveFrame(const FramePlan& plan, FrameBuffers& buf) {
  const size_t pointSlots = plan.pointSlots, ns = plan.ns;
  buf.pts.reserve(pointSlots);
  buf.pointBounds.reserve(pointSlots);
  buf.pointCold.reserve(pointSlots);
  buf.gouraud.reserve(pointSlots);
  if (buf.pointTiles.size() < pointSlots) buf.pointTiles.resize(pointSlots);
  if (buf.segs.size() < ns) buf.segs.resize(ns);
  buf.segStatus.resize(ns);
  if (buf.segTiles.size() < ns) buf.segTiles.resize(ns);
  if (plan.lod) {
    if (buf.segLod.size() < ns) buf.segLod.resize(ns);
    buf.lodPts.reserve(ns);
    buf.lodBounds.reserve(ns);
    buf.lodCold.reserve(ns);
    buf.lodGouraud.reserve(ns);
  }
  buf.counts.assign(plan.chunks * plan.tiles, 0);
  buf.chunkVisible.assign(plan.pointChunks, 0);
  buf.chunkCounts.assign(plan.pointChunks, PointSetupCounts{});
  buf.chunkSeconds.assign(plan.chunks, 0.0);
}

/// The points, chunk by chunk in parallel: a chunk's visible points densely into its slots (in
/// primitive order, with their coverage constants as alpha when coverage alpha is on), and their
/// tiles counted in the chunk's bins.
void preparePointChunks(const FramePlan& plan, const FrameContext& frame, const HybridModel& model,
                        const ModelFacts& facts, FrameBuffers& buf) {
  const size_t np = plan.np, tiles = plan.tiles, chunkPoints = plan.chunkPoints;
  PreparedPoint* const pts = buf.pts.data();
  const PixelRect* const pointBounds = buf.pointBounds.data();
  const PointSlots pointOut = buf.pointSlots();
  TileSpan* const spans = buf.pointTiles.data();
  const bool coverage = plan.coverage;
  const float invC = plan.invC;
  const float* const covC = facts.coverage;
  const PointSetupFrame setup = pointSetupFrame(frame);
  parallelFor(0, plan.pointChunks, [&](size_t c) {
    const double t0 = threadCpuSeconds();
    uint32_t* cnt = buf.counts.data() + c * tiles;
    const size_t base = c * chunkPoints;
    size_t k = base;
    for (size_t i = base, e = std::min(np, base + chunkPoints); i < e; i += kSetupBatch) {
      const int n = preparePoints(model.points.data(), uint32_t(i), int(std::min<size_t>(kSetupBatch, e - i)),
                                  frame, setup, pointOut + k, buf.chunkCounts[c]);
      if (coverage)
        for (size_t j = k; j < k + size_t(n); ++j) pts[j].color[3] = covC[pointOut.cold[j].index] * invC;
      for (size_t j = k; j < k + size_t(n); ++j) plan.countSpan(cnt, spans[j] = plan.tileSpan(pointBounds[j]));
      k += size_t(n);
    }
    buf.chunkVisible[c] = uint32_t(k - base);
    buf.chunkSeconds[c] = threadCpuSeconds() - t0;
  }, 1);
}

/// The segments, in parallel ranges of batches: prepared (segment_setup.h), their statuses counted
/// and the tiles of the visible ones taken (and the short ones turned into point splats, segment
/// level of detail) while their records are in the cache: counting and binning then read only
/// segStatus and segTiles, not the records. Returns the counters; the thread time to `seconds`.
SegmentSetupCounts prepareSegmentRanges(const FramePlan& plan, const FrameContext& frame, const HybridModel& model,
                                        const ModelFacts& facts, FrameBuffers& buf, double& seconds) {
  const size_t np = plan.np, ns = plan.ns;
  PreparedSegment* const segs = buf.segs.data();
  PrimitiveStatus* const segStatus = buf.segStatus.data();
  TileSpan* const segTiles = buf.segTiles.data();
  uint8_t* const segLod = plan.lod ? buf.segLod.data() : nullptr;
  const PointSlots lodOut = buf.lodSlots();
  const bool coverage = plan.coverage, lod = plan.lod;
  const float invC = plan.invC;
  const float* const covC = facts.coverage;
  const float maxLambda = frame.opt().segmentLod;
  std::atomic<int64_t> segmentNs{0};
  std::mutex mutex;
  SegmentSetupCounts total;
  const SegmentSetupFrame segSetup = segmentSetupFrame(frame);
  parallelForRange(0, ns, [&](size_t r0, size_t r1) {
    const double t0 = threadCpuSeconds();
    SegmentSetupCounts n;
    uint64_t byStatus[8] = {};  // counted by status without a branch (a mispredicted one per segment)
    for (size_t i0 = r0; i0 < r1; i0 += kSegmentBatch) {
      const size_t i1 = std::min(r1, i0 + kSegmentBatch);
      prepareSegments(model.segments.data(), uint32_t(i0), i1 - i0, frame, segSetup, segs + i0, segStatus + i0);
      for (size_t i = i0; i < i1; ++i) {
        ++byStatus[uint8_t(segStatus[i]) & 7u];
        if (!visible(segStatus[i])) continue;
        if (coverage) segs[i].attr[Z3Tile::kA] = covC[np + i] * invC;
        n.fallback += segs[i].fallback;
        if (lod && (segLod[i] = segmentLodPoint(segs[i], frame, maxLambda, lodOut + i))) {
          segTiles[i] = plan.tileSpan(lodOut.bounds[i]);
          ++n.lod;
          continue;
        }
        segTiles[i] = plan.tileSpan(segs[i].bounds);
      }
    }
    using PS = PrimitiveStatus;
    n.drawn = byStatus[uint8_t(PS::Drawn)] + byStatus[uint8_t(PS::Clipped)], n.clipped = byStatus[uint8_t(PS::Clipped)];
    n.culled = byStatus[uint8_t(PS::Culled)], n.outside = byStatus[uint8_t(PS::Outside)];
    n.degenerate = byStatus[uint8_t(PS::Degenerate)];
    {
      std::lock_guard<std::mutex> hold(mutex);
      total += n;
    }
    segmentNs += int64_t(1e9 * (threadCpuSeconds() - t0));
  }, 256);
  seconds = 1e-9 * double(segmentNs.load());
  return total;
}

}  // namespace

FramePlan planFrame(const Camera& cam, const RenderOptions& opt, size_t np, size_t ns, const ModelFacts& model) {
  FramePlan p;
  const int T = p.tileSize = opt.tileSize;
  p.tilesX = (cam.width() + T - 1) / T, p.tilesY = (cam.height() + T - 1) / T;
  if (p.tilesX > 65536 || p.tilesY > 65536)
    throwBadOption("tileSize", "too small for this image (at most 65536 tiles a side)");
  p.tiles = size_t(p.tilesX) * size_t(p.tilesY);
  p.np = np, p.ns = ns;
  // the per-chunk tile counts stay small: larger chunks for small tiles
  const size_t chunkBatches = std::max<size_t>(32, (p.tiles / 256) * 32);
  p.chunkPoints = chunkBatches * kSetupBatch;
  p.pointChunks = (np + p.chunkPoints - 1) / p.chunkPoints;
  p.segChunks = (ns + p.segChunkSize - 1) / p.segChunkSize;
  p.chunks = p.pointChunks + p.segChunks;
  p.pointSlots = p.pointChunks * p.chunkPoints;
  p.lodBase = p.pointSlots + ns;
  p.lod = opt.segmentLod > 0 && ns > 0 && p.lodBase + ns <= size_t(UINT32_MAX);
  // bounds are clamped to the view (non-negative): a shift for power-of-two tiles (the default)
  p.tileShift = (T & (T - 1)) == 0 ? std::countr_zero(unsigned(T)) : -1;
  const bool translucent = opt.alphaOverride >= 0 && opt.alphaOverride < 1;
  p.coverage = model.coverageMax > 0 && !translucent && opt.defaultColor.w() >= 1;
  p.coverageScale = p.coverage ? 2 * opt.coverageGain * model.coverageMax : 0.0f;
  p.opaqueFrame = model.opaque && !translucent && opt.defaultColor.w() >= 1;
  p.invC = p.coverage ? 0.5f / model.coverageMax : 0.0f;
  p.silhouettes = p.coverage && opt.coverageReach > 0;
  p.tailsOn = opt.tailLayers && opt.segmentMethod == SegmentMethod::ScreenSpace && p.opaqueFrame && p.coverageScale <= 0;
  p.tailScale = p.tailsOn ? opt.tailCoverage * model.tailCoverageC : 0.0f;
  return p;
}

void prepareFrame(const FramePlan& plan, const FrameContext& frame, const HybridModel& model, const ModelFacts& facts,
                  FrameBuffers& buf, RenderStats& st) {
  Timer t;
  reserveFrame(plan, buf);
  preparePointChunks(plan, frame, model, facts, buf);
  double segmentSeconds = 0;
  const SegmentSetupCounts s = prepareSegmentRanges(plan, frame, model, facts, buf, segmentSeconds);
  for (const PointSetupCounts& c : buf.chunkCounts) {
    st.pointsDrawn += c.drawn + c.clipped;
    st.pointsClipped += c.clipped;
    st.pointsCulled += c.culled;
    st.pointsOutside += c.outside;
    st.pointsDegenerate += c.degenerate;
  }
  st.segmentsDrawn = s.drawn, st.segmentsClipped = s.clipped, st.segmentsCulled = s.culled;
  st.segmentsOutside = s.outside, st.segmentsDegenerate = s.degenerate, st.segmentsFallback = s.fallback;
  st.segmentsLod = s.lod;
  // the visible segments' tiles counted per chunk of segments (after the ranges: fixed chunks)
  const PrimitiveStatus* const segStatus = buf.segStatus.data();
  const TileSpan* const segTiles = buf.segTiles.data();
  parallelFor(0, plan.segChunks, [&](size_t c) {
    uint32_t* cnt = buf.counts.data() + (plan.pointChunks + c) * plan.tiles;
    for (size_t i = c * plan.segChunkSize, e = std::min(plan.ns, i + plan.segChunkSize); i < e; ++i)
      if (visible(segStatus[i])) plan.countSpan(cnt, segTiles[i]);
  }, 1);
  st.prepareThreadSeconds = segmentSeconds;
  for (double c : buf.chunkSeconds) st.prepareThreadSeconds += c;
  st.prepareSeconds = t.seconds();
}

}  // namespace linesurf::detail
