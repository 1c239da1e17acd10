// (epsilon, delta) extraction (thesis §3.1) timings: the 437k-point dragon vertex cloud (skipped
// when the shared data is absent) and synthetic planes / cylinders that are always available.
// Counters give the result (points, segments, reduction) and where the time goes per stage.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <memory>

#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

namespace {

using namespace linesurf;

std::filesystem::path sharedData() {
  auto p = std::filesystem::path(LINESURF_SOURCE_DIR) / ".." / "shared" / "data";
  if (const char* env = std::getenv("LINESURF_SHARED_DATA")) p = env;
  return p;
}

GeometryOptions extractionGeometry() {
  GeometryOptions go;
  go.curvature = false;  // §3.1 needs normals, Delaunay neighbours and spacing only
  return go;
}

struct Prepared {
  HybridModel cloud;
  PointGeometry geometry;
  double geometrySeconds = 0;
};

const Prepared* dragon() {
  static std::unique_ptr<Prepared> p = []() -> std::unique_ptr<Prepared> {
    auto path = sharedData() / "dragon_mesh.ply";
    std::error_code ec;
    if (!std::filesystem::exists(path, ec)) return nullptr;
    auto r = std::make_unique<Prepared>();
    r->cloud = readModel(path);  // mesh vertices as points
    Timer t;
    r->geometry = computePointGeometry(r->cloud, extractionGeometry());
    r->geometrySeconds = t.seconds();
    return r;
  }();
  return p.get();
}

void report(benchmark::State& state, const EpsDeltaStats& s) {
  state.counters["points_in"] = double(s.inputPoints);
  state.counters["points_out"] = double(s.keptPoints);
  state.counters["segments"] = double(s.segments);
  state.counters["replaced_%"] = 100.0 * s.replacedFraction();
  state.counters["reduction_%"] = 100.0 * s.dataReduction();
  state.counters["grow_s"] = s.growSeconds;
  state.counters["select_s"] = s.selectSeconds;
  state.counters["build_s"] = s.outputSeconds;
}

// Extraction alone (geometry computed once), 1 and 2 threads.
void BM_EpsDeltaDragon(benchmark::State& state) {
  const Prepared* d = dragon();
  if (!d) {
    state.SkipWithError("shared data absent: dragon_mesh.ply not found");
    return;
  }
  ThreadLimit limit(int(state.range(0)));
  EpsDeltaStats s;
  for (auto _ : state) {
    HybridModel m = extractEpsDelta(d->cloud, d->geometry, {}, &s);
    benchmark::DoNotOptimize(m.segments.data());
  }
  report(state, s);
}
BENCHMARK(BM_EpsDeltaDragon)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

// The §6.1 stages extraction needs (kNN, normals + MST orientation, local Delaunay, spacing).
void BM_EpsDeltaDragonGeometry(benchmark::State& state) {
  const Prepared* d = dragon();
  if (!d) {
    state.SkipWithError("shared data absent: dragon_mesh.ply not found");
    return;
  }
  ThreadLimit limit(int(state.range(0)));
  PointGeometry g;
  for (auto _ : state) {
    g = computePointGeometry(d->cloud, extractionGeometry());
    benchmark::DoNotOptimize(g.normals.data());
  }
  state.counters["knn_s"] = g.times.neighbours;
  state.counters["normals_s"] = g.times.normals;
  state.counters["orient_s"] = g.times.orientation;
  state.counters["delaunay_s"] = g.times.delaunay;
  state.counters["spacing_s"] = g.times.spacing;
}
BENCHMARK(BM_EpsDeltaDragonGeometry)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

// Synthetic shapes: 0 regular plane, 1 regular cylinder, 2 plane with noise 1% of the spacing,
// 3 noise 10%, 4 uniform random plane, 5 regular plane with maxReplaced = 32. Geometry from the
// real §6.1 pipeline.
void BM_EpsDeltaShapes(benchmark::State& state) {
  HybridModel cloud;
  switch (state.range(0)) {
    case 0: cloud = shapes::plane(2, 2, 300, 300); break;
    case 1: cloud = shapes::cylinder(1, 6, 200, 300); break;
    case 2: cloud = shapes::plane(2, 2, 300, 300, {.noise = 0.01f, .seed = 2}); break;
    case 3: cloud = shapes::plane(2, 2, 300, 300, {.noise = 0.1f, .seed = 3}); break;
    case 4: cloud = shapes::plane(2, 2, 300, 300, {.irregular = true, .seed = 4}); break;
    default: cloud = shapes::plane(2, 2, 300, 300); break;
  }
  EpsDeltaOptions o;
  if (state.range(0) == 5) o.maxReplaced = 32;
  cloud.attributes.normals = false;
  PointGeometry g = computePointGeometry(cloud, extractionGeometry());
  ThreadLimit limit(2);
  EpsDeltaStats s;
  for (auto _ : state) {
    HybridModel m = extractEpsDelta(cloud, g, o, &s);
    benchmark::DoNotOptimize(m.segments.data());
  }
  report(state, s);
}
BENCHMARK(BM_EpsDeltaShapes)->DenseRange(0, 5)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(2);

}  // namespace
