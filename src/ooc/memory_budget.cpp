// The out-of-core pipeline's memory budget (see memory_budget.h).
#include "ooc/memory_budget.h"

#include <fmt/format.h>
#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <algorithm>
#include <cctype>
#include <fstream>
#include <string>

#include "linesurf/core/error.h"
#include "linesurf/ooc/point_stream.h"
#include "ooc/tile_store.h"

namespace linesurf::ooc::detail {
namespace {

constexpr double kMiB = 1024.0 * 1024.0;

#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

/// The resident set of this process now (bytes): binary, libraries and whatever the caller holds.
double residentBytes() {
  // Under AddressSanitizer the resident set is mostly its shadow memory and quarantine (3 to 5
  // times the program's), which says nothing of the budget's tiles: counted as the release CLI
  // measures itself at the start of a run (12 MiB).
  if (kAddressSanitizer) return 12 * kMiB;
  std::ifstream f("/proc/self/status");
  std::string line;
  while (std::getline(f, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) * 1024.0;
  return 32 * kMiB;  // no /proc: about what the binary and its libraries take on Linux
}

/// Points in the input, when its header says so cheaply (binary PLY); else a full merge window.
uint64_t pointsOf(const std::filesystem::path& in) {
  std::string ext = in.extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".ply") {
    try {
      return PointReader(in).info().count;
    } catch (const Error&) {
      // The pipeline's reader reports the file.
    }
  }
  return kBlock;
}

}  // namespace

double ioBufferBytes(const OocNormalsOptions& o) { return std::clamp(o.memoryBytes / 8, 8.0 * kMiB, 256.0 * kMiB); }

size_t readChunkPoints(const OocNormalsOptions& o) {
  // A quarter of the I/O share for the reader's rows and their decoded positions, normals, radii.
  return size_t(std::clamp(ioBufferBytes(o) / 4 / 64.0, 4096.0, double(kBlock)));
}

double bytesPerTilePoint(const OocNormalsOptions& o, bool extraction, bool extractionCurvature) {
  // (ε,δ) also holds Delaunay lists and candidates per tile: a quarter more.
  // Curvature keeps the Delaunay lists (~12 entries of index + weight) and its results.
  const bool curvature = o.geometry.curvature && (!extraction || extractionCurvature);
  return inMemoryNormalsBytesPerPoint(o.geometry.k) * (extraction ? 1.25 : 1.0) + (curvature ? 140.0 : 0.0);
}

double tilePointBudget(const OocNormalsOptions& o, bool extraction, bool extractionCurvature) {
  // Sized for kTilesInFlight tiles whatever the thread count, so the tiles (and the output) do
  // not depend on it.
  const double base = std::min(64.0 * kMiB, o.memoryBytes / 4);
  const double tileBytes = std::max(1.0, (o.memoryBytes - ioBufferBytes(o) - base) / double(kTilesInFlight));
  return tileBytes / bytesPerTilePoint(o, extraction, extractionCurvature);
}

void releaseFreedMemory() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

BudgetFloor budgetFloor(const std::filesystem::path& in, const OocNormalsOptions& o, bool extraction, bool extractionCurvature) {
  BudgetFloor f;
  releaseFreedMemory();  // what the process holds, not what its allocator kept of earlier work
  f.process = residentBytes();
  const double window = double(std::min<uint64_t>(pointsOf(in), kBlock));
  // The merge: a window of the output's rows (position, normal, radius, filled flag; curvature's
  // five floats), or the hybrid's kept points twice (read, then in index order) with their order;
  // beside it the writer's buffer, each tile's piece of the window and the join's votes before it
  // (3 M points with one far outlier at the floor: `normals` peaked at 0.94 of it, `extract
  // eps-delta` at 1.05 with 20 MiB beside its window, hence 30 for the hybrid).
  const bool curvatureOut = o.geometry.curvature && !extraction;
  const double merge = window * (extraction ? 72.0 : 29.0 + (curvatureOut ? 20.0 : 0.0)) + (extraction ? 30 : 20) * kMiB;
  const double perPoint = bytesPerTilePoint(o, extraction, extractionCurvature);
  f.tiles = double(kTilesInFlight) * kMinTilePoints * kHaloShare * perPoint;
  auto buffers = [&](const OocNormalsOptions& t) {
    // The partition: the reader's chunk, the tiles' buffers (up to twice their fill as strings
    // grow) and the 64^3 histogram.
    const double io = ioBufferBytes(t);
    return std::max(merge, io / 4 + 2 * io + 2 * kMiB);
  };
  auto fits = [&](double bytes) {
    OocNormalsOptions t = o;
    t.memoryBytes = bytes;
    const double base = std::min(64.0 * kMiB, bytes / 4);
    // The tiles take what the sizing leaves them, so the process must fit in what it keeps back.
    return f.process + buffers(t) <= bytes && f.process <= ioBufferBytes(t) + base &&
           tilePointBudget(t, extraction, extractionCurvature) >= kMinTilePoints * kHaloShare;
  };
  double lo = 1 * kMiB, hi = 1e18;
  for (int i = 0; i < 200 && hi - lo > 0.5 * kMiB; ++i) {
    const double mid = 0.5 * (lo + hi);
    (fits(mid) ? hi : lo) = mid;
  }
  f.total = std::ceil(hi / kMiB) * kMiB;
  OocNormalsOptions at = o;
  at.memoryBytes = f.total;
  f.buffers = buffers(at);
  return f;
}

void requireBudget(const std::filesystem::path& in, const OocNormalsOptions& o, bool extraction, bool extractionCurvature) {
  const BudgetFloor f = budgetFloor(in, o, extraction, extractionCurvature);
  if (o.memoryBytes >= f.total) return;
  throwBadParameter(o.budgetName, fmt::format("the out-of-core path needs at least {:.0f} MiB (this process holds {:.0f} MiB, "
                                              "its largest stage's buffers {:.0f} MiB, {} tiles of {:.0f} points {:.0f} MiB), "
                                              "more than {} {:g}",
                                              f.total / kMiB, f.process / kMiB, f.buffers / kMiB, kTilesInFlight, kMinTilePoints,
                                              f.tiles / kMiB, o.budgetName, o.memoryBytes / kMiB));
}

}  // namespace linesurf::ooc::detail

namespace linesurf::ooc {

void requireOutOfCoreBudget(const std::filesystem::path& in, const OocNormalsOptions& o, bool extraction) {
  detail::requireBudget(in, o, extraction, extraction && o.geometry.curvature);
}

}  // namespace linesurf::ooc
