// The out-of-core memory budget (ooc/ooc_normals.h): tiles follow where the points are, so far
// outliers that stretch the bounding box leave no tile over its share; a budget the run cannot
// keep is refused before any work.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "linesurf/core/error.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/ooc/ooc_normals.h"
#include "linesurf/ooc/synthetic_scan.h"
#include "test_util.h"

namespace linesurf {
namespace {

namespace fs = std::filesystem;

std::string bytesOf(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

/// A 200,000-point scan with `outliers` points appended, `far` scan diagonals from its centre in
/// directions spread over the sphere (the corrupted points a real scan may hold).
fs::path scanWithOutliers(const fs::path& d, int outliers, double far) {
  ooc::SyntheticScanOptions s;
  s.count = 200000;
  s.seed = 9;
  ooc::writeSyntheticScan(d / "clean.ply", s);
  HybridModel m = readModel(d / "clean.ply");
  Bounds3f bb;
  for (const Point& p : m.points) bb.extend(p.position);
  const Vec3d c = bb.center().cast<double>();
  const double diag = double(bb.diagonal().norm());
  for (int i = 0; i < outliers; ++i) {
    const double t = (i + 0.5) / outliers, phi = 2.399963 * i;  // golden-angle spiral
    const double z = 1 - 2 * t, r = std::sqrt(1 - z * z);
    const Vec3d dir(r * std::cos(phi), r * std::sin(phi), z);
    m.points.push_back({.position = (c + far * diag * (outliers == 1 ? Vec3d(1, 1, 1).normalized() : dir)).cast<float>()});
  }
  const fs::path out = d / "scan.ply";
  writeModel(out, m);
  return out;
}

/// Points (in input order) whose output records differ between two `normals` files with the same
/// header (x y z nx ny nz radius rows).
std::vector<size_t> differingRecords(const std::string& a, const std::string& b, size_t points) {
  std::vector<size_t> out;
  if (a.size() != b.size() || a.size() < points * 28) return {size_t(-1)};
  const size_t body = a.size() - points * 28;
  if (a.compare(0, body, b, 0, body) != 0) return {size_t(-1)};
  for (size_t i = 0; i < points; ++i)
    if (a.compare(body + i * 28, 28, b, body + i * 28, 28) != 0) out.push_back(i);
  return out;
}

/// `normals` in memory and out of core under a small budget: no tile over its share, and every
/// record the in-memory one but those of outliers whose neighbours lie beyond every halo.
void checkBudgetHolds(const fs::path& d, int outliers, double far) {
  const fs::path in = scanWithOutliers(d, outliers, far);
  ooc::OocNormalsOptions o;
  o.geometry.delaunayNeighbours = o.geometry.curvature = false;
  o.workDir = d / "tiles";
  o.memoryBytes = 128.0 * 1024 * 1024;  // tiles of about 60,000 points
  // Out of core first: the budget counts what this process holds already.
  const ooc::OocNormalsReport r = ooc::computeNormalsOutOfCore(in, d / "ooc.ply", o);
  {
    HybridModel m = readModel(in);
    GeometryOptions g;
    g.delaunayNeighbours = g.curvature = false;
    applyGeometry(m, computePointGeometry(m, g));
    writeModel(d / "mem.ply", m);
  }
  EXPECT_EQ(r.points, 200000u + uint64_t(outliers));
  // The grid over the stretched box holds the scan in one cell: cut again until each tile fits.
  if (outliers > 0) {
    EXPECT_GE(r.refinedTiles, 1u);
  } else {
    EXPECT_EQ(r.refinedTiles, 0u);
  }
  EXPECT_GE(r.tiles, 4u);
  EXPECT_GT(r.tileInteriorBudget, 10000.0);
  EXPECT_LE(double(r.tileInteriorMax), r.tileInteriorBudget) << r.tiles << " tiles";
  const std::vector<size_t> diff = differingRecords(bytesOf(d / "mem.ply"), bytesOf(d / "ooc.ply"), r.points);
  for (size_t i : diff) EXPECT_GE(i, 200000u) << "scan point " << i << " differs from the in-memory record";
  EXPECT_LE(diff.size(), size_t(outliers));
  EXPECT_LE(r.inexactPoints, uint64_t(outliers));
}

TEST(OocBudget, CleanScanKeepsItsTilingAndTheInMemoryBytes) {
  const fs::path d = test::scratchDir("ooc_budget_clean");
  checkBudgetHolds(d, 0, 0);
  EXPECT_TRUE(bytesOf(d / "ooc.ply") == bytesOf(d / "mem.ply"));
}

TEST(OocBudget, OneFarOutlierLeavesNoTileOverItsShare) { checkBudgetHolds(test::scratchDir("ooc_budget_one"), 1, 1000); }

TEST(OocBudget, FiftyFarOutliersLeaveNoTileOverItsShare) { checkBudgetHolds(test::scratchDir("ooc_budget_fifty"), 50, 1000); }

TEST(OocBudget, AnOutlierAMillionDiagonalsAwayLeavesNoTileOverItsShare) {
  checkBudgetHolds(test::scratchDir("ooc_budget_million"), 1, 1e6);
}

// A budget below what the process, the stages' buffers and the smallest tiles need: one
// BadParameter naming the budget with the figure, before any file or folder is made.
TEST(OocBudget, ABudgetTheRunCannotKeepIsRefusedBeforeAnyWork) {
  const fs::path d = test::scratchDir("ooc_budget_refused");
  ooc::SyntheticScanOptions s;
  s.count = 20000;
  ooc::writeSyntheticScan(d / "scan.ply", s);
  ooc::OocNormalsOptions o;
  o.workDir = d / "tiles";
  o.memoryBytes = 4.0 * 1024 * 1024;
  o.budgetName = "--max-mb";
  try {
    ooc::computeNormalsOutOfCore(d / "scan.ply", d / "out.ply", o);
    FAIL() << "a 4 MiB budget was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadParameter);
    const std::string m = e.what();
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
    EXPECT_NE(m.find("--max-mb: the out-of-core path needs at least "), std::string::npos) << m;
    EXPECT_NE(m.find("more than --max-mb 4"), std::string::npos) << m;
  }
  EXPECT_FALSE(fs::exists(d / "out.ply"));
  EXPECT_FALSE(fs::exists(d / "tiles"));

  // The CLI: exit 1 (a bad parameter), one line, nothing written.
  const std::string q = "'" + d.string() + "/";
  const auto r = test::runCli("-q normals " + q + "scan.ply' -o " + q + "cli.ply' --out-of-core --max-mb 16");
  EXPECT_EQ(r.exitCode, 1) << r.out;
  EXPECT_NE(r.out.find("--max-mb: the out-of-core path needs at least "), std::string::npos) << r.out;
  EXPECT_EQ(r.out.find('\n'), r.out.size() - 1) << r.out;
  EXPECT_FALSE(fs::exists(d / "cli.ply"));
  EXPECT_FALSE(fs::exists(d / "cli.ply.tiles"));
  const auto e = test::runCli("-q extract eps-delta " + q + "scan.ply' -o " + q + "cli.ply' --tiles 4 --max-mb 16");
  EXPECT_EQ(e.exitCode, 1) << e.out;
  EXPECT_NE(e.out.find("--max-mb 16"), std::string::npos) << e.out;
  EXPECT_FALSE(fs::exists(d / "cli.ply"));
}

}  // namespace
}  // namespace linesurf
