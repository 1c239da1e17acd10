// Model IO timings: reading the 16.6 MB binary dragon (437645 vertices, 871414 faces; skipped
// when the shared data is absent), writing it, and parsing synthetic ascii / binary PLY in memory.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <random>

#include "linesurf/io/model_io.h"

namespace {

using namespace linesurf;

std::filesystem::path dragonPath() {
  auto p = std::filesystem::path(LINESURF_SOURCE_DIR) / ".." / "shared" / "data";
  if (const char* env = std::getenv("LINESURF_SHARED_DATA")) p = env;
  return p / "dragon_mesh.ply";
}

void BM_ReadMeshDragon(benchmark::State& state) {
  std::error_code ec;
  if (!std::filesystem::exists(dragonPath(), ec)) {
    state.SkipWithError("shared data absent (../shared/data/dragon_mesh.ply)");
    return;
  }
  size_t faces = 0;
  for (auto _ : state) {
    TriangleMesh m = readMesh(dragonPath());
    faces = m.faces.size();
    benchmark::DoNotOptimize(m.positions.data());
  }
  state.counters["faces"] = double(faces);
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(std::filesystem::file_size(dragonPath())));
}
BENCHMARK(BM_ReadMeshDragon)->Unit(benchmark::kMillisecond);

void BM_ReadModelDragonVertices(benchmark::State& state) {
  std::error_code ec;
  if (!std::filesystem::exists(dragonPath(), ec)) {
    state.SkipWithError("shared data absent (../shared/data/dragon_mesh.ply)");
    return;
  }
  for (auto _ : state) {
    HybridModel m = readModel(dragonPath());  // faces walked and skipped
    benchmark::DoNotOptimize(m.points.data());
  }
}
BENCHMARK(BM_ReadModelDragonVertices)->Unit(benchmark::kMillisecond);

void BM_WriteMeshDragonBinary(benchmark::State& state) {
  std::error_code ec;
  if (!std::filesystem::exists(dragonPath(), ec)) {
    state.SkipWithError("shared data absent (../shared/data/dragon_mesh.ply)");
    return;
  }
  TriangleMesh m = readMesh(dragonPath());
  auto out = std::filesystem::temp_directory_path() / "linesurf_io_bench_dragon.ply";
  for (auto _ : state) writeMesh(out, m);
  std::filesystem::remove(out, ec);
}
BENCHMARK(BM_WriteMeshDragonBinary)->Unit(benchmark::kMillisecond);

/// 100k random points with normals, encoded once as PLY bytes in the given encoding.
std::string syntheticPly(PlyEncoding enc) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> U(-1, 1);
  HybridModel m;
  m.points.resize(100000);
  for (Point& p : m.points) {
    p.position = Vec3f(U(rng), U(rng), U(rng));
    p.normal = p.position.normalized();
  }
  m.attributes.normals = true;
  auto path = std::filesystem::temp_directory_path() / "linesurf_io_bench_points.ply";
  writeModel(path, m, {.encoding = enc});
  std::string bytes(std::filesystem::file_size(path), '\0');
  FILE* f = std::fopen(path.string().c_str(), "rb");
  size_t n = std::fread(bytes.data(), 1, bytes.size(), f);
  std::fclose(f);
  std::filesystem::remove(path);
  bytes.resize(n);
  return bytes;
}

void BM_ParsePoints100kAscii(benchmark::State& state) {
  static const std::string bytes = syntheticPly(PlyEncoding::Ascii);
  for (auto _ : state) benchmark::DoNotOptimize(readPlyModelFromMemory(bytes, "mem.ply").points.data());
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(bytes.size()));
}
BENCHMARK(BM_ParsePoints100kAscii)->Unit(benchmark::kMillisecond);

void BM_ParsePoints100kBinary(benchmark::State& state) {
  static const std::string bytes = syntheticPly(PlyEncoding::BinaryLittleEndian);
  for (auto _ : state) benchmark::DoNotOptimize(readPlyModelFromMemory(bytes, "mem.ply").points.data());
  state.SetBytesProcessed(int64_t(state.iterations()) * int64_t(bytes.size()));
}
BENCHMARK(BM_ParsePoints100kBinary)->Unit(benchmark::kMillisecond);

}  // namespace
