// The default camera (boundingSphere + orbit, §6.2.2) frames where a model's surface is, so a
// cloud and the (ε,δ) hybrid extracted from it (§3.1) are drawn from the same view without the
// caller passing a camera: the README's Python snippet compares their default renders.
#include <gtest/gtest.h>

#include "linesurf/eval/image_metrics.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/renderer.h"
#include "test_util.h"

namespace linesurf {
namespace {

TEST(DefaultFrame, SplatRadiiDoNotMoveTheFrame) {
  HybridModel m;
  for (int i = 0; i < 8; ++i) {
    Point p;
    p.position = Vec3f(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
    p.normal = Vec3f(0, 0, 1);
    p.radius = 0.01f;
    m.points.push_back(p);
  }
  const BoundingSphere small = boundingSphere(m);
  m.points[3].radius = 0.5f;  // one wide splat
  const BoundingSphere wide = boundingSphere(m);
  EXPECT_EQ(small.center, wide.center);
  EXPECT_EQ(small.radius, wide.radius);
  EXPECT_NEAR(small.radius, std::sqrt(3.0f) / 2, 1e-6f);
  EXPECT_EQ(small.center, Vec3f(0.5f, 0.5f, 0.5f));
}

TEST(DefaultFrame, OnePointFramesItsSplat) {
  HybridModel m;
  Point p;
  p.position = Vec3f(1, 2, 3);
  p.normal = Vec3f(0, 0, 1);
  p.radius = 0.25f;
  m.points.push_back(p);
  EXPECT_EQ(boundingSphere(m).radius, 0.25f);
  m.points[0].radius = 0;
  EXPECT_EQ(boundingSphere(m).radius, 1.0f);
}

// A cloud with normals but no radii and its (ε,δ) hybrid: the extraction gives the hybrid radii of
// its own, unlike those that prepareForRendering gives the cloud, and the largest splat radius used
// to enter the frame, so the two default renders did not line up (19.8 dB apart at 512²).
TEST(DefaultFrame, CloudAndItsHybridShareTheDefaultCamera) {
  HybridModel cloud = readModel(test::bundledData() / "igea_points.ply");
  const PointGeometry geo = computePointGeometry(cloud, {.k = 12, .curvature = false});
  const HybridModel hybrid = extractEpsDelta(cloud, geo, {.epsilonRelative = 0.05, .delta = 0.004});
  ASSERT_GT(hybrid.segments.size(), 1000u);
  prepareForRendering(cloud);

  const BoundingSphere a = boundingSphere(cloud), b = boundingSphere(hybrid);
  // Segment endpoints lie within ε (0.05 x spacing) of the points they replace.
  EXPECT_LT((a.center - b.center).norm(), 1e-3f * a.radius);
  EXPECT_NEAR(a.radius, b.radius, 1e-3f * a.radius);
  const Camera ca = viewCameras(a, {})[0], cb = viewCameras(b, {})[0];
  EXPECT_LT((ca.eye() - cb.eye()).norm(), 2e-3f * a.radius);
}

// The README's Python snippet in C++: the cloud made ready to render, the hybrid extracted from it,
// each drawn with its own default camera (512²); the pictures agree to >= 35 dB.
TEST(DefaultFrame, ReadmeSnippetHybridMatchesItsCloud) {
  HybridModel cloud = readModel(test::bundledData() / "igea_points.ply");
  prepareForRendering(cloud);
  const PointGeometry geo = computePointGeometry(cloud, {.k = 12, .curvature = false});
  const HybridModel hybrid = extractEpsDelta(cloud, geo, {.epsilonRelative = 0.05, .delta = 0.004});
  const Camera ca = viewCameras(boundingSphere(cloud), {})[0], cb = viewCameras(boundingSphere(hybrid), {})[0];
  const ImageMetrics m = compareImages(renderImage(cloud, ca).color, renderImage(hybrid, cb).color);
  EXPECT_GE(m.psnr, 35.0) << "ssim " << m.ssim;
}

}  // namespace
}  // namespace linesurf
