// Tests of contour-plane extraction (thesis §3.3).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/extract/contour.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

using namespace linesurf;

namespace {

// Barycentric coordinates of p with respect to triangle (a, b, c), from the projection onto its
// plane; also returns the distance of p from the plane.
Vec3d barycentric(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& p, double* planeDistance = nullptr) {
  Vec3d n = (b - a).cross(c - a);
  double area2 = n.squaredNorm();
  if (planeDistance) *planeDistance = std::abs((p - a).dot(n)) / std::sqrt(area2);
  double wa = (c - b).cross(p - b).dot(n) / area2;
  double wb = (a - c).cross(p - c).dot(n) / area2;
  return Vec3d(wa, wb, 1 - wa - wb);
}

struct Tri {
  Vec3d a, b, c;
};
Tri triangle(const TriangleMesh& m, size_t f) {
  const auto& F = m.faces[f];
  return {m.positions[F[0]].cast<double>(), m.positions[F[1]].cast<double>(), m.positions[F[2]].cast<double>()};
}

// Distance from p to the closest point of triangle t (segment distances near the edges).
double distanceToTriangle(const Tri& t, const Vec3d& p) {
  double planeDist;
  Vec3d w = barycentric(t.a, t.b, t.c, p, &planeDist);
  if (w.minCoeff() >= 0) return planeDist;
  auto toSegment = [&](const Vec3d& a, const Vec3d& b) {
    Vec3d e = b - a;
    double tau = std::clamp((p - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    return (a + tau * e - p).norm();
  };
  return std::min({toSegment(t.a, t.b), toSegment(t.b, t.c), toSegment(t.c, t.a)});
}

// Every endpoint lies on its source triangle, within `tol` of the face's size plus the float
// rounding of the endpoint's coordinates.
void expectEndpointsOnTriangles(const TriangleMesh& mesh, const HybridModel& model, const ContourStats& st, double tol) {
  ASSERT_EQ(st.segmentFaces.size(), model.segments.size());
  size_t bad = 0;
  for (size_t i = 0; i < model.segments.size(); ++i) {
    Tri t = triangle(mesh, st.segmentFaces[i]);
    double scale = std::max({(t.b - t.a).norm(), (t.c - t.b).norm(), (t.a - t.c).norm()});
    for (const Vec3f& p : {model.segments[i].p0, model.segments[i].p1}) {
      double dist = distanceToTriangle(t, p.cast<double>());
      if (dist > tol * scale + 2e-7 * p.norm() && ++bad <= 5)
        ADD_FAILURE() << "segment " << i << " endpoint " << dist << " off its face (size " << scale << ")";
    }
  }
  EXPECT_EQ(bad, 0u);
}

// On every face, neighbouring (parallel) segments are at most d apart, and every vertex of a cut
// face is within d of one of its segment lines (measured in the face, across the lines).
void expectSpacingAtMostD(const TriangleMesh& mesh, const HybridModel& model, const ContourStats& st) {
  std::map<uint32_t, std::vector<size_t>> byFace;
  for (size_t i = 0; i < model.segments.size(); ++i) byFace[st.segmentFaces[i]].push_back(i);
  const double d = st.spacing, tol = 1e-4 * d;
  double worst = 0;
  for (auto& [f, segs] : byFace) {
    Tri t = triangle(mesh, f);
    Vec3d n = (t.b - t.a).cross(t.c - t.a).normalized();
    Vec3d dir = (model.segments[segs[0]].p1 - model.segments[segs[0]].p0).cast<double>().normalized();
    Vec3d across = n.cross(dir).normalized();
    std::vector<double> pos;
    for (size_t i : segs) {
      const Segment& s = model.segments[i];
      // All segments of a face are parallel (one family per face).
      Vec3d di = (s.p1 - s.p0).cast<double>();
      // Float endpoints: the direction of a segment of length l is good to ~1e-7 |p| / l.
      double angleTol = 1e-5 + 4e-7 * (s.p0.norm() + 1) * (1 / di.norm() + 1 / (model.segments[segs[0]].p1 - model.segments[segs[0]].p0).norm());
      EXPECT_LT(di.normalized().cross(dir).norm(), angleTol) << "face " << f;
      pos.push_back(0.5 * (s.p0 + s.p1).cast<double>().dot(across));
    }
    std::sort(pos.begin(), pos.end());
    for (size_t j = 1; j < pos.size(); ++j) worst = std::max(worst, pos[j] - pos[j - 1]);
    for (const Vec3d& v : {t.a, t.b, t.c}) {
      double x = v.dot(across), nearest = 1e300;
      for (double p : pos) nearest = std::min(nearest, std::abs(x - p));
      EXPECT_LE(nearest, d + tol) << "face " << f;
    }
  }
  EXPECT_LE(worst, d + tol);
}

// The raw cut: one segment per face and plane crossed (no polyline merging).
ContourOptions unmerged(ContourOptions o = {}) {
  o.mergeNormalDeviation = 0;
  return o;
}
// The raw cut with the source face of every primitive.
ContourOptions withFaces(ContourOptions o = {}) {
  o.recordFaces = true;
  return unmerged(o);
}

// Open cylinder of radius r, height h along z, with a seam (duplicated vertices) and per-corner
// uv = (angle / 2π, z / h + 1/2).
TriangleMesh cylinderMesh(float r, float h, int nAround, int nAlong) {
  TriangleMesh m;
  for (int j = 0; j <= nAlong; ++j)
    for (int i = 0; i <= nAround; ++i) {
      double a = 2 * std::numbers::pi * i / nAround;
      m.positions.emplace_back(float(r * std::cos(a)), float(r * std::sin(a)), h * (float(j) / nAlong - 0.5f));
    }
  auto id = [&](int i, int j) { return uint32_t(j * (nAround + 1) + i); };
  auto uv = [&](int i, int j) { return Vec2f(float(i) / nAround, float(j) / nAlong); };
  for (int j = 0; j < nAlong; ++j)
    for (int i = 0; i < nAround; ++i) {
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.cornerUVs.push_back({uv(i, j), uv(i + 1, j), uv(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      m.cornerUVs.push_back({uv(i, j), uv(i + 1, j + 1), uv(i, j + 1)});
    }
  return m;
}

// A smooth colourful texture (so that bilinear sampling differences show uv errors).
std::shared_ptr<Image> testTexture(int w, int h) {
  auto img = std::make_shared<Image>(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      img->at(x, y) = Color(0.5f + 0.5f * std::sin(0.3f * x), 0.5f + 0.5f * std::cos(0.2f * y), float(x + y) / float(w + h), 1);
  return img;
}

}  // namespace

TEST(Contour, SphereEndpointsLieOnTheirSourceTriangles) {
  TriangleMesh mesh = shapes::sphereMesh(1.0f, 3);
  ContourStats st;
  HybridModel model = extractContour(mesh, withFaces(), &st);
  ASSERT_GT(model.segments.size(), mesh.faces.size() / 4);
  EXPECT_EQ(st.degenerateTriangles, 0u);
  EXPECT_EQ(st.cutByFamily[0] + st.cutByFamily[1], mesh.faces.size());
  EXPECT_GT(st.cutByFamily[0], 0u);
  EXPECT_GT(st.cutByFamily[1], 0u);
  expectEndpointsOnTriangles(mesh, model, st, 1e-6);
  for (const Segment& s : model.segments) {
    EXPECT_NEAR(s.normal.norm(), 1.0f, 1e-5f);
    EXPECT_LT(std::abs(s.normal.dot((s.p1 - s.p0).normalized())), 1e-5f + 4e-7f / s.length());
    EXPECT_GT(s.normal.dot(s.p0), 0.0f);  // outward, like the faces
    EXPECT_GT(s.length(), 0.0f);
    EXPECT_FLOAT_EQ(s.radius, float(0.55 * st.spacing));
  }
  EXPECT_TRUE(model.points.empty());
  EXPECT_FALSE(model.attributes.texcoords);
}

TEST(Contour, SphereNeighbouringSegmentsAtMostDApart) {
  TriangleMesh mesh = shapes::sphereMesh(1.0f, 3);
  for (float scale : {0.5f, 1.0f, 2.5f}) {
    ContourStats st;
    ContourOptions o = withFaces();
    o.spacingScale = scale;
    o.diagonalDivisions = 0;  // d from the mean edge alone
    o.seed = 7;
    HybridModel model = extractContour(mesh, o, &st);
    EXPECT_NEAR(st.spacing, scale * st.meanEdgeLength, 1e-9);
    EXPECT_FALSE(st.spacingFromDiagonal);
    expectSpacingAtMostD(mesh, model, st);
    // Larger-sine family choice: max(sin θ) >= 1/√2, so the level is 0 or 1 (spacing d or d/2).
    EXPECT_LE(st.halvedSpacing, mesh.faces.size());
  }
}

TEST(Contour, DefaultSpacingCappedByTheDiagonalOnCoarseMeshes) {
  // A coarse icosphere (mean edge ~0.15 of a unit sphere, diagonal 2 sqrt 3): the default d is
  // diagonal / 200, with the spacing contract intact; a cap above the mean edge leaves the edge.
  TriangleMesh mesh = shapes::sphereMesh(1.0f, 3);
  ContourStats capped, edge, half;
  ContourOptions o = withFaces();
  o.seed = 3;
  HybridModel fine = extractContour(mesh, o, &capped);
  EXPECT_TRUE(capped.spacingFromDiagonal);
  EXPECT_NEAR(capped.diagonal, 2 * std::sqrt(3.0), 1e-5);
  EXPECT_NEAR(capped.spacing, capped.diagonal / 200, 1e-9);
  EXPECT_LT(capped.spacing, capped.meanEdgeLength);
  expectSpacingAtMostD(mesh, fine, capped);
  o.diagonalDivisions = 1;  // cap = the diagonal: the mean edge is smaller
  HybridModel coarse = extractContour(mesh, o, &edge);
  EXPECT_FALSE(edge.spacingFromDiagonal);
  EXPECT_NEAR(edge.spacing, edge.meanEdgeLength, 1e-9);
  EXPECT_GT(fine.segments.size(), 4 * coarse.segments.size());
  o.diagonalDivisions = 200, o.spacingScale = 0.5f;  // the scale multiplies the capped d
  extractContour(mesh, o, &half);
  EXPECT_NEAR(half.spacing, 0.5 * capped.spacing, 1e-9);
  EXPECT_NEAR(contourSpacing(o, edge.meanEdgeLength, capped.diagonal), half.spacing, 1e-12);
  o.spacing = 0.25f;  // an explicit d wins
  EXPECT_EQ(contourSpacing(o, edge.meanEdgeLength, capped.diagonal), 0.25);
  for (float bad : {-1.0f, std::numeric_limits<float>::quiet_NaN(), 2e6f}) {
    ContourOptions b;
    b.diagonalDivisions = bad;
    EXPECT_THROW(validate(b), OptionError) << bad;
  }
}

TEST(Contour, SphereSurfaceCoveredWithinD) {
  TriangleMesh mesh = shapes::sphereMesh(1.0f, 3);
  ContourStats st;
  HybridModel model = extractContour(mesh, {}, &st);
  // Random surface points: the nearest segment is within d (strips of radius >= d/2 overlap).
  uint64_t state = 12345;
  auto rnd = [&] { state = state * 6364136223846793005ull + 1442695040888963407ull; return double(state >> 11) * 0x1.0p-53; };
  double worst = 0;
  for (int i = 0; i < 1500; ++i) {
    Tri t = triangle(mesh, size_t(rnd() * double(mesh.faces.size())) % mesh.faces.size());
    double u = rnd(), v = rnd();
    if (u + v > 1) u = 1 - u, v = 1 - v;
    Vec3d x = t.a + u * (t.b - t.a) + v * (t.c - t.a);
    double best = 1e300;
    for (const Segment& s : model.segments) {
      Vec3d p0 = s.p0.cast<double>(), e = (s.p1 - s.p0).cast<double>();
      double tau = std::clamp((x - p0).dot(e) / e.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (p0 + tau * e - x).norm());
    }
    worst = std::max(worst, best);
  }
  EXPECT_LE(worst, st.spacing) << "d = " << st.spacing;
}

TEST(Contour, PlanesThroughVerticesAndEdgesGiveEachSegmentOnce) {
  // Grid in [0,1]^2 with planes x = k/8 through every column of vertices and along the grid's
  // vertical edges: each vertical edge must come out exactly once, nothing else.
  TriangleMesh mesh = shapes::gridMesh(8, 5);
  ContourOptions o = withFaces();
  o.spacing = 0.125f;
  o.planes = ContourPlanes{{Vec3d(1, 0, 0), Vec3d(0, 1, 0)}, {0.0, 0.0}};
  ContourStats st;
  HybridModel model = extractContour(mesh, o, &st);
  EXPECT_EQ(model.segments.size(), 8u * 5u);
  std::set<std::tuple<float, float, float, float>> seen;
  for (const Segment& s : model.segments) {
    EXPECT_EQ(s.p0.x(), s.p1.x());
    float k = s.p0.x() * 8;
    EXPECT_EQ(k, std::round(k));
    EXPECT_GE(k, 1.0f);
    EXPECT_NEAR(s.length(), 0.2f, 1e-6f);
    float y0 = std::min(s.p0.y(), s.p1.y()), y1 = std::max(s.p0.y(), s.p1.y());
    EXPECT_TRUE(seen.insert({s.p0.x(), y0, y1, 0}).second) << "duplicate segment";
  }
  EXPECT_GT(st.vertexTouches, 0u);
  expectEndpointsOnTriangles(mesh, model, st, 1e-6);
}

TEST(Contour, SingleFamilyContoursAreClosedOnAClosedMesh) {
  // With one family and planes through vertices and along edges (x = 0 on the icosphere), every
  // coarse plane's contour is a set of closed polygons: each endpoint is shared by exactly two
  // segments. A lost or duplicated segment breaks this.
  TriangleMesh mesh = shapes::sphereMesh(1.0f, 3);
  for (int variant = 0; variant < 2; ++variant) {
    ContourOptions o = withFaces();
    o.spacing = 0.25f;
    o.familySwitchSine = 0;
    if (variant == 0) o.planes = ContourPlanes{{Vec3d(1, 0, 0), Vec3d(0, 1, 0)}, {0.0, 0.0}};
    ContourStats st;
    HybridModel model = extractContour(mesh, o, &st);
    EXPECT_EQ(st.cutByFamily[0], mesh.faces.size());
    const Vec3d n = st.planes.normal[0];
    std::map<std::tuple<float, float, float>, int> ends;
    size_t coarse = 0;
    for (const Segment& s : model.segments) {
      double v = (n.dot(s.p0.cast<double>()) - st.planes.offset[0]) / st.spacing;
      if (std::abs(v - std::round(v)) > 1e-5) continue;  // a finer plane: ends at a T-junction
      ++coarse;
      for (const Vec3f& p : {s.p0, s.p1}) ++ends[{p.x(), p.y(), p.z()}];
    }
    EXPECT_GT(coarse, 50u);
    size_t open = 0;
    for (auto& [p, count] : ends) open += count != 2;
    EXPECT_EQ(open, 0u) << "variant " << variant;
  }
}

TEST(Contour, DeterministicForAnyThreadCount) {
  TriangleMesh mesh = shapes::sphereMesh(1.0f, 4);
  ContourOptions o;
  o.pointsBelow = 0.3f * 0.05f;
  HybridModel a = extractContour(mesh, o);
  HybridModel b;
  {
    ThreadLimit one(1);
    b = extractContour(mesh, o);
  }
  ASSERT_EQ(a.segments.size(), b.segments.size());
  ASSERT_EQ(a.points.size(), b.points.size());
  for (size_t i = 0; i < a.segments.size(); ++i) {
    ASSERT_EQ(a.segments[i].p0, b.segments[i].p0);
    ASSERT_EQ(a.segments[i].p1, b.segments[i].p1);
    ASSERT_EQ(a.segments[i].normal, b.segments[i].normal);
  }
  for (size_t i = 0; i < a.points.size(); ++i) ASSERT_EQ(a.points[i].position, b.points[i].position);
  // A different seed gives different planes.
  o.seed = 2;
  HybridModel c = extractContour(mesh, o);
  EXPECT_TRUE(c.segments.size() != a.segments.size() || c.segments[0].p0 != a.segments[0].p0);
}

TEST(Contour, RandomPlanesArePerpendicularAndNotAxisAligned) {
  for (uint64_t seed = 0; seed < 50; ++seed) {
    ContourPlanes p = randomContourPlanes(seed, 0.1);
    EXPECT_NEAR(p.normal[0].norm(), 1.0, 1e-12);
    EXPECT_NEAR(p.normal[1].norm(), 1.0, 1e-12);
    EXPECT_NEAR(p.normal[0].dot(p.normal[1]), 0.0, 1e-12);
    EXPECT_LT(p.normal[0].cwiseAbs().maxCoeff(), 0.9);
    EXPECT_LT(p.normal[1].cwiseAbs().maxCoeff(), 0.9);
    for (double off : p.offset) EXPECT_TRUE(off >= 0 && off < 0.1);
  }
}

TEST(Contour, AllPointsGivesCeilLOverDPlusOnePointsAtMostDApart) {
  TriangleMesh mesh = shapes::sphereMesh(1.0f, 2);
  ContourStats segSt, ptSt;
  HybridModel segs = extractContour(mesh, unmerged(), &segSt);
  ContourOptions o = withFaces();
  o.allPoints = true;
  HybridModel pts = extractContour(mesh, o, &ptSt);
  EXPECT_TRUE(pts.segments.empty());
  size_t expected = 0;
  for (const Segment& s : segs.segments) expected += size_t(std::ceil(s.length() / segSt.spacing)) + 1;
  EXPECT_EQ(pts.points.size(), expected);
  EXPECT_EQ(ptSt.convertedSegments, segs.segments.size());
  // the thesis's one-normal model: every point carries its segment's (the triangle's) normal
  ContourOptions flat = withFaces();
  flat.endpointNormals = false;
  const HybridModel flatSegs = extractContour(mesh, flat);
  flat.allPoints = true;
  const HybridModel flatPts = extractContour(mesh, flat);
  ASSERT_EQ(flatPts.points.size(), pts.points.size());
  ASSERT_EQ(flatSegs.segments.size(), segs.segments.size());
  const float cos10 = std::cos(10.0f * 3.14159265f / 180.0f);
  // Points of one segment are consecutive in the output: neighbours at most d apart.
  size_t i = 0;
  for (size_t k = 0; k < segs.segments.size(); ++k) {
    const Segment& s = segs.segments[k];
    const Vec3f fn = flatSegs.segments[k].normal;  // the triangle's normal
    size_t n = size_t(std::ceil(s.length() / segSt.spacing)) + 1;
    EXPECT_EQ(pts.points[i].position, s.p0);
    EXPECT_NEAR((pts.points[i + n - 1].position - s.p1).norm(), 0.0f, 1e-6f);
    for (size_t j = 1; j < n; ++j)
      EXPECT_LE((pts.points[i + j].position - pts.points[i + j - 1].position).norm(), segSt.spacing * (1 + 1e-5));
    for (size_t j = 0; j < n; ++j) {
      EXPECT_EQ(flatPts.points[i + j].normal, fn);
      // smooth model: the interpolated normal there (unit, perpendicular to the segment, radial
      // on the sphere), leaning at most 10 degrees from the triangle's normal
      const Vec3f& pn = pts.points[i + j].normal;
      EXPECT_NEAR(pn.norm(), 1.0f, 1e-5f);
      EXPECT_LT(std::abs(pn.dot((s.p1 - s.p0).normalized())), 1e-4f);
      EXPECT_GT(pn.dot(pts.points[i + j].position.normalized()), 0.98f);
      EXPECT_GE(pn.dot(fn), cos10 - 1e-5f);
      EXPECT_FLOAT_EQ(pts.points[i + j].radius, s.radius);
    }
    // at the ends: the shading normal is the endpoint normal itself (both the full interpolated
    // vertex normal), and the plane is that normal made perpendicular to the segment
    // where it leans less than 10 degrees
    ASSERT_TRUE(pts.attributes.shadingNormals);
    EXPECT_LT((pts.pointShadingNormals[i] - s.normal0).norm(), 1e-5f);
    EXPECT_LT((pts.pointShadingNormals[i + n - 1] - s.normal1).norm(), 1e-5f);
    const Vec3f dir = (s.p1 - s.p0).normalized();
    const Vec3f q0 = (s.normal0 - s.normal0.dot(dir) * dir).normalized(), q1 = (s.normal1 - s.normal1.dot(dir) * dir).normalized();
    if (q0.dot(fn) > cos10 + 1e-4f) { EXPECT_LT((pts.points[i].normal - q0).norm(), 1e-5f); }
    if (q1.dot(fn) > cos10 + 1e-4f) { EXPECT_LT((pts.points[i + n - 1].normal - q1).norm(), 1e-5f); }
    // point masses (docs/decisions.md "Point masses"): the length each stands for over the radius,
    // half a spacing at the ends, so the segment's points weigh l / r together, as the segment does
    double sum = 0;
    for (size_t j = 0; j < n; ++j) {
      const double spacing = s.length() / double(n - 1), share = j == 0 || j + 1 == n ? 0.5 : 1.0;
      const float m = (*pointMasses(pts))[i + j];
      EXPECT_NEAR(m, std::max(1e-3, share * spacing / s.radius), 1e-5 * spacing / s.radius) << k << " " << j;
      sum += m;
    }
    EXPECT_NEAR(sum, std::max(double(s.length()) / s.radius, 1e-3 * double(n)), 1e-4 * n) << k;
    i += n;
  }
  // the thesis's unit splats on request
  ContourOptions unit = o;
  unit.pointMasses = false;
  const HybridModel unitPts = extractContour(mesh, unit);
  EXPECT_EQ(pointMasses(unitPts), nullptr);
  EXPECT_TRUE(unitPts.pointProperties.empty());
  EXPECT_EQ(pointMasses(segs), nullptr);  // no points, no masses
}

TEST(Contour, PointsBelowMakesAHybridModel) {
  TriangleMesh mesh = shapes::sphereMesh(1.0f, 3);
  ContourStats all;
  HybridModel segs = extractContour(mesh, unmerged(), &all);
  ContourOptions o = unmerged();
  o.pointsBelow = float(0.5 * all.spacing);
  ContourStats st;
  HybridModel hybrid = extractContour(mesh, o, &st);
  size_t shortOnes = 0, shortPoints = 0;
  for (const Segment& s : segs.segments)
    if (s.length() < o.pointsBelow) ++shortOnes, shortPoints += size_t(std::ceil(s.length() / all.spacing)) + 1;
  ASSERT_GT(shortOnes, 0u);
  EXPECT_EQ(st.convertedSegments, shortOnes);
  EXPECT_EQ(hybrid.segments.size(), segs.segments.size() - shortOnes);
  EXPECT_EQ(hybrid.points.size(), shortPoints);
  for (const Segment& s : hybrid.segments) EXPECT_GE(s.length(), o.pointsBelow);
  // the points weigh what the short segments they replace weigh (length / radius)
  ASSERT_NE(pointMasses(hybrid), nullptr);
  double mass = 0, length = 0;
  for (float m : *pointMasses(hybrid)) mass += m;
  for (const Segment& s : segs.segments)
    if (s.length() < o.pointsBelow) length += s.length() / s.radius;
  EXPECT_NEAR(mass, length, 1e-3 * length + 1e-3 * double(shortPoints));
}

TEST(Contour, TexturedGridUvsReproduceTheTexture) {
  // gridMesh has uv = (x, y), so the uv of a segment endpoint must equal its position, and the
  // texture sampled at the segment's uv equals the texture at the mesh surface point.
  TriangleMesh mesh = shapes::gridMesh(6, 6);
  mesh.texture = testTexture(64, 48);
  ContourOptions o = withFaces();
  o.spacing = 0.05f;
  ContourStats st;
  HybridModel model = extractContour(mesh, o, &st);
  ASSERT_GT(model.segments.size(), 100u);
  EXPECT_TRUE(model.attributes.texcoords);
  EXPECT_TRUE(model.attributes.colors);
  EXPECT_EQ(model.texture.get(), mesh.texture.get());
  for (const Segment& s : model.segments) {
    EXPECT_NEAR(s.uv0.x(), s.p0.x(), 1e-6f);
    EXPECT_NEAR(s.uv0.y(), s.p0.y(), 1e-6f);
    EXPECT_NEAR(s.uv1.x(), s.p1.x(), 1e-6f);
    EXPECT_NEAR(s.uv1.y(), s.p1.y(), 1e-6f);
    Vec3f mid = 0.5f * (s.p0 + s.p1);
    Color expected = mesh.texture->sampleBilinear(mid.x(), mid.y());
    EXPECT_LT((s.color - expected).cwiseAbs().maxCoeff(), 1e-4f);
    for (float tau : {0.0f, 0.3f, 1.0f}) {  // the renderer interpolates uv linearly (§5.2.4)
      Vec2f uv = s.uv0 + tau * (s.uv1 - s.uv0);
      Vec3f p = s.p0 + tau * (s.p1 - s.p0);
      EXPECT_LT((mesh.texture->sampleBilinear(uv.x(), uv.y()) - mesh.texture->sampleBilinear(p.x(), p.y())).cwiseAbs().maxCoeff(), 1e-3f);
    }
  }
}

TEST(Contour, TexturedCylinderUvsAreTheBarycentricInterpolation) {
  TriangleMesh mesh = cylinderMesh(1.0f, 2.0f, 40, 10);
  mesh.texture = testTexture(80, 40);
  ContourStats st;
  HybridModel model = extractContour(mesh, withFaces(), &st);
  ASSERT_GT(model.segments.size(), 200u);
  expectEndpointsOnTriangles(mesh, model, st, 1e-6);
  for (size_t i = 0; i < model.segments.size(); ++i) {
    const Segment& s = model.segments[i];
    size_t f = st.segmentFaces[i];
    Tri t = triangle(mesh, f);
    const auto& c = mesh.cornerUVs[f];
    for (int e = 0; e < 2; ++e) {
      Vec3d w = barycentric(t.a, t.b, t.c, (e ? s.p1 : s.p0).cast<double>());
      Vec2d uv = w[0] * c[0].cast<double>() + w[1] * c[1].cast<double>() + w[2] * c[2].cast<double>();
      Vec2f got = e ? s.uv1 : s.uv0;
      EXPECT_NEAR(got.x(), uv.x(), 2e-5);
      EXPECT_NEAR(got.y(), uv.y(), 2e-5);
    }
    // Independent check against the surface parameterisation: u = angle / 2π, v = z / h + 1/2.
    Vec3f mid = 0.5f * (s.p0 + s.p1);
    Vec2f uvMid = 0.5f * (s.uv0 + s.uv1);
    EXPECT_NEAR(uvMid.y(), mid.z() / 2.0f + 0.5f, 1e-5f);
    double angle = std::atan2(double(mid.y()), double(mid.x()));
    if (angle < 0) angle += 2 * std::numbers::pi;
    double du = std::abs(uvMid.x() - angle / (2 * std::numbers::pi));
    EXPECT_LT(std::min(du, 1 - du), 0.5 / 40) << "within one column";
    Color expected = mesh.texture->sampleBilinear(uvMid.x(), uvMid.y());
    EXPECT_LT((s.color - expected).cwiseAbs().maxCoeff(), 1e-4f);
  }
}

TEST(Contour, VertexColoursAndNormalsAreInterpolated) {
  TriangleMesh mesh = shapes::gridMesh(4, 4);
  for (const Vec3f& p : mesh.positions) mesh.colors.emplace_back(p.x(), p.y(), 0.25f, 1.0f);
  mesh.normals.clear();
  for (const Vec3f& p : mesh.positions) mesh.normals.push_back(Vec3f(p.x() - 0.5f, 0, 2).normalized() * 3.0f);
  ContourOptions o;
  o.spacing = 0.1f;
  o.vertexNormals = true;
  HybridModel model = extractContour(mesh, o);
  ASSERT_FALSE(model.segments.empty());
  EXPECT_TRUE(model.attributes.colors);
  for (const Segment& s : model.segments) {
    Vec3f mid = 0.5f * (s.p0 + s.p1);
    EXPECT_NEAR(s.color.x(), mid.x(), 1e-5f);
    EXPECT_NEAR(s.color.y(), mid.y(), 1e-5f);
    EXPECT_NEAR(s.color.z(), 0.25f, 1e-6f);
    EXPECT_NEAR(s.normal.norm(), 1.0f, 1e-5f);
    EXPECT_LT(std::abs(s.normal.dot((s.p1 - s.p0).normalized())), 1e-4f);
    EXPECT_GT(s.normal.z(), 0.9f);
  }
  // Without the option and without endpoint normals (the thesis's model), the face normal (+z).
  o.vertexNormals = false;
  o.endpointNormals = false;
  for (const Segment& s : extractContour(mesh, o).segments) EXPECT_EQ(s.normal, Vec3f(0, 0, 1));
}

TEST(Contour, DegenerateAndNonManifoldInputIsCountedNotFatal) {
  TriangleMesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.5f},   // 0..3
                    {0, 0, 0}, {1, 0, 0},                            // 4, 5: duplicates of 0, 1
                    {2, 0, 0},                                       // 6: collinear with 0, 1
                    {0.5f, -1, 0.3f},                                // 7: third face on edge 0-1
                    {NAN, 0, 0},                                     // 8
                    {0.5f, 1e-7f, 0}};                               // 9: sliver apex
  mesh.faces = {{0, 1, 2}, {1, 3, 2}, {4, 5, 2} /* duplicate face via duplicate vertices */,
                {0, 1, 6} /* collinear */, {0, 0, 2} /* repeated index */, {0, 1, 7} /* non-manifold */,
                {0, 8, 2} /* NaN */, {0, 1, 9} /* sliver */};
  ContourOptions o = withFaces();
  o.spacing = 0.05f;
  ContourStats st;
  HybridModel model = extractContour(mesh, o, &st);
  EXPECT_EQ(st.degenerateTriangles, 3u);
  EXPECT_GT(model.segments.size(), 10u);
  for (const Segment& s : model.segments) {
    EXPECT_TRUE(s.p0.allFinite() && s.p1.allFinite() && s.normal.allFinite() && s.color.allFinite());
    EXPECT_GT(s.length(), 0.0f);
  }
  expectEndpointsOnTriangles(mesh, model, st, 1e-6);
  // Faces 0 and 2 are the same triangle (duplicate vertices): identical cuts.
  std::vector<const Segment*> f0, f2;
  for (size_t i = 0; i < model.segments.size(); ++i) {
    if (st.segmentFaces[i] == 0) f0.push_back(&model.segments[i]);
    if (st.segmentFaces[i] == 2) f2.push_back(&model.segments[i]);
  }
  ASSERT_EQ(f0.size(), f2.size());
  for (size_t i = 0; i < f0.size(); ++i) EXPECT_EQ(f0[i]->p0, f2[i]->p0);
  // An all-degenerate mesh gives an empty model, and an empty mesh too.
  TriangleMesh flat;
  flat.positions = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.faces = {{0, 1, 2}};
  EXPECT_TRUE(extractContour(flat).empty());
  EXPECT_TRUE(extractContour(TriangleMesh{}).empty());
}

TEST(Contour, BadParametersAndIndicesThrow) {
  TriangleMesh mesh = shapes::sphereMesh(1.0f, 1);
  auto kindOf = [&](const ContourOptions& o, const TriangleMesh& m) {
    try {
      extractContour(m, o);
    } catch (const Error& e) {
      return int(e.kind());
    }
    return -1;
  };
  const int badParameter = int(Error::Kind::BadParameter), badInput = int(Error::Kind::BadInput);
  ContourOptions o;
  o.spacing = -1;
  EXPECT_EQ(kindOf(o, mesh), badParameter);
  o = {};
  o.spacing = NAN;
  EXPECT_EQ(kindOf(o, mesh), badParameter);
  o = {};
  o.allPoints = true;
  o.pointsBelow = 0.1f;
  EXPECT_EQ(kindOf(o, mesh), badParameter);
  o = {};
  o.radiusScale = 0;
  EXPECT_EQ(kindOf(o, mesh), badParameter);
  o = {};
  o.spacing = 1e-6f;  // would be billions of segments
  o.maxPrimitives = 1000000;
  EXPECT_EQ(kindOf(o, mesh), badParameter);
  o = {};
  o.spacing = 1e-30f;  // plane indices beyond exact doubles
  EXPECT_EQ(kindOf(o, mesh), badParameter);
  o = {};
  o.planes = ContourPlanes{{Vec3d(1, 0, 0), Vec3d(1, 0, 0)}, {0, 0}};
  EXPECT_EQ(kindOf(o, mesh), badParameter);
  TriangleMesh broken = mesh;
  broken.faces.push_back({0, 1, uint32_t(broken.positions.size())});
  EXPECT_EQ(kindOf({}, broken), badInput);
  EXPECT_EQ(kindOf({}, mesh), -1);
}

// ---- Through files and the CLI -------------------------------------------------------------

TEST(Contour, TexturedObjThroughTheCliReproducesTheTexture) {
  // A textured quad mesh written as OBJ + MTL + PNG, cut by `linesurf extract contour`, read
  // back: the texture sampled at each segment's uv equals the texture at its mesh surface point
  // (grid uv = (x, y)), and the output carries the texture.
  auto dir = test::scratchDir("contour_obj");
  TriangleMesh mesh = shapes::gridMesh(5, 5);
  mesh.texture = testTexture(32, 32);
  writeMesh(dir / "quad.obj", mesh);
  const TriangleMesh back = readMesh(dir / "quad.obj");
  ASSERT_TRUE(back.texture);
  auto r = test::runCli(fmt::format("extract contour {} -o {} --spacing 0.04 --seed 3", (dir / "quad.obj").string(),
                                    (dir / "quad_lines.ply").string()));
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("segments"), std::string::npos) << r.out;
  HybridModel model = readModel(dir / "quad_lines.ply");
  ASSERT_GT(model.segments.size(), 100u);
  ASSERT_TRUE(model.texture);
  EXPECT_TRUE(model.attributes.texcoords);
  size_t bad = 0;
  for (const Segment& s : model.segments) {
    for (float tau : {0.0f, 0.5f, 1.0f}) {
      Vec2f uv = s.uv0 + tau * (s.uv1 - s.uv0);
      Vec3f p = s.p0 + tau * (s.p1 - s.p0);
      // PNG round trip quantises the texture to 8 bits: compare at 1.5 grey levels.
      Color a = model.texture->sampleBilinear(uv.x(), uv.y()), b = back.texture->sampleBilinear(p.x(), p.y());
      bad += (a - b).cwiseAbs().maxCoeff() > 1.5f / 255;
    }
  }
  EXPECT_EQ(bad, 0u);
}

TEST(Contour, CliCountsModesAndErrors) {
  auto dir = test::scratchDir("contour_cli");
  writeMesh(dir / "sphere.ply", shapes::sphereMesh(1.0f, 3));
  const std::string in = (dir / "sphere.ply").string();
  auto lines = test::runCli(fmt::format("extract contour {} -o {} --merge-normal-deviation 0", in, (dir / "lines.ply").string()));
  ASSERT_EQ(lines.exitCode, 0) << lines.out;
  auto points = test::runCli(fmt::format("extract contour {} -o {} --all-points", in, (dir / "points.ply").string()));
  ASSERT_EQ(points.exitCode, 0) << points.out;
  ContourStats st;
  ContourOptions all;
  all.allPoints = true;
  extractContour(shapes::sphereMesh(1.0f, 3), all, &st);
  EXPECT_EQ(readModel(dir / "points.ply").points.size(), st.points);
  EXPECT_TRUE(readModel(dir / "points.ply").segments.empty());
  EXPECT_EQ(readModel(dir / "lines.ply").segments.size(), st.convertedSegments);
  // Usage errors exit 1, a missing or bad input 2, and nothing is written.
  EXPECT_EQ(test::runCli(fmt::format("extract contour {} -o {} --all-points --points-below 0.01", in, (dir / "x.ply").string())).exitCode, 1);
  EXPECT_EQ(test::runCli(fmt::format("extract contour {} -o {} --spacing -1", in, (dir / "x.ply").string())).exitCode, 1);
  EXPECT_EQ(test::runCli(fmt::format("extract contour {} -o {}", (dir / "missing.ply").string(), (dir / "x.ply").string())).exitCode, 2);
  EXPECT_FALSE(std::filesystem::exists(dir / "x.ply"));
}

// ---- Shared models (../shared/data) ---------------------------------------------------------

TEST(SharedContour, MeshEndpointsOnTrianglesAndSpacingAtMostD) {
  LINESURF_REQUIRE_SHARED_DATA();
  for (const char* name : {"bunny_mesh.ply", "horse_mesh.ply", "gargoyle_mesh.ply", "buddha_mesh.ply", "al_mesh.ply"}) {
    SCOPED_TRACE(name);
    const TriangleMesh mesh = readMesh(test::sharedData() / name);
    ContourStats st;
    HybridModel model = extractContour(mesh, withFaces(), &st);
    EXPECT_GT(model.segments.size(), mesh.faces.size() / 2);
    expectEndpointsOnTriangles(mesh, model, st, 1e-6);
    expectSpacingAtMostD(mesh, model, st);
    for (const Segment& s : model.segments)
      ASSERT_TRUE(s.p0.allFinite() && s.p1.allFinite() && s.normal.allFinite() && s.length() > 0);
  }
}

TEST(Contour, NearlyParallelFacesUseFinerSubLattices) {
  // A strip of faces tilted 1e-3 rad against P=, cut with P= only: the level must rise to
  // m = ⌈log2(1/sin θ)⌉ = 10 so that the segments on each face are still at most d apart.
  TriangleMesh mesh = shapes::gridMesh(4, 4);
  for (Vec3f& p : mesh.positions) p.z() = 1e-3f * p.x();
  ContourOptions o = withFaces();
  o.spacing = 0.1f;
  o.familySwitchSine = 0;
  o.planes = ContourPlanes{{Vec3d(0, 0, 1), Vec3d(1, 0, 0)}, {0.0, 0.0}};
  ContourStats st;
  HybridModel model = extractContour(mesh, o, &st);
  EXPECT_EQ(st.cutByFamily[0], mesh.faces.size());
  EXPECT_GE(model.segments.size(), 8u);
  expectEndpointsOnTriangles(mesh, model, st, 1e-6);
  expectSpacingAtMostD(mesh, model, st);
  // The default rule takes P‖ (sin θ ~ 1) instead, at level 1 (sin θ just below 1).
  o.familySwitchSine = 1;
  ContourStats st1;
  HybridModel model1 = extractContour(mesh, o, &st1);
  EXPECT_EQ(st1.cutByFamily[1], mesh.faces.size());
  EXPECT_LT(model1.segments.size(), model.segments.size() * 2);
  expectSpacingAtMostD(mesh, model1, st1);
}
