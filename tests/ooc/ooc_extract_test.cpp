// (ε,δ) extraction out of core (ooc/ooc_normals.h) against the in-memory extraction.
#include <gtest/gtest.h>

#include <array>
#include <map>

#include "linesurf/extract/eps_delta.h"
#include "linesurf/io/model_io.h"
#include "linesurf/ooc/ooc_normals.h"
#include "linesurf/ooc/synthetic_scan.h"
#include "test_util.h"

namespace linesurf {
namespace {

namespace fs = std::filesystem;

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
  ASSERT_EQ(out.provenance.size(), out.segments.size());
  // Every input point exactly once: kept (matched by position, in input order) or in one segment.
  std::vector<int> seen(cloud.points.size(), 0);
  for (const auto& prov : out.provenance)
    for (uint32_t i : prov) ++seen[i];
  size_t k = 0;
  for (size_t i = 0; i < cloud.points.size(); ++i)
    if (!seen[i]) {
      ASSERT_LT(k, out.points.size());
      EXPECT_EQ(out.points[k++].position, cloud.points[i].position);
      seen[i] = 1;
    }
  EXPECT_EQ(k, out.points.size());
  for (int c : seen) ASSERT_EQ(c, 1);
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

}  // namespace
}  // namespace linesurf
