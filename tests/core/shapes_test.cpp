#include <gtest/gtest.h>

#include "shapes.h"

using namespace linesurf;

TEST(Shapes, SamplesLieOnTheirSurfacesWithUnitOutwardNormals) {
  for (const Point& p : shapes::sphere(2.0f, 500).points) {
    EXPECT_NEAR(p.position.norm(), 2.0f, 1e-5f);
    EXPECT_GT(p.normal.dot(p.position), 0.0f);
  }
  for (const Point& p : shapes::cylinder(1.0f, 3.0f, 40, 20).points) {
    EXPECT_NEAR(p.position.head<2>().norm(), 1.0f, 1e-5f);
    EXPECT_NEAR(p.normal.norm(), 1.0f, 1e-5f);
  }
  for (const Point& p : shapes::torus(2.0f, 0.5f, 60, 20).points) {
    Vec3f c(p.position.x(), p.position.y(), 0);
    c = 2.0f * c.normalized();
    EXPECT_NEAR((p.position - c).norm(), 0.5f, 1e-5f);
  }
  EXPECT_EQ(shapes::plane(1, 1, 10, 20).points.size(), 200u);
}

TEST(Shapes, IcosphereVerticesOnSphereAndClosed) {
  TriangleMesh m = shapes::sphereMesh(1.5f, 2);
  EXPECT_EQ(m.faces.size(), 20u * 16u);
  EXPECT_EQ(m.positions.size(), 162u);  // V - E + F = 2
  for (const Vec3f& p : m.positions) EXPECT_NEAR(p.norm(), 1.5f, 1e-5f);
}
