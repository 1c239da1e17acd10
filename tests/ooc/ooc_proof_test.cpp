// Kept tile folders (ooc/tile_store.h): every result file proves its stage, input, arguments and
// tile before a resumed run uses it. Each kind of damage (another tile's file copied over, one
// flipped byte, a truncated file, an input changed with its old mtime restored) against each
// result kind and stage must give the clean run's bytes: the damaged tile is recomputed, never
// trusted.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "linesurf/extract/eps_delta.h"
#include "linesurf/ooc/ooc_extract.h"
#include "linesurf/ooc/ooc_normals.h"
#include "linesurf/ooc/synthetic_scan.h"
#include "test_util.h"

namespace linesurf {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

void spit(const fs::path& p, const std::string& bytes) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f << bytes;
}

enum class Damage { Swapped, Flipped, Truncated };

const char* name(Damage d) { return d == Damage::Swapped ? "swapped" : d == Damage::Flipped ? "flipped" : "truncated"; }

/// Damages `results/PREFIX_000001.res` (from tile 0's file when swapped).
void damage(const fs::path& results, const std::string& prefix, Damage d) {
  const fs::path victim = results / (prefix + "_000001.res"), donor = results / (prefix + "_000000.res");
  ASSERT_TRUE(fs::exists(victim)) << victim;
  std::string bytes = slurp(victim);
  ASSERT_GT(bytes.size(), 64u);
  switch (d) {
    case Damage::Swapped: bytes = slurp(donor); break;
    case Damage::Flipped: bytes[bytes.size() / 3] ^= 0x10; break;
    case Damage::Truncated: bytes.resize(bytes.size() / 2); break;
  }
  spit(victim, bytes);
}

struct Folder {
  fs::path dir, scan;
  ooc::OocNormalsOptions options;
};

Folder makeFolder(const std::string& tag) {
  Folder f;
  f.dir = test::scratchDir(tag);
  f.scan = f.dir / "scan.ply";
  ooc::SyntheticScanOptions s;
  s.count = 40000;
  s.seed = 9;
  ooc::writeSyntheticScan(f.scan, s);
  f.options.geometry.delaunayNeighbours = f.options.geometry.curvature = false;
  f.options.workDir = f.dir / "tiles";
  f.options.minTiles = 4;
  f.options.keepWorkDir = true;
  return f;
}

TEST(OocProof, NormalsRecomputeADamagedTileResult) {
  for (Damage d : {Damage::Swapped, Damage::Flipped, Damage::Truncated}) {
    SCOPED_TRACE(name(d));
    Folder f = makeFolder(std::string("ooc_proof_normals_") + name(d));
    const ooc::OocNormalsReport clean = ooc::computeNormalsOutOfCore(f.scan, f.dir / "clean.ply", f.options);
    ASSERT_GE(clean.tiles, 4u);
    damage(f.options.workDir / "results", "tile", d);
    const ooc::OocNormalsReport again = ooc::computeNormalsOutOfCore(f.scan, f.dir / "again.ply", f.options);
    EXPECT_EQ(again.tilesRecomputed, 1u);
    EXPECT_EQ(again.tilesReused, clean.tiles - 1);
    EXPECT_TRUE(slurp(f.dir / "again.ply") == slurp(f.dir / "clean.ply"));
  }
}

TEST(OocProof, EpsDeltaRecomputesADamagedGeometryOrExtractionFile) {
  EpsDeltaOptions e;
  e.provenance = true;
  for (const std::string prefix : {"tile", "extract"})
    for (Damage d : {Damage::Swapped, Damage::Flipped, Damage::Truncated}) {
      SCOPED_TRACE(prefix + " " + name(d));
      Folder f = makeFolder("ooc_proof_eps_" + prefix + "_" + name(d));
      const ooc::OocEpsDeltaReport clean = ooc::extractEpsDeltaOutOfCore(f.scan, f.dir / "clean.ply", f.options, e);
      ASSERT_GE(clean.geometry.tiles, 4u);
      ASSERT_GT(clean.segments, 0u);
      damage(f.options.workDir / "results", prefix, d);
      const ooc::OocEpsDeltaReport again = ooc::extractEpsDeltaOutOfCore(f.scan, f.dir / "again.ply", f.options, e);
      EXPECT_GE(again.geometry.tilesRecomputed, 1u);
      EXPECT_TRUE(slurp(f.dir / "again.ply") == slurp(f.dir / "clean.ply"));
    }
}

// An input edited where a sampled identity would not look, its size and mtime restored: the
// whole content is hashed, so the folder is rebuilt and the output is that of the new input.
TEST(OocProof, AnInputChangedUnderItsOldMtimeIsNotReused) {
  Folder f = makeFolder("ooc_proof_stale");
  ooc::computeNormalsOutOfCore(f.scan, f.dir / "old.ply", f.options);
  const auto mtime = fs::last_write_time(f.scan);
  std::string bytes = slurp(f.scan);
  // A byte in the middle of a binary float: a position moves by a few ulps.
  bytes[bytes.size() / 2 + 1] ^= 0x01;
  spit(f.scan, bytes);
  fs::last_write_time(f.scan, mtime);
  const ooc::OocNormalsReport again = ooc::computeNormalsOutOfCore(f.scan, f.dir / "again.ply", f.options);
  EXPECT_EQ(again.tilesReused, 0u);

  ooc::OocNormalsOptions fresh = f.options;
  fresh.workDir = f.dir / "fresh_tiles";
  ooc::computeNormalsOutOfCore(f.scan, f.dir / "fresh.ply", fresh);
  EXPECT_TRUE(slurp(f.dir / "again.ply") == slurp(f.dir / "fresh.ply"));
  EXPECT_FALSE(slurp(f.dir / "again.ply") == slurp(f.dir / "old.ply"));
}

}  // namespace
}  // namespace linesurf
