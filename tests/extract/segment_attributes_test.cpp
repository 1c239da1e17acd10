// The point properties segments take from the points they replace: the mean, the mode for a
// class (extract/detail/segment_attributes.h), in the extractions, and through PLY.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "extract/detail/segment_attributes.h"
#include "extract/detail/segment_width.h"
#include "linesurf/core/error.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

namespace linesurf {
namespace {

// Hand-made owners: the mean of each segment's members, the mode of a class with ties to the
// smallest value, 0 for a segment without members, kept points ignored.
TEST(SegmentAttributes, MeanAndModeOfTheMembers) {
  HybridModel cloud;
  cloud.points.resize(7);
  cloud.pointProperties["intensity"] = {1, 2, 3, 10, 20, 100, 5};
  cloud.pointProperties["classification"] = {6, 2, 6, 9, 3, 4, 7};
  cloud.pointProperties["short"] = {1, 2};  // not one per point: not carried
  HybridModel out;
  out.segments.resize(4);
  const uint32_t K = detail::kKeptPoint;
  const std::vector<uint32_t> owner = {0, 0, 0, 1, 1, K, 3};
  detail::setSegmentProperties(out, cloud, owner);
  ASSERT_EQ(out.segmentProperties.size(), 2u);
  EXPECT_EQ(out.segmentProperties.at("intensity"), (std::vector<float>{2, 15, 0, 5}));
  EXPECT_EQ(out.segmentProperties.at("classification"), (std::vector<float>{6, 3, 0, 7}));  // {9, 3}: a tie, 3
  EXPECT_TRUE(detail::isClassProperty("class"));
  EXPECT_TRUE(detail::isClassProperty("label"));
  EXPECT_FALSE(detail::isClassProperty("intensity"));
}

/// A wavy sheet with an intensity ramp and three classes in bands.
HybridModel attributedSheet() {
  HybridModel m;
  for (int y = 0; y < 120; ++y)
    for (int x = 0; x < 120; ++x) {
      const float fx = 0.01f * float(x) + 0.001f * float((x * 7 + y * 3) % 5), fy = 0.01f * float(y);
      m.points.push_back({.position = Vec3f(fx, fy, 0.02f * std::sin(8 * fx))});
      m.pointProperties["intensity"].push_back(float(x + 1000 * ((x + y) % 3)));
      m.pointProperties["classification"].push_back(float((x / 13 + y / 17) % 3));
    }
  return m;
}

/// Every segment's properties follow the rule over its provenance, the kept points keep theirs,
/// and the file keeps both.
void expectTheRule(const HybridModel& cloud, const HybridModel& out) {
  ASSERT_GT(out.segments.size(), 20u);
  ASSERT_EQ(out.provenance.size(), out.segments.size());
  const auto& si = out.segmentProperties.at("intensity");
  const auto& sc = out.segmentProperties.at("classification");
  ASSERT_EQ(si.size(), out.segments.size());
  ASSERT_EQ(sc.size(), out.segments.size());
  size_t mixed = 0;
  for (size_t s = 0; s < out.segments.size(); ++s) {
    double sum = 0;
    std::map<float, int> count;
    for (uint32_t j : out.provenance[s]) sum += cloud.pointProperties.at("intensity")[j], ++count[cloud.pointProperties.at("classification")[j]];
    EXPECT_FLOAT_EQ(si[s], float(sum / double(out.provenance[s].size()))) << s;
    float mode = 0;
    int best = 0;
    for (const auto& [v, c] : count)
      if (c > best) best = c, mode = v;
    EXPECT_EQ(sc[s], mode) << s;
    mixed += count.size() > 1;
  }
  EXPECT_GT(mixed, 0u);  // some segments cross a class border: the mode, not the mean, decides
  const std::filesystem::path f = test::scratchDir("segment_attributes") / "out.ply";
  writeModel(f, out);
  const HybridModel back = readModel(f);
  EXPECT_EQ(back.segmentProperties, out.segmentProperties);
  EXPECT_EQ(back.pointProperties, out.pointProperties);
}

TEST(SegmentAttributes, EpsDeltaSegmentsTakeTheMeanAndTheMode) {
  const HybridModel cloud = attributedSheet();
  const PointGeometry g = computePointGeometry(cloud, GeometryOptions{});
  EpsDeltaOptions o;
  o.provenance = true;
  o.epsilonRelative = 0.3;
  expectTheRule(cloud, extractEpsDelta(cloud, g, o));
}

TEST(SegmentAttributes, ShapeApproxSegmentsTakeTheMeanAndTheMode) {
  const HybridModel cloud = attributedSheet();
  const PointGeometry g = computePointGeometry(cloud, GeometryOptions{});
  ShapeApproxOptions o;
  o.provenance = true;
  expectTheRule(cloud, extractShapeApprox(cloud, g, o));
}

// A segment property of a name the writer cannot write is refused by name; one of a standard
// segment name too.
TEST(SegmentAttributes, WriterRefusesBadNamesAndCounts) {
  HybridModel m;
  m.segments.resize(2);
  m.segmentProperties["radius"] = {1, 2};
  const std::filesystem::path f = test::scratchDir("segment_attributes_bad") / "bad.ply";
  EXPECT_THROW(writeModel(f, m), Error);
  m.segmentProperties.clear();
  m.segmentProperties["intensity"] = {1};
  EXPECT_THROW(writeModel(f, m), Error);
}

}  // namespace
}  // namespace linesurf
