// The out-of-core pipeline, stage after stage (see pipeline.h; folder format in docs/file-format.md
// "Tile folder"; design in docs/decisions.md).
//
// Passes over the input: (1) bounding box, (2) a 64^3 histogram that sizes the tiles, (3) binning
// into one file per tile, tiles over the budget cut again over their own points (partition.cpp). Then every tile is processed with its halo by
// computePointGeometry (tile_geometry.cpp: tiles in flight in parallel, each with the in-memory
// code inside), its results written to a file of its own (a killed run resumes from them). The
// orientation pass joins the tiles' MST orientations through the points they share (join.cpp),
// and the write pass merges the tiles back into the input's order (normals_writer.cpp), or the
// extraction runs per tile and its hybrid is merged (tile_extract.cpp).
#include "ooc/pipeline.h"

#include <algorithm>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "ooc/join.h"
#include "ooc/memory_budget.h"
#include "ooc/normals_writer.h"
#include "ooc/partition.h"
#include "ooc/tile_geometry.h"

namespace linesurf::ooc {
namespace detail {

OocNormalsReport runPipeline(const fs::path& in, const fs::path& out, const OocNormalsOptions& o, const TileExtraction* extraction,
                             ExtractTotals* et) {
  validate(o.geometry);
  if (o.workDir.empty()) throwBadParameter("workDir", "empty path");
  if (o.ranks < 1 || o.rank < 0 || o.rank >= o.ranks) throwBadParameter("rank", "must be in [0, ranks)");
  // Before any work and before any file: a budget the run cannot keep.
  requireBudget(in, o, extraction != nullptr, extraction && extraction->usesCurvature());
  OocNormalsReport rep;
  Run r{o, in, out, o.workDir};
  r.extraction = extraction;
  r.extractionCurvature = extraction && extraction->usesCurvature();
  const bool extract = r.extracting();
  r.concurrent = size_t(std::max(1, std::min(currentThreadCount(), kTilesInFlight)));
  r.ioBytes = ioBufferBytes(o);

  if (o.ranks > 1 && !o.barrier) throwBadParameter("barrier", "needed when ranks > 1");
  const FileIdentity id = fileIdentity(in);
  const json wantInput = identityJson(in, id), wantArgs = argumentsJson(o, extraction);
  r.inputHash = id.hash;
  r.argsHash = hash64(wantArgs.dump().data(), wantArgs.dump().size());
  std::error_code ec;
  if (o.rank == 0) prepareFolder(r, rep, id, wantInput, wantArgs);
  if (o.barrier) o.barrier();
  if (o.rank != 0) loadSharedManifest(r, wantInput, wantArgs);
  releaseFreedMemory();
  rep.points = r.info.count;
  rep.tiles = r.tileIds.size();
  rep.refinedTiles = r.refinements.size();
  rep.tileInteriorBudget = r.tilePoints / kHaloShare;
  for (uint64_t c : r.tileCounts) rep.tileInteriorMax = std::max(rep.tileInteriorMax, c);
  {
    const Vec3f diag = r.bounds.diagonal();
    r.dupTol = 1e-6f * (r.info.count > 0 ? diag.norm() : 0.0f);
  }

  // Tiles: this rank's share, those without a result file, a few in flight at once.
  Timer t;
  std::vector<uint32_t> todo;
  for (size_t d = 0; d < r.tileIds.size(); ++d) {
    if (int(d % size_t(o.ranks)) != o.rank) continue;
    const uint32_t tile = r.tileIds[d];
    // Done: its result, with the curvature of `normals --curvature`, or with the geometry the
    // extraction reads (unless the tile is extracted already, which removes it), each proving
    // it is this tile's, of this input and these arguments, and whole. Anything else is removed
    // and the tile computed again: a swapped, damaged, truncated or foreign file is never read.
    if (proven(r, Stage::Result, tile, r.resultPath(tile)) &&
        (!r.curvatureOut() || proven(r, Stage::Curvature, tile, r.curvaturePath(tile))) &&
        (!extract || proven(r, Stage::Geometry, tile, r.ownGeometryPath(tile)) ||
         proven(r, Stage::Extraction, tile, r.extractPath(tile)))) {
      ++rep.tilesReused;
      continue;
    }
    bool any = false;
    for (const fs::path& p : {r.resultPath(tile), r.curvaturePath(tile), r.ownGeometryPath(tile), r.extractPath(tile)})
      any = fs::remove(p, ec) || any;
    if (any) ++rep.tilesRecomputed;
    todo.push_back(tile);
  }
  reportProgress(o.progress, "tiles", 0.0);
  forEachTile(r, todo, "tiles", [&](uint32_t tile) { processTile(r, tile); });
  rep.tTiles = t.seconds();
  releaseFreedMemory();
  if (o.barrier) o.barrier();
  if (o.rank != 0 && !extract) return rep;  // rank 0 joins the orientations and writes the output
  std::vector<size_t> nodeOffset;
  std::vector<uint8_t> flip;
  if (o.rank != 0) {
    // The extraction needs rank 0's orientation: wait for it, then read it.
    o.barrier();
    readOrientation(r, nodeOffset, flip, rep.averageSpacing);
  } else {
    joinTiles(r, rep, nodeOffset, flip);
    if (extract && o.ranks > 1) {
      writeOrientation(r, nodeOffset, flip, rep.averageSpacing);
      o.barrier();
    }
  }
  releaseFreedMemory();
  if (extract) {
    extractTiles(r, nodeOffset, flip, rep.averageSpacing, *et);
    releaseFreedMemory();
    if (o.barrier) o.barrier();
    if (o.rank != 0) return rep;
    t.reset();
    writeHybrid(r, *et);
    et->tWrite = t.seconds();
  } else {
    t.reset();
    writeNormals(r, flip, nodeOffset, rep.averageSpacing);
    rep.tWrite = t.seconds();
  }
  if (!o.keepWorkDir) fs::remove_all(r.dir, ec);
  return rep;
}

}  // namespace detail

double inMemoryNormalsBytesPerPoint(int k) {
  // Model point (~64 B), neighbour rows (8k), PCA and flags (~40), symmetrised adjacency with its
  // edge keys (~11k, packed) and the forest's per-point sets (~50) while the orientation runs,
  // later the Delaunay scratch (8k + 4), spacing and cover radius (8), kd-tree (~8), plus the
  // reader's copy of the file's rows while the model is built (~24). Measured at k = 12: 386 B a
  // point at 2 M points, 372 at 10 M, under the 478 this gives.
  return 190.0 + 24.0 * double(k);
}

OocNormalsReport computeNormalsOutOfCore(const std::filesystem::path& in, const std::filesystem::path& out,
                                         const OocNormalsOptions& o) {
  return detail::runPipeline(in, out, o, nullptr, nullptr);
}

}  // namespace linesurf::ooc
