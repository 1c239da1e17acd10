// Contour-plane extraction (thesis §3.3) timings: the 871k-face dragon (skipped when the shared
// data is absent) and a synthetic icosphere of similar size that is always available.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/extract/contour.h"
#include "linesurf/io/model_io.h"

namespace {

using namespace linesurf;

std::filesystem::path sharedData() {
  auto p = std::filesystem::path(LINESURF_SOURCE_DIR) / ".." / "shared" / "data";
  if (const char* env = std::getenv("LINESURF_SHARED_DATA")) p = env;
  return p;
}

const TriangleMesh* dragon() {
  static std::unique_ptr<TriangleMesh> mesh = [] {
    auto path = sharedData() / "dragon_mesh.ply";
    std::error_code ec;
    return std::filesystem::exists(path, ec) ? std::make_unique<TriangleMesh>(readMesh(path)) : nullptr;
  }();
  return mesh.get();
}

const TriangleMesh& sphere() {
  static TriangleMesh mesh = shapes::sphereMesh(1.0f, 8);  // 1.3M faces
  return mesh;
}

void run(benchmark::State& state, const TriangleMesh& mesh, bool allPoints) {
  ThreadLimit limit(int(state.range(0)));
  ContourOptions o;
  o.allPoints = allPoints;
  ContourStats s;
  for (auto _ : state) {
    HybridModel m = extractContour(mesh, o, &s);
    benchmark::DoNotOptimize(m.segments.data());
  }
  state.counters["faces"] = double(mesh.faces.size());
  state.counters["segments"] = double(s.segments);
  state.counters["points"] = double(s.points);
  state.counters["Mfaces/s"] = benchmark::Counter(double(mesh.faces.size()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_ContourDragon(benchmark::State& state) {
  if (!dragon()) return state.SkipWithError("shared data absent: ../shared/data/dragon_mesh.ply");
  run(state, *dragon(), false);
}
void BM_ContourDragonAllPoints(benchmark::State& state) {
  if (!dragon()) return state.SkipWithError("shared data absent: ../shared/data/dragon_mesh.ply");
  run(state, *dragon(), true);
}
void BM_ContourIcosphere(benchmark::State& state) { run(state, sphere(), false); }

BENCHMARK(BM_ContourDragon)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
BENCHMARK(BM_ContourDragonAllPoints)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);
BENCHMARK(BM_ContourIcosphere)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

}  // namespace
