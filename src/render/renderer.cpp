// The splatting pipeline of thesis §6.2 (see renderer.h): prepare in parallel, deterministic
// binning to screen tiles, per-tile rasterisation into the modified Z^3 buffer, resolve.
#include "linesurf/render/renderer.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstdlib>
#include <ctime>
#include <memory>
#include <mutex>
#include <new>
#include <type_traits>

#include <fmt/format.h>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "coverage.h"
#include "detail/splat_rows.h"
#include "point_setup.h"
#include "point_splat.h"
#include "segment_setup.h"
#include "segment_splat.h"
#include "linesurf/render/splat_context.h"

namespace linesurf {

namespace detail {
/// The screen tiles a primitive touches: columns x0 .. x1, rows y0 .. y1 (inclusive).
struct TileSpan {
  uint16_t x0, y0, x1, y1;
};
}  // namespace detail
using detail::TileSpan;

/// Storage for up to capacity() objects of T that the user constructs slot by slot (placement
/// new; T is trivially destructible): a first frame touches, and so faults in, only the pages of
/// the slots it writes. (Transparent huge pages were tried: direct compaction made the first
/// frame of the dragon 6x slower.)
template <class T>
class SlotBuffer {
  static_assert(std::is_trivially_destructible_v<T>);

 public:
  SlotBuffer() = default;
  SlotBuffer(const SlotBuffer&) = delete;
  SlotBuffer& operator=(const SlotBuffer&) = delete;
  ~SlotBuffer() { std::free(data_); }
  /// Makes room for n slots (the contents are lost when the buffer grows).
  void reserve(size_t n) {
    if (n <= capacity_) return;
    std::free(data_);
    data_ = nullptr, capacity_ = 0;
    const size_t align = std::max<size_t>(64, alignof(T));
    const size_t bytes = (n * sizeof(T) + align - 1) / align * align;
    data_ = static_cast<T*>(std::aligned_alloc(align, bytes));
    if (!data_) throw std::bad_alloc();
    capacity_ = n;
  }
  T* data() const { return data_; }
  size_t capacity() const { return capacity_; }

 private:
  T* data_ = nullptr;
  size_t capacity_ = 0;
};

/// Per-frame buffers, kept from one frame to the next (no allocation, page faults or zeroing of
/// the prepared primitives per frame); one render() at a time uses them, a concurrent one its own.
struct Renderer::Buffers {
  std::mutex mutex;
  SlotBuffer<PreparedPoint> pts;      ///< point slots' hot records: per chunk, its visible points first
  SlotBuffer<PixelRect> pointBounds;  ///< the point slots' screen bounds
  SlotBuffer<PointCold> pointCold;    ///< the point slots' normals and indices
  SlotBuffer<PointGouraud> gouraud;   ///< the Gouraud colours of the point slots that need them
  std::vector<TileSpan> pointTiles;   ///< tiles each point slot touches
  std::vector<PreparedSegment> segs;
  std::vector<PrimitiveStatus> segStatus;
  std::vector<TileSpan> segTiles;     ///< tiles each visible segment touches (dense: binning reads no record)
  /// Segment level of detail (RenderOptions::segmentLod): per segment slot, whether it is drawn as
  /// the point splat in the lod* slots below (same slot), not as a segment
  std::vector<uint8_t> segLod;
  SlotBuffer<PreparedPoint> lodPts;
  SlotBuffer<PixelRect> lodBounds;
  SlotBuffer<PointCold> lodCold;
  SlotBuffer<PointGouraud> lodGouraud;
  std::vector<uint32_t> chunkVisible;
  std::vector<double> chunkSeconds;   ///< thread CPU time per chunk (prepare, then binning)
  std::vector<PointSetupCounts> chunkCounts;
  std::vector<uint32_t> counts;       ///< per chunk and tile: bins
  std::vector<size_t> tileStart, offset;
  std::vector<uint32_t> refs;         ///< tile lists: point slot, or pointSlots + segment index
  /// Coverage at silhouettes only (RenderOptions::coverageReach): the front depths of the frame,
  /// and per tile its partly covered pixels (coverage.h)
  std::vector<float> frontZ;
  std::vector<std::vector<detail::SilhouettePixel>> silhouette;
  std::vector<uint8_t> partial;  ///< 1 where a pixel's front layer is partly covered
  /// Tail coverage (RenderOptions::tailCoverage): 1 where a pixel holds a layer, and per tile its
  /// tail-only pixels with their faded alpha
  std::vector<uint8_t> covered;
  struct TailPixel {
    uint32_t x, y;
    float alpha;
  };
  std::vector<std::vector<TailPixel>> tailPixels;
};

Renderer::Renderer(const HybridModel& model, const RenderOptions& options)
    : model_(model), options_(options), sphere_(boundingSphere(model)), buffers_(std::make_shared<Buffers>()) {
  validate(options_);
  if (const std::vector<float>* m = pointMasses(model_))
    for (size_t i = 0; i < m->size(); ++i)
      if (!validPointMass((*m)[i]))
        throwBadParameter("pointProperties['mass']", fmt::format("point {} has mass {:g}; masses must be in (0, 1e6]", i, (*m)[i]));
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

namespace {

// Stage 3 reads each tile's primitives in bin order; their prepared records are fetched this
// many references ahead (issue 13: contour segments' records missed the cache on every tile).
constexpr size_t kPrefetchAhead = 4;

void prefetchPrimitive(uint32_t ref, size_t pointSlots, size_t lodBase, const PreparedPoint* pts,
                       const PreparedSegment* segs, const PreparedPoint* lodPts) {
  const char* a;
  size_t bytes;
  if (ref < pointSlots) a = reinterpret_cast<const char*>(pts + ref), bytes = sizeof(PreparedPoint);
  else if (ref >= lodBase) a = reinterpret_cast<const char*>(lodPts + (ref - lodBase)), bytes = sizeof(PreparedPoint);
  else a = reinterpret_cast<const char*>(segs + (ref - pointSlots)), bytes = kSegmentHotBytes;  // its hot lines
  for (size_t o = 0; o < bytes; o += 64) __builtin_prefetch(a + o);
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
  if (model_.attributes.shadingNormals && model_.pointShadingNormals.size() == model_.points.size())
    frame.pointShadingNormals = model_.pointShadingNormals.data();
  if (const std::vector<float>* m = pointMasses(model_)) frame.pointMasses = m->data();

  // 1. prepare (parallel) and count the tile bins. Points go in chunks of kChunkBatches batches
  // of detail::kSetupBatch; a chunk writes its visible points densely into its own range of
  // slots (in primitive order) and counts, per tile, the points whose bounds touch it. Chunks
  // are fixed (not a function of the thread count), so the bins below are too. Segments: one
  // slot each, counted after.
  Timer t;
  const size_t np = model_.points.size(), ns = model_.segments.size();
  std::unique_lock<std::mutex> lock(buffers_->mutex, std::try_to_lock);
  std::unique_ptr<Buffers> own;  // another render() of this Renderer holds the shared buffers
  Buffers& buf = lock.owns_lock() ? *buffers_ : *(own = std::make_unique<Buffers>());
  const int T = opt.tileSize;
  const int tilesX = (cam.width() + T - 1) / T, tilesY = (cam.height() + T - 1) / T;
  if (tilesX > 65536 || tilesY > 65536) throwBadOption("tileSize", "too small for this image (at most 65536 tiles a side)");
  const size_t tiles = size_t(tilesX) * size_t(tilesY);
  // the per-chunk tile counts stay small: larger chunks for small tiles
  const size_t chunkBatches = std::max<size_t>(32, (tiles / 256) * 32);
  const size_t chunkPoints = chunkBatches * detail::kSetupBatch;
  const size_t pointChunks = (np + chunkPoints - 1) / chunkPoints;
  const size_t segChunkSize = 8192;
  const size_t segChunks = (ns + segChunkSize - 1) / segChunkSize;
  const size_t chunks = pointChunks + segChunks;
  const size_t pointSlots = pointChunks * chunkPoints;  // refs below pointSlots are points
  // refs from lodBase on are segments drawn as point splats (RenderOptions::segmentLod; not for
  // models too large for those refs)
  const size_t lodBase = pointSlots + ns;
  const bool lod = opt.segmentLod > 0 && ns > 0 && lodBase + ns <= size_t(UINT32_MAX);
  buf.pts.reserve(pointSlots);
  buf.pointBounds.reserve(pointSlots);
  buf.pointCold.reserve(pointSlots);
  buf.gouraud.reserve(pointSlots);
  if (buf.pointTiles.size() < pointSlots) buf.pointTiles.resize(pointSlots);
  if (buf.segs.size() < ns) buf.segs.resize(ns);
  buf.segStatus.resize(ns);
  if (buf.segTiles.size() < ns) buf.segTiles.resize(ns);
  if (lod) {
    if (buf.segLod.size() < ns) buf.segLod.resize(ns);
    buf.lodPts.reserve(ns);
    buf.lodBounds.reserve(ns);
    buf.lodCold.reserve(ns);
    buf.lodGouraud.reserve(ns);
  }
  uint8_t* const segLod = lod ? buf.segLod.data() : nullptr;
  const PointSlots lodOut{buf.lodPts.data(), buf.lodBounds.data(), buf.lodCold.data(), buf.lodGouraud.data()};
  buf.counts.assign(chunks * tiles, 0);
  buf.chunkVisible.assign(pointChunks, 0);
  buf.chunkCounts.assign(pointChunks, PointSetupCounts{});
  buf.chunkSeconds.assign(chunks, 0.0);
  PreparedPoint* const pts = buf.pts.data();
  const PixelRect* const pointBounds = buf.pointBounds.data();
  const PointSlots pointOut{pts, buf.pointBounds.data(), buf.pointCold.data(), buf.gouraud.data()};
  PreparedSegment* const segs = buf.segs.data();
  TileSpan* const spans = buf.pointTiles.data();
  // bounds are clamped to the view (non-negative): a shift for power-of-two tiles (the default)
  const int tileShift = (T & (T - 1)) == 0 ? std::countr_zero(unsigned(T)) : -1;
  auto tileSpan = [&](const PixelRect& b) {
    if (tileShift >= 0)
      return TileSpan{uint16_t(b.x0 >> tileShift), uint16_t(b.y0 >> tileShift), uint16_t((b.x1 - 1) >> tileShift),
                      uint16_t((b.y1 - 1) >> tileShift)};
    return TileSpan{uint16_t(b.x0 / T), uint16_t(b.y0 / T), uint16_t((b.x1 - 1) / T), uint16_t((b.y1 - 1) / T)};
  };
  auto countSpan = [&](uint32_t* cnt, const TileSpan& s) {
    for (int ty = s.y0; ty <= s.y1; ++ty)
      for (int tx = s.x0; tx <= s.x1; ++tx) ++cnt[size_t(ty) * size_t(tilesX) + size_t(tx)];
  };
  // Coverage alpha (RenderOptions::coverageGain, beyond the thesis): a primitive's alpha attribute
  // becomes its coverage constant g c_k (coverage.h), stored as c_k / (2 cMax) (at most 1/2: no
  // fragment is opaque on its own) with the tile's scale 2 g cMax (Z3Tile::setCoverageScale).
  const bool coverage = coverageMax_ > 0 && !(opt.alphaOverride >= 0 && opt.alphaOverride < 1) && opt.defaultColor.w() >= 1;
  const float coverageScale = coverage ? 2 * opt.coverageGain * coverageMax_ : 0.0f;
  // every fragment of the frame opaque (tail layers, Z3Tile::setTailLayers, assume it)
  const bool opaqueFrame = opaqueModel_ && !(opt.alphaOverride >= 0 && opt.alphaOverride < 1) && opt.defaultColor.w() >= 1;
  const float invC = coverage ? 0.5f / coverageMax_ : 0.0f;
  const float* const covC = coverage_.data();
  const detail::PointSetupFrame setup = pointSetupFrame(frame);
  parallelFor(0, pointChunks, [&](size_t c) {
    const double t0 = threadCpuSeconds();
    uint32_t* cnt = buf.counts.data() + c * tiles;
    const size_t base = c * chunkPoints;
    size_t k = base;
    for (size_t i = base, e = std::min(np, base + chunkPoints); i < e; i += detail::kSetupBatch) {
      const int n = preparePoints(model_.points.data(), uint32_t(i), int(std::min<size_t>(detail::kSetupBatch, e - i)),
                                  frame, setup, pointOut + k, buf.chunkCounts[c]);
      if (coverage)
        for (size_t j = k; j < k + size_t(n); ++j) pts[j].color[3] = covC[pointOut.cold[j].index] * invC;
      for (size_t j = k; j < k + size_t(n); ++j) countSpan(cnt, spans[j] = tileSpan(pointBounds[j]));
      k += size_t(n);
    }
    buf.chunkVisible[c] = uint32_t(k - base);
    buf.chunkSeconds[c] = threadCpuSeconds() - t0;
  }, 1);
  PrimitiveStatus* const segStatus = buf.segStatus.data();
  TileSpan* const segTiles = buf.segTiles.data();
  std::atomic<int64_t> segmentNs{0};
  // drawn (clipped included), clipped, culled, outside, degenerate, approx fallbacks, drawn as points
  std::atomic<uint64_t> segCounts[7] = {};
  const detail::SegmentSetupFrame segSetup = segmentSetupFrame(frame);
  parallelForRange(0, ns, [&](size_t r0, size_t r1) {
    const double t0 = threadCpuSeconds();
    uint64_t n[7] = {};
    uint64_t byStatus[8] = {};  // counted by status without a branch (issue 13, i13prep4)
    // in pieces of kSegmentBatch: the statuses counted, the tiles and fallback flags of the visible
    // ones taken (and short ones turned into point splats) while their records are in the cache:
    // counting and binning below read only segStatus and segTiles (issue 13: a record's miss per
    // visible segment in each of three loops, one of them serial)
    for (size_t i0 = r0; i0 < r1; i0 += detail::kSegmentBatch) {
      const size_t i1 = std::min(r1, i0 + detail::kSegmentBatch);
      prepareSegments(model_.segments.data(), uint32_t(i0), i1 - i0, frame, segSetup, segs + i0, segStatus + i0);
      for (size_t i = i0; i < i1; ++i) {
        ++byStatus[uint8_t(segStatus[i]) & 7u];
        if (!visible(segStatus[i])) continue;
        if (coverage) segs[i].attr[Z3Tile::kA] = covC[np + i] * invC;
        n[5] += segs[i].fallback;
        if (lod && (segLod[i] = segmentLodPoint(segs[i], frame, opt.segmentLod, lodOut + i))) {
          segTiles[i] = tileSpan(lodOut.bounds[i]);
          ++n[6];
          continue;
        }
        segTiles[i] = tileSpan(segs[i].bounds);
      }
    }
    using PS = PrimitiveStatus;
    n[0] = byStatus[uint8_t(PS::Drawn)] + byStatus[uint8_t(PS::Clipped)], n[1] = byStatus[uint8_t(PS::Clipped)];
    n[2] = byStatus[uint8_t(PS::Culled)], n[3] = byStatus[uint8_t(PS::Outside)], n[4] = byStatus[uint8_t(PS::Degenerate)];
    for (int k = 0; k < 7; ++k) segCounts[k] += n[k];
    segmentNs += int64_t(1e9 * (threadCpuSeconds() - t0));
  }, 256);
  for (const PointSetupCounts& c : buf.chunkCounts) {
    st.pointsDrawn += c.drawn + c.clipped;
    st.pointsClipped += c.clipped;
    st.pointsCulled += c.culled;
    st.pointsOutside += c.outside;
    st.pointsDegenerate += c.degenerate;
  }
  st.segmentsDrawn = segCounts[0], st.segmentsClipped = segCounts[1], st.segmentsCulled = segCounts[2];
  st.segmentsOutside = segCounts[3], st.segmentsDegenerate = segCounts[4], st.segmentsFallback = segCounts[5];
  st.segmentsLod = segCounts[6];
  parallelFor(0, segChunks, [&](size_t c) {
    uint32_t* cnt = buf.counts.data() + (pointChunks + c) * tiles;
    for (size_t i = c * segChunkSize, e = std::min(ns, i + segChunkSize); i < e; ++i)
      if (visible(segStatus[i])) countSpan(cnt, segTiles[i]);
  }, 1);
  st.prepareThreadSeconds = 1e-9 * double(segmentNs.load());
  for (double s : buf.chunkSeconds) st.prepareThreadSeconds += s;
  st.prepareSeconds = t.seconds();
  reportProgress(opt.progress, "render", 0.1);

  // 2. binning: every visible primitive goes to every tile its bounds touch; each tile's list is
  // in primitive order (points, then segments): offsets tile-major, chunk-minor.
  t.reset();
  buf.tileStart.resize(tiles + 1);
  buf.offset.resize(chunks * tiles);
  size_t run = 0;
  for (size_t tile = 0; tile < tiles; ++tile) {
    buf.tileStart[tile] = run;
    for (size_t c = 0; c < chunks; ++c) {
      buf.offset[c * tiles + tile] = run;
      run += buf.counts[c * tiles + tile];
    }
  }
  buf.tileStart[tiles] = run;
  if (buf.refs.size() < run) buf.refs.resize(run);
  uint32_t* const refs = buf.refs.data();
  const size_t* const tileStart = buf.tileStart.data();
  auto fillSpan = [&](size_t* off, const TileSpan& s, uint32_t ref) {
    for (int ty = s.y0; ty <= s.y1; ++ty)
      for (int tx = s.x0; tx <= s.x1; ++tx) refs[off[size_t(ty) * size_t(tilesX) + size_t(tx)]++] = ref;
  };
  parallelFor(0, chunks, [&](size_t c) {
    const double t0 = threadCpuSeconds();
    size_t* off = buf.offset.data() + c * tiles;
    if (c < pointChunks) {
      for (size_t j = c * chunkPoints, e = j + buf.chunkVisible[c]; j < e; ++j) fillSpan(off, spans[j], uint32_t(j));
    } else {
      const size_t c0 = (c - pointChunks) * segChunkSize;
      for (size_t i = c0, e = std::min(ns, c0 + segChunkSize); i < e; ++i)
        if (visible(segStatus[i])) fillSpan(off, segTiles[i], uint32_t((lod && segLod[i] ? lodBase : pointSlots) + i));
    }
    buf.chunkSeconds[c] = threadCpuSeconds() - t0;
  }, 1);
  for (double s : buf.chunkSeconds) st.binThreadSeconds += s;
  st.tileBins = run;
  st.binSeconds = t.seconds();

  // 3. rasterise + resolve, tiles in parallel; each tile writes only its own pixels
  t.reset();
  // the colour image is not filled here (4 MB at 512^2, one thread): each tile writes every pixel
  // of its own, the background where nothing was drawn (Color() leaves the pixels uninitialised)
  res.color.width = cam.width(), res.color.height = cam.height();
  res.color.pixels.resize(size_t(cam.width()) * size_t(cam.height()));
  if (opt.depthBuffer) res.depth = Image(cam.width(), cam.height(), Color(0, 0, 0, 0));
  if (opt.alphaBuffer) res.alpha = Image(cam.width(), cam.height(), Color(0, 0, 0, 0));
  if (opt.normalBuffer) res.normal = Image(cam.width(), cam.height(), Color(0, 0, 0, 0));
  // coverage at silhouettes only: every pixel resolved with its front layer opaque, the partly
  // covered ones kept with their coverage result until every tile's front depths are known
  const bool silhouettes = coverage && opt.coverageReach > 0;
  float* const frontZ = silhouettes ? (buf.frontZ.resize(res.color.pixels.size()), buf.frontZ.data()) : nullptr;
  if (silhouettes) buf.silhouette.resize(std::max(buf.silhouette.size(), tiles));
  std::vector<Z3Counters> tileCounters(tiles);
  std::vector<std::pair<double, double>> tileSeconds(tiles);  // rasterise, resolve
  const Color bg = opt.background;
  // a resolved pixel (premultiplied) composited over the background, as the image stores it
  auto overBackground = [&bg](const Color& px) {
    const float a = px.w();
    Color c = px;
    c.head<3>() += (1 - a) * bg.w() * bg.head<3>();
    c.w() = a + (1 - a) * bg.w();
    if (bg.w() > 0 && c.w() > 0 && c.w() < 1) c.head<3>() /= c.w();  // straight colour for PNG
    if (bg.w() == 0 && a > 0) c.head<3>() /= a;
    return c;
  };
  // tail layers in this frame (Z3Tile::setTailLayers), and tail coverage's scale s: a tail-only
  // pixel's alpha is min(1, s W) where it borders an empty pixel (after every tile, below)
  const bool tailsOn = opt.tailLayers && opt.segmentMethod == SegmentMethod::ScreenSpace && opaqueFrame && coverageScale <= 0;
  const float tailScale = tailsOn ? opt.tailCoverage * tailCoverageC_ : 0.0f;
  uint8_t* const covered = tailScale > 0 ? (buf.covered.resize(res.color.pixels.size()), buf.covered.data()) : nullptr;
  if (covered) buf.tailPixels.resize(std::max(buf.tailPixels.size(), tiles));
  auto doTile = [&](size_t tile) {
    const int tx = int(tile % size_t(tilesX)), ty = int(tile / size_t(tilesX));
    PixelRect rect{tx * T, ty * T, std::min(cam.width(), (tx + 1) * T), std::min(cam.height(), (ty + 1) * T)};
    thread_local std::unique_ptr<Z3Tile> buffer;
    if (!buffer || buffer->layers() != opt.layers)
      buffer = std::make_unique<Z3Tile>(rect, opt.layers);
    else buffer->reset(rect);
    Z3Tile& z3 = *buffer;
    z3.setBlendNormals(opt.perPixelLighting || opt.normalBuffer);
    z3.setCoverageScale(coverageScale);
    z3.setCoverageOccludes(!silhouettes);  // at silhouettes only: an opaque frame's layers
    z3.setTailLayers(tailsOn);  // (Z3Tile: an opaque frame)
    SplatContext ctx{frame, rect, z3};
    const double t0 = threadCpuSeconds();
    const size_t kEnd = tileStart[tile + 1];
    for (size_t k = tileStart[tile]; k < kEnd;) {
      // the bins visit primitives in index order with gaps: their prepared records are cold
      // (a PreparedSegment spans several cache lines), so fetch the record kPrefetchAhead on
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
          prefetchPrimitive(refs[k + kRasterBatch], pointSlots, lodBase, pts, segs, buf.lodPts.data());
        batch[n++] = &segs[refs[k] - pointSlots];
      }
      rasterizeSegments(batch, n, ctx);
    }
    const double t1 = threadCpuSeconds();
    tileSeconds[tile].first = t1 - t0;
    // pixels with one layer (nearly all) in SIMD rows, unless lighting is deferred or another
    // buffer is written; the rest pixel by pixel
    const bool simdResolve = !opt.perPixelLighting && !res.depth && !res.alpha && !res.normal;
    const float bgRGBA[4] = {bg.x(), bg.y(), bg.z(), bg.w()};
    const int32_t* layerCounts = z3.counts();
    std::vector<detail::SilhouettePixel>* cands = silhouettes ? &buf.silhouette[tile] : nullptr;
    if (cands) cands->clear();
    std::vector<Buffers::TailPixel>* tailPx = covered ? &buf.tailPixels[tile] : nullptr;
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
      float* rowZ = frontZ ? frontZ + size_t(y) * size_t(cam.width()) : nullptr;
      const int done = simdResolve ? detail::resolveSingleLayerRow(z3, y, rect.x0, rect.width(), bgRGBA,
                                                                   res.color.at(rect.x0, y).data(), others,
                                                                   rowZ ? rowZ + rect.x0 : nullptr, cands)
                                   : 0;
      const int32_t* rowCounts = layerCounts + z3.index(rect.x0, y);
      for (int x = others ? rect.x0 : rect.x0 + done; x < rect.x1; ++x) {
        const int layers = rowCounts[x - rect.x0];
        if (x - rect.x0 < done && layers <= 1) continue;  // written by the SIMD row
        if (layers == 0) {
          res.color.at(x, y) = bg;
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
          const Color c = overBackground(pc.color);
          cands->push_back({uint32_t(x), uint32_t(y), z3.frontThreshold(x, y), {c.x(), c.y(), c.z(), c.w()}, pc.color.w()});
        }
        const float a = px.color.w();
        res.color.at(x, y) = overBackground(px.color);
        if (res.depth) res.depth->at(x, y) = Color(px.depth, px.depth, px.depth, 1);
        if (res.alpha) res.alpha->at(x, y) = Color(a, a, a, a);
        if (res.normal)
          res.normal->at(x, y) = Color(0.5f * (px.normal.x() + 1), 0.5f * (px.normal.y() + 1), 0.5f * (px.normal.z() + 1), 1);
      }
      if (tailPx) {  // tail coverage: which pixels hold a layer, and the tail-only ones (a tail-only
                     // layer is always a pixel's only one in an opaque frame, Z3Tile::setTailLayers)
        const size_t p0 = z3.index(rect.x0, y);
        const float* flag = z3.plane(0, Z3Tile::kOpaque) + p0;
        const float* W = z3.plane(0, Z3Tile::kW) + p0;
        uint8_t* row = covered + size_t(y) * size_t(cam.width()) + rect.x0;
        const int n = rect.width();
        for (int i = 0; i < n; ++i) row[i] = rowCounts[i] > 0;  // (two loops: this one vectorises)
        for (int i = 0; i < n; ++i)
          if (flag[i] < 0 && rowCounts[i] == 1) {
            const float a = std::min(1.0f, tailScale * W[i]);
            if (a < 1.0f) tailPx->push_back({uint32_t(rect.x0 + i), uint32_t(y), a});
          }
      }
    }
    if (cands) {
      // Candidates whose neighbourhood lies in this tile are decided now (their front depths are
      // all known: the same test as after the frame), the others after every tile; the kept ones
      // take what lay behind their front layer (Z3Tile::resolveBehind) while the tile holds it.
      const int reach = opt.coverageReach;
      size_t kept = 0;
      for (detail::SilhouettePixel& c : *cands) {
        const int x = int(c.x), y = int(c.y);
        const bool inTile = std::max(0, x - reach) >= rect.x0 && std::min(cam.width() - 1, x + reach) < rect.x1 &&
                            std::max(0, y - reach) >= rect.y0 && std::min(cam.height() - 1, y + reach) < rect.y1;
        if (inTile && !detail::atSilhouette(c, frontZ, cam.width(), cam.height(), reach)) continue;
        const Color b = opt.perPixelLighting ? z3.resolveBehind(x, y, shadeAt(x, y)) : z3.resolveBehind(x, y, keep);
        for (int k = 0; k < 4; ++k) c.behind[k] = b[k];
        (*cands)[kept++] = c;
      }
      cands->resize(kept);
    }
    tileCounters[tile] = z3.counters();
    tileSeconds[tile].second = threadCpuSeconds() - t1;
  };
  const size_t batch = 64;
  for (size_t b0 = 0; b0 < tiles; b0 += batch) {
    parallelFor(b0, std::min(tiles, b0 + batch), doTile, 1);
    reportProgress(opt.progress, "render", 0.1 + 0.9 * double(std::min(tiles, b0 + batch)) / double(tiles));
  }
  if (silhouettes) {
    // The partly covered pixels at silhouettes take their coverage result, composited over what
    // lies beyond them: the frame kept no layer behind a front one (Z3Tile::setCoverageOccludes),
    // so over the nearest neighbour that shows the background or a farther surface (coverage.h,
    // silhouetteBehind). Two passes, the second writing what the first computed from the opaque
    // images alone, so the result does not depend on the order of the tiles or the threads.
    const int w = cam.width(), h = cam.height();
    std::vector<uint8_t>& partial = buf.partial;
    partial.assign(res.color.pixels.size(), 0);
    for (size_t tile = 0; tile < tiles; ++tile)
      for (const detail::SilhouettePixel& c : buf.silhouette[tile]) partial[size_t(c.y) * size_t(w) + c.x] = 1;
    std::vector<std::vector<std::pair<size_t, Color>>> out(tiles), outAlpha(tiles);
    parallelFor(0, tiles, [&](size_t tile) {
      const double t0 = threadCpuSeconds();
      for (const detail::SilhouettePixel& c : buf.silhouette[tile]) {
        const int64_t behind = detail::silhouetteBehind(c, frontZ, partial.data(), w, h, opt.coverageReach);
        if (behind < 0) continue;
        const size_t i = size_t(c.y) * size_t(w) + c.x;
        // premultiplied: the front = the stored result (straight, times its alpha) less the
        // background's share; then over the neighbour's (opaque-frame) pixel
        const float a = c.alpha, cw = c.rgba[3];
        const Vec3f front = Vec3f(c.rgba[0], c.rgba[1], c.rgba[2]) * cw - (1 - a) * bg.w() * bg.head<3>();
        // over what lay behind it in this pixel, then over the neighbour
        const float ab = c.behind[3];
        const Vec3f under = Vec3f(c.behind[0], c.behind[1], c.behind[2]);
        const bool toBackground = std::isinf(frontZ[behind]);
        const Color& nb = toBackground ? bg : res.color.pixels[size_t(behind)];
        const float na = toBackground ? bg.w() : nb.w();
        Color r;
        r.head<3>() = front + (1 - a) * (under + (1 - ab) * na * nb.head<3>());
        r.w() = a + (1 - a) * (ab + (1 - ab) * na);
        if (r.w() > 0 && r.w() < 1) r.head<3>() /= r.w();
        out[tile].push_back({i, r});
        if (res.alpha) {
          const float nAlpha = toBackground ? 0.0f : res.alpha->pixels[size_t(behind)].w();
          const float ar = a + (1 - a) * (ab + (1 - ab) * nAlpha);
          outAlpha[tile].push_back({i, Color(ar, ar, ar, ar)});
        }
      }
      tileSeconds[tile].second += threadCpuSeconds() - t0;
    }, 1);
    for (size_t tile = 0; tile < tiles; ++tile) {
      for (const auto& [i, c] : out[tile]) res.color.pixels[i] = c;
      for (const auto& [i, c] : outAlpha[tile]) res.alpha->pixels[i] = c;
    }
  }
  if (covered) {
    // Tail coverage: a tail-only pixel next to an empty one (3 x 3) lies past a silhouette, where
    // only the prefilter reached: its colour (written opaque) is composited over the background
    // with its faded alpha. One that no empty pixel borders fills a gap inside a surface and stays
    // opaque. Reads only the covered mask, writes only these pixels: independent of tile order.
    const int w = cam.width(), h = cam.height();
    auto bordersEmpty = [&](int x, int y) {
      for (int yy = std::max(0, y - 1); yy <= std::min(h - 1, y + 1); ++yy)
        for (int xx = std::max(0, x - 1); xx <= std::min(w - 1, x + 1); ++xx)
          if (!covered[size_t(yy) * size_t(w) + size_t(xx)]) return true;
      return false;
    };
    for (size_t tile = 0; tile < tiles; ++tile)
      for (const Buffers::TailPixel& t : buf.tailPixels[tile]) {
        const int x = int(t.x), y = int(t.y);
        if (!bordersEmpty(x, y)) continue;
        Color& c = res.color.at(x, y);  // written opaque: its straight colour
        const float a = t.alpha;
        c = overBackground(Color(a * c.x(), a * c.y(), a * c.z(), a));
        if (res.alpha) res.alpha->at(x, y) = Color(a, a, a, a);
      }
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
