// Level-of-detail hierarchy (include/linesurf/lod/lod.h): build throughput and the frame time of
// budgeted renders at 1024², on a synthetic hybrid sphere (half points, half rings of segments) of
// LINESURF_LOD_BENCH_N primitives (default 1 M). The frame time should follow the budget, not N:
// run with N = 1 M and 10 M and compare BM_LodFrame at the same budget.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>

#include <unistd.h>

#include "linesurf/lod/lod.h"
#include "linesurf/render/renderer.h"

namespace {

using namespace linesurf;

size_t benchSize() {
  const char* e = std::getenv("LINESURF_LOD_BENCH_N");
  return e ? size_t(std::atoll(e)) : size_t(1000000);
}

// A unit sphere with a ripple: points (Fibonacci lattice) on the upper half, rings of segments
// four spacings long on the lower half; about n primitives' worth of surface samples.
const HybridModel& model() {
  static std::unique_ptr<HybridModel> m = [] {
    auto out = std::make_unique<HybridModel>();
    const size_t n = benchSize();
    const float h = std::sqrt(4 * std::numbers::pi_v<float> / float(n));
    const float golden = std::numbers::pi_v<float> * (3 - std::sqrt(5.0f));
    auto surf = [](float theta, float phi) {  // rippled sphere
      const float r = 1 + 0.03f * std::sin(12 * theta) * std::sin(9 * phi);
      return Vec3f(r * std::cos(phi) * std::cos(theta), r * std::sin(phi), r * std::cos(phi) * std::sin(theta));
    };
    for (size_t i = 0; i < n; ++i) {
      const float y = 1 - 2 * (float(i) + 0.5f) / float(n);
      if (y < 0) break;
      Point p;
      const float theta = golden * float(i), phi = std::asin(y);
      p.position = surf(theta, phi);
      const Vec3f a = surf(theta + 1e-3f, phi) - p.position, b = surf(theta, phi + 1e-3f) - p.position;
      p.normal = b.cross(a).normalized();
      if (p.normal.dot(p.position) < 0) p.normal = -p.normal;
      p.radius = h;
      out->points.push_back(p);
    }
    for (float phi = -h / 2; phi > -std::numbers::pi_v<float> / 2 + h; phi -= h) {
      const float r = std::cos(phi);
      const int pieces = std::max(3, int(2 * std::numbers::pi_v<float> * r / (4 * h)));
      for (int k = 0; k < pieces; ++k) {
        const float t0 = 2 * std::numbers::pi_v<float> * float(k) / float(pieces);
        const float t1 = 2 * std::numbers::pi_v<float> * float(k + 1) / float(pieces);
        Segment s;
        s.p0 = surf(t0, phi), s.p1 = surf(t1, phi);
        const Vec3f mid = surf(0.5f * (t0 + t1), phi), d = (s.p1 - s.p0).normalized();
        const Vec3f across = surf(0.5f * (t0 + t1), phi + 1e-3f) - mid;
        s.normal = d.cross(across).normalized();
        if (s.normal.dot(mid) < 0) s.normal = -s.normal;
        s.radius = h;
        out->segments.push_back(s);
      }
    }
    out->attributes.normals = out->attributes.radii = true;
    return out;
  }();
  return *m;
}

void BM_LodBuild(benchmark::State& state) {
  const HybridModel& m = model();
  for (auto _ : state) benchmark::DoNotOptimize(lod::buildLod(m, ModelFrame{}));
  const double n = double(m.points.size() + m.segments.size());
  state.counters["primitives"] = n;
  state.counters["primitives/s"] = benchmark::Counter(n, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_LodBuild)->Unit(benchmark::kMillisecond)->Iterations(1)->UseRealTime();

// The hierarchy in a temporary file (removed at exit), read by byte range as `render` reads it.
const lod::LodFile& hierarchy() {
  struct Held {
    std::filesystem::path path = std::filesystem::temp_directory_path() /
                                 ("linesurf_lod_bench_" + std::to_string(::getpid()) + ".lod");
    std::unique_ptr<lod::LodFile> file;
    ~Held() {
      file.reset();
      std::error_code ec;
      std::filesystem::remove(path, ec);
    }
  };
  static Held held;
  if (!held.file) {
    const std::string bytes = lod::buildLod(model(), ModelFrame{});
    std::ofstream(held.path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    held.file = std::make_unique<lod::LodFile>(held.path);
  }
  return *held.file;
}

// One frame at 1024² with a budget: node selection, reading the nodes, rendering.
void BM_LodFrame(benchmark::State& state) {
  const lod::LodFile& f = hierarchy();
  const lod::LodRenderer r(f, RenderOptions{}, uint64_t(state.range(0)));
  const Camera cam = Camera::orbit(r.sphere(), 30, 20, 0, 1024, 1024);
  double select = 0, load = 0, render = 0, splats = 0;
  for (auto _ : state) {
    const lod::LodFrameResult res = r.render(cam);
    select += res.selectSeconds, load += res.loadSeconds, render += res.render.stats.totalSeconds;
    splats = double(res.selection.primitives);
  }
  const double it = double(state.iterations());
  state.counters["select_ms"] = 1000 * select / it;
  state.counters["load_ms"] = 1000 * load / it;
  state.counters["render_ms"] = 1000 * render / it;
  state.counters["splats"] = splats;
  state.counters["model"] = double(f.header().points + f.header().segments);
}
BENCHMARK(BM_LodFrame)->Arg(500000)->Arg(2000000)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
