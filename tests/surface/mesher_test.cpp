// Meshes of the MLS surface (surface/mesh_extract.h): closed and manifold on closed shapes, with
// the topology of the shape, open where the data is, outward, the same bytes for any thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <string>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/surface/mesh_extract.h"
#include "shapes.h"
#include "test_util.h"

namespace linesurf {
namespace {

struct Topology {
  size_t edges = 0, boundary = 0, overShared = 0, misoriented = 0;
  long euler = 0;
};

/// Edges by their endpoints: how many triangles share each, and whether the two triangles of an
/// edge run it in opposite directions (a consistent orientation).
Topology topology(const TriangleMesh& m) {
  std::map<std::pair<uint32_t, uint32_t>, std::pair<int, int>> edges;  // (lo, hi) -> (lo->hi, hi->lo)
  for (const auto& f : m.faces)
    for (int e = 0; e < 3; ++e) {
      const uint32_t a = f[size_t(e)], b = f[size_t((e + 1) % 3)];
      auto& c = edges[{std::min(a, b), std::max(a, b)}];
      (a < b ? c.first : c.second)++;
    }
  Topology t;
  t.edges = edges.size();
  for (const auto& [key, c] : edges) {
    const int n = c.first + c.second;
    t.boundary += n == 1, t.overShared += n > 2;
    t.misoriented += n == 2 && (c.first != 1 || c.second != 1);
  }
  t.euler = long(m.positions.size()) - long(t.edges) + long(m.faces.size());
  return t;
}

Vec3d faceNormal(const TriangleMesh& m, const std::array<uint32_t, 3>& f) {
  const Vec3d a = m.positions[f[0]].cast<double>(), b = m.positions[f[1]].cast<double>(), c = m.positions[f[2]].cast<double>();
  return (b - a).cross(c - a);
}

TEST(Mesher, SphereIsClosedManifoldOutwardAndOnTheSphere) {
  const HybridModel cloud = shapes::sphere(1, 8000);
  MeshStats st;
  const TriangleMesh m = extractMesh(cloud, {}, &st);
  ASSERT_GT(m.faces.size(), 1000u);
  const Topology t = topology(m);
  EXPECT_EQ(t.boundary, 0u);
  EXPECT_EQ(st.boundaryEdges, 0u);
  EXPECT_EQ(t.overShared, 0u);
  EXPECT_EQ(t.misoriented, 0u);
  EXPECT_EQ(t.euler, 2);
  EXPECT_EQ(st.vertices, m.positions.size());
  double worst = 0;
  for (const Vec3f& p : m.positions) worst = std::max(worst, std::abs(double(p.norm()) - 1));
  EXPECT_LT(worst, 0.05 * st.medianSpacing) << "spacing " << st.medianSpacing;
  size_t inward = 0;
  for (const auto& f : m.faces) {
    const Vec3d n = faceNormal(m, f);
    if (n.norm() > 1e-12) inward += n.dot((m.positions[f[0]] + m.positions[f[1]] + m.positions[f[2]]).cast<double>()) <= 0;
  }
  EXPECT_EQ(inward, 0u);
  for (size_t i = 0; i < m.positions.size(); ++i) EXPECT_GT(m.normals[i].dot(m.positions[i].normalized()), 0.99f) << i;
}

TEST(Mesher, OpenHemisphereHasABoundaryLoopNearTheData) {
  HybridModel cloud = shapes::sphere(1, 8000);
  std::erase_if(cloud.points, [](const Point& p) { return p.position.z() < 0; });
  MeshStats st;
  const TriangleMesh m = extractMesh(cloud, {}, &st);
  ASSERT_GT(m.faces.size(), 500u);
  const Topology t = topology(m);
  EXPECT_GT(t.boundary, 0u);
  EXPECT_EQ(t.overShared, 0u);
  EXPECT_EQ(t.misoriented, 0u);
  EXPECT_EQ(t.euler, 1);  // a disc
  // Boundary edges form loops: at every boundary vertex one starts and one ends.
  std::set<std::pair<uint32_t, uint32_t>> directed;
  for (const auto& f : m.faces)
    for (int e = 0; e < 3; ++e) directed.insert({f[size_t(e)], f[size_t((e + 1) % 3)]});
  std::map<uint32_t, std::pair<int, int>> ends;  // vertex -> (boundary edges leaving, arriving)
  for (const auto& [a, b] : directed)
    if (!directed.count({b, a})) ++ends[a].first, ++ends[b].second;
  EXPECT_GT(ends.size(), 10u);
  for (const auto& [v, n] : ends) EXPECT_TRUE(n.first == 1 && n.second == 1) << v;
  const double h2 = 2 * MlsOptions{}.supportScale * st.medianSpacing;
  double farthest = 0;
  for (const Vec3f& v : m.positions) {
    float best = INFINITY;
    for (const Point& p : cloud.points) best = std::min(best, (p.position - v).squaredNorm());
    farthest = std::max(farthest, double(std::sqrt(best)));
  }
  EXPECT_LT(farthest, h2);
}

TEST(Mesher, TorusHasEulerCharacteristicZero) {
  const TriangleMesh m = extractMesh(shapes::torus(1, 0.3f, 240, 72));
  const Topology t = topology(m);
  EXPECT_EQ(t.boundary, 0u);
  EXPECT_EQ(t.overShared, 0u);
  EXPECT_EQ(t.misoriented, 0u);
  EXPECT_EQ(t.euler, 0);
}

TEST(Mesher, LineModelAndHybridMeshToo) {
  // A square of strips alone: a flat disc.
  MeshStats st;
  const TriangleMesh square = extractMesh(test::squareStrips(), {}, &st);
  ASSERT_GT(square.faces.size(), 100u);
  Topology t = topology(square);
  EXPECT_GT(t.boundary, 0u);
  EXPECT_EQ(t.overShared, 0u);
  EXPECT_EQ(t.euler, 1);
  for (const Vec3f& p : square.positions) EXPECT_LT(std::abs(p.z()), 1e-3f);
  // The (ε,δ) hybrid of a sphere: closed, on the sphere.
  const HybridModel cloud = shapes::sphere(1, 8000);
  const HybridModel hybrid = extractEpsDelta(cloud, computePointGeometry(cloud), {});
  ASSERT_GT(hybrid.segments.size(), 100u);
  const TriangleMesh m = extractMesh(hybrid, {}, &st);
  t = topology(m);
  EXPECT_EQ(t.boundary, 0u);
  EXPECT_EQ(t.overShared, 0u);
  EXPECT_EQ(t.euler, 2);
  double worst = 0;
  for (const Vec3f& p : m.positions) worst = std::max(worst, std::abs(double(p.norm()) - 1));
  EXPECT_LT(worst, 0.1 * st.medianSpacing);
}

TEST(Mesher, BadInputIsRefusedNotMeshed) {
  HybridModel noNormals = shapes::sphere(1, 500);
  noNormals.attributes.normals = false;
  EXPECT_THROW(extractMesh(noNormals), Error);
  EXPECT_THROW(extractMesh(HybridModel{}), Error);
  HybridModel nan = shapes::sphere(1, 500);
  nan.points[7].position.x() = NAN;
  EXPECT_THROW(extractMesh(nan), Error);
  EXPECT_THROW(extractMesh(shapes::sphere(1, 500), {.cellScale = 0.1f}), Error);
  // Cells coarser than 0.4 x the support have corners no support reaches: refused, naming the bound.
  MeshOptions coarse;
  coarse.cellScale = 1.5f, coarse.mls.supportScale = 3.0f;
  try {
    extractMesh(shapes::sphere(1, 500), coarse);
    ADD_FAILURE() << "cell 1.5 with support 3 was not refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("0.4 x"), std::string::npos) << e.what();
  }
  coarse.mls.supportScale = 4.0f;  // 1.5 <= 1.6: accepted
  EXPECT_NO_THROW(extractMesh(shapes::sphere(1, 500), coarse));
  try {
    extractMesh(shapes::sphere(1, 500), {}, nullptr, Budget(0.01, "--max-mb"));
    ADD_FAILURE() << "no refusal";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadParameter);
    EXPECT_NE(std::string(e.what()).find("needs about"), std::string::npos) << e.what();
  }
}

TEST(Mesher, SameBytesForAnyThreadCount) {
  const HybridModel cloud = shapes::sphere(1, 6000, {.noise = 0.1f, .irregular = true, .seed = 4});
  TriangleMesh one, two;
  {
    ThreadLimit l(1);
    one = extractMesh(cloud);
  }
  {
    ThreadLimit l(2);
    two = extractMesh(cloud);
  }
  ASSERT_EQ(one.positions.size(), two.positions.size());
  ASSERT_EQ(one.faces.size(), two.faces.size());
  EXPECT_EQ(std::memcmp(one.positions.data(), two.positions.data(), one.positions.size() * sizeof(Vec3f)), 0);
  EXPECT_EQ(std::memcmp(one.normals.data(), two.normals.data(), one.normals.size() * sizeof(Vec3f)), 0);
  EXPECT_EQ(std::memcmp(one.faces.data(), two.faces.data(), one.faces.size() * sizeof(one.faces[0])), 0);
}

TEST(MeshCli, WritesAMeshAndRefusesOverBudgetWithoutWriting) {
  const auto dir = test::scratchDir("mesh_cli");
  writeModel(dir / "in.ply", shapes::sphere(1, 4000));
  auto r = test::runCli("mesh " + (dir / "in.ply").string() + " -o " + (dir / "out.ply").string());
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("0 boundary edges (closed)"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find(" triangles"), std::string::npos) << r.out;
  const TriangleMesh m = readMesh(dir / "out.ply");
  EXPECT_GT(m.faces.size(), 1000u);
  EXPECT_EQ(m.normals.size(), m.positions.size());
  r = test::runCli("--max-mb 0.05 mesh " + (dir / "in.ply").string() + " -o " + (dir / "refused.ply").string());
  EXPECT_EQ(r.exitCode, 1) << r.out;
  EXPECT_NE(r.out.find("--max-mb"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "refused.ply"));
  HybridModel bare = shapes::sphere(1, 500);
  bare.attributes.normals = false;
  writeModel(dir / "bare.ply", bare);
  r = test::runCli("mesh " + (dir / "bare.ply").string() + " -o " + (dir / "bare_mesh.ply").string());
  EXPECT_EQ(r.exitCode, 2) << r.out;
  EXPECT_NE(r.out.find("bare.ply"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("no normals"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace linesurf
