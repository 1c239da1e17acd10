// The SIMD splat rows (src/render/point_rows.cpp, segment_rows.cpp, resolve.cpp; Highway runtime dispatch) give the same picture
// on every target this machine runs: each target is forced in turn and the images of a hybrid
// model (points, ScreenSpace segments, a textured-free smooth surface) compared with the first.
#include <gtest/gtest.h>

#include <hwy/targets.h>

#include <set>
#include <string>

#include "shapes.h"
#include "linesurf/render/renderer.h"

namespace linesurf {
namespace {

// A sphere of points with a band of segments (rows of 8 points replaced by one segment).
HybridModel hybridSphere() {
  HybridModel m = shapes::sphere(1, 12000);
  HybridModel out;
  out.attributes = m.attributes;
  for (const Point& p : m.points) {
    if (std::abs(p.position.y()) > 0.3f) {
      out.points.push_back(p);
      continue;
    }
    Segment s;  // a short strip along the sphere's parallel through p
    const Vec3f t = Vec3f(0, 1, 0).cross(p.normal).normalized();
    s.p0 = p.position - 1.5f * p.radius * t;
    s.p1 = p.position + 1.5f * p.radius * t;
    s.normal = p.normal;
    s.color = p.color;
    s.radius = p.radius;
    out.segments.push_back(s);
  }
  return out;
}

struct TargetReset {
  ~TargetReset() {
    hwy::SetSupportedTargetsForTest(0);
    hwy::GetChosenTarget().Update(hwy::SupportedTargets());
  }
};

TEST(RenderSimd, ImagesAgreeAcrossEveryTargetThisMachineRuns) {
  const HybridModel m = hybridSphere();
  ASSERT_GT(m.segments.size(), 1000u);
  ASSERT_GT(m.points.size(), 5000u);
  const Camera cam = Camera::orbit(boundingSphere(m), 20, 10, 0, 160, 120);
  RenderOptions o;
  o.normalBuffer = true;
  TargetReset reset;
  Image first;
  std::string firstName;
  std::set<std::string> ran;
  for (int64_t target : hwy::SupportedAndGeneratedTargets()) {
    hwy::SetSupportedTargetsForTest(target);
    hwy::GetChosenTarget().Update(hwy::SupportedTargets());
    const std::string name = renderSimdTarget();
    EXPECT_EQ(name, hwy::TargetName(target)) << "the forced target runs";
    ran.insert(name);
    const RenderResult r = renderImage(m, cam, o);
    ASSERT_GT(r.stats.segmentsDrawn, 300u);
    if (first.pixels.empty()) {
      first = r.color;
      firstName = name;
      continue;
    }
    double worst = 0;
    for (size_t i = 0; i < first.pixels.size(); ++i)
      worst = std::max(worst, double((first.pixels[i] - r.color.pixels[i]).head<3>().cwiseAbs().maxCoeff()));
    EXPECT_LE(worst * 255, 1.0) << name << " vs " << firstName << ": " << worst * 255 << " grey levels";
    std::printf("%s vs %s: largest channel difference %.4f grey levels\n", name.c_str(), firstName.c_str(), worst * 255);
  }
  std::string list;
  for (const std::string& t : ran) list += t + " ";
  std::printf("SIMD targets compared: %s\n", list.c_str());
  EXPECT_GE(ran.size(), 1u);
}

}  // namespace
}  // namespace linesurf
