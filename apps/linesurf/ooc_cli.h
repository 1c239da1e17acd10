#pragma once
// The out-of-core path's CLI side, shared by `normals` and the extractions: its flags, the memory
// budget that decides it, the progress label with the time left, and MPI (optional,
// LINESURF_HAVE_MPI).
#include <functional>
#include <string>

#include "linesurf/core/progress.h"
#include "linesurf/ooc/ooc_normals.h"

namespace CLI {
class App;
}

namespace linesurf::cli {

struct MpiRun;

/// --out-of-core, --tiles, --tile-dir, --keep-tiles.
struct OutOfCoreFlags {
  bool outOfCore = false;
  int tiles = 0;
  std::string tileDir;
  bool keepTiles = false;
  /// Why the command must go out of core whatever the budget ("--tiles 8", "started by mpirun",
  /// "--out-of-core"), or empty.
  std::string requested() const;
};
void bindOutOfCoreFlags(CLI::App* command, OutOfCoreFlags& flags);

/// One out-of-core run's options (budget, tile folder OUT.tiles unless --tile-dir, progress, this
/// MPI rank), after saying "IN: out of core (why), tiles in DIR"; first refuses (exit 1) a
/// --max-mb the run cannot keep, with the figure it needs. `extraction`: a point extraction.
ooc::OocNormalsOptions outOfCoreOptions(const GeometryOptions& geometry, const std::string& in, const std::string& out,
                                        const OutOfCoreFlags& flags, const MpiRun& mpi, const std::string& why, bool extraction);

/// The extractions' lines on the tiles: input, tiles, reuse, halos.
void sayTiles(const ooc::OocNormalsReport& r, const std::string& in);

/// The memory budget of a run, bytes: --max-mb. (One place, so that a reworked budget
/// mechanism changes only this.)
double memoryBudgetBytes();
/// The budget of an out-of-core run, bytes; refuses (exit 1) a budget below the path's floor.
double outOfCoreBudgetBytes();

/// Estimated bytes of the in-memory path for `in`, from its header (PLY) or size (XYZ).
double inMemoryEstimate(const std::string& in, int k);

/// "stage  12s left": a time-left estimate for the progress bar (per stage, from its rate so far).
ProgressFn withTimeLeft(ProgressFn bar);

/// Processes an MPI launcher started (mpirun sets OMPI_COMM_WORLD_SIZE / PMI_SIZE), else 1.
int launchedRanks();
/// This process's rank when mpirun started it (0 otherwise).
int launchedRank();

/// MPI for the length of one out-of-core run: this process's rank, the barrier between phases.
/// Without MPI in the build, constructing it under mpirun throws "built without MPI; install
/// openmpi-bin libopenmpi-dev".
struct MpiRun {
  int rank = 0, ranks = 1;
  bool active = false;
  MpiRun();
  ~MpiRun();
  MpiRun(const MpiRun&) = delete;
  MpiRun& operator=(const MpiRun&) = delete;
  std::function<void()> barrier() const;
  /// Runs f; on an error stops the whole job with the error's exit code (a failed rank would
  /// leave the others waiting at the next barrier). Without MPI: just f().
  void guard(const std::function<void()>& f) const;
};

}  // namespace linesurf::cli
