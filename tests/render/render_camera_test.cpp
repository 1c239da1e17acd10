// Camera: projection conventions, orbit framing, spread views, parameter checks.
#include <gtest/gtest.h>

#include <cmath>

#include "linesurf/core/error.h"
#include "linesurf/render/camera.h"

namespace linesurf {
namespace {

TEST(RenderCamera, LookAtProjectsTargetToImageCentre) {
  Camera c = Camera::lookAt(Vec3f(1, 2, 5), Vec3f(1, 2, 0), Vec3f(0, 1, 0), 60, 200, 100);
  Vec3f s = c.project(c.toCamera(Vec3f(1, 2, 0)));
  EXPECT_NEAR(s.x(), 100, 1e-4);
  EXPECT_NEAR(s.y(), 50, 1e-4);
  EXPECT_NEAR(s.z(), 5, 1e-5);
  // +y world is up on screen (smaller pixel y), +x is right
  EXPECT_LT(c.project(c.toCamera(Vec3f(1, 2.5f, 0))).y(), 50);
  EXPECT_GT(c.project(c.toCamera(Vec3f(1.5f, 2, 0))).x(), 100);
  // top edge of the view at half the field of view
  float top = 5 * std::tan(30.0f * 3.14159265f / 180);
  EXPECT_NEAR(c.project(c.toCamera(Vec3f(1, 2 + top, 0))).y(), 0, 1e-3);
  // screenFromCamera agrees with project
  Vec3f pc = c.toCamera(Vec3f(1.3f, 1.9f, -0.5f));
  Vec4f h = c.screenFromCamera() * Vec4f(pc.x(), pc.y(), pc.z(), 1);
  Vec3f s2 = c.project(pc);
  EXPECT_NEAR(h.x() / h.w(), s2.x(), 1e-3);
  EXPECT_NEAR(h.y() / h.w(), s2.y(), 1e-3);
  EXPECT_NEAR(h.z(), s2.z(), 1e-5);
  // ray through a pixel hits the projected point
  Vec3f r = c.rayThrough(s2.x(), s2.y()) * s2.z();
  EXPECT_NEAR((r - pc).norm(), 0, 1e-4);
}

TEST(RenderCamera, FrustumPlanesContainVisiblePointsOnly) {
  Camera c = Camera::lookAt(Vec3f(0, 0, 5), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 64, 48, 1, 10);
  auto inside = [&](const Vec3f& w) {
    Vec3f p = c.toCamera(w);
    for (const Vec4f& pl : c.frustumPlanes())
      if (pl.head<3>().dot(p) + pl.w() < 0) return false;
    return true;
  };
  EXPECT_TRUE(inside(Vec3f(0, 0, 0)));
  EXPECT_FALSE(inside(Vec3f(0, 0, 4.5f)));   // nearer than near
  EXPECT_FALSE(inside(Vec3f(0, 0, -6)));     // beyond far
  EXPECT_FALSE(inside(Vec3f(10, 0, 0)));     // right of the view
  EXPECT_FALSE(inside(Vec3f(0, -10, 0)));    // below
}

TEST(RenderCamera, OrbitFramesTheBoundingSphere) {
  BoundingSphere s{Vec3f(1, -2, 3), 2.5f};
  for (float az : {0.f, 75.f, 200.f})
    for (float el : {-90.f, -30.f, 0.f, 45.f, 90.f}) {
      Camera c = Camera::orbit(s, az, el, 0, 320, 200, 35);
      EXPECT_NEAR((c.eye() - s.center).norm() * std::sin(17.5f * 3.14159265f / 180), 1.05f * s.radius, 1e-3f);
      // extreme points of the sphere project inside the image
      for (int axis = 0; axis < 3; ++axis)
        for (float sign : {-1.f, 1.f}) {
          Vec3f p = s.center + sign * s.radius * Vec3f::Unit(axis);
          Vec3f q = c.project(c.toCamera(p));
          EXPECT_GT(q.x(), 0); EXPECT_LT(q.x(), 320);
          EXPECT_GT(q.y(), 0); EXPECT_LT(q.y(), 200);
          EXPECT_GT(q.z(), c.nearDepth()); EXPECT_LT(q.z(), c.farDepth());
        }
    }
  Camera front = Camera::orbit(s, 0, 0, 10, 64, 64);
  EXPECT_NEAR((front.eye() - (s.center + Vec3f(0, 0, 10))).norm(), 0, 1e-4);
  Camera side = Camera::orbit(s, 90, 0, 10, 64, 64);
  EXPECT_NEAR((side.eye() - (s.center + Vec3f(10, 0, 0))).norm(), 0, 1e-4);
  Camera zup = Camera::orbit(s, 0, 0, 10, 64, 64, 30, Vec3f(0, 0, 1));
  EXPECT_NEAR((zup.eye() - (s.center + Vec3f(0, -10, 0))).norm(), 0, 1e-4);
}

TEST(RenderCamera, SpreadViewsAreDeterministicAndDistinct) {
  auto a = Camera::spreadViewAngles(12), b = Camera::spreadViewAngles(12);
  ASSERT_EQ(a.size(), 12u);
  for (size_t i = 0; i < a.size(); ++i) EXPECT_EQ(a[i], b[i]);
  EXPECT_EQ(a[0].x(), 0.0f);
  auto dir = [](const Vec2f& v) {
    float az = v.x() * 3.14159265f / 180, el = v.y() * 3.14159265f / 180;
    return Vec3f(std::cos(el) * std::sin(az), std::sin(el), std::cos(el) * std::cos(az));
  };
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = i + 1; j < a.size(); ++j) EXPECT_GT((dir(a[i]) - dir(a[j])).norm(), 0.3f);
  EXPECT_EQ(Camera::spreadViews(BoundingSphere{Vec3f::Zero(), 1}, 5, 32, 32).size(), 5u);
}

TEST(RenderCamera, AbsurdParametersThrow) {
  EXPECT_THROW(Camera::lookAt(Vec3f(0, 0, 1), Vec3f(0, 0, 1), Vec3f(0, 1, 0), 30, 10, 10), Error);
  EXPECT_THROW(Camera::lookAt(Vec3f(0, 0, 1), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 190, 10, 10), Error);
  EXPECT_THROW(Camera::lookAt(Vec3f(0, 0, 1), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 30, 0, 10), Error);
  EXPECT_THROW(Camera::orbit(BoundingSphere{}, 0, 95, 0, 10, 10), Error);
  EXPECT_THROW(Camera::spreadViewAngles(0), Error);
  // up parallel to the view direction still gives a valid camera
  Camera c = Camera::lookAt(Vec3f(0, 5, 0), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 30, 10, 10);
  EXPECT_TRUE(c.cameraFromWorld().allFinite());
}

}  // namespace
}  // namespace linesurf
