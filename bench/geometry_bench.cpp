// Google Benchmark of the §6.1 geometry pipeline (peers: bench/peers/, scripts/bench_peers.sh).
#include <benchmark/benchmark.h>

#include <filesystem>

#include "shapes.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

using namespace linesurf;

namespace {

const HybridModel& torus() {
  static const HybridModel m = [] {
    auto t = shapes::torus(2, 0.6f, 600, 500, {.noise = 0.1f, .irregular = true, .seed = 2});
    t.attributes.normals = false;
    return t;
  }();
  return m;
}

const HybridModel* igea() {
  static const HybridModel* m = []() -> HybridModel* {
    auto p = std::filesystem::path(LINESURF_SOURCE_DIR) / ".." / "shared" / "data" / "igea_points.ply";
    if (!std::filesystem::exists(p)) return nullptr;
    return new HybridModel(readModel(p));
  }();
  return m;
}

/// range(0): last stage run (0 kNN+normals, 1 + orientation, 2 + local Delaunay, 3 + curvature).
void run(benchmark::State& state, const HybridModel* model) {
  if (!model) {
    state.SkipWithError("shared igea model not found");
    return;
  }
  GeometryOptions o;
  o.recomputeNormals = true;
  o.orientNormals = state.range(0) >= 1;
  o.delaunayNeighbours = state.range(0) >= 2;
  o.curvature = state.range(0) >= 3;
  GeometryStageTimes sum;
  for (auto _ : state) {
    auto g = computePointGeometry(*model, o);
    benchmark::DoNotOptimize(g.normals.data());
    sum.neighbours += g.times.neighbours, sum.normals += g.times.normals, sum.orientation += g.times.orientation;
    sum.delaunay += g.times.delaunay, sum.curvature += g.times.curvature;
  }
  const double it = double(state.iterations());
  state.counters["knn_s"] = sum.neighbours / it;
  state.counters["pca_s"] = sum.normals / it;
  state.counters["mst_s"] = sum.orientation / it;
  state.counters["delaunay_s"] = sum.delaunay / it;
  state.counters["curv_s"] = sum.curvature / it;
  state.counters["points"] = double(model->points.size());
}

void BM_GeometryTorus300k(benchmark::State& s) { run(s, &torus()); }
void BM_GeometryIgea(benchmark::State& s) { run(s, igea()); }

}  // namespace

BENCHMARK(BM_GeometryTorus300k)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_GeometryIgea)->DenseRange(0, 3)->Unit(benchmark::kMillisecond)->UseRealTime();
