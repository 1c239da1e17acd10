// Line-segment splatting (thesis §5) timings.
//  - BM_SegmentRate/<method>: a 512^2 frame of a plane made of segments only: segments per
//    second for each segment method.
//  - BM_HybridFrame/<model>/<kind>/<method>: frame time at 512^2 on 2 threads of a shared point
//    model (../shared/data) as pure points (kind 0) and as the hybrid models of the extraction
//    methods: (eps, delta) (1, Table 1), shape approximation with greedy (2, Table 2) and
//    hierarchical (3, Table 3) clustering. Eight orbit views cycled; the thesis's "speedup" is
//    1 - t_hybrid / t_points (docs/results.md "Rendering speedups"); counters: prepare and
//    rasterisation CPU of all threads per frame (prep_cpu_ms, raster_cpu_ms).
//  - BM_ContourFrame/<mesh>/<kind>: the same for the pure point (kind 0) and pure line (kind 1)
//    models that contour extraction (§3.3, Table 5) cuts from a shared mesh with its defaults, at
//    512^2 on 2 threads, 8 views; counters: the stages' milliseconds per frame (prepare: wall;
//    raster, resolve: CPU of all threads) and fragments.
//  - BM_ContourTileRaster/<0|1>/<mesh>: a contour line model's rasterisation alone, ns per (segment, tile).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>

#include "linesurf/core/parallel.h"
#include "linesurf/extract/contour.h"
#include "linesurf/extract/curvature_lines.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/render/renderer.h"
#include "render/point_setup.h"
#include "render/segment_setup.h"
#include "render/segment_lod.h"
#include "render/segment_splat.h"

namespace {

using namespace linesurf;

// RenderOptions::segmentLod of the frame benchmarks: the default, or LINESURF_BENCH_SEGMENT_LOD
// (0 = every segment exact) for A/B runs of one binary.
float benchSegmentLod() {
  const char* env = std::getenv("LINESURF_BENCH_SEGMENT_LOD");
  return env ? float(std::atof(env)) : RenderOptions{}.segmentLod;
}

// RenderOptions::tailLayers for the frame benchmarks: LINESURF_BENCH_TAIL_LAYERS=1
// (docs/decisions.md "Tail layers")
bool benchTailLayers() {
  const char* env = std::getenv("LINESURF_BENCH_TAIL_LAYERS");
  return env ? std::atoi(env) != 0 : RenderOptions{}.tailLayers;
}

std::filesystem::path sharedData() {
  auto p = std::filesystem::path(LINESURF_SOURCE_DIR) / ".." / "shared" / "data";
  if (const char* env = std::getenv("LINESURF_SHARED_DATA")) p = env;
  return p;
}

const char* kModels[] = {"screwdriver", "rockerarm", "santa", "armadillo", "igea"};
const SegmentMethod kMethods[] = {SegmentMethod::ScreenSpace, SegmentMethod::Approx, SegmentMethod::Reference};

// A plane of rows of segments (10 point spacings each) filling the 512^2 view.
HybridModel segmentPlane(int rows, int cols, float h) {
  HybridModel m;
  m.attributes.normals = m.attributes.radii = true;
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < cols; ++k) {
      Segment s;
      const float y = (j - 0.5f * rows) * h, x0 = (k - 0.5f * cols) * 10 * h;
      s.p0 = Vec3f(x0, y, 0);
      s.p1 = Vec3f(x0 + 10 * h, y, 0);
      s.normal = Vec3f(0, 0, 1);
      s.radius = h;
      m.segments.push_back(s);
    }
  return m;
}

// Renders `cam` once per iteration; counts rasterisation nanoseconds per Z^3 fragment (the
// renderer's own counters, thread time without the per-pixel resolve) and labels the SIMD target. Returns the last frame's statistics.
RenderStats timeFrames(benchmark::State& state, const Renderer& r, const Camera& cam) {
  RenderStats st;
  double raster = 0;
  for (auto _ : state) {
    st = r.render(cam).stats;
    raster += st.fragmentThreadSeconds;
  }
  // rasterisation only (fragments into Z^3; the resolve is per pixel, not per fragment)
  state.counters["ns/frag"] = 1e9 * raster / double(state.iterations()) / double(std::max<uint64_t>(1, st.fragments));
  state.SetLabel(std::string("simd=") + renderSimdTarget());
  return st;
}

void BM_SegmentRate(benchmark::State& state) {
  ThreadLimit limit(1);
  static const HybridModel plane = segmentPlane(200, 20, 0.01f);  // 4000 segments, ~2.5 px spacing
  RenderOptions o;
  o.segmentMethod = kMethods[state.range(0)];
  const Renderer r(plane, o);
  const Camera cam = Camera::lookAt(Vec3f(0.1f, -1.0f, 2.6f), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 512, 512);
  const RenderStats st = timeFrames(state, r, cam);
  state.counters["segments/s"] =
      benchmark::Counter(double(plane.segments.size()), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["drawn"] = double(st.segmentsDrawn);
  state.counters["fragments"] = double(st.fragments);
}
BENCHMARK(BM_SegmentRate)->DenseRange(0, 2)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// The same plane as points (10 per segment): the pure point model the segments replace.
void BM_PointRate(benchmark::State& state) {
  ThreadLimit limit(1);
  static const HybridModel plane = [] {
    HybridModel m;
    m.attributes.normals = m.attributes.radii = true;
    for (const Segment& s : segmentPlane(200, 20, 0.01f).segments)
      for (int i = 0; i < 10; ++i) m.points.push_back({s.p0 + (i + 0.5f) / 10 * (s.p1 - s.p0), s.normal, Color(1, 1, 1, 1), s.radius});
    return m;
  }();
  const Renderer r(plane, RenderOptions{});
  const Camera cam = Camera::lookAt(Vec3f(0.1f, -1.0f, 2.6f), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 512, 512);
  const RenderStats st = timeFrames(state, r, cam);
  state.counters["points/s"] = benchmark::Counter(double(plane.points.size()), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["fragments"] = double(st.fragments);
}
BENCHMARK(BM_PointRate)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// The model made by `make` from the shared file `name`, once per (name, kind); null (and
// `error`) when the shared data is absent.
template <class Make>
const HybridModel* cachedModel(const std::string& name, int kind, std::string& error, Make&& make) {
  static std::mutex mutex;
  static std::map<std::pair<std::string, int>, std::unique_ptr<HybridModel>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[{name, kind}];
  if (slot) return slot.get();
  const auto path = sharedData() / name;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    error = "shared data absent: " + path.string();
    return nullptr;
  }
  slot = std::make_unique<HybridModel>(make(path));
  return slot.get();
}

// kind 0: points; 1: eps-delta; 2: shape approx greedy; 3: shape approx hierarchical; 4: curvature
// lines (chains of segments with bit-equal shared endpoints).
const HybridModel* model(int m, int kind, std::string& error) {
  return cachedModel(std::string(kModels[m]) + "_points.ply", kind, error, [&](const std::filesystem::path& path) {
    HybridModel cloud = readModel(path);
    const PointGeometry geo = computePointGeometry(cloud);
    applyGeometry(cloud, geo);
    if (kind == 1) return extractEpsDelta(cloud, geo);
    if (kind == 4) return extractCurvatureLines(cloud, geo);
    if (kind == 0) return cloud;
    ShapeApproxOptions o;
    o.method = kind == 2 ? ClusteringMethod::Greedy : ClusteringMethod::Hierarchical;
    return extractShapeApprox(cloud, geo, o);
  });
}

void BM_HybridFrame(benchmark::State& state) {
  std::string error;
  const HybridModel* m = model(int(state.range(0)), int(state.range(1)), error);
  if (!m) return state.SkipWithError(error.c_str());
  ThreadLimit limit(2);
  RenderOptions o;
  o.segmentMethod = kMethods[state.range(2)];
  o.segmentLod = benchSegmentLod();
  o.tailLayers = benchTailLayers();
  const Renderer r(*m, o);
  const std::vector<Camera> views = Camera::spreadViews(r.sphere(), 8, 512, 512);
  size_t v = 0;
  double prepCpu = 0, raster = 0;
  for (auto _ : state) {
    const RenderResult res = r.render(views[v++ % views.size()]);
    benchmark::DoNotOptimize(res.color.pixels.data());
    prepCpu += res.stats.prepareThreadSeconds;
    raster += res.stats.fragmentThreadSeconds;
  }
  state.counters["prep_cpu_ms"] = 1e3 * prepCpu / double(std::max<int64_t>(1, state.iterations()));
  state.counters["raster_cpu_ms"] = 1e3 * raster / double(std::max<int64_t>(1, state.iterations()));
  state.SetLabel(std::string(kModels[state.range(0)]) + (state.range(1) == 0 ? " points" : state.range(1) == 1 ? " eps-delta" : state.range(1) == 2 ? " greedy" : " hierarchical"));
  state.counters["points"] = double(m->points.size());
  state.counters["segments"] = double(m->segments.size());
}
BENCHMARK(BM_HybridFrame)
    ->ArgsProduct({{0, 1, 2, 3, 4}, {0, 1, 2, 3}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()  // CPU seconds of both threads: robust on a shared, loaded machine
    ->UseRealTime()
    ->MinTime(1.0);

const char* kMeshes[] = {"bunny", "dragon", "horse", "gargoyle", "al", "buddha", "skull"};

// kind 0: the contour point model; 1: the contour line model (experiment.cpp, Table 5).
const HybridModel* contourModel(int m, int kind, std::string& error) {
  return cachedModel(std::string(kMeshes[m]) + "_mesh.ply", kind, error, [&](const std::filesystem::path& path) {
    ContourOptions co;
    co.allPoints = kind == 0;
    return extractContour(readMesh(path), co);
  });
}

void BM_ContourFrame(benchmark::State& state) {
  std::string error;
  const HybridModel* m = contourModel(int(state.range(0)), int(state.range(1)), error);
  if (!m) return state.SkipWithError(error.c_str());
  ThreadLimit limit(2);
  RenderOptions o;
  o.alphaBuffer = true;  // as the experiment renders meshes' models
  o.segmentLod = benchSegmentLod();
  o.tailLayers = benchTailLayers();
  const Renderer r(*m, o);
  const std::vector<Camera> views = Camera::spreadViews(r.sphere(), 8, 512, 512);
  size_t v = 0;
  double prepare = 0, prepCpu = 0, raster = 0, resolve = 0, fragments = 0, allocated = 0;
  for (auto _ : state) {
    const RenderStats st = r.render(views[v++ % views.size()]).stats;
    prepare += st.prepareSeconds;
    prepCpu += st.prepareThreadSeconds;
    raster += st.fragmentThreadSeconds;
    resolve += st.resolveThreadSeconds;
    fragments += double(st.fragments);
    allocated += double(st.allocated);
  }
  const double n = double(std::max<int64_t>(1, state.iterations()));
  state.counters["prepare_ms"] = 1e3 * prepare / n;
  state.counters["prep_cpu_ms"] = 1e3 * prepCpu / n;
  state.counters["raster_cpu_ms"] = 1e3 * raster / n;
  state.counters["resolve_cpu_ms"] = 1e3 * resolve / n;
  state.counters["kfrags"] = fragments / n / 1e3;
  state.counters["new_layer"] = allocated / std::max(1.0, fragments);  // fraction of fragments opening a Z^3 layer
  state.counters["ns/frag"] = 1e9 * raster / std::max(1.0, fragments);
  state.counters["primitives"] = double(m->points.size() + m->segments.size());
  state.counters["lod"] = double(o.segmentLod);
  state.SetLabel(std::string(kMeshes[state.range(0)]) + (state.range(1) == 0 ? " points" : " lines") +
                 " simd=" + renderSimdTarget());
}
// The prepare stage alone, one thread: ns per primitive of the bunny's contour points (SIMD
// batches, as the renderer runs them) and contour segments (second argument: 0 SIMD batches as
// the renderer runs them, 1 the exact path prepareSegment alone, one at a time).
void BM_ContourPrepare(benchmark::State& state) {
  std::string error;
  const HybridModel* m = contourModel(0, int(state.range(0)), error);
  if (!m) return state.SkipWithError(error.c_str());
  RenderOptions o;
  const Renderer r(*m, o);
  const std::vector<Camera> views = Camera::spreadViews(r.sphere(), 8, 512, 512);
  std::vector<PreparedPoint> pts(m->points.size());
  std::vector<PixelRect> bounds(m->points.size());
  std::vector<PointCold> cold(m->points.size());
  std::vector<PointGouraud> gouraud(m->points.size());
  std::vector<PreparedSegment> segs(m->segments.size());
  std::vector<PrimitiveStatus> status(std::max(pts.size(), segs.size()));
  size_t v = 0;
  for (auto _ : state) {
    FrameContext frame = FrameContext::make(views[v++ % views.size()], o, r.sphere(), m->attributes.colors);
    frame.endpointNormals = m->attributes.endpointNormals;
    if (!pts.empty()) {
      const detail::PointSetupFrame setup = pointSetupFrame(frame);
      PointSetupCounts counts;
      for (size_t i = 0; i < pts.size(); i += detail::kSetupBatch)
        preparePoints(m->points.data(), uint32_t(i), int(std::min<size_t>(detail::kSetupBatch, pts.size() - i)), frame,
                      setup, PointSlots{pts.data(), bounds.data(), cold.data(), gouraud.data()} + i, counts);
    }
    if (state.range(1) == 0)  // as the renderer runs them: SIMD batches, the exact path for the lanes they leave
      prepareSegments(m->segments.data(), 0, segs.size(), frame, segmentSetupFrame(frame), segs.data(), status.data());
    else  // the exact path alone, one at a time
      for (size_t i = 0; i < segs.size(); ++i) status[i] = prepareSegment(m->segments[i], uint32_t(i), frame, segs[i]);
    benchmark::DoNotOptimize(status.data());
  }
  state.counters["ns/primitive"] = benchmark::Counter(double(pts.size() + segs.size()),
                                                      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  const char* path[] = {" (batches)", " (exact path)"};
  state.SetLabel(std::string(state.range(0) == 0 ? "bunny contour points" : "bunny contour lines") +
                 (segs.empty() ? "" : path[state.range(1)]) + " simd=" + renderSimdTarget());
}
BENCHMARK(BM_ContourPrepare)->Args({0, 0})->Args({1, 0})->Args({1, 1})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// The segments of model m prepared as the renderer does (SIMD batches, the exact path for the
// lanes they leave), 8 views, one thread: ns per segment and the share of the segments the
// batches handed to the exact path.
void segmentPrepare(benchmark::State& state, const HybridModel& m, const RenderOptions& o, bool shareChainEnds = true) {
  const Renderer r(m, o);
  const std::vector<Camera> views = Camera::spreadViews(r.sphere(), 8, 512, 512);
  std::vector<PreparedSegment> segs(m.segments.size());
  std::vector<PrimitiveStatus> status(segs.size());
  size_t v = 0, exact = 0, all = 0;
  for (auto _ : state) {
    FrameContext frame = FrameContext::make(views[v++ % views.size()], o, r.sphere(), m.attributes.colors);
    frame.endpointNormals = m.attributes.endpointNormals;
    detail::SegmentSetupFrame setup = segmentSetupFrame(frame);
    setup.shareChainEnds = shareChainEnds;
    exact += prepareSegments(m.segments.data(), 0, segs.size(), frame, setup, segs.data(), status.data());
    all += segs.size();
    benchmark::DoNotOptimize(status.data());
  }
  state.counters["ns/segment"] = benchmark::Counter(double(segs.size()), benchmark::Counter::kIsIterationInvariantRate |
                                                                           benchmark::Counter::kInvert);
  state.counters["exact_share"] = double(exact) / double(std::max<size_t>(1, all));
  state.counters["segments"] = double(segs.size());
}

// segmentPrepare of the contour line model of mesh range(0) (kMeshes)
// (docs/decisions.md "Segment prepare").
void BM_ContourSegmentPrepare(benchmark::State& state) {
  std::string error;
  const HybridModel* m = contourModel(int(state.range(0)), 1, error);
  if (!m) return state.SkipWithError(error.c_str());
  RenderOptions o;
  o.alphaBuffer = true;
  segmentPrepare(state, *m, o);
  state.SetLabel(std::string(kMeshes[state.range(0)]) + " contour lines simd=" + renderSimdTarget());
}
BENCHMARK(BM_ContourSegmentPrepare)->DenseRange(0, 6)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// segmentPrepare of hybrid model range(0) (kModels) of kind range(1) (1 eps-delta, 2 greedy, 3
// hierarchical): their long segments with several sub-segments
// (docs/decisions.md "Segment prepare").
void BM_HybridSegmentPrepare(benchmark::State& state) {
  std::string error;
  const HybridModel* m = model(int(state.range(0)), int(state.range(1)), error);
  if (!m) return state.SkipWithError(error.c_str());
  segmentPrepare(state, *m, RenderOptions{});
  state.SetLabel(std::string(kModels[state.range(0)]) +
                 (state.range(1) == 1 ? " eps-delta" : state.range(1) == 2 ? " greedy" : " hierarchical") +
                 " simd=" + renderSimdTarget());
}
BENCHMARK(BM_HybridSegmentPrepare)->ArgsProduct({{3, 4}, {1, 2, 3}})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// Chained against isolated endpoints (SegmentSetupFrame::shareChainEnds): segmentPrepare of
// Igea's curvature lines (range(0) 0) or the dragon's contour lines (1), each endpoint set up on
// its own (range(1) 0) or a chain's shared endpoint once (1), both segment methods (range(2):
// ScreenSpace, Approx). The ratio of the two ns/segment is the saving.
void BM_ChainPrepare(benchmark::State& state) {
  std::string error;
  const HybridModel* m = state.range(0) == 0 ? model(4, 4, error) : contourModel(1, 1, error);
  if (!m) return state.SkipWithError(error.c_str());
  RenderOptions o;
  o.segmentMethod = kMethods[state.range(2)];
  segmentPrepare(state, *m, o, state.range(1) == 1);
  state.SetLabel(std::string(state.range(0) == 0 ? "igea curvature lines" : "dragon contour lines") +
                 (state.range(1) == 1 ? " chained" : " isolated") +
                 (state.range(2) == 0 ? " screen-space" : " approx") + " simd=" + renderSimdTarget());
}
BENCHMARK(BM_ChainPrepare)->ArgsProduct({{0, 1}, {0, 1}, {0, 1}})->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

// The bunny contour segments of one view prepared one at a time (prepareSegment), the first
// `limit` drawn ones (their records in the cache: the arithmetic alone for the benchmarks below).
struct DrawnSegments {
  std::unique_ptr<Renderer> renderer;
  FrameContext frame;
  std::vector<PreparedSegment> segs;
  std::vector<const PreparedSegment*> drawn;
};
bool drawnBunnySegments(const RenderOptions& o, size_t limit, DrawnSegments& out, std::string& error) {
  const HybridModel* m = contourModel(0, 1, error);
  if (!m) return false;
  out.renderer = std::make_unique<Renderer>(*m, o);
  const Camera cam = Camera::spreadViews(out.renderer->sphere(), 8, 512, 512)[0];
  out.frame = FrameContext::make(cam, o, out.renderer->sphere(), m->attributes.colors);
  out.frame.endpointNormals = m->attributes.endpointNormals;
  out.segs.resize(m->segments.size());
  for (size_t i = 0; i < out.segs.size() && out.drawn.size() < limit; ++i) {
    const PrimitiveStatus st = prepareSegment(m->segments[i], uint32_t(i), out.frame, out.segs[i]);
    if (st == PrimitiveStatus::Drawn || st == PrimitiveStatus::Clipped) out.drawn.push_back(&out.segs[i]);
  }
  return true;
}

// The rows' spans of the bunny contour segments' cutoff regions alone (detail::segmentSpans,
// what the segment rows walk), 1000 of one view's, one thread: ns per drawn segment.
void BM_SegmentSpans(benchmark::State& state) {
  std::string error;
  static const RenderOptions o;  // the frame keeps a pointer to it
  DrawnSegments d;
  if (!drawnBunnySegments(o, 1000, d, error)) return state.SkipWithError(error.c_str());
  std::vector<detail::RowSpan> rows(512);
  size_t spans = 0;
  for (auto _ : state)
    for (const PreparedSegment* sp : d.drawn) spans += size_t(std::max(0, detail::segmentSpans(sp->raster, sp->bounds, 0.05f, rows.data())));
  benchmark::DoNotOptimize(spans);
  state.counters["ns/segment"] = benchmark::Counter(double(d.drawn.size()), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["spans/segment"] = double(spans) / double(state.iterations()) / double(std::max<size_t>(1, d.drawn.size()));
}
// The segment level of detail's conversion alone (segmentLodPoint at segmentLod 2) of 1000 drawn
// bunny contour segments of one view, one thread: ns per segment; the share converted.
void BM_SegmentLodConvert(benchmark::State& state) {
  std::string error;
  static const RenderOptions o;
  DrawnSegments d;
  if (!drawnBunnySegments(o, 1000, d, error)) return state.SkipWithError(error.c_str());
  const size_t n = d.drawn.size();
  std::vector<PreparedPoint> hot(n);
  std::vector<PixelRect> bounds(n);
  std::vector<PointCold> cold(n);
  std::vector<PointGouraud> gouraud(n);
  const PointSlots slots{hot.data(), bounds.data(), cold.data(), gouraud.data()};
  size_t converted = 0;
  for (auto _ : state)
    for (size_t i = 0; i < n; ++i) converted += segmentLodPoint(*d.drawn[i], d.frame, 2.0f, slots + i);
  benchmark::DoNotOptimize(converted);
  state.counters["ns/segment"] = benchmark::Counter(double(n), benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["converted"] = double(converted) / double(state.iterations()) / double(std::max<size_t>(1, n));
}
BENCHMARK(BM_SegmentLodConvert)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

BENCHMARK(BM_SegmentSpans)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime()->UseRealTime();

BENCHMARK(BM_ContourFrame)
    ->ArgsProduct({{0, 1, 2, 3, 4, 5, 6}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->MinTime(1.0);

}  // namespace
namespace {
// The rasterisation of a contour line model alone (range(1): kMeshes, bunny, horse, al, buddha),
// one thread, one view (512^2, 64-pixel tiles, the renderer's batches of kRasterBatch, but not its
// record prefetches): every tile of the frame in turn (arg 0) or the busiest tile 64 times (arg 1:
// fewer records to fetch); counters: ns per (segment, tile) pair, pairs per frame, pixels walked
// and row spans per pair, the share of pairs with several pieces and with lighting stations.
// What a short segment's fixed cost is (docs/decisions.md "Segment rows"); under
// `valgrind --tool=callgrind --toggle-collect='linesurf::rasterizeSegments*'` it counts
// instructions per pair (AVX2 there: valgrind runs no AVX-512).
void BM_ContourTileRaster(benchmark::State& state) {
  std::string error;
  const HybridModel* m = contourModel(int(state.range(1)), 1, error);
  if (!m) return state.SkipWithError(error.c_str());
  RenderOptions o;
  o.alphaBuffer = true;
  const Renderer r(*m, o);
  const Camera cam = Camera::spreadViews(r.sphere(), 8, 512, 512)[0];
  FrameContext frame = FrameContext::make(cam, o, r.sphere(), m->attributes.colors);
  frame.endpointNormals = m->attributes.endpointNormals;
  std::vector<PreparedSegment> segs(m->segments.size());
  std::vector<PrimitiveStatus> status(segs.size());
  prepareSegments(m->segments.data(), 0, segs.size(), frame, segmentSetupFrame(frame), segs.data(), status.data());
  const int T = 64;
  std::vector<std::vector<const PreparedSegment*>> bins(64);
  for (size_t i = 0; i < segs.size(); ++i) {
    if (status[i] != PrimitiveStatus::Drawn && status[i] != PrimitiveStatus::Clipped) continue;
    const PixelRect& b = segs[i].bounds;
    for (int ty = std::max(0, b.y0 / T); ty <= std::min(7, (b.y1 - 1) / T); ++ty)
      for (int tx = std::max(0, b.x0 / T); tx <= std::min(7, (b.x1 - 1) / T); ++tx) bins[size_t(ty * 8 + tx)].push_back(&segs[i]);
  }
  int busiest = 0;
  for (int t = 0; t < 64; ++t) if (bins[size_t(t)].size() > bins[size_t(busiest)].size()) busiest = t;
  Z3Tile z3(PixelRect{0, 0, T, T}, o.layers);
  z3.setBlendNormals(false);
  double pairs = 0;
  for (auto _ : state) {
    for (int t = 0; t < 64; ++t) {
      const int tile = state.range(0) ? busiest : t;
      const PixelRect rect{(tile % 8) * T, (tile / 8) * T, (tile % 8 + 1) * T, (tile / 8 + 1) * T};
      z3.reset(rect);
      SplatContext ctx{frame, rect, z3};
      const auto& bin = bins[size_t(tile)];
      for (size_t k = 0; k < bin.size(); k += kRasterBatch)
        rasterizeSegments(bin.data() + k, int(std::min<size_t>(kRasterBatch, bin.size() - k)), ctx);
      pairs += double(bin.size());
    }
  }
  state.counters["ns/pair"] = benchmark::Counter(pairs, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["pairs"] = pairs / double(state.iterations());
  // the pairs' shape: pixels walked and row spans per pair, the share of multi-piece and
  // Stations segments (over every tile once)
  double walked = 0, rows = 0, n = 0, multi = 0, stations = 0;
  for (int t = 0; t < 64; ++t) {
    const PixelRect rect{(t % 8) * T, (t / 8) * T, (t % 8 + 1) * T, (t / 8 + 1) * T};
    for (const PreparedSegment* sp : bins[size_t(t)]) {
      for (const detail::RowSpan& s : segmentRowSpans(*sp, rect, true)) walked += s.x1 - s.x0, rows += 1;
      n += 1, multi += sp->pieceCount() > 1, stations += sp->shade == SegmentShade::Stations;
    }
  }
  state.counters["px/pair"] = walked / std::max(1.0, n);
  state.counters["spans/pair"] = rows / std::max(1.0, n);
  state.counters["multi"] = multi / std::max(1.0, n);
  state.counters["stations"] = stations / std::max(1.0, n);
  state.SetLabel(std::string(kMeshes[state.range(1)]) + " contour lines simd=" + renderSimdTarget());
}
}  // namespace
BENCHMARK(BM_ContourTileRaster)->ArgsProduct({{0, 1}, {0, 2, 4, 5}})->Unit(benchmark::kMillisecond);
