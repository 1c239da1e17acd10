// Splatting throughput of the §6.2 pipeline on the shared point models (igea, armadillo, dragon
// vertices) at 512^2 and 1024^2: time per frame, input splats per second, and the split between
// prepare (transform, cull, warp, clip, light), binning and rasterisation + Z^3 + resolve, and
// the CPU time per input point of prepare and binning (prep_ns/pt, bin_ns/pt: thread CPU time
// summed over the workers, RenderStats::prepareThreadSeconds).
// Normals and radii come from the §6.1 geometry stage once per model (not timed).
// Arguments: size, threads. Run: build/linesurf_bench --benchmark_filter=Render  (set LINESURF_SHARED_DATA if needed)
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "linesurf/core/parallel.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/render/renderer.h"

namespace {

using namespace linesurf;

std::filesystem::path sharedData() {
  if (const char* env = std::getenv("LINESURF_SHARED_DATA")) return env;
  return std::filesystem::path(LINESURF_SOURCE_DIR) / ".." / "shared" / "data";
}

// Loads a model once (mesh files: their vertices), with normals and radii from §6.1.
const HybridModel* model(const std::string& file) {
  static std::map<std::string, std::unique_ptr<HybridModel>> cache;
  auto it = cache.find(file);
  if (it != cache.end()) return it->second.get();
  auto path = sharedData() / file;
  if (!std::filesystem::exists(path)) return nullptr;
  auto m = std::make_unique<HybridModel>();
  if (fileHoldsMesh(path)) {
    TriangleMesh mesh = readMesh(path);
    for (const Vec3f& p : mesh.positions) {
      Point q;
      q.position = p;
      m->points.push_back(q);
    }
  } else {
    *m = readModel(path);
  }
  GeometryOptions go;
  go.delaunayNeighbours = false;
  go.curvature = false;
  applyGeometry(*m, computePointGeometry(*m, go));
  return (cache[file] = std::move(m)).get();
}

void renderBench(benchmark::State& state, const std::string& file) {
  const HybridModel* m = model(file);
  if (!m) {
    state.SkipWithError("shared model not found (set LINESURF_SHARED_DATA)");
    return;
  }
  ThreadLimit limit(int(state.range(1)));
  const int size = int(state.range(0));
  Renderer renderer(*m);
  const Camera cam = Camera::orbit(renderer.sphere(), 30, 20, 0, size, size);
  RenderStats last;
  double prep = 0, bin = 0, raster = 0, prepCpu = 0, binCpu = 0, fragCpu = 0, resolveCpu = 0;
  for (auto _ : state) {
    RenderResult r = renderer.render(cam);
    benchmark::DoNotOptimize(r.color.pixels.data());
    last = r.stats;
    prep += r.stats.prepareSeconds;
    bin += r.stats.binSeconds;
    raster += r.stats.rasterSeconds;
    prepCpu += r.stats.prepareThreadSeconds;
    binCpu += r.stats.binThreadSeconds;
    fragCpu += r.stats.fragmentThreadSeconds;
    resolveCpu += r.stats.resolveThreadSeconds;
  }
  const double it = double(state.iterations());
  state.counters["Msplats/s"] =
      benchmark::Counter(double(m->points.size()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["drawn"] = double(last.pointsDrawn);
  state.counters["frag/drawn"] = double(last.fragments) / double(std::max<uint64_t>(1, last.pointsDrawn));
  state.counters["prepare_ms"] = 1e3 * prep / it;
  state.counters["bin_ms"] = 1e3 * bin / it;
  state.counters["raster_ms"] = 1e3 * raster / it;
  // stage 3 in CPU seconds of the worker threads (robust on a loaded machine): fragments, resolve
  state.counters["frag_cpu_ms"] = 1e3 * fragCpu / it;
  state.counters["resolve_cpu_ms"] = 1e3 * resolveCpu / it;
  state.counters["fragments"] = double(last.fragments);
  // CPU time per input point summed over the threads (robust on a shared machine)
  const double points = double(m->points.size()) * it;
  state.counters["prep_ns/pt"] = 1e9 * prepCpu / points;
  state.counters["bin_ns/pt"] = 1e9 * binCpu / points;
  state.SetLabel(std::string("simd=") + renderSimdTarget());
}

void RenderIgea(benchmark::State& s) { renderBench(s, "igea_points.ply"); }
void RenderArmadillo(benchmark::State& s) { renderBench(s, "armadillo_points.ply"); }
void RenderDragonVertices(benchmark::State& s) { renderBench(s, "dragon_mesh.ply"); }

BENCHMARK(RenderIgea)->ArgsProduct({{512, 1024}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(RenderArmadillo)->ArgsProduct({{512, 1024}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(RenderDragonVertices)->ArgsProduct({{512, 1024}, {1, 2}})->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
