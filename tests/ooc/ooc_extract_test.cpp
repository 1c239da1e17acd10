// The extractions out of core (ooc/ooc_extract.h), (ε,δ), shape approximation and lines of
// curvature, against the in-memory extractions.
#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <map>
#include <sstream>

#include "linesurf/core/parallel.h"
#include "linesurf/extract/curvature_lines.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/io/model_io.h"
#include "linesurf/ooc/ooc_extract.h"
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

/// Every input point exactly once in a hybrid with provenance: kept (matched by position, in
/// input order) or in exactly one segment.
void expectEveryPointOnce(const HybridModel& cloud, const HybridModel& out) {
  ASSERT_EQ(out.provenance.size(), out.segments.size());
  std::vector<int> seen(cloud.points.size(), 0);
  for (const auto& prov : out.provenance)
    for (uint32_t i : prov) {
      ASSERT_LT(i, seen.size());
      ++seen[i];
    }
  size_t k = 0;
  for (size_t i = 0; i < cloud.points.size(); ++i)
    if (!seen[i]) {
      ASSERT_LT(k, out.points.size());
      EXPECT_EQ(out.points[k++].position, cloud.points[i].position);
      seen[i] = 1;
    }
  EXPECT_EQ(k, out.points.size());
  for (int c : seen) ASSERT_EQ(c, 1);
}

TEST(OocEpsDelta, TilesKeepEveryPointOnceAndTheBounds) {
  const fs::path d = test::scratchDir("ooc_eps_delta");
  ooc::SyntheticScanOptions s;
  s.count = 200000;
  s.seed = 12;
  s.noise = 0.02;  // smoother than the default: more segments to lose at the seams
  ooc::writeSyntheticScan(d / "scan.ply", s);
  EpsDeltaOptions e;
  e.provenance = true;

  const HybridModel cloud = readModel(d / "scan.ply");
  GeometryOptions go;
  go.curvature = false;
  const PointGeometry g = computePointGeometry(cloud, go);
  EpsDeltaStats ref;
  extractEpsDelta(cloud, g, e, &ref);

  ooc::OocNormalsOptions o;
  o.geometry = go;
  o.workDir = d / "tiles";
  o.minTiles = 16;
  const ooc::OocEpsDeltaReport r = ooc::extractEpsDeltaOutOfCore(d / "scan.ply", d / "ooc.ply", o, e);
  EXPECT_GE(r.geometry.tiles, 16u);
  EXPECT_EQ(r.epsilon, ref.epsilon);  // the whole cloud's average spacing, not a tile's
  const HybridModel out = readModel(d / "ooc.ply");
  ASSERT_EQ(out.points.size(), r.keptPoints);
  ASSERT_EQ(out.segments.size(), r.segments);
  expectEveryPointOnce(cloud, out);
  // Counts near the in-memory extraction: segments cannot cross a tile border.
  EXPECT_NEAR(double(r.keptPoints), double(ref.keptPoints), 0.01 * double(ref.keptPoints));
  EXPECT_NEAR(double(r.segments), double(ref.segments), 0.05 * double(ref.segments));
  EXPECT_GT(r.segments, 0u);
  // And the (ε,δ) bound of every segment, proved by verify-extraction.
  const auto v = test::runCli("verify-extraction '" + (d / "scan.ply").string() + "' '" + (d / "ooc.ply").string() + "'");
  EXPECT_EQ(v.exitCode, 0) << v.out;
}

// The output of `normals` (with its radii) goes on out of core, and the extraction keeps each
// kept point's radius from the file as the in-memory extraction does (it used to drop them and
// fall back on the spacing).
TEST(OocEpsDelta, KeepsTheRadiiOfItsInput) {
  const fs::path d = test::scratchDir("ooc_eps_delta_radii");
  ooc::SyntheticScanOptions s;
  s.count = 60000;
  s.seed = 4;
  ooc::writeSyntheticScan(d / "scan.ply", s);
  const std::string q = "'" + d.string() + "/";
  ASSERT_EQ(test::runCli("-q normals " + q + "scan.ply' -o " + q + "n.ply'").exitCode, 0);
  ASSERT_EQ(test::runCli("-q extract eps-delta " + q + "n.ply' -o " + q + "mem.ply'").exitCode, 0);
  const auto r = test::runCli("extract eps-delta " + q + "n.ply' -o " + q + "ooc.ply' --tiles 8");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("out of core"), std::string::npos) << r.out;
  const HybridModel in = readModel(d / "n.ply"), mem = readModel(d / "mem.ply"), ooc = readModel(d / "ooc.ply");
  ASSERT_TRUE(in.attributes.radii);
  std::map<std::array<float, 3>, float> radiusAt;
  for (const Point& p : in.points) radiusAt[{p.position.x(), p.position.y(), p.position.z()}] = p.radius;
  size_t same = 0;
  for (const Point& p : ooc.points) same += radiusAt.at({p.position.x(), p.position.y(), p.position.z()}) == p.radius;
  EXPECT_EQ(same, ooc.points.size());
  size_t memSame = 0;
  for (const Point& p : mem.points) memSame += radiusAt.at({p.position.x(), p.position.y(), p.position.z()}) == p.radius;
  EXPECT_EQ(memSame, mem.points.size());  // the in-memory rule this mirrors
}

// With one tile the out-of-core run is the in-memory run: the same geometry, the same clusters,
// the same bytes, for both clusterings of §3.2.3.
TEST(OocShapeApprox, OneTileWritesTheInMemoryBytes) {
  const fs::path d = test::scratchDir("ooc_shape_one");
  const std::string in = "'" + (test::bundledData() / "igea_points.ply").string() + "'", q = "'" + d.string() + "/";
  for (const std::string method : {"greedy", "hierarchical"}) {
    const std::string args = " --clustering " + method + " --provenance";
    ASSERT_EQ(test::runCli("-q extract shape-approx " + in + " -o " + q + "mem.ply'" + args).exitCode, 0);
    const auto r = test::runCli("extract shape-approx " + in + " -o " + q + "ooc.ply'" + args + " --tiles 1");
    ASSERT_EQ(r.exitCode, 0) << r.out;
    EXPECT_NE(r.out.find("out of core"), std::string::npos) << r.out;
    EXPECT_TRUE(slurp(d / "ooc.ply") == slurp(d / "mem.ply")) << method;
  }
}

// In 16 tiles and more: every input point once, counts near the in-memory extraction (clusters
// are cut at tile borders), the same bytes at any thread count, and a resumed run (its tiles'
// geometry spent by the extraction) writes the same bytes again.
TEST(OocShapeApprox, TilesKeepEveryPointOnceAtAnyThreadCount) {
  const fs::path d = test::scratchDir("ooc_shape_tiles");
  ooc::SyntheticScanOptions s;
  s.count = 200000;
  s.seed = 21;
  ooc::writeSyntheticScan(d / "scan.ply", s);
  const HybridModel cloud = readModel(d / "scan.ply");
  GeometryOptions go;  // curvature on: the k_min directions of §3.2.4.2
  ShapeApproxOptions sa;
  sa.provenance = true;
  ShapeApproxStats ref;
  extractShapeApprox(cloud, computePointGeometry(cloud, go), sa, &ref);

  ooc::OocNormalsOptions o;
  o.geometry = go;
  o.workDir = d / "tiles";
  o.minTiles = 16;
  o.keepWorkDir = true;
  const ooc::OocShapeApproxReport r = ooc::extractShapeApproxOutOfCore(d / "scan.ply", d / "ooc.ply", o, sa);
  EXPECT_GE(r.geometry.tiles, 16u);
  const HybridModel out = readModel(d / "ooc.ply");
  ASSERT_EQ(out.points.size(), r.stats.pointsKept);
  ASSERT_EQ(out.segments.size(), r.stats.segments);
  expectEveryPointOnce(cloud, out);
  EXPECT_GT(ref.segments, 1000u);
  EXPECT_NEAR(double(r.stats.pointsReplaced), double(ref.pointsReplaced), 0.05 * double(ref.pointsReplaced));
  EXPECT_NEAR(double(r.stats.segments), double(ref.segments), 0.03 * double(ref.segments));
  EXPECT_GE(r.stats.clusters, ref.clusters);  // a cluster across a border is two
  EXPECT_GT(r.stats.curvatureDirectionUsed, 0u);
  // The second pass spent every tile's geometry file.
  for (const auto& f : fs::directory_iterator(d / "tiles" / "results"))
    EXPECT_NE(f.path().filename().string().rfind("geom_", 0), 0u) << f.path();

  // Resume: with half the extraction files gone, those tiles' geometry is computed again.
  std::vector<fs::path> done;
  for (const auto& f : fs::directory_iterator(d / "tiles" / "results"))
    if (f.path().filename().string().rfind("extract_", 0) == 0) done.push_back(f.path());
  std::sort(done.begin(), done.end());
  for (size_t i = 0; i < done.size(); i += 2) fs::remove(done[i]);
  const ooc::OocShapeApproxReport again = ooc::extractShapeApproxOutOfCore(d / "scan.ply", d / "resumed.ply", o, sa);
  EXPECT_EQ(again.geometry.tilesReused, r.geometry.tiles - (done.size() + 1) / 2);
  EXPECT_TRUE(slurp(d / "resumed.ply") == slurp(d / "ooc.ply"));

  // One thread, hierarchical clustering against two threads.
  sa.method = ClusteringMethod::Hierarchical;
  o.keepWorkDir = false;
  o.workDir = d / "tiles1";
  {
    const ThreadLimit one(1);
    ooc::extractShapeApproxOutOfCore(d / "scan.ply", d / "h1.ply", o, sa);
  }
  {
    const ThreadLimit two(2);
    o.workDir = d / "tiles2";
    ooc::extractShapeApproxOutOfCore(d / "scan.ply", d / "h2.ply", o, sa);
  }
  EXPECT_TRUE(slurp(d / "h1.ply") == slurp(d / "h2.ply"));
  EXPECT_FALSE(slurp(d / "h1.ply") == slurp(d / "ooc.ply"));  // the clustering option reached the tiles
  expectEveryPointOnce(cloud, readModel(d / "h1.ply"));
}


// Lines of curvature (§9.2) out of core: with one tile the in-memory bytes (the field smooths
// over the local Delaunay stars in both); with many, every point once and lines ending at the
// tile borders.
TEST(OocCurvatureLines, OneTileIsTheInMemoryResultAndTilesKeepEveryPointOnce) {
  const fs::path d = test::scratchDir("ooc_curvature_lines");
  ooc::SyntheticScanOptions s;
  s.count = 30000;
  s.seed = 5;
  ooc::writeSyntheticScan(d / "scan.ply", s);
  const std::string q = "'" + d.string() + "/";
  ASSERT_EQ(test::runCli("-q normals " + q + "scan.ply' -o " + q + "n.ply'").exitCode, 0);
  ASSERT_EQ(test::runCli("-q extract curvature-lines " + q + "n.ply' -o " + q + "mem.ply'").exitCode, 0);
  const auto one = test::runCli("-q extract curvature-lines " + q + "n.ply' -o " + q + "one.ply' --out-of-core --tiles 1");
  ASSERT_EQ(one.exitCode, 0) << one.out;
  EXPECT_EQ(slurp(d / "one.ply"), slurp(d / "mem.ply"));

  const HybridModel cloud = readModel(d / "n.ply");
  ooc::OocNormalsOptions o;
  o.workDir = d / "tiles";
  o.minTiles = 8;
  CurvatureLineOptions c;
  c.provenance = true;
  const ooc::OocCurvatureLineReport r = ooc::extractCurvatureLinesOutOfCore(d / "n.ply", d / "ooc.ply", o, c);
  EXPECT_GE(r.geometry.tiles, 8u);
  const HybridModel out = readModel(d / "ooc.ply");
  ASSERT_EQ(out.points.size(), r.keptPoints);
  ASSERT_EQ(out.segments.size(), r.segments);
  EXPECT_GT(r.lines, 0u);
  EXPECT_GT(r.replacedPoints, cloud.points.size() / 2);
  expectEveryPointOnce(cloud, out);
}

}  // namespace
}  // namespace linesurf
