// The batched point set-up and the per-frame buffers of the pipeline (src/render/point_setup.h,
// renderer.cpp): the early back-face test culls exactly what the scalar reference culls, every
// point ends with the reference's status, and a Renderer that reuses its buffers (frame after
// frame, other views in between, two frames at once) draws what a fresh one draws.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <thread>

#include "shapes.h"
#include "linesurf/render/renderer.h"
#include "render/point_setup.h"

namespace linesurf {
namespace {

bool sameImage(const Image& a, const Image& b) { return a.width == b.width && a.height == b.height && a.pixels == b.pixels; }

// Storage for n prepared points (PointSlots' four arrays).
struct Slots {
  std::vector<PreparedPoint> hot;
  std::vector<PixelRect> bounds;
  std::vector<PointCold> cold;
  std::vector<PointGouraud> gouraud;
  explicit Slots(size_t n) : hot(n), bounds(n), cold(n), gouraud(n) {}
  PointSlots at(size_t k) { return PointSlots{hot.data(), bounds.data(), cold.data(), gouraud.data()} + k; }
};

// A noisy sphere seen from outside, plus points the set-up must hand to the exact path or count
// as degenerate: grazing normals, no normal, zero and infinite radius, NaN, behind the eye.
HybridModel noisySphere() {
  HybridModel m = shapes::sphere(1, 6000);
  std::mt19937 rng(7);
  std::normal_distribution<float> jitter(0, 0.3f);
  for (Point& p : m.points) p.normal = (p.normal + jitter(rng) * Vec3f(jitter(rng), jitter(rng), jitter(rng))).normalized();
  return m;
}
HybridModel awkwardSphere() {
  HybridModel m = noisySphere();
  const Point base = m.points[0];
  for (int k = 0; k < 8; ++k) {
    Point p = base;
    switch (k) {
      case 0: p.normal = Vec3f::Zero(); break;
      case 1: p.radius = 0; break;
      case 2: p.radius = INFINITY; break;
      case 3: p.position.x() = NAN; break;
      case 4: p.normal = Vec3f(NAN, 0, 0); break;
      case 5: p.position = Vec3f(0, 0, 6); break;   // behind the eye (at z = 5)
      case 6: p.position = Vec3f(0, 0, 4.9f); break;  // crossing the near plane
      case 7: p.radius *= 100; break;
    }
    m.points.push_back(p);
  }
  return m;
}

TEST(PointSetup, BatchesGiveTheReferenceStatusOfEveryPoint) {
  const HybridModel m = awkwardSphere();
  for (bool cull : {true, false}) {
    RenderOptions o;
    o.backfaceCulling = cull;
    const Camera cam = Camera::lookAt(Vec3f(0, 0, 5), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 160, 120);
    FrameContext frame = FrameContext::make(cam, o, boundingSphere(m));
    const detail::PointSetupFrame setup = pointSetupFrame(frame);
    PointSetupCounts batched, reference;
    std::vector<uint32_t> visible, visibleRef;
    Slots out(detail::kSetupBatch);
    for (size_t i = 0; i < m.points.size(); i += detail::kSetupBatch) {
      const int n = int(std::min<size_t>(detail::kSetupBatch, m.points.size() - i));
      const int k = preparePoints(m.points.data(), uint32_t(i), n, frame, setup, out.at(0), batched);
      ASSERT_LE(k, n);
      for (int j = 0; j < k; ++j) {
        visible.push_back(out.cold[j].index);
        EXPECT_FALSE(out.bounds[j].empty());
      }
    }
    for (size_t i = 0; i < m.points.size(); ++i) {
      Slots p(1);
      switch (preparePoint(m.points[i], uint32_t(i), frame, p.at(0))) {
        case PrimitiveStatus::Drawn: ++reference.drawn, visibleRef.push_back(uint32_t(i)); break;
        case PrimitiveStatus::Clipped: ++reference.clipped, visibleRef.push_back(uint32_t(i)); break;
        case PrimitiveStatus::Culled: ++reference.culled; break;
        case PrimitiveStatus::Outside: ++reference.outside; break;
        case PrimitiveStatus::Degenerate: ++reference.degenerate; break;
      }
    }
    EXPECT_EQ(visible, visibleRef);  // the same points, in index order
    EXPECT_EQ(batched.drawn, reference.drawn);
    EXPECT_EQ(batched.clipped, reference.clipped);
    EXPECT_EQ(batched.culled, reference.culled);
    EXPECT_EQ(batched.outside, reference.outside);
    EXPECT_EQ(batched.degenerate, reference.degenerate);
    EXPECT_EQ(batched.degenerate, 4u);
    if (cull) {
      EXPECT_GT(batched.culled, m.points.size() / 3);
    } else {
      EXPECT_LT(batched.culled, 20u);  // only edge-on ones
    }
  }
}

// The SIMD set-up (closed form, and the thesis's construction for splats stretched past
// kMaxStretch) computes what preparePoint computes, up to float rounding.
// With shading normals (docs/decisions.md "Smooth contour models") both light with them and put
// them in the normal buffer.
TEST(PointSetup, SimdLanesMatchTheScalarReference) {
  for (int variant = 0; variant < 4; ++variant) {
    const float radiusScale = variant % 2 ? 0.03f : 1.0f;  // small radii: the prefilter stretches grazing splats
    const bool shading = variant >= 2;  // shading normals and point masses
    HybridModel m = noisySphere();
    for (Point& p : m.points) p.radius *= radiusScale;
    // shading normals: the exact sphere normal (the plane normals are noisy)
    std::vector<Vec3f> sn;
    std::vector<float> mass;
    for (const Point& p : m.points) {
      sn.push_back(p.position.normalized());
      mass.push_back(0.25f + 0.5f * float(mass.size() % 7));
    }
    RenderOptions o;
    const Camera cam = Camera::lookAt(Vec3f(0, 0.5f, 4), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 200, 150);
    FrameContext frame = FrameContext::make(cam, o, boundingSphere(m)), massless = frame;
    if (shading) frame.pointShadingNormals = massless.pointShadingNormals = sn.data(), frame.pointMasses = mass.data();
    const detail::PointSetupFrame setup = pointSetupFrame(frame);
    Slots out(detail::kSetupBatch);
    PointSetupCounts counts;
    int compared = 0, shaded = 0, stretched = 0;
    for (size_t i = 0; i < m.points.size(); i += detail::kSetupBatch) {
      const int n = int(std::min<size_t>(detail::kSetupBatch, m.points.size() - i));
      const int k = preparePoints(m.points.data(), uint32_t(i), n, frame, setup, out.at(0), counts);
      for (int j = 0; j < k; ++j) {
        const PreparedPoint& a = out.hot[j];
        const PixelRect& ab = out.bounds[j];
        const uint32_t index = out.cold[j].index;
        Slots ref(1);
        ASSERT_EQ(preparePoint(m.points[index], index, frame, ref.at(0)), PrimitiveStatus::Drawn);
        const PreparedPoint& r = ref.hot[0];
        const PixelRect& rb = ref.bounds[0];
        if (shading) {  // a mass scales the weight and nothing else
          Slots one(1);
          ASSERT_EQ(preparePoint(m.points[index], index, massless, one.at(0)), PrimitiveStatus::Drawn);
          EXPECT_FLOAT_EQ(r.weightScale(), mass[index] * one.hot[0].weightScale());
          EXPECT_EQ(r.zThreshold, one.hot[0].zThreshold);
        }
        const Point& p = m.points[index];
        const Vec3f nc = cam.rotation() * p.normal;
        stretched += std::abs(nc.dot(cam.toCamera(p.position).normalized())) < 0.1f;
        EXPECT_NEAR(ab.x0, rb.x0, 1);
        EXPECT_NEAR(ab.x1, rb.x1, 1);
        EXPECT_NEAR(ab.y0, rb.y0, 1);
        EXPECT_NEAR(ab.y1, rb.y1, 1);
        EXPECT_FALSE(a.clipDepth());
        EXPECT_FALSE(r.clipDepth());
        // the splat's weight and depth at its pixels: the plane constants agree relative to their size
        const detail::PointRaster x = pointRaster(a, frame), y = pointRaster(r, frame);
        for (int px = ab.x0; px < ab.x1; ++px)
          for (int py = ab.y0; py < ab.y1; ++py) {
            const float fx = float(px) + 0.5f, fy = float(py) + 0.5f;
            const float Na = x.N.at(fx, fy), Nr = y.N.at(fx, fy);
            const float sa = x.S.at(fx, fy) / Na, ta = x.T.at(fx, fy) / Na, sr = y.S.at(fx, fy) / Nr, tr = y.T.at(fx, fy) / Nr;
            const float qa = sa * sa + ta * ta, qr = sr * sr + tr * tr;
            if (qr > 0.9f * frame.cutoffQ && qr < 1.1f * frame.cutoffQ) continue;  // the rim may go either way
            EXPECT_NEAR(std::exp(-0.5f * qa) * x.weightScale, std::exp(-0.5f * qr) * y.weightScale, 2e-3f * y.weightScale);
            if (qr < frame.cutoffQ) {
              EXPECT_NEAR(x.depthNum / Na, y.depthNum / Nr, 2e-5f * std::abs(y.depthNum / Nr));
            }
          }
        EXPECT_NEAR(a.zThreshold, r.zThreshold, 1e-3f * r.zThreshold);
        const bool ag = PreparedPoint::gouraud(ab, o.perPixelLighting), rg = PreparedPoint::gouraud(rb, o.perPixelLighting);
        EXPECT_EQ(ag, rg);
        shaded += ag;
        for (int c = 0; c < 4; ++c) EXPECT_NEAR(a.color[c], r.color[c], 1e-3f) << c;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.cold[j].normal[c], ref.cold[0].normal[c], 1e-3f) << c;
        {  // the normal lit with: the shading normal (flipped with the plane), else the plane's
          Vec3f want = cam.rotation() * (shading ? sn[index] : p.normal.normalized());
          const Vec3f plane = cam.rotation() * p.normal;
          if (plane.dot(cam.toCamera(p.position)) > 0) want = -want;
          for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.cold[j].normal[c], want[c], 1e-4f) << c;
        }
        if (ag && rg)
          for (int c = 0; c < 3; ++c) {
            const PointGouraud &ga = out.gouraud[j], &gr = ref.gouraud[0];
            EXPECT_NEAR(ga.C0[c], gr.C0[c], 1e-3f);
            EXPECT_NEAR(ga.Cs[c], gr.Cs[c], 1e-3f);
            EXPECT_NEAR(ga.Ct[c], gr.Ct[c], 1e-3f);
            EXPECT_NEAR(ga.Cst[c], gr.Cst[c], 1e-3f);
          }
        ++compared;
      }
    }
    EXPECT_GT(compared, 2000);
    EXPECT_GT(stretched, 50);
    if (radiusScale == 1.0f) {
      EXPECT_GT(shaded, 100);
    }
  }
}

TEST(PointSetup, ReusedBuffersDrawWhatFreshOnesDraw) {
  const HybridModel m = noisySphere();
  RenderOptions o;
  o.tileSize = 16;
  Renderer renderer(m, o);
  const Camera a = Camera::orbit(renderer.sphere(), 30, 20, 0, 128, 96);
  // another size, and close enough that splats cross the near plane
  const Camera b = Camera::orbit(renderer.sphere(), 200, -40, 1.1f, 200, 150);
  const RenderResult freshA = renderImage(m, a, o), freshB = renderImage(m, b, o);
  for (int round = 0; round < 2; ++round) {
    const RenderResult ra = renderer.render(a), rb = renderer.render(b);
    EXPECT_TRUE(sameImage(ra.color, freshA.color));
    EXPECT_TRUE(sameImage(rb.color, freshB.color));
    EXPECT_EQ(ra.stats.pointsDrawn, freshA.stats.pointsDrawn);
    EXPECT_EQ(ra.stats.tileBins, freshA.stats.tileBins);
    EXPECT_EQ(rb.stats.pointsCulled, freshB.stats.pointsCulled);
    EXPECT_GT(rb.stats.pointsClipped, 0u);
  }
  // two frames at once: one uses the shared buffers, the other its own
  RenderResult r1, r2;
  std::thread t1([&] { r1 = renderer.render(a); }), t2([&] { r2 = renderer.render(b); });
  t1.join();
  t2.join();
  EXPECT_TRUE(sameImage(r1.color, freshA.color));
  EXPECT_TRUE(sameImage(r2.color, freshB.color));
}

}  // namespace
}  // namespace linesurf
