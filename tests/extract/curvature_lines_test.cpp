// Lines of curvature traced on the MLS surface (extract/curvature_lines.h, thesis §9.2): the
// traced segments against the analytic lines of curvature of a torus and an ellipsoid, the
// chains' shared endpoints, the cover of every input point, determinism, degenerate clouds.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <random>

#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/extract/curvature_lines.h"
#include "shapes.h"

namespace linesurf {
namespace {

constexpr double kDeg = 180.0 / 3.14159265358979323846;

struct Truth {
  Vec3d minDir, maxDir;
  bool umbilic = false;  ///< too near an umbilic to have directions
};

/// Angles (degrees, modulo 180) between each segment and the true direction of its family, and
/// how many segments lie nearer the other family's direction than their own.
struct AngleFigures {
  std::vector<double> angles;
  size_t swaps = 0;
  double quantile(double q) const {
    std::vector<double> a = angles;
    if (a.empty()) return 0;
    const size_t k = std::min(a.size() - 1, size_t(q * double(a.size())));
    std::nth_element(a.begin(), a.begin() + ptrdiff_t(k), a.end());
    return a[k];
  }
};

template <typename TruthFn>
AngleFigures angleFigures(const HybridModel& m, TruthFn truth, bool minFamily) {
  AngleFigures f;
  for (const Segment& s : m.segments) {
    const Vec3d mid = (0.5f * (s.p0 + s.p1)).cast<double>();
    const Truth t = truth(mid);
    if (t.umbilic) continue;
    const Vec3d d = (s.p1 - s.p0).cast<double>().normalized();
    const Vec3d own = minFamily ? t.minDir : t.maxDir, other = minFamily ? t.maxDir : t.minDir;
    const double a = std::acos(std::min(1.0, std::abs(d.dot(own)))) * kDeg;
    const double b = std::acos(std::min(1.0, std::abs(d.dot(other)))) * kDeg;
    if (b < a) ++f.swaps;
    f.angles.push_back(a);
  }
  return f;
}

// Torus about z, R = 1, r = 0.3: the parallels (circles about z) are the lines of least
// curvature (|cos v / (R + r cos v)| <= 0.77 < 1/r), the meridians those of greatest.
Truth torusTruth(const Vec3d& p) {
  const double a = std::atan2(p.y(), p.x());
  const Vec3d par(-std::sin(a), std::cos(a), 0);
  const Vec3d n = (p - Vec3d(std::cos(a), std::sin(a), 0)).normalized();
  return {par, n.cross(par).normalized()};
}

HybridModel torusCloud(int nMajor, int nMinor, float noise = 0) {
  return shapes::torus(1.0f, 0.3f, nMajor, nMinor, {.noise = noise, .irregular = true, .seed = 7});
}

// Ellipsoid x^2/a^2 + y^2/b^2 + z^2/c^2 = 1 with a > b > c: its principal directions from the
// shape operator of the implicit, its four umbilics in the xz-plane.
constexpr double kA = 1.0, kB = 0.7, kC = 0.5;

HybridModel ellipsoidCloud(int n) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0, 1);
  HybridModel m;
  for (int i = 0; i < n; ++i) {
    Vec3d u(g(rng), g(rng), g(rng));
    u.normalize();
    const Vec3d p(kA * u.x(), kB * u.y(), kC * u.z());
    const Vec3d nrm = Vec3d(p.x() / (kA * kA), p.y() / (kB * kB), p.z() / (kC * kC)).normalized();
    Point pt;
    pt.position = p.cast<float>(), pt.normal = nrm.cast<float>();
    m.points.push_back(pt);
  }
  m.attributes.normals = true;
  return m;
}

Truth ellipsoidTruth(const Vec3d& x, double umbilicRadius) {
  // Project onto the ellipsoid along the radial direction (the segment midpoints lie within
  // epsilon of it).
  const double s = 1.0 / std::sqrt(x.x() * x.x() / (kA * kA) + x.y() * x.y() / (kB * kB) + x.z() * x.z() / (kC * kC));
  const Vec3d p = s * x;
  const double ux = kA * std::sqrt((kA * kA - kB * kB) / (kA * kA - kC * kC));
  const double uz = kC * std::sqrt((kB * kB - kC * kC) / (kA * kA - kC * kC));
  Truth t;
  for (double sx : {-1.0, 1.0})
    for (double sz : {-1.0, 1.0})
      if ((p - Vec3d(sx * ux, 0, sz * uz)).norm() < umbilicRadius) t.umbilic = true;
  const Vec3d grad(2 * p.x() / (kA * kA), 2 * p.y() / (kB * kB), 2 * p.z() / (kC * kC));
  const Vec3d n = grad.normalized();
  const Mat3d P = Mat3d::Identity() - n * n.transpose();
  const Mat3d H = Vec3d(2 / (kA * kA), 2 / (kB * kB), 2 / (kC * kC)).asDiagonal();
  const Mat3d S = P * H * P / grad.norm();
  Eigen::SelfAdjointEigenSolver<Mat3d> es(0.5 * (S + S.transpose()));
  int along = 0;
  for (int e = 1; e < 3; ++e)
    if (std::abs(es.eigenvectors().col(e).dot(n)) > std::abs(es.eigenvectors().col(along).dot(n))) along = e;
  const int a = along == 0 ? 1 : 0, b = along == 2 ? 1 : 2;
  t.minDir = es.eigenvectors().col(a), t.maxDir = es.eigenvectors().col(b);
  return t;
}

struct Extraction {
  HybridModel model;
  CurvatureLineStats stats;
  PointGeometry geometry;
};

Extraction extract(const HybridModel& cloud, CurvatureLineOptions o = {}) {
  GeometryOptions go;
  go.curvature = false;
  Extraction r;
  r.geometry = computePointGeometry(cloud, go);
  o.provenance = true;
  r.model = extractCurvatureLines(cloud, r.geometry, o, &r.stats);
  return r;
}

TEST(CurvatureLines, TorusSegmentsFollowTheParallels) {
  const Extraction r = extract(torusCloud(240, 60));
  ASSERT_GT(r.model.segments.size(), 50u);
  const AngleFigures f = angleFigures(r.model, torusTruth, true);
  // Measured 0.5 and 1.7 degrees.
  EXPECT_LE(f.quantile(0.5), 1.0);
  EXPECT_LE(f.quantile(0.95), 3.0);
  EXPECT_LE(double(f.swaps), 0.02 * double(f.angles.size()));
  // The parallels are closed: most chains close on themselves.
  EXPECT_GT(r.stats.closedLines, r.stats.lines / 2);
}

TEST(CurvatureLines, TorusMaxFamilyFollowsTheMeridians) {
  CurvatureLineOptions o;
  o.family = CurvatureFamily::Max;
  const Extraction r = extract(torusCloud(240, 60), o);
  ASSERT_GT(r.model.segments.size(), 50u);
  const AngleFigures f = angleFigures(r.model, torusTruth, false);
  EXPECT_LE(f.quantile(0.5), 2.0);
  EXPECT_LE(f.quantile(0.95), 6.0);
  EXPECT_LE(double(f.swaps), 0.02 * double(f.angles.size()));
}

TEST(CurvatureLines, EllipsoidAwayFromItsUmbilics) {
  CurvatureLineOptions o;
  const Extraction r = extract(ellipsoidCloud(16000), o);
  ASSERT_GT(r.model.segments.size(), 50u);
  const double exclude = 2 * o.separation * r.stats.averageSpacing;
  const AngleFigures f = angleFigures(r.model, [&](const Vec3d& x) { return ellipsoidTruth(x, exclude); }, true);
  ASSERT_GT(f.angles.size(), r.model.segments.size() / 2);
  EXPECT_LE(f.quantile(0.5), 2.0);
  EXPECT_LE(f.quantile(0.95), 6.0);
  EXPECT_LE(double(f.swaps), 0.05 * double(f.angles.size()));
}

TEST(CurvatureLines, ChainsShareEndpointsAndEveryPointIsCoveredOnce) {
  const HybridModel cloud = torusCloud(240, 60);
  const Extraction r = extract(cloud);
  const CurvatureLineStats& st = r.stats;
  EXPECT_EQ(st.segments, r.model.segments.size());
  EXPECT_EQ(st.keptPoints, r.model.points.size());
  EXPECT_EQ(st.keptPoints + st.replacedPoints, cloud.points.size());
  // Consecutive segments of a chain share bit-equal endpoints: segments - chains joints.
  size_t joints = 0;
  for (size_t j = 1; j < r.model.segments.size(); ++j) joints += r.model.segments[j].p0 == r.model.segments[j - 1].p1;
  EXPECT_EQ(joints, st.segments - st.lines);
  // Provenance partitions the replaced points, and each lies inside its strip.
  std::vector<int> seen(cloud.points.size(), 0);
  size_t replaced = 0;
  ASSERT_EQ(r.model.provenance.size(), r.model.segments.size());
  for (size_t j = 0; j < r.model.segments.size(); ++j) {
    const Segment& s = r.model.segments[j];
    for (uint32_t i : r.model.provenance[j]) {
      ++seen[i], ++replaced;
      const Vec3f q = cloud.points[i].position;
      const Vec3f d = s.p1 - s.p0;
      const float t = std::clamp((q - s.p0).dot(d) / d.squaredNorm(), 0.0f, 1.0f);
      const Vec3f off = q - (s.p0 + t * d);
      const Vec3f lateral = off - off.dot(s.normal) * s.normal;
      EXPECT_LE(lateral.norm(), s.radius * (1 + 1e-5f));
    }
  }
  EXPECT_EQ(replaced, st.replacedPoints);
  for (int c : seen) ASSERT_LE(c, 1);
  // The lines replace most of the torus, and the result is far smaller than the cloud.
  EXPECT_GT(st.replacedPoints, cloud.points.size() * 8 / 10);
  EXPECT_GT(st.dataReduction(), 0.6);
  EXPECT_GT(st.chainDataReduction(), st.dataReduction());
  // Segments are unit-normal, perpendicular to themselves, with the strip's width.
  for (const Segment& s : r.model.segments) {
    EXPECT_NEAR(s.normal.norm(), 1.0f, 1e-4f);
    EXPECT_LT(std::abs(s.normal.dot((s.p1 - s.p0).normalized())), 1e-3f);
    EXPECT_GT(s.radius, 0.0f);
  }
}

TEST(CurvatureLines, SameOutputForAnyThreadCount) {
  const HybridModel cloud = torusCloud(160, 40);
  Extraction a, b;
  {
    ThreadLimit one(1);
    a = extract(cloud);
  }
  b = extract(cloud);
  ASSERT_EQ(a.model.segments.size(), b.model.segments.size());
  ASSERT_EQ(a.model.points.size(), b.model.points.size());
  for (size_t j = 0; j < a.model.segments.size(); ++j) {
    ASSERT_EQ(a.model.segments[j].p0, b.model.segments[j].p0) << j;
    ASSERT_EQ(a.model.segments[j].p1, b.model.segments[j].p1) << j;
    ASSERT_EQ(a.model.segments[j].radius, b.model.segments[j].radius) << j;
  }
  EXPECT_EQ(a.model.provenance, b.model.provenance);
}

TEST(CurvatureLines, NoisyTorusStaysClose) {
  // Noise of 0.25 spacings: the median may grow by 3 degrees over the clean torus's (measured
  // 1.2 against 0.5).
  const Extraction r = extract(torusCloud(240, 60, 0.25f));
  const AngleFigures f = angleFigures(r.model, torusTruth, true);
  ASSERT_GT(f.angles.size(), 50u);
  EXPECT_LE(f.quantile(0.5), 0.5 + 3.0);
  EXPECT_LE(double(f.swaps), 0.02 * double(f.angles.size()));
}

TEST(CurvatureLines, CloudsWithoutASurfaceKeepEveryPoint) {
  // Collinear points: no tangent plane, every point kept, no segment.
  HybridModel line;
  for (int i = 0; i < 200; ++i) {
    Point p;
    p.position = Vec3f(0.01f * float(i), 0, 0);
    line.points.push_back(p);
  }
  const Extraction r = extract(line);
  EXPECT_TRUE(r.model.segments.empty());
  EXPECT_EQ(r.model.points.size(), line.points.size());
  // Too few points for a neighbourhood.
  HybridModel few;
  few.points.resize(5);
  for (int i = 0; i < 5; ++i) few.points[size_t(i)].position = Vec3f(float(i), float(i * i % 3), 0);
  const Extraction f = extract(few);
  EXPECT_EQ(f.model.points.size(), 5u);
  EXPECT_TRUE(f.model.segments.empty());
}

TEST(CurvatureLines, PlaneGivesStraightFullLengthLines) {
  const HybridModel plane = shapes::plane(1, 1, 60, 60, {.irregular = true, .seed = 3});
  const Extraction r = extract(plane);
  ASSERT_FALSE(r.model.segments.empty());
  // A flat cloud: chords run as long as the lines (one segment per line or nearly).
  EXPECT_LE(double(r.stats.segments), 2.0 * double(r.stats.lines));
  for (const Segment& s : r.model.segments) EXPECT_NEAR(std::abs(s.normal.z()), 1.0f, 1e-3f);
}

TEST(CurvatureLines, RejectsAbsurdOptions) {
  CurvatureLineOptions o;
  o.separation = std::nan("");
  EXPECT_THROW(validate(o), OptionError);
  o = {};
  o.minSeparation = 5;  // above separation 4
  EXPECT_THROW(validate(o), OptionError);
  o = {};
  o.step = 0;
  EXPECT_THROW(validate(o), OptionError);
  o = {};
  o.widthScale = 0.5;
  EXPECT_THROW(validate(o), OptionError);
  EXPECT_NO_THROW(validate(CurvatureLineOptions{}));
}

}  // namespace
}  // namespace linesurf
