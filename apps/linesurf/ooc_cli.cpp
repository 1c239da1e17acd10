// CLI side of the out-of-core path (see ooc_cli.h).
#include "ooc_cli.h"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <thread>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#ifdef LINESURF_HAVE_MPI
#include <mpi.h>
#endif

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/ooc/ooc_normals.h"
#include "linesurf/ooc/point_stream.h"

namespace linesurf::cli {

double memoryBudgetBytes() { return budget().bytes(); }

std::string OutOfCoreFlags::requested() const {
  if (tiles > 0) return fmt::format("--tiles {}", tiles);
  if (launchedRanks() > 1) return "started by mpirun";
  if (outOfCore || !tileDir.empty()) return "--out-of-core";
  return "";
}

void bindOutOfCoreFlags(CLI::App* sub, OutOfCoreFlags& f) {
  sub->add_flag("--out-of-core", f.outOfCore,
                "Process the cloud in tiles streamed from disk (chosen by itself when it would not fit --max-mb)");
  sub->add_option("--tiles", f.tiles, "Out of core with at least N tiles (implies --out-of-core), [1, 1000000]")
      ->check(CLI::Range(1, 1000000).description(""))
      ->type_name("N");
  sub->add_option("--tile-dir", f.tileDir, "Working folder of the out-of-core path (default OUT.tiles; a killed run resumes from it)")
      ->type_name("DIR");
  sub->add_flag("--keep-tiles", f.keepTiles, "Keep the tile folder after a successful out-of-core run");
}

ooc::OocNormalsOptions outOfCoreOptions(const GeometryOptions& geometry, const std::string& in, const std::string& out,
                                        const OutOfCoreFlags& f, const MpiRun& mpi, const std::string& why, bool extraction) {
  ooc::OocNormalsOptions o;
  o.geometry = geometry;
  o.workDir = f.tileDir.empty() ? out + ".tiles" : f.tileDir;
  o.memoryBytes = memoryBudgetBytes();
  o.budgetName = "--max-mb";
  // Before saying anything: a budget the run cannot keep is one line with the figure it needs.
  ooc::requireOutOfCoreBudget(in, o, extraction);
#if defined(__GLIBC__)
  // Buffers of 1 MiB and more straight from the system and back to it when freed: glibc's
  // threshold otherwise grows with the tiles' buffers, which then stay resident in its arenas
  // under the next stage's (3 M points at --max-mb 62: 76 MiB peak, with this 59).
  mallopt(M_MMAP_THRESHOLD, 1 << 20);
#endif
  o.minTiles = f.tiles;
  o.keepWorkDir = f.keepTiles;
  o.progress = withTimeLeft(progressBar());
  o.rank = mpi.rank;
  o.ranks = mpi.ranks;
  o.barrier = mpi.barrier();
  say(fmt::format("{}: out of core ({}), tiles in {}{}", in, why, o.workDir.string(),
                  mpi.ranks > 1 ? fmt::format(", {} MPI ranks", mpi.ranks) : ""));
  return o;
}

void sayTiles(const ooc::OocNormalsReport& g, const std::string& in) {
  if (g.folderCleared) say("tile folder held another input's or other arguments' tiles: not reused, rebuilt");
  say(fmt::format("input        {} points ({}), {} tiles (largest {} points with halo){}, {} threads", g.points, in, g.tiles,
                  g.tilePointsMax, g.tilesReused ? fmt::format(", {} reused", g.tilesReused) : "", currentThreadCount()));
  if (g.tilesRecomputed)
    say(fmt::format("tile folder  {} tile(s) whose working files failed their proof (another tile's or input's, damaged, truncated): recomputed",
                    g.tilesRecomputed));
  say(fmt::format("halo         {} tile(s) widened, {} point(s) whose neighbours reach past the widest halo", g.haloWidenings,
                  g.inexactPoints));
}

double outOfCoreBudgetBytes() {
  // The streaming reader's and writer's buffers (8 MiB each at least) and one tile in flight: below
  // this floor the out-of-core path cannot keep its resident set within the budget.
  constexpr double kFloor = 16.0 * 1024 * 1024;
  budget().require("--max-mb", kFloor, "the out-of-core path (its read and write buffers and one tile)");
  return budget().bytes();
}

double inMemoryEstimate(const std::string& in, int k) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const double size = double(fs::file_size(in, ec));
  if (ec) return 0;  // the reader reports a missing file
  double points = size / 12.0;  // binary x y z floats, the densest encoding
  std::string ext = fs::path(in).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".ply") {
    try {
      points = double(ooc::PointReader(in).info().count);
    } catch (const Error&) {
      return 0;  // not a file the streaming reader takes: the in-memory reader says why
    }
  } else if (ext == ".xyz") {
    points = size / 24.0;  // ~8 characters per coordinate
  }
  return points * ooc::inMemoryNormalsBytesPerPoint(k) + size;
}

ProgressFn withTimeLeft(ProgressFn bar) {
  if (!bar) return {};
  struct State {
    std::string stage;
    std::chrono::steady_clock::time_point start;
  };
  auto st = std::make_shared<State>();
  return [bar, st](std::string_view stage, double f) {
    const auto now = std::chrono::steady_clock::now();
    if (stage != st->stage) st->stage = std::string(stage), st->start = now;
    const double el = std::chrono::duration<double>(now - st->start).count();
    std::string label(stage);
    if (f > 0.01 && f < 1 && el > 1) {
      const int left = int(el * (1 - f) / f + 0.5);
      label += left >= 60 ? fmt::format(" {}m{:02d}s left", left / 60, left % 60) : fmt::format(" {}s left", left);
    }
    bar(label, f);
  };
}

int launchedRank() {
  for (const char* v : {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"})
    if (const char* r = std::getenv(v)) return std::atoi(r);
  return 0;
}

int launchedRanks() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"})
    if (const char* s = std::getenv(v)) return std::max(1, std::atoi(s));
  return 1;
}

#ifdef LINESURF_HAVE_MPI
MpiRun::MpiRun() {
  if (launchedRanks() <= 1) return;
  int ready = 0;
  MPI_Initialized(&ready);
  if (!ready) MPI_Init(nullptr, nullptr);
  active = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
}
MpiRun::~MpiRun() {
  if (active) MPI_Finalize();
}
std::function<void()> MpiRun::barrier() const {
  if (!active) return {};
  return [] { MPI_Barrier(MPI_COMM_WORLD); };
}
void MpiRun::guard(const std::function<void()>& f) const {
  if (!active) return f();
  auto stop = [this](const std::string& message, int code) {
    // A bad input fails every rank alike: rank 0 speaks and its abort ends the others before they
    // repeat it; an error of one rank's own tiles is still said, by that rank, a moment later.
    if (rank != 0) std::this_thread::sleep_for(std::chrono::milliseconds(500));
    std::fprintf(stderr, "%s\n", message.c_str());
    std::fflush(stderr);
    MPI_Abort(MPI_COMM_WORLD, code);
    std::exit(code);
  };
  try {
    f();
  } catch (const Error& e) {
    stop(e.what(), e.kind() == Error::Kind::BadParameter ? 1 : e.kind() == Error::Kind::BadInput ? 2 : 3);
  } catch (const std::exception& e) {
    stop(std::string("linesurf: error: ") + e.what(), 3);
  }
}
#else
MpiRun::MpiRun() {
  if (launchedRanks() > 1)
    throwBadParameter("mpirun", "this linesurf was built without MPI; install openmpi-bin libopenmpi-dev and rebuild");
}
MpiRun::~MpiRun() = default;
std::function<void()> MpiRun::barrier() const { return {}; }
void MpiRun::guard(const std::function<void()>& f) const { f(); }
#endif

}  // namespace linesurf::cli
