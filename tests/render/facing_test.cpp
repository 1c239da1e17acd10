// Which side of the surface a picture shows (RenderOptions::facingCheck, RenderStats::facing*):
// a closed model with outward normals shows few back faces, the same with its normals flipped and
// a terrain whose normals point down show mostly back faces, and the CLI says so in one line.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "linesurf/io/model_io.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/renderer.h"
#include "shapes.h"
#include "test_util.h"

namespace linesurf {
namespace {

RenderStats facing(const HybridModel& m, const Camera& cam, bool check = true) {
  RenderOptions o;
  o.facingCheck = check;
  return renderImage(m, cam, o).stats;
}

HybridModel flipped(HybridModel m) {
  for (Point& p : m.points) p.normal = -p.normal;
  return m;
}

Camera orbit(const HybridModel& m, float elevation) {
  return Camera::orbit(boundingSphere(m), 30, elevation, 0, 256, 192);
}

TEST(Facing, OutwardSphereShowsItsFront) {
  const HybridModel s = shapes::sphere(1, 20000);
  const RenderStats st = facing(s, orbit(s, 20));
  EXPECT_GT(st.facingPixels, 5000u);  // the 160 x 120 check image is mostly covered
  EXPECT_LT(st.backFacingShare(), 0.03);
  EXPECT_TRUE(backFacingWarning(st, "sphere").empty());
}

TEST(Facing, FlippedSphereShowsItsInside) {
  // Culled, the far half's inward normals face the viewer: a picture, but of the wrong surface.
  const HybridModel s = flipped(shapes::sphere(1, 20000));
  const RenderStats st = facing(s, orbit(s, 20));
  EXPECT_GT(st.backFacingShare(), 0.9);
  EXPECT_LT(double(st.facingEmptyPixels), 0.1 * double(st.facingPixels));
  const std::string w = backFacingWarning(st, "sphere.ply");
  EXPECT_NE(w.find("sphere.ply: "), std::string::npos) << w;
  EXPECT_NE(w.find("--orient"), std::string::npos) << w;
}

TEST(Facing, TerrainWithNormalsDownIsEmpty) {
  HybridModel ground = shapes::plane(2, 2, 120, 120);  // z = 0, normals +z
  for (Point& p : ground.points) p.position = Vec3f(p.position.x(), p.position.z(), p.position.y());  // y up
  for (Point& p : ground.points) p.normal = Vec3f(0, 1, 0);
  const Camera above = orbit(ground, 45);
  EXPECT_LT(facing(ground, above).backFacingShare(), 0.02);
  const RenderStats down = facing(flipped(ground), above);
  EXPECT_GT(down.backFacingShare(), 0.98);
  EXPECT_GT(double(down.facingEmptyPixels), 0.98 * double(down.facingPixels));
}

TEST(Facing, OffByDefaultAndWithoutCulling) {
  const HybridModel s = flipped(shapes::sphere(1, 5000));
  EXPECT_EQ(facing(s, orbit(s, 20), false).facingPixels, 0u);
  RenderOptions o;
  o.facingCheck = true;
  o.backfaceCulling = false;  // two-sided: every surface is drawn, nothing to warn about
  EXPECT_EQ(renderImage(s, orbit(s, 20), o).stats.facingPixels, 0u);
  // The check leaves the picture itself alone.
  RenderOptions plain, checked;
  checked.facingCheck = true;
  EXPECT_EQ(renderImage(s, orbit(s, 20), plain).color.pixels, renderImage(s, orbit(s, 20), checked).color.pixels);
}

TEST(Facing, CliWarnsInOneLine) {
  auto dir = test::scratchDir("render_facing");
  writeModel(dir / "inside_out.ply", flipped(shapes::sphere(1, 5000)));
  writeModel(dir / "sphere.ply", shapes::sphere(1, 5000));
  auto bad = test::runCli("-q render '" + (dir / "inside_out.ply").string() + "' -o '" + (dir / "a.png").string() + "' --size 96x96");
  EXPECT_EQ(bad.exitCode, 0) << bad.out;  // a picture, drawn as asked, with the warning
  EXPECT_NE(bad.out.find("warning: " + (dir / "inside_out.ply").string() + ": "), std::string::npos) << bad.out;
  EXPECT_EQ(std::count(bad.out.begin(), bad.out.end(), '\n'), 1) << bad.out;
  auto good = test::runCli("-q render '" + (dir / "sphere.ply").string() + "' -o '" + (dir / "b.png").string() + "' --size 96x96");
  EXPECT_EQ(good.exitCode, 0) << good.out;
  EXPECT_EQ(good.out.find("warning"), std::string::npos) << good.out;
  auto twoSided = test::runCli("-q render '" + (dir / "inside_out.ply").string() + "' -o '" + (dir / "c.png").string() +
                               "' --size 96x96 --no-cull");
  EXPECT_EQ(twoSided.out.find("warning"), std::string::npos) << twoSided.out;
}

TEST(Facing, ViewWarnsAtThePagesFirstView) {
  auto dir = test::scratchDir("view_facing");
  writeModel(dir / "inside_out.ply", flipped(shapes::sphere(1, 5000)));
  writeModel(dir / "sphere.ply", shapes::sphere(1, 5000));
  auto bad = test::runCli("-q view '" + (dir / "inside_out.ply").string() + "' -o '" + (dir / "a.html").string() + "'");
  EXPECT_EQ(bad.exitCode, 0) << bad.out;  // the page is written as asked, with the warning
  EXPECT_TRUE(std::filesystem::exists(dir / "a.html"));
  EXPECT_NE(bad.out.find("warning: " + (dir / "inside_out.ply").string() + ": "), std::string::npos) << bad.out;
  EXPECT_EQ(std::count(bad.out.begin(), bad.out.end(), '\n'), 1) << bad.out;
  auto good = test::runCli("-q view '" + (dir / "sphere.ply").string() + "' -o '" + (dir / "b.html").string() + "'");
  EXPECT_EQ(good.exitCode, 0) << good.out;
  EXPECT_EQ(good.out.find("warning"), std::string::npos) << good.out;
}

}  // namespace
}  // namespace linesurf
