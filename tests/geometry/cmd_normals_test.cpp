// The `linesurf normals` subcommand end to end: normals and curvature properties written.
#include <gtest/gtest.h>

#include "shapes.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

using namespace linesurf;

TEST(CmdNormals, WritesOrientedNormalsAndCurvature) {
  auto dir = test::scratchDir("cmd_normals");
  auto cloud = shapes::sphere(1, 2000);
  HybridModel bare;
  for (const auto& p : cloud.points) bare.points.push_back({.position = p.position});
  writeModel(dir / "in.ply", bare);
  auto r = test::runCli("normals " + (dir / "in.ply").string() + " -o " + (dir / "out.ply").string() + " --curvature");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("degenerate"), std::string::npos) << r.out;
  auto out = readModel(dir / "out.ply");
  ASSERT_EQ(out.points.size(), cloud.points.size());
  EXPECT_TRUE(out.attributes.normals);
  for (size_t i = 0; i < out.points.size(); ++i) EXPECT_GT(out.points[i].normal.dot(cloud.points[i].normal), 0.99f) << i;
  for (const char* name : {"k_min", "k_max", "dmin_x", "dmin_y", "dmin_z"}) {
    ASSERT_TRUE(out.pointProperties.count(name)) << name;
    EXPECT_EQ(out.pointProperties.at(name).size(), out.points.size()) << name;
  }
}

TEST(CmdNormals, RejectsBadK) {
  auto dir = test::scratchDir("cmd_normals_bad");
  writeModel(dir / "in.ply", shapes::sphere(1, 100));
  auto r = test::runCli("normals " + (dir / "in.ply").string() + " -o " + (dir / "out.ply").string() + " --k 2");
  EXPECT_EQ(r.exitCode, 1) << r.out;
}
