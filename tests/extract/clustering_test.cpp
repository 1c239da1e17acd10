// Tests of the §3.2.3 normal-variation clustering (greedy and hierarchical).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/extract/clustering.h"
#include "linesurf/geometry/point_geometry.h"

using namespace linesurf;

namespace {

/// Geometry of a grid-sampled shape (index j * nu + i) built by hand: exact normals, the
/// triangulated grid as local Delaunay neighbours (4-neighbours + one diagonal), optional wrap.
PointGeometry gridGeometry(const HybridModel& cloud, int nu, int nv, bool wrapU, bool wrapV) {
  PointGeometry g;
  const size_t n = cloud.points.size();
  for (const Point& p : cloud.points) {
    g.normals.push_back(p.normal);
    g.surfaceVariation.push_back(0.0f);
    g.spacing.push_back(p.radius);
  }
  g.flags.assign(n, 0);
  g.delaunayOffsets.push_back(0);
  const int di[6] = {1, -1, 0, 0, 1, -1}, dj[6] = {0, 0, 1, -1, 1, -1};
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      for (int e = 0; e < 6; ++e) {
        int a = i + di[e], b = j + dj[e];
        if (wrapU) a = (a + nu) % nu;
        if (wrapV) b = (b + nv) % nv;
        if (a < 0 || a >= nu || b < 0 || b >= nv) continue;
        g.delaunayIndices.push_back(uint32_t(b * nu + a));
      }
      g.delaunayOffsets.push_back(uint32_t(g.delaunayIndices.size()));
    }
  return g;
}

/// Checks the partition and the §3.2.2 invariant; returns false on the first failure.
void expectValidClustering(const Clustering& c, const PointGeometry& g, float delta) {
  const size_t n = g.size();
  ASSERT_EQ(c.labels.size(), n);
  ASSERT_EQ(c.offsets.size(), c.size() + 1);
  ASSERT_EQ(c.members.size(), n);
  std::vector<int> seen(n, 0);
  for (size_t k = 0; k < c.size(); ++k) {
    auto m = c.membersOf(k);
    ASSERT_FALSE(m.empty());
    EXPECT_TRUE(std::is_sorted(m.begin(), m.end()));
    if (k > 0) { EXPECT_LT(c.membersOf(k - 1)[0], m[0]) << "clusters ordered by smallest member"; }
    for (uint32_t p : m) {
      EXPECT_EQ(c.labels[p], k);
      ++seen[p];
    }
    const float v = clusterMaxVariation(c, g, k);
    EXPECT_LE(v, delta) << "cluster " << k << " breaks the delta_n invariant";
    EXPECT_NEAR(v, c.maxVariation[k], 1e-6f);
    EXPECT_NEAR(c.seedingNormals[k].norm(), 1.0f, 1e-4f);
    // Connected through the neighbour graph.
    std::set<uint32_t> members(m.begin(), m.end()), reached = {m[0]};
    std::vector<uint32_t> stack = {m[0]};
    while (!stack.empty()) {
      uint32_t p = stack.back();
      stack.pop_back();
      for (uint32_t q : g.delaunayOf(p))
        if (members.count(q) && reached.insert(q).second) stack.push_back(q);
    }
    EXPECT_EQ(reached.size(), members.size()) << "cluster " << k << " is not connected";
  }
  for (size_t i = 0; i < n; ++i) EXPECT_EQ(seen[i], 1);
}

}  // namespace

TEST(Clustering, GreedyInvariantOnTorus) {
  HybridModel torus = shapes::torus(2.0f, 0.6f, 90, 36);
  PointGeometry g = gridGeometry(torus, 90, 36, true, true);
  for (float delta : {0.008f, 0.05f, 0.3f}) {
    Clustering c = clusterGreedy(g, {.deltaN = delta});
    expectValidClustering(c, g, delta);
    EXPECT_GT(c.size(), 1u);
    EXPECT_EQ(c.components, 1u);
  }
}

TEST(Clustering, HierarchicalInvariantOnTorus) {
  HybridModel torus = shapes::torus(2.0f, 0.6f, 90, 36);
  PointGeometry g = gridGeometry(torus, 90, 36, true, true);
  for (float delta : {0.008f, 0.05f, 0.3f}) {
    Clustering c = clusterHierarchical(g, {.deltaN = delta, .seed = 7});
    expectValidClustering(c, g, delta);
    EXPECT_GT(c.splits, 0u);
    EXPECT_EQ(c.size(), c.splits + 1) << "a binary split tree over one component";
  }
}

TEST(Clustering, InvariantOnNoisyNormals) {
  // Perturbed normals make clusters small and irregular: the invariant must still hold.
  HybridModel sphere = shapes::sphere(1.0f, 2000, {.irregular = false});
  HybridModel plane = shapes::plane(1, 1, 50, 40);
  uint64_t state = 12345;
  auto rnd = [&] {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    return float((state >> 33) & 0xffffff) / float(0xffffff) - 0.5f;
  };
  for (Point& p : plane.points) p.normal = (p.normal + 0.15f * Vec3f(rnd(), rnd(), rnd())).normalized();
  PointGeometry g = gridGeometry(plane, 50, 40, false, false);
  for (size_t i = 0; i < g.size(); ++i) g.surfaceVariation[i] = std::abs(rnd());
  SCOPED_TRACE("greedy");
  expectValidClustering(clusterGreedy(g, {.deltaN = 0.008f}), g, 0.008f);
  SCOPED_TRACE("hierarchical");
  expectValidClustering(clusterHierarchical(g, {.deltaN = 0.008f, .maxIterations = 4}), g, 0.008f);
}

TEST(Clustering, PlaneIsOneCluster) {
  HybridModel plane = shapes::plane(2, 1, 30, 15);
  PointGeometry g = gridGeometry(plane, 30, 15, false, false);
  EXPECT_EQ(clusterGreedy(g).size(), 1u);
  Clustering h = clusterHierarchical(g);
  EXPECT_EQ(h.size(), 1u);
  EXPECT_EQ(h.splits, 0u);
}

TEST(Clustering, ComponentsNeverMerge) {
  // Two parallel planes with no neighbour links between them: at least two clusters.
  HybridModel a = shapes::plane(1, 1, 10, 10);
  PointGeometry g = gridGeometry(a, 10, 10, false, false);
  // Cut the grid into two halves (rows 0-4 and 5-9) by dropping links across.
  PointGeometry cut = g;
  cut.delaunayIndices.clear();
  cut.delaunayOffsets = {0};
  for (size_t i = 0; i < g.size(); ++i) {
    for (uint32_t q : g.delaunayOf(i))
      if ((i / 10 < 5) == (q / 10 < 5)) cut.delaunayIndices.push_back(q);
    cut.delaunayOffsets.push_back(uint32_t(cut.delaunayIndices.size()));
  }
  for (const Clustering& c : {clusterGreedy(cut), clusterHierarchical(cut)}) {
    EXPECT_EQ(c.size(), 2u);
    EXPECT_EQ(c.components, 2u);
    EXPECT_NE(c.labels[0], c.labels[99]);
  }
}

TEST(Clustering, GreedyFloodsFlattestPointFirst) {
  HybridModel plane = shapes::plane(1, 1, 5, 5);
  // Normals tilt with x so that one seed cannot take the whole row.
  for (Point& p : plane.points) p.normal = Vec3f(std::sin(p.position.x()), 0, std::cos(p.position.x()));
  PointGeometry g = gridGeometry(plane, 5, 5, false, false);
  for (size_t i = 0; i < g.size(); ++i) g.surfaceVariation[i] = 1.0f;
  g.surfaceVariation[12] = 0.0f;  // the centre point is the flattest
  Clustering c = clusterGreedy(g, {.deltaN = 0.1f});
  EXPECT_EQ(c.seeds[c.labels[12]], 12u);
  EXPECT_TRUE(c.seedingNormals[c.labels[12]].isApprox(g.normals[12]));
}

TEST(Clustering, HierarchicalSameSeedSameResultAnyThreads) {
  HybridModel torus = shapes::torus(2.0f, 0.6f, 90, 36);
  PointGeometry g = gridGeometry(torus, 90, 36, true, true);
  Clustering a = clusterHierarchical(g, {.seed = 3});
  Clustering b;
  {
    ThreadLimit one(1);
    b = clusterHierarchical(g, {.seed = 3});
  }
  EXPECT_EQ(a.labels, b.labels);
  EXPECT_EQ(a.seeds, b.seeds);
  Clustering other = clusterHierarchical(g, {.seed = 4});
  expectValidClustering(other, g, 0.008f);
}

TEST(Clustering, RejectsAbsurdParameters) {
  HybridModel plane = shapes::plane(1, 1, 4, 4);
  PointGeometry g = gridGeometry(plane, 4, 4, false, false);
  for (float bad : {0.0f, -0.1f, 2.0f, 5.0f, std::nanf("")}) {
    EXPECT_THROW(clusterGreedy(g, {.deltaN = bad}), Error) << bad;
    EXPECT_THROW(clusterHierarchical(g, {.deltaN = bad}), Error) << bad;
  }
  EXPECT_THROW(clusterHierarchical(g, {.maxIterations = 0}), Error);
  try {
    clusterGreedy(g, {.deltaN = 3.0f});
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadParameter);
    EXPECT_NE(std::string(e.what()).find("deltaN"), std::string::npos);
  }
}

TEST(Clustering, EmptyAndMissingNormals) {
  PointGeometry empty;
  empty.delaunayOffsets = {0};
  EXPECT_EQ(clusterGreedy(empty).size(), 0u);
  EXPECT_EQ(clusterHierarchical(empty).size(), 0u);
  HybridModel plane = shapes::plane(1, 1, 4, 4);
  PointGeometry g = gridGeometry(plane, 4, 4, false, false);
  g.normals[5] = Vec3f::Zero();
  g.normals[6] = Vec3f(NAN, 0, 0);
  for (const Clustering& c : {clusterGreedy(g), clusterHierarchical(g)}) {
    EXPECT_EQ(c.zeroNormals, 2u);
    EXPECT_EQ(c.clusterSize(c.labels[5]), 1u);
    EXPECT_EQ(c.clusterSize(c.labels[6]), 1u);
    EXPECT_EQ(c.labels.size(), 16u);
  }
}

TEST(Clustering, ColoursAreDeterministicAndDistinct) {
  for (size_t id = 0; id < 200; ++id) {
    EXPECT_EQ(clusterColor(id), clusterColor(id));
    EXPECT_GT((clusterColor(id) - clusterColor(id + 1)).head<3>().norm(), 0.1f) << id;
    for (int ch = 0; ch < 3; ++ch) EXPECT_TRUE(clusterColor(id)[ch] >= 0 && clusterColor(id)[ch] <= 1);
  }
  HybridModel plane = shapes::plane(1, 1, 6, 6);
  PointGeometry g = gridGeometry(plane, 6, 6, false, false);
  Clustering c = clusterGreedy(g);
  HybridModel coloured = colorByCluster(plane, g, c);
  ASSERT_EQ(coloured.points.size(), plane.points.size());
  EXPECT_TRUE(coloured.attributes.colors);
  EXPECT_EQ(coloured.points[3].color, clusterColor(c.labels[3]));
}
