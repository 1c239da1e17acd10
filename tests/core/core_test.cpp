#include <gtest/gtest.h>

#include <atomic>
#include <vector>

#include "linesurf/core/error.h"
#include "linesurf/core/model.h"
#include "linesurf/core/parallel.h"

using namespace linesurf;

TEST(Error, MessageNamesPathWhereAndWhat) {
  try {
    throwBadInput("a.ply", "line 3", "non-numeric token 'x'");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "a.ply: line 3: non-numeric token 'x'");
    EXPECT_EQ(e.kind(), Error::Kind::BadInput);
  }
}

TEST(Parallel, EveryIndexVisitedOnceForAnyThreadCount) {
  for (int threads : {1, 2, 4}) {
    ThreadLimit limit(threads);
    std::vector<std::atomic<int>> hits(10007);
    parallelFor(0, hits.size(), [&](size_t i) { hits[i]++; }, 64);
    for (auto& h : hits) ASSERT_EQ(h.load(), 1);
  }
}

TEST(Model, BoundsCoverPointsAndSegmentEndpoints) {
  HybridModel m;
  EXPECT_TRUE(m.bounds().empty());
  m.points.push_back({Vec3f(1, 2, 3)});
  Segment s;
  s.p0 = Vec3f(-1, 0, 0);
  s.p1 = Vec3f(0, 5, 0);
  m.segments.push_back(s);
  Bounds3f b = m.bounds();
  EXPECT_EQ(b.min, Vec3f(-1, 0, 0));
  EXPECT_EQ(b.max, Vec3f(1, 5, 3));
}

TEST(Image, BilinearSampleAtTexelCentreIsTexel) {
  Image img(2, 2);
  img.at(0, 0) = Color(1, 0, 0, 1);  // top-left
  img.at(1, 0) = Color(0, 1, 0, 1);
  img.at(0, 1) = Color(0, 0, 1, 1);  // bottom-left
  img.at(1, 1) = Color(1, 1, 1, 1);
  EXPECT_TRUE(img.sampleBilinear(0.25f, 0.25f).isApprox(Color(0, 0, 1, 1)));  // v up: bottom row
  EXPECT_TRUE(img.sampleBilinear(0.75f, 0.75f).isApprox(Color(0, 1, 0, 1)));
  Color mid = img.sampleBilinear(0.5f, 0.5f);
  EXPECT_NEAR(mid[0], 0.5f, 1e-6f);
}
