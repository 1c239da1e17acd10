// linesurf render: bundled raw scan (no normals, no radii) end to end, --views naming, buffers,
// and error messages for absurd parameters.
#include <gtest/gtest.h>

#include <filesystem>

#include "linesurf/io/image_io.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

namespace linesurf {
namespace {

TEST(RenderCli, RawScanRendersWithSummaryAndBuffers) {
  auto dir = test::scratchDir("render_cli");
  auto out = dir / "santa.png";
  auto r = test::runCli("render " + (test::bundledData() / "santa_points.ply").string() + " -o " + out.string() +
                        " --size 96x64 --up-axis z --depth-out " + (dir / "d.png").string() + " --normal-out " +
                        (dir / "n.png").string());
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("drawn"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("culled"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("geometry"), std::string::npos) << r.out;  // normals + radii computed
  Image im = readImage(out);
  EXPECT_EQ(im.width, 96);
  EXPECT_EQ(im.height, 64);
  // something drawn on the white background, and the background is white
  size_t covered = 0;
  for (const Color& c : im.pixels) covered += c.head<3>().minCoeff() < 0.9f;
  EXPECT_GT(covered, 200u);
  EXPECT_GT(im.at(0, 0).head<3>().minCoeff(), 0.99f);
  EXPECT_TRUE(std::filesystem::exists(dir / "d.png"));
  EXPECT_TRUE(std::filesystem::exists(dir / "n.png"));
}

// A file that recorded its up axis (LAS is z-up; a PLY made from one keeps the comment) orbits
// about it unless --up-axis is given.
TEST(RenderCli, RecordedUpAxisIsTheDefault) {
  auto dir = test::scratchDir("render_cli_up");
  HybridModel santa = readModel(test::bundledData() / "santa_points.ply");
  santa.comments.push_back("linesurf_up_axis z");
  writeModel(dir / "santa_z.ply", santa);
  auto run = [&](const std::string& in, const std::string& flags, const std::string& out) {
    auto r = test::runCli("render '" + in + "' -o '" + (dir / out).string() + "' --size 64x48 " + flags);
    EXPECT_EQ(r.exitCode, 0) << r.out;
    return r.out;
  };
  const std::string orig = (test::bundledData() / "santa_points.ply").string(), tagged = (dir / "santa_z.ply").string();
  EXPECT_NE(run(tagged, "", "a.png").find("up axis z (recorded in the file"), std::string::npos);
  run(orig, "--up-axis z", "b.png");
  EXPECT_EQ(run(tagged, "--up-axis y", "c.png").find("recorded in the file"), std::string::npos);
  run(orig, "--up-axis y", "d.png");
  EXPECT_EQ(readImage(dir / "a.png").pixels, readImage(dir / "b.png").pixels);
  EXPECT_EQ(readImage(dir / "c.png").pixels, readImage(dir / "d.png").pixels);
  EXPECT_NE(readImage(dir / "a.png").pixels, readImage(dir / "c.png").pixels);
}

TEST(RenderCli, ViewsAreNumbered) {
  auto dir = test::scratchDir("render_cli_views");
  auto r = test::runCli("-q render " + (test::bundledData() / "santa_points.ply").string() + " -o " +
                        (dir / "v.png").string() + " --size 32x32 --views 3");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  for (const char* name : {"v_000.png", "v_001.png", "v_002.png"}) EXPECT_TRUE(std::filesystem::exists(dir / name)) << name;
  EXPECT_FALSE(std::filesystem::exists(dir / "v.png"));
}

TEST(RenderCli, AbsurdParametersFailWithExitCode1) {
  const std::string model = (test::bundledData() / "santa_points.ply").string();
  auto dir = test::scratchDir("render_cli_bad");
  for (const char* bad : {"--layers 0", "--cutoff 0.2", "--size 10by10", "--z-mode sometimes", "--up-axis w",
                        "--prefilter -1", "--background purple"}) {
    auto r = test::runCli("render " + model + " -o " + (dir / "x.png").string() + " " + bad);
    EXPECT_EQ(r.exitCode, 1) << bad << ": " << r.out;
  }
  auto r = test::runCli("render " + (dir / "missing.ply").string() + " -o " + (dir / "x.png").string());
  EXPECT_NE(r.exitCode, 0);
}

}  // namespace
}  // namespace linesurf
