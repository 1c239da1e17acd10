// Shape-approximation extraction (thesis §3.2) timings, per stage: greedy clustering (§3.2.3.1),
// hierarchical clustering (§3.2.3.2) and the per-cluster segment extraction (§3.2.4), on igea
// (134,345 points) and the dragon's 437,645 vertices (skipped when the shared data is absent), and
// on a synthetic torus that is always available. The §6.1 geometry is computed once per model,
// outside the timed loops (geometry_bench times it).
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <memory>
#include <string>

#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

namespace {

using namespace linesurf;

std::filesystem::path sharedData() {
  if (const char* env = std::getenv("LINESURF_SHARED_DATA")) return env;
  return std::filesystem::path(LINESURF_SOURCE_DIR) / ".." / "shared" / "data";
}

struct Prepared {
  HybridModel cloud;
  PointGeometry geometry;
};

/// The model (points of a cloud file, vertices of a mesh file) and its geometry, computed once.
const Prepared* prepared(const std::string& name) {
  static std::map<std::string, std::unique_ptr<Prepared>> cache;
  auto it = cache.find(name);
  if (it != cache.end()) return it->second.get();
  std::unique_ptr<Prepared> p;
  if (name == "torus") {
    p = std::make_unique<Prepared>();
    p->cloud = shapes::torus(2.0f, 0.6f, 600, 200, {.irregular = true, .seed = 3});
  } else {
    auto path = sharedData() / name;
    std::error_code ec;
    if (std::filesystem::exists(path, ec)) {
      p = std::make_unique<Prepared>();
      if (fileHoldsMesh(path)) {
        TriangleMesh mesh = readMesh(path);
        for (const Vec3f& v : mesh.positions) p->cloud.points.push_back({.position = v});
      } else {
        p->cloud = readModel(path);
      }
    }
  }
  if (p) {
    p->cloud.attributes.normals = false;
    p->geometry = computePointGeometry(p->cloud);
  }
  return (cache[name] = std::move(p)).get();
}

enum class Stage { Greedy, Hierarchical, SegmentsGreedy };

void run(benchmark::State& state, const std::string& name, Stage stage) {
  const Prepared* p = prepared(name);
  if (!p) return state.SkipWithError(("shared data absent: " + (sharedData() / name).string()).c_str());
  ThreadLimit limit(int(state.range(0)));
  ShapeApproxOptions o;
  Clustering clustering;
  if (stage == Stage::SegmentsGreedy) clustering = clusterGreedy(p->geometry, o.clustering);
  ShapeApproxStats st;
  for (auto _ : state) {
    if (stage == Stage::Greedy) {
      clustering = clusterGreedy(p->geometry, o.clustering);
    } else if (stage == Stage::Hierarchical) {
      clustering = clusterHierarchical(p->geometry, o.clustering);
    } else {
      HybridModel m = extractShapeApprox(p->cloud, p->geometry, clustering, o, &st);
      benchmark::DoNotOptimize(m.segments.data());
    }
  }
  state.counters["points"] = double(p->cloud.points.size());
  state.counters["clusters"] = double(clustering.size());
  if (stage == Stage::SegmentsGreedy) state.counters["segments"] = double(st.segments);
  state.counters["Mpoints/s"] =
      benchmark::Counter(double(p->cloud.points.size()) * 1e-6, benchmark::Counter::kIsIterationInvariantRate);
}

void BM_ShapeApproxGreedyIgea(benchmark::State& s) { run(s, "igea_points.ply", Stage::Greedy); }
void BM_ShapeApproxHierarchicalIgea(benchmark::State& s) { run(s, "igea_points.ply", Stage::Hierarchical); }
void BM_ShapeApproxSegmentsIgea(benchmark::State& s) { run(s, "igea_points.ply", Stage::SegmentsGreedy); }
void BM_ShapeApproxGreedyDragon(benchmark::State& s) { run(s, "dragon_mesh.ply", Stage::Greedy); }
void BM_ShapeApproxHierarchicalDragon(benchmark::State& s) { run(s, "dragon_mesh.ply", Stage::Hierarchical); }
void BM_ShapeApproxSegmentsDragon(benchmark::State& s) { run(s, "dragon_mesh.ply", Stage::SegmentsGreedy); }
void BM_ShapeApproxGreedyTorus(benchmark::State& s) { run(s, "torus", Stage::Greedy); }
void BM_ShapeApproxHierarchicalTorus(benchmark::State& s) { run(s, "torus", Stage::Hierarchical); }
void BM_ShapeApproxSegmentsTorus(benchmark::State& s) { run(s, "torus", Stage::SegmentsGreedy); }

}  // namespace

#define SHAPE_APPROX_BENCH(fn) BENCHMARK(fn)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()
SHAPE_APPROX_BENCH(BM_ShapeApproxGreedyIgea);
SHAPE_APPROX_BENCH(BM_ShapeApproxHierarchicalIgea);
SHAPE_APPROX_BENCH(BM_ShapeApproxSegmentsIgea);
SHAPE_APPROX_BENCH(BM_ShapeApproxGreedyDragon);
SHAPE_APPROX_BENCH(BM_ShapeApproxHierarchicalDragon);
SHAPE_APPROX_BENCH(BM_ShapeApproxSegmentsDragon);
SHAPE_APPROX_BENCH(BM_ShapeApproxGreedyTorus);
SHAPE_APPROX_BENCH(BM_ShapeApproxHierarchicalTorus);
SHAPE_APPROX_BENCH(BM_ShapeApproxSegmentsTorus);
