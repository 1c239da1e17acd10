// The mesh ground-truth renderer (render/mesh_render.h): coverage against analytic silhouettes,
// exact Phong colour of a flat-lit quad, anti-aliased edges, determinism, CLI --primitive.
#include "linesurf/render/mesh_render.h"

#include <gtest/gtest.h>

#include <cmath>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/eval/image_metrics.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_io.h"
#include "shapes.h"
#include "linesurf/core/mesh_normals.h"
#include "test_util.h"

namespace linesurf {
namespace {

constexpr float kPi = 3.14159265358979323846f;

TriangleMesh quad(float half, float z = 0) {
  TriangleMesh m;
  m.positions = {Vec3f(-half, -half, z), Vec3f(half, -half, z), Vec3f(half, half, z), Vec3f(-half, half, z)};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

double alphaSum(const Image& alpha) {
  double s = 0;
  for (const Color& c : alpha.pixels) s += c.w();
  return s;
}

TEST(MeshRender, SphereCoverageMatchesAnalyticSilhouette) {
  // A sphere of radius r seen from distance D (on the axis) projects to a disc of screen radius
  // f tan(asin(r / D)). The icosphere (5 subdivisions, 20,480 faces) is inscribed: its
  // silhouette area is within 0.2% below the sphere's.
  const float r = 1, D = 4;
  const TriangleMesh mesh = shapes::sphereMesh(r, 5);
  RenderOptions o;
  o.alphaBuffer = true;
  const Camera cam = Camera::lookAt(Vec3f(0, 0, D), Vec3f::Zero(), Vec3f(0, 1, 0), 30, 256, 256, 0.1f, 10);
  const MeshRenderResult res = renderMesh(mesh, cam, o);
  const float R = cam.focalPixels() * std::tan(std::asin(r / D));
  const double area = kPi * R * R;
  const double cov = alphaSum(*res.alpha);
  EXPECT_LT(cov, area * 1.0005);
  EXPECT_GT(cov, area * 0.995);
  // every pixel more than 1.5 px inside the disc is fully covered, every one 1.5 px outside empty
  int wrong = 0;
  for (int y = 0; y < 256; ++y)
    for (int x = 0; x < 256; ++x) {
      const float d = std::hypot(x + 0.5f - 128, y + 0.5f - 128);
      const float a = res.alpha->at(x, y).w();
      if (d < R - 1.5f && a < 1) ++wrong;
      if (d > R + 1.5f && a > 0) ++wrong;
    }
  EXPECT_EQ(wrong, 0);
  EXPECT_EQ(res.stats.trianglesDrawn + res.stats.trianglesCulled, mesh.faces.size());
  EXPECT_GT(res.stats.trianglesCulled, mesh.faces.size() / 3);  // the back half
}

TEST(MeshRender, FlatLitQuadHasThePhongColour) {
  // A quad facing the camera, light along the view axis: n.l = 1 at every pixel, no specular:
  // colour = albedo * (ambient + diffuse) exactly, composited over nothing where covered.
  const TriangleMesh mesh = quad(0.5f);
  RenderOptions o;
  o.material = {0.3f, 0.5f, 0.0f, 24};
  o.light.direction = Vec3f(0, 0, 1);
  o.defaultColor = Color(0.5f, 1.0f, 0.25f, 1);
  o.background = Color(0, 0, 0, 1);
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 3), Vec3f::Zero(), Vec3f(0, 1, 0), 30, 64, 64, 0.1f, 10);
  const MeshRenderResult res = renderMesh(mesh, cam, o);
  const Color c = res.color.at(32, 32);
  EXPECT_NEAR(c.x(), 0.5f * 0.8f, 1e-5);
  EXPECT_NEAR(c.y(), 1.0f * 0.8f, 1e-5);
  EXPECT_NEAR(c.z(), 0.25f * 0.8f, 1e-5);
  EXPECT_EQ(res.color.at(0, 0), Color(0, 0, 0, 1));  // background outside
}

TEST(MeshRender, EdgeCoverageIsTheAreaFraction) {
  // A quad whose left edge lies at x = 0: seen head-on, it crosses the screen centre column at
  // pixel x = 32 exactly on its left boundary (sample columns 0..3 at 32.125 .. 32.875): full
  // coverage there, none in column 31. Shift it by a quarter pixel: 3 of 4 sample columns.
  RenderOptions o;
  o.alphaBuffer = true;
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 3), Vec3f::Zero(), Vec3f(0, 1, 0), 30, 64, 64, 0.1f, 10);
  const float px = 3.0f / cam.focalPixels();  // object size of one pixel at depth 3
  TriangleMesh m = quad(0.5f);
  for (Vec3f& p : m.positions) p.x() += 0.5f + 0.25f * px;  // left edge at x = +0.25 px
  const MeshRenderResult res = renderMesh(m, cam, o);
  EXPECT_FLOAT_EQ(res.alpha->at(31, 32).w(), 0.0f);
  EXPECT_FLOAT_EQ(res.alpha->at(32, 32).w(), 0.75f);
  EXPECT_FLOAT_EQ(res.alpha->at(33, 32).w(), 1.0f);
}

TEST(MeshRender, NearestSurfaceWinsAndBackFacesAreCulled) {
  // two quads, the red one in front: only red is seen; flipped winding of the front one with
  // culling on: green shows through
  TriangleMesh m = quad(1, 0.5f);
  TriangleMesh back = quad(1, -0.5f);
  m.colors = {Color(1, 0, 0, 1), Color(1, 0, 0, 1), Color(1, 0, 0, 1), Color(1, 0, 0, 1)};
  for (const Vec3f& p : back.positions) { m.positions.push_back(p); m.colors.push_back(Color(0, 1, 0, 1)); }
  m.faces.push_back({4, 5, 6});
  m.faces.push_back({4, 6, 7});
  RenderOptions o;
  o.material = {1, 0, 0, 24};  // ambient only: the albedo
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 3), Vec3f::Zero(), Vec3f(0, 1, 0), 30, 32, 32, 0.1f, 10);
  EXPECT_EQ(renderMesh(m, cam, o).color.at(16, 16), Color(1, 0, 0, 1));
  std::swap(m.faces[0][1], m.faces[0][2]);
  std::swap(m.faces[1][1], m.faces[1][2]);
  const MeshRenderResult culled = renderMesh(m, cam, o);
  EXPECT_EQ(culled.color.at(16, 16), Color(0, 1, 0, 1));
  EXPECT_EQ(culled.stats.trianglesCulled, 2u);
  o.backfaceCulling = false;
  EXPECT_EQ(renderMesh(m, cam, o).color.at(16, 16), Color(1, 0, 0, 1));
}

TEST(MeshRender, SameImageForAnyThreadCount) {
  const TriangleMesh mesh = shapes::sphereMesh(1, 4);
  RenderOptions o;
  o.tileSize = 16;
  const Camera cam = Camera::orbit(boundingSphere(mesh), 30, 20, 0, 200, 150);
  Image one, two;
  {
    ThreadLimit limit(1);
    one = renderMesh(mesh, cam, o).color;
  }
  {
    ThreadLimit limit(2);
    two = renderMesh(mesh, cam, o).color;
  }
  EXPECT_EQ(one.pixels, two.pixels);
}

TEST(MeshRender, NearPlaneClipsInsteadOfDropping) {
  // the camera sits inside a large quad's extent, close to it: the quad crosses the near plane
  // when tilted; the visible part is still drawn
  TriangleMesh m = quad(10);
  for (Vec3f& p : m.positions) p.z() = -0.5f * p.y();  // tilted towards the camera at the top
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 3), Vec3f::Zero(), Vec3f(0, 1, 0), 60, 64, 64, 1.0f, 50);
  RenderOptions o;
  o.alphaBuffer = true;
  const MeshRenderResult res = renderMesh(m, cam, o);
  EXPECT_EQ(res.stats.trianglesClipped, 2u);
  EXPECT_FLOAT_EQ(res.alpha->at(32, 40).w(), 1.0f);
}

TEST(MeshNormals, AreaWeightedWhenAbsent) {
  TriangleMesh m = shapes::sphereMesh(2, 3);
  m.normals.clear();
  const std::vector<Vec3f> n = meshVertexNormals(m);
  ASSERT_EQ(n.size(), m.positions.size());
  float worst = 1;
  for (size_t i = 0; i < n.size(); ++i) worst = std::min(worst, n[i].dot(m.positions[i].normalized()));
  EXPECT_GT(worst, 0.995f);  // close to the radial direction on a fine icosphere
  m.faces.push_back({0, 1, uint32_t(m.positions.size())});
  EXPECT_THROW(meshVertexNormals(m), Error);
}

TEST(MeshRenderCli, PrimitiveMeshPointsAndErrors) {
  const auto dir = test::scratchDir("mesh_render_cli");
  const std::string al = (test::bundledData() / "al_mesh.ply").string();
  auto r = test::runCli("render " + al + " --primitive mesh --size 64x64 -o " + (dir / "m.png").string());
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("triangles:"), std::string::npos) << r.out;
  r = test::runCli("render " + al + " --primitive points --size 64x64 -o " + (dir / "p.png").string());
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("rendering its 3618 vertices as points"), std::string::npos) << r.out;
  r = test::runCli("render " + al + " --views 2 --size 32x32 -o " + (dir / "v.png").string());
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "v_001.png"));
  r = test::runCli("render " + al + " --primitive triangles -o " + (dir / "x.png").string());
  EXPECT_EQ(r.exitCode, 1) << r.out;
  const std::string cloud = (test::bundledData() / "igea_points.ply").string();
  r = test::runCli("render " + cloud + " --primitive mesh -o " + (dir / "y.png").string());
  EXPECT_EQ(r.exitCode, 1) << r.out;
}

// --primitive surface: a cloud's MLS surface meshed and drawn under the splats' own camera, so that
// the splat picture and its hole map line up with it pixel for pixel.
TEST(MeshRenderCli, PrimitiveSurfaceIsTheSplatsReferenceWithoutHoles) {
  const auto dir = test::scratchDir("surface_render_cli");
  writeModel(dir / "sphere.ply", shapes::sphere(1, 6000));
  const std::string in = "'" + (dir / "sphere.ply").string() + "'";
  auto r = test::runCli("render " + in + " --primitive surface --size 128x128 --background transparent -o '" +
                        (dir / "s.png").string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("MLS surface"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("0 boundary edges"), std::string::npos) << r.out;
  r = test::runCli("-q render " + in + " --size 128x128 --background transparent -o '" + (dir / "p.png").string() + "'");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  const Image surface = readImage(dir / "s.png"), points = readImage(dir / "p.png");
  // A sphere's disc: the same pixels within a one-pixel rim, no holes inside, similar shading.
  const HoleMap h = holeMap(surface, points);
  ASSERT_TRUE(h.byAlpha);
  EXPECT_GT(h.referencePixels, 128u * 128u / 2);  // the orbit frames the sphere: a disc of ~70% of the view
  EXPECT_LT(h.referencePixels, 128u * 128u * 4 / 5);
  EXPECT_LT(h.holeShare(), 0.01) << h.holes;
  EXPECT_LT(double(h.extra), 0.03 * double(h.referencePixels)) << h.extra;
  EXPECT_GT(compareImages(surface, points).ssim, 0.9);
  // A hole punched into the cloud shows in the map: a cap of the sphere removed.
  HybridModel capless = shapes::sphere(1, 6000);
  std::erase_if(capless.points, [](const Point& p) { return p.position.z() > 0.9f; });
  writeModel(dir / "capless.ply", capless);
  r = test::runCli("-q render '" + (dir / "capless.ply").string() + "' --size 128x128 --background transparent -o '" +
                   (dir / "c.png").string() + "' --eye 0 0 4 --target 0 0 0");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  r = test::runCli("-q render " + in + " --primitive surface --size 128x128 --background transparent -o '" +
                   (dir / "s0.png").string() + "' --eye 0 0 4 --target 0 0 0");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_GT(holeMap(readImage(dir / "s0.png"), readImage(dir / "c.png")).holeShare(), 0.05);
  // Refused in one line: a mesh file, a drawing style.
  r = test::runCli("render " + (test::bundledData() / "al_mesh.ply").string() + " --primitive surface -o '" +
                   (dir / "x.png").string() + "'");
  EXPECT_NE(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("is a mesh"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.png"));
}

}  // namespace
}  // namespace linesurf
