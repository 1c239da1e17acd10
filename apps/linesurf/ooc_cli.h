#pragma once
// The out-of-core path's CLI side, shared by `normals` and `extract eps-delta`: the memory budget
// that decides it, the progress label with the time left, and MPI (optional, LINESURF_HAVE_MPI).
#include <functional>
#include <string>

#include "linesurf/core/progress.h"

namespace linesurf::cli {

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
