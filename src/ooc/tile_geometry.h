#pragma once
// The per-tile geometry stage of the out-of-core pipeline (§6.1 on tiles): each tile with its
// halo through the in-memory code (computePointGeometry), so that every point whose neighbour
// queries stay inside the halo gets exactly the in-memory kNN, PCA normal, spacing and cover
// radius; the halo is widened until they do (or it is one tile wide).
#include <algorithm>
#include <atomic>
#include <mutex>
#include <string_view>

#include "linesurf/core/parallel.h"
#include "linesurf/core/progress.h"
#include "ooc/tile_store.h"

namespace linesurf::ooc::detail {

/// Computes one tile's geometry and writes its result file (and, with `normals --curvature`, its
/// curvature file; for an extraction, its own points' geometry). The result file is written last:
/// its presence marks the tile done.
void processTile(const Run& r, uint32_t tile);

/// Runs f on every tile of `todo`, at most r.concurrent at once (the memory budget holds that
/// many tiles), each worker taking the next tile as soon as it is free: tiles differ in size by
/// orders of magnitude, and running them in fixed groups left a core idle while the largest tile
/// of a group finished (the per-tile MST is serial). Results do not depend on the schedule: each
/// tile writes its own files. Progress follows the points done.
template <class F>
void forEachTile(const Run& r, const std::vector<uint32_t>& todo, std::string_view stage, const F& f) {
  uint64_t total = 0;
  for (uint32_t tile : todo) total += r.tileCounts[r.denseOf.at(tile)];
  std::atomic<size_t> next{0};
  std::atomic<bool> failed{false};
  std::mutex progressMutex;
  uint64_t done = 0;
  const size_t workers = std::min(r.concurrent, std::max<size_t>(todo.size(), 1));
  parallelFor(0, workers, [&](size_t) {
    for (;;) {
      const size_t i = next++;
      if (i >= todo.size() || failed) return;
      try {
        f(todo[i]);
      } catch (...) {
        failed = true;
        throw;
      }
      std::lock_guard<std::mutex> lock(progressMutex);
      done += r.tileCounts[r.denseOf.at(todo[i])];
      reportProgress(r.o.progress, stage, total ? double(done) / double(total) : 1.0);
    }
  }, 1);
}

}  // namespace linesurf::ooc::detail
