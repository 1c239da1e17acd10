// The MLS surface of a point model (surface/mls.h): exact derivatives against finite
// differences, projection onto shapes with known surfaces, curvature with known answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>

#include "linesurf/core/error.h"
#include "linesurf/surface/mls.h"
#include "shapes.h"

namespace linesurf {
namespace {

HybridModel noRadii(HybridModel m) {
  for (Point& p : m.points) p.radius = 0;
  m.attributes.radii = false;
  return m;
}

TEST(MlsSurface, GradientAndHessianAreExact) {
  const MlsSurface s(shapes::sphere(1, 4000, {.irregular = true, .seed = 3}));
  std::mt19937_64 rng(1);
  std::normal_distribution<double> g(0, 1);
  for (int t = 0; t < 50; ++t) {
    const Vec3d x = Vec3d(g(rng), g(rng), g(rng)).normalized() * (1 + 0.02 * g(rng));
    const MlsSample a = s.evaluate(x);
    ASSERT_TRUE(a.valid());
    const double e = 1e-5;
    for (int d = 0; d < 3; ++d) {
      const Vec3d dx = e * Vec3d::Unit(d);
      const MlsSample p = s.evaluate(x + dx), m = s.evaluate(x - dx);
      EXPECT_NEAR(a.gradient[d], (p.value - m.value) / (2 * e), 1e-5 * (1 + a.gradient.norm())) << t;
      const Vec3d col = (p.gradient - m.gradient) / (2 * e);
      for (int r = 0; r < 3; ++r) EXPECT_NEAR(a.hessian(r, d), col[r], 1e-4 * (1 + a.hessian.norm())) << t;
      const Vec3d ncol = (p.normalField - m.normalField) / (2 * e);
      for (int r = 0; r < 3; ++r)
        EXPECT_NEAR(a.normalJacobian(r, d), ncol[r], 1e-4 * (1 + a.normalJacobian.norm())) << t;
    }
    EXPECT_LT((a.hessian - a.hessian.transpose()).norm(), 1e-9 * (1 + a.hessian.norm()));
  }
}

// Median and largest of |k - 1/r| over projections of points near a sphere of radius 2 (20,000
// samples, noise 0.05 spacing), and the largest distance of a projection from the sphere.
struct SphereFigures {
  double kMedian = 0, kMax = 0, distance = 0;
};

SphereFigures sphereFigures(bool irregular) {
  const MlsSurface s(shapes::sphere(2, 20000, {.noise = 0.05f, .irregular = irregular, .seed = 5}));
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g(0, 1);
  std::vector<double> err;
  SphereFigures f;
  for (int t = 0; t < 200; ++t) {
    const Vec3d dir = Vec3d(g(rng), g(rng), g(rng)).normalized();
    const MlsProjection p = s.project(dir * (2 + 0.05 * g(rng)));
    EXPECT_TRUE(p.converged) << t;
    EXPECT_LE(p.iterations, 8);
    f.distance = std::max(f.distance, std::abs(p.point.norm() - 2));
    EXPECT_GT(p.normal.dot(p.point.normalized()), 0.999) << t;
    const MlsCurvature c = s.curvature(p.point);
    EXPECT_TRUE(c.valid);
    EXPECT_NEAR(c.dirMin.dot(c.normal), 0, 1e-9);
    EXPECT_NEAR(c.dirMin.cross(c.dirMax).dot(c.normal), 1, 1e-9);
    err.push_back(std::max(std::abs(c.kMin - 0.5), std::abs(c.kMax - 0.5)));
  }
  std::sort(err.begin(), err.end());
  f.kMedian = err[err.size() / 2], f.kMax = err.back();
  EXPECT_GT(s.evaluate(Vec3d(0, 0, 2.05)).value, 0);  // positive where the normals face
  EXPECT_LT(s.evaluate(Vec3d(0, 0, 1.95)).value, 0);
  return f;
}

TEST(MlsSurface, ProjectsOntoASphereAndReadsItsCurvature) {
  const double spacing = std::sqrt(4 * 3.14159265 * 4 / 20000);
  const SphereFigures even = sphereFigures(false);
  EXPECT_LT(even.distance, 0.15 * spacing);  // IMLS's bias on a curved surface, within the noise
  EXPECT_LT(even.kMax, 0.05);                // 1 / r within 10% everywhere
  EXPECT_LT(even.kMedian, 0.01);
  // Random (Poisson) sampling clumps and the weights follow the clumps: the curvature is rougher
  // (23% off at the median), the surface as close.
  const SphereFigures random = sphereFigures(true);
  EXPECT_LT(random.distance, 0.15 * spacing);
  EXPECT_LT(random.kMedian, 0.125);
}

TEST(MlsSurface, CylinderCurvatureAndDirections) {
  const MlsSurface s(noRadii(shapes::cylinder(1, 6, 200, 300)));
  for (double z : {-1.0, 0.0, 1.5})
    for (double a : {0.3, 2.0, 4.4}) {
      const MlsProjection p = s.project(Vec3d(1.03 * std::cos(a), 1.03 * std::sin(a), z));
      ASSERT_TRUE(p.converged);
      EXPECT_NEAR(std::hypot(p.point.x(), p.point.y()), 1, 1e-3);
      const MlsCurvature c = s.curvature(p.point);
      EXPECT_NEAR(c.kMin, 0, 0.02);
      EXPECT_NEAR(c.kMax, 1, 0.05);
      EXPECT_GT(std::abs(c.dirMin.z()), 0.999);  // the minimum direction is the axis
    }
}

TEST(MlsSurface, FarFromTheSourcesProjectionFails) {
  const MlsSurface s(shapes::plane(1, 1, 40, 40));
  const MlsProjection far = s.project(Vec3d(0, 0, 5));
  EXPECT_FALSE(far.converged);
  EXPECT_FALSE(s.evaluate(Vec3d(0, 0, 5)).valid());
  EXPECT_FALSE(s.curvature(Vec3d(0, 0, 5)).valid);
  const MlsProjection near = s.project(Vec3d(0.1, -0.2, 0.02));
  EXPECT_TRUE(near.converged);
  EXPECT_NEAR(near.point.z(), 0, 1e-6);
  EXPECT_NEAR(s.curvature(near.point).kMax, 0, 1e-6);
}

// A segment's terms are integrated in closed form: against a fine midpoint rule along it, and
// its derivatives against central differences.
TEST(MlsSurface, SegmentSourcesIntegrateExactly) {
  HybridModel m;
  Segment sg;
  sg.p0 = Vec3f(-0.3f, 0.1f, 0), sg.p1 = Vec3f(0.5f, -0.2f, 0.05f);
  sg.normal0 = Vec3f(0.1f, 0, 1).normalized(), sg.normal1 = Vec3f(-0.2f, 0.1f, 1).normalized();
  sg.normal = (sg.normal0 + sg.normal1).normalized();
  sg.radius = 0.1f;
  m.segments.push_back(sg);
  m.attributes.endpointNormals = true;
  const MlsSurface s(m);
  const double h = 3 * 0.1, h2 = h * h, w = 2 * 0.1 * (sg.p1 - sg.p0).cast<double>().norm();
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int checked = 0;
  for (int t = 0; t < 40; ++t) {
    // Near the strip, within half the support (and past its ends now and then).
    const double q0 = 0.5 + 0.6 * u(rng);
    const Vec3d x = sg.p0.cast<double>() * (1 - q0) + sg.p1.cast<double>() * q0 + 0.5 * h * Vec3d(u(rng), u(rng), u(rng)) / 1.8;
    const MlsSample a = s.evaluate(x);
    if (!a.valid()) continue;
    ++checked;
    double N = 0, D = 0;
    const int steps = 200000;
    for (int k = 0; k < steps; ++k) {
      const double q = (k + 0.5) / steps;
      const Vec3d p = (sg.p0.cast<double>() * (1 - q) + sg.p1.cast<double>() * q);
      const Vec3d n = sg.normal0.cast<double>() * (1 - q) + sg.normal1.cast<double>() * q;
      const double tt = (x - p).squaredNorm() / h2;
      if (tt >= 1) continue;
      const double phi = w * std::pow(1 - tt, 4) / steps;
      N += phi * n.dot(x - p), D += phi;
    }
    EXPECT_NEAR(a.weight, D, 1e-5 * D) << t;
    EXPECT_NEAR(a.value, N / D, 1e-6) << t;
    const double e = 1e-5;
    for (int d = 0; d < 3; ++d) {
      const Vec3d dx = e * Vec3d::Unit(d);
      const MlsSample p = s.evaluate(x + dx), q = s.evaluate(x - dx);
      EXPECT_NEAR(a.gradient[d], (p.value - q.value) / (2 * e), 1e-5 * (1 + a.gradient.norm())) << t;
      const Vec3d col = (p.gradient - q.gradient) / (2 * e);
      const Vec3d ncol = (p.normalField - q.normalField) / (2 * e);
      for (int r = 0; r < 3; ++r) {
        EXPECT_NEAR(a.hessian(r, d), col[r], 1e-4 * (1 + a.hessian.norm())) << t;
        EXPECT_NEAR(a.normalJacobian(r, d), ncol[r], 1e-4 * (1 + a.normalJacobian.norm())) << t;
      }
    }
  }
  EXPECT_GT(checked, 20);
}

// A cylinder drawn as segments along its axis (a line model) implies the cylinder.
TEST(MlsSurface, ALineModelImpliesItsSurface) {
  HybridModel m;
  const int around = 120;
  for (int a = 0; a < around; ++a)
    for (int z = 0; z < 6; ++z) {
      const double th = 2 * 3.14159265358979 * a / around;
      Segment sg;
      const Vec3f n(float(std::cos(th)), float(std::sin(th)), 0);
      sg.p0 = n + Vec3f(0, 0, -3.0f + float(z));
      sg.p1 = n + Vec3f(0, 0, -2.0f + float(z));
      sg.normal = n;
      sg.radius = float(3.14159265358979 / around);  // strips that meet around the circle
      m.segments.push_back(sg);
    }
  const MlsSurface s(m);
  for (double z : {-1.2, 0.3, 1.7})
    for (double a : {0.2, 2.5, 4.0}) {
      const MlsProjection p = s.project(Vec3d(0.96 * std::cos(a), 0.96 * std::sin(a), z));
      ASSERT_TRUE(p.converged);
      EXPECT_NEAR(std::hypot(p.point.x(), p.point.y()), 1, 2e-3);
      const MlsCurvature c = s.curvature(p.point);
      // The support (3 x the half-width) spans 1.5 strips: the normal field ripples between
      // the lines, and the curvature with it.
      EXPECT_NEAR(c.kMax, 1, 0.1);
      EXPECT_NEAR(c.kMin, 0, 0.03);
      EXPECT_GT(std::abs(c.dirMin.z()), 0.999);
    }
}

/// The surface of the cube [-1, 1]^3 sampled on an n x n grid per face, exact face normals.
HybridModel cube(int n) {
  HybridModel m;
  m.attributes.normals = true;
  for (int axis = 0; axis < 3; ++axis)
    for (int side : {-1, 1})
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          Vec3f p, nrm = Vec3f::Zero();
          p[axis] = float(side), nrm[axis] = float(side);
          p[(axis + 1) % 3] = -1 + 2 * (i + 0.5f) / n, p[(axis + 2) % 3] = -1 + 2 * (j + 0.5f) / n;
          m.points.push_back({p, nrm});
        }
  return m;
}

// RIMLS keeps the cube's edges: near them the plain IMLS rounds the surface off (its normal
// turns across a band of a support's width), the robust fit keeps each face's normal.
TEST(MlsSurface, RobustVariantKeepsCreases) {
  const int n = 40;
  const HybridModel m = cube(n);
  const double spacing = 2.0 / n, h = 3 * spacing;
  MlsOptions robust;
  robust.robust = true;
  const MlsSurface plain(m), rimls(m, robust);
  // Points on the face z = 1 within 3h of its edge x = 1, moved off the surface a little.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> along(-0.5, 0.5), across(0.0, 3 * h), off(-0.3 * spacing, 0.3 * spacing);
  std::vector<double> errPlain, errRobust;
  int failed = 0;
  for (int q = 0; q < 400; ++q) {
    const Vec3d x(1 - across(rng), along(rng), 1 + off(rng));
    const MlsProjection a = plain.project(x), b = rimls.project(x);
    if (!a.converged || !b.converged) {
      ++failed;
      continue;
    }
    // The true normal of the face the projection lands on: the one whose coordinate is largest.
    auto truth = [](const Vec3d& p) { return p.x() > p.z() ? Vec3d(1, 0, 0) : Vec3d(0, 0, 1); };
    errPlain.push_back(std::acos(std::clamp(a.normal.dot(truth(a.point)), -1.0, 1.0)));
    errRobust.push_back(std::acos(std::clamp(b.normal.dot(truth(b.point)), -1.0, 1.0)));
  }
  EXPECT_LE(failed, 4);
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  // Beyond h from the edge only one face is in reach and both fits are exact: compare the mean
  // over the band and the median over the part of it within h, where the faces meet.
  auto mean = [](const std::vector<double>& v) {
    double t = 0;
    for (double e : v) t += e;
    return t / double(v.size());
  };
  std::vector<double> nearPlain, nearRobust;
  for (size_t i = 0; i < errPlain.size(); ++i)
    if (errPlain[i] > 1e-6 || errRobust[i] > 1e-6) nearPlain.push_back(errPlain[i]), nearRobust.push_back(errRobust[i]);
  const double mp = mean(errPlain), mr = mean(errRobust);
  const double np = median(nearPlain), nr = median(nearRobust);
  EXPECT_LT(mr, 0.7 * mp) << "mean normal error within 3h, degrees: plain " << mp * 57.3 << ", robust " << mr * 57.3;
  EXPECT_LT(nr, 0.7 * np) << "median where the faces meet, degrees: plain " << np * 57.3 << ", robust " << nr * 57.3;
  std::printf("cube edge, 3h band: mean normal error plain %.2f deg, robust %.2f deg; where the faces meet "
              "(%zu of %zu): median %.2f / %.2f deg\n", mp * 57.2958, mr * 57.2958, nearPlain.size(), errPlain.size(),
              np * 57.2958, nr * 57.2958);
  // Away from creases the robust fit is the plain one's surface: a sphere within the same bias.
  const HybridModel ball = noRadii(shapes::sphere(2, 20000));
  const MlsSurface smooth(ball, robust);
  double worst = 0;
  for (int i = 0; i < 20000; i += 97) {
    const MlsProjection p = smooth.project(ball.points[size_t(i)].position.cast<double>() * 1.01);
    ASSERT_TRUE(p.converged);
    worst = std::max(worst, std::abs(p.point.norm() - 2));
  }
  EXPECT_LT(worst, 0.15 * std::sqrt(4 * 3.14159265 * 4 / 20000));
  MlsOptions bad = robust;
  bad.sigmaNormal = 0;
  EXPECT_THROW(MlsSurface(m, bad), Error);
  bad = robust, bad.robustIterations = 11;
  EXPECT_THROW(MlsSurface(m, bad), Error);
}

TEST(MlsSurface, BadModelsAndOptionsAreRefused) {
  HybridModel m = shapes::plane(1, 1, 10, 10);
  MlsOptions o;
  o.supportScale = 0.5f;
  EXPECT_THROW(MlsSurface(m, o), Error);
  m.attributes.normals = false;
  EXPECT_THROW(MlsSurface{m}, Error);
  EXPECT_THROW(MlsSurface{HybridModel{}}, Error);
  m = shapes::plane(1, 1, 10, 10);
  m.points[3].normal = Vec3f(0, 0, 2);
  EXPECT_THROW(MlsSurface{m}, Error);
}

}  // namespace
}  // namespace linesurf
