// Out-of-core normals (ooc/ooc_normals.h) against the in-memory path, and the streaming I/O.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "linesurf/core/error.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/ooc/ooc_normals.h"
#include "linesurf/ooc/point_stream.h"
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

/// What `linesurf normals IN -o OUT` writes in memory.
HybridModel inMemoryNormals(const fs::path& in, const fs::path& out) {
  HybridModel m = readModel(in);
  GeometryOptions o;
  o.delaunayNeighbours = o.curvature = false;
  const PointGeometry g = computePointGeometry(m, o);
  applyGeometry(m, g);
  writeModel(out, m);
  return m;
}

ooc::OocNormalsOptions tiled(const fs::path& dir, int tiles) {
  ooc::OocNormalsOptions o;
  o.geometry.delaunayNeighbours = o.geometry.curvature = false;
  o.workDir = dir;
  o.minTiles = tiles;
  o.keepWorkDir = true;
  return o;
}

// An open sheet scanned from above, in tiles: the join sums the tiles' side votes to the
// in-memory rule's, so the file is the in-memory one and the normals face up.
TEST(OocNormals, TerrainInTilesFacesUpAsInMemory) {
  const fs::path d = test::scratchDir("ooc_terrain");
  HybridModel sheet;
  uint64_t s = 12345;
  auto next = [&s] {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return float(double(s >> 11) * (1.0 / 9007199254740992.0));
  };
  for (int i = 0; i < 120000; ++i) {
    const float x = 100 * next(), y = 100 * next();
    const float z = 2.0f * std::sin(0.11f * x) * std::cos(0.07f * y) + 0.05f * (next() - 0.5f);
    sheet.points.push_back({.position = Vec3f(x, y, z)});
  }
  writeModel(d / "terrain.ply", sheet);
  const HybridModel ref = inMemoryNormals(d / "terrain.ply", d / "mem.ply");
  const ooc::OocNormalsReport r = ooc::computeNormalsOutOfCore(d / "terrain.ply", d / "ooc.ply", tiled(d / "tiles", 12));
  EXPECT_GE(r.tiles, 9u);
  EXPECT_TRUE(slurp(d / "ooc.ply") == slurp(d / "mem.ply"));
  size_t up = 0;
  for (const Point& p : ref.points) up += p.normal.z() > 0;
  EXPECT_GE(double(up), 0.99 * double(ref.points.size()));
}

TEST(OocNormals, ForcedTilesMatchTheInMemoryPath) {
  const fs::path d = test::scratchDir("ooc_match");
  ooc::SyntheticScanOptions s;
  s.count = 300000;
  s.seed = 5;
  ooc::writeSyntheticScan(d / "scan.ply", s);
  const HybridModel ref = inMemoryNormals(d / "scan.ply", d / "mem.ply");

  const ooc::OocNormalsReport r = ooc::computeNormalsOutOfCore(d / "scan.ply", d / "ooc.ply", tiled(d / "tiles", 24));
  EXPECT_GE(r.tiles, 16u);
  EXPECT_EQ(r.points, s.count);
  const HybridModel got = readModel(d / "ooc.ply");
  ASSERT_EQ(got.points.size(), ref.points.size());
  size_t samePos = 0, closeNormal = 0, agree = 0, sameRadius = 0;
  for (size_t i = 0; i < ref.points.size(); ++i) {
    const Point &a = ref.points[i], &b = got.points[i];
    samePos += a.position == b.position;  // every point exactly once, in the input's order
    closeNormal += (a.normal - b.normal).cwiseAbs().maxCoeff() <= 1e-6f || (a.normal + b.normal).cwiseAbs().maxCoeff() <= 1e-6f;
    agree += a.normal.dot(b.normal) > 0;
    sameRadius += std::abs(a.radius - b.radius) <= 1e-6f * a.radius;
  }
  const double n = double(ref.points.size());
  EXPECT_EQ(samePos, ref.points.size());
  EXPECT_GE(double(closeNormal) / n, 0.999);
  EXPECT_GE(double(agree) / n, 0.999);
  EXPECT_GE(double(sameRadius) / n, 0.999);
  // Beyond the bound: on this scan every halo holds, so the file is the in-memory one byte for byte.
  EXPECT_EQ(r.inexactPoints, 0u);
  EXPECT_TRUE(slurp(d / "ooc.ply") == slurp(d / "mem.ply"));

  // A killed run: half of the tile results gone; the rerun reuses the rest, same bytes.
  std::vector<fs::path> results;
  for (const auto& e : fs::directory_iterator(d / "tiles" / "results")) results.push_back(e.path());
  std::sort(results.begin(), results.end());
  ASSERT_EQ(results.size(), r.tiles);
  for (size_t i = 0; i < results.size(); i += 2) fs::remove(results[i]);
  const ooc::OocNormalsReport again = ooc::computeNormalsOutOfCore(d / "scan.ply", d / "resumed.ply", tiled(d / "tiles", 24));
  EXPECT_EQ(again.tilesReused, r.tiles / 2);
  EXPECT_FALSE(again.folderCleared);
  EXPECT_TRUE(slurp(d / "resumed.ply") == slurp(d / "ooc.ply"));

  // The same folder for another input: detected, not reused.
  s.seed = 6;
  s.count = 20000;
  ooc::writeSyntheticScan(d / "other.ply", s);
  const ooc::OocNormalsReport other = ooc::computeNormalsOutOfCore(d / "other.ply", d / "other_ooc.ply", tiled(d / "tiles", 4));
  EXPECT_TRUE(other.folderCleared);
  EXPECT_EQ(other.tilesReused, 0u);
  EXPECT_EQ(readModel(d / "other_ooc.ply").points.size(), s.count);
}

TEST(OocNormals, RefusesAFolderThatIsNotATileFolder) {
  const fs::path d = test::scratchDir("ooc_foreign");
  ooc::SyntheticScanOptions s;
  s.count = 5000;
  ooc::writeSyntheticScan(d / "scan.ply", s);
  fs::create_directories(d / "mine");
  std::ofstream(d / "mine" / "notes.txt") << "keep me\n";
  try {
    ooc::computeNormalsOutOfCore(d / "scan.ply", d / "out.ply", tiled(d / "mine", 2));
    FAIL() << "a foreign folder was used";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadParameter);
  }
  EXPECT_TRUE(fs::exists(d / "mine" / "notes.txt"));
  EXPECT_FALSE(fs::exists(d / "out.ply"));
}

TEST(OocNormals, TruncatedInputFailsBeforeWorkAndLeavesNothing) {
  const fs::path d = test::scratchDir("ooc_trunc");
  ooc::SyntheticScanOptions s;
  s.count = 10000;
  ooc::writeSyntheticScan(d / "scan.ply", s);
  const std::string bytes = slurp(d / "scan.ply");
  std::ofstream(d / "cut.ply", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  try {
    ooc::computeNormalsOutOfCore(d / "cut.ply", d / "out.ply", tiled(d / "tiles", 2));
    FAIL() << "a truncated file was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadInput);
    EXPECT_NE(std::string(e.what()).find("truncated binary body"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(fs::exists(d / "out.ply"));
  EXPECT_FALSE(fs::exists(d / "tiles"));
}

TEST(PointStream, ChunksReadWhatTheWholeFileReaderReads) {
  const fs::path d = test::scratchDir("ooc_stream");
  HybridModel m;
  for (int i = 0; i < 1000; ++i) {
    Point p;
    p.position = Vec3f(float(i) * 0.5f, std::sin(float(i)), float(i % 7));
    p.normal = Vec3f(0, float(i % 3), 1).normalized();
    m.points.push_back(p);
  }
  m.attributes.normals = true;
  m.comments = {"a comment"};
  writeModel(d / "m.ply", m);
  writeModel(d / "m.xyz", m);
  for (const char* name : {"m.ply", "m.xyz"}) {
    const HybridModel whole = readModel(d / name);
    ooc::PointReader r(d / name);
    EXPECT_EQ(r.info().count, whole.points.size()) << name;
    EXPECT_TRUE(r.info().normals) << name;
    EXPECT_EQ(r.info().comments, whole.comments) << name;
    std::vector<Vec3f> pos, nrm;
    size_t at = 0;
    while (r.read(pos, nrm, 77) > 0) {
      for (size_t i = 0; i < pos.size(); ++i, ++at) {
        ASSERT_LT(at, whole.points.size());
        EXPECT_EQ(pos[i], whole.points[at].position) << name << " point " << at;
        EXPECT_EQ(nrm[i], whole.points[at].normal) << name << " point " << at;
      }
    }
    EXPECT_EQ(at, whole.points.size()) << name;
  }
}

TEST(PointStream, WriterWritesTheBytesWriteModelWrites) {
  const fs::path d = test::scratchDir("ooc_writer");
  HybridModel m;
  std::vector<Vec3f> pos, nrm;
  std::vector<float> rad;
  for (int i = 0; i < 500; ++i) {
    Point p;
    p.position = Vec3f(float(i), float(2 * i), -float(i));
    p.normal = Vec3f(1, 0, 0);
    p.radius = 0.25f * float(i);
    m.points.push_back(p);
    pos.push_back(p.position), nrm.push_back(p.normal), rad.push_back(p.radius);
  }
  m.attributes.normals = m.attributes.radii = true;
  m.comments = {"first", "TextureFile looks like a key"};
  writeModel(d / "whole.ply", m);
  {
    ooc::PlyPointWriter w(d / "streamed.ply", pos.size(), m.comments, true, true);
    w.write(pos.data(), nrm.data(), rad.data(), 123);
    w.write(pos.data() + 123, nrm.data() + 123, rad.data() + 123, pos.size() - 123);
    w.finish();
  }
  EXPECT_TRUE(slurp(d / "streamed.ply") == slurp(d / "whole.ply"));
  {
    ooc::PlyPointWriter w(d / "abandoned.ply", pos.size(), {}, true, true);
    w.write(pos.data(), nrm.data(), rad.data(), 10);
  }  // destroyed unfinished: nothing left
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(d)) files += e.path().filename().string().find("abandoned") != std::string::npos;
  EXPECT_EQ(files, 0u);
}

// Curvature (§6.1.2) out of core: each tile's interior points under the tile's orientation, turned
// (values negated and swapped, directions exchanged) where the join flips the tile's component:
// the in-memory file byte for byte, with both fits.
TEST(OocNormals, CurvatureInTilesIsTheInMemoryCurvature) {
  const fs::path d = test::scratchDir("ooc_curvature");
  ooc::SyntheticScanOptions s;
  s.count = 120000;
  s.seed = 3;
  ooc::writeSyntheticScan(d / "scan.ply", s);
  const std::string in = "'" + (d / "scan.ply").string() + "'";
  for (const std::string fit : {"taubin", "quadric"}) {
    const std::string mem = "'" + (d / ("mem_" + fit + ".ply")).string() + "'";
    const std::string ooc = "'" + (d / ("ooc_" + fit + ".ply")).string() + "'";
    ASSERT_EQ(test::runCli("-q normals " + in + " -o " + mem + " --curvature --curvature-fit " + fit).exitCode, 0);
    const auto r = test::runCli("normals " + in + " -o " + ooc + " --curvature --curvature-fit " + fit + " --tiles 40");
    ASSERT_EQ(r.exitCode, 0) << r.out;
    // The flip path is taken: some tile components are turned by the join.
    EXPECT_EQ(r.out.find(" 0 tile component(s) flipped"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("tile component(s) flipped"), std::string::npos) << r.out;
    const HybridModel m = readModel(d / ("ooc_" + fit + ".ply"));
    ASSERT_TRUE(m.pointProperties.count("k_min") && m.pointProperties.count("dmin_z")) << fit;
    EXPECT_TRUE(slurp(d / ("ooc_" + fit + ".ply")) == slurp(d / ("mem_" + fit + ".ply"))) << fit;
  }
}

TEST(OocNormals, CliPicksTheOutOfCorePathWhenTheInputDoesNotFit) {
  const fs::path d = test::scratchDir("ooc_cli");
  ooc::SyntheticScanOptions s;
  s.count = 200000;  // about 95 MiB in memory, over --max-mb 64; the out-of-core path needs less
  ooc::writeSyntheticScan(d / "scan.ply", s);
  const auto big = test::runCli("normals '" + (d / "scan.ply").string() + "' -o '" + (d / "mem.ply").string() + "'");
  ASSERT_EQ(big.exitCode, 0) << big.out;
  EXPECT_EQ(big.out.find("out of core"), std::string::npos) << big.out;
  const auto small = test::runCli("normals '" + (d / "scan.ply").string() + "' -o '" + (d / "ooc.ply").string() + "' --max-mb 64");
  ASSERT_EQ(small.exitCode, 0) << small.out;
  EXPECT_NE(small.out.find("out of core"), std::string::npos) << small.out;
  EXPECT_TRUE(slurp(d / "ooc.ply") == slurp(d / "mem.ply"));
  EXPECT_FALSE(fs::exists(d / "ooc.ply.tiles"));  // removed after success
  // The output of `normals` (x y z nx ny nz radius) goes on out of core: eps-delta on it picks
  // the out-of-core path by itself under a small budget (the radius is skipped, as in memory
  // every radius is set again).
  const auto next = test::runCli("extract eps-delta '" + (d / "ooc.ply").string() + "' -o '" + (d / "hybrid.ply").string() +
                                 "' --max-mb 64");
  ASSERT_EQ(next.exitCode, 0) << next.out;
  EXPECT_NE(next.out.find("out of core"), std::string::npos) << next.out;
}

}  // namespace
}  // namespace linesurf
