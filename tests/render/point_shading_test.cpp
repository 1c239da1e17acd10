// Point shading normals (beyond the thesis; HybridModel::pointShadingNormals): they
// light a point while its own normal stays its splat plane and its back-face test.
#include <gtest/gtest.h>

#include <cmath>

#include "linesurf/render/renderer.h"

namespace linesurf {
namespace {

// A flat disc of points in z = 0 (plane normals +z), seen from straight above; every point gets
// the shading normal `sn` when given.
HybridModel flatDisc(const Vec3f* sn) {
  HybridModel m;
  m.attributes.normals = m.attributes.radii = true;
  for (int y = -20; y <= 20; ++y)
    for (int x = -20; x <= 20; ++x) {
      if (x * x + y * y > 400) continue;
      Point p;
      p.position = Vec3f(0.05f * float(x), 0.05f * float(y), 0);
      p.normal = Vec3f(0, 0, 1);
      p.radius = 0.06f;
      m.points.push_back(p);
    }
  if (sn) {
    m.attributes.shadingNormals = true;
    m.pointShadingNormals.assign(m.points.size(), *sn);
  }
  return m;
}

// Lambert: with no specular term a disc of one shading normal n is albedo (ambient + diffuse
// max(0, n.l)) wherever it covers the pixel fully, for the Gouraud/flat path (small and large
// splats) and the deferred path; the splat's plane (and so its coverage) does not change.
TEST(PointShading, ShadingNormalsLightTheDiscAsLambertPredicts) {
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 4), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 30, 96, 96);
  for (bool perPixel : {false, true}) {
    RenderOptions o;
    o.material.specular = 0;
    o.light.direction = Vec3f(0, 0, 1);  // headlight along the view axis: n.l = n_z
    o.perPixelLighting = perPixel;
    o.normalBuffer = true;
    const HybridModel plain = flatDisc(nullptr);
    const RenderResult ref = renderImage(plain, cam, o);
    const Color albedo = o.defaultColor;
    const Color centre = ref.color.at(48, 48);
    EXPECT_NEAR(centre.x(), albedo.x() * (o.material.ambient + o.material.diffuse), 1e-3f);
    for (float deg : {0.0f, 30.0f, 60.0f, 80.0f, 120.0f}) {
      const float t = deg * 3.14159265f / 180.0f;
      const Vec3f sn(0, std::sin(t), std::cos(t));
      const HybridModel m = flatDisc(&sn);
      const RenderResult r = renderImage(m, cam, o);
      const float want = albedo.x() * (o.material.ambient + o.material.diffuse * std::max(0.0f, std::cos(t)));
      int checked = 0;
      for (int y = 38; y <= 58; y += 4)
        for (int x = 38; x <= 58; x += 4) {
          EXPECT_NEAR(r.color.at(x, y).x(), want, 2e-3f) << deg << " deg at " << x << "," << y << (perPixel ? " per pixel" : "");
          // the normal buffer holds the shading normal (camera space = world space here)
          const Color nb = r.normal->at(x, y);
          EXPECT_NEAR(2 * nb.y() - 1, sn.y(), 2e-3f);
          EXPECT_NEAR(2 * nb.z() - 1, sn.z(), 2e-3f);
          ++checked;
        }
      EXPECT_EQ(checked, 36);
      // coverage is the plane's: the same pixels are covered (alpha of the composite)
      for (size_t i = 0; i < r.color.pixels.size(); ++i)
        ASSERT_EQ(r.normal->pixels[i].w(), ref.normal->pixels[i].w()) << i;
    }
  }
}

// The shading normal flips with the plane for two-sided lighting (culling off, disc seen from
// below), and a model whose flag is off renders exactly as one without shading normals.
TEST(PointShading, FlipsWithThePlaneAndNeedsTheAttribute) {
  const Camera below = Camera::lookAt(Vec3f(0, 0, -4), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 30, 96, 96);
  RenderOptions o;
  o.material.specular = 0;
  o.light.direction = Vec3f(0, 0, 1);
  o.backfaceCulling = false;
  const float t = 50.0f * 3.14159265f / 180.0f;
  const Vec3f sn(0, std::sin(t), std::cos(t));
  HybridModel m = flatDisc(&sn);
  const RenderResult r = renderImage(m, below, o);
  const float want = o.defaultColor.x() * (o.material.ambient + o.material.diffuse * std::cos(t));
  EXPECT_NEAR(r.color.at(48, 48).x(), want, 2e-3f);
  m.attributes.shadingNormals = false;
  const RenderResult off = renderImage(m, below, o);
  const RenderResult plain = renderImage(flatDisc(nullptr), below, o);
  EXPECT_EQ(off.color.pixels, plain.color.pixels);
  EXPECT_NEAR(plain.color.at(48, 48).x(), o.defaultColor.x() * (o.material.ambient + o.material.diffuse), 1e-3f);
}

}  // namespace
}  // namespace linesurf
