// Segment level of detail (RenderOptions::segmentLod, beyond the thesis): a short
// ScreenSpace segment drawn as its moment-matched elliptical point splat. The ellipse against the
// exact segment kernel (segmentWeightAt) as a function of the length in kernel sigmas; images with
// the level of detail on and off; thread counts.
#include "render/segment_lod.h"
#include "render/segment_splat.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/eval/image_metrics.h"
#include "linesurf/render/renderer.h"

namespace linesurf {
namespace {

// The weight the point rows give the LOD splat at a pixel centre (detail::PointRaster's formula).
float pointWeightAt(const PreparedPoint& p, float cutoffQ, float px, float py) {
  const float n = p.N.at(px, py);
  if (!(n < 0)) return 0;
  const float s = p.S.at(px, py) / n, t = p.T.at(px, py) / n;
  const float q = s * s + t * t;
  return q <= cutoffQ ? std::exp(-0.5f * q) * p.weightScale() : 0.0f;
}

struct LodError {
  bool converted = false;
  double lambda = 0;       ///< length in kernel sigmas along the segment
  double maxRel = 0;       ///< max |ellipse - exact| / exact peak
  double maxRelBoth = 0;   ///< the same where both have a weight (the cutoffs' difference left out)
  double meanRel = 0;      ///< mean |ellipse - exact| / mean exact, over the exact support
  double massRatio = 0;    ///< sum ellipse / sum exact
  double lostPeak = 0;     ///< largest exact weight (/ peak) where the ellipse has none
  double lostFraction = 0; ///< exact's pixels (with a weight) the ellipse does not cover
  double extraFraction = 0;///< the ellipse's pixels outside the exact support, / exact's pixels
};

struct LodCase {
  float length, radius;
  Vec3f eye;
};

LodError lodError(const LodCase& c, float cutoff, float lodMax = 4.0f) {
  Segment s;
  s.p0 = Vec3f(-0.5f * c.length, 0.01f, 0), s.p1 = Vec3f(0.5f * c.length, -0.01f, 0.002f);
  s.normal = Vec3f(0, 0, 1);
  s.radius = c.radius;
  const Camera cam = Camera::lookAt(c.eye, Vec3f(0, 0, 0), Vec3f(0, 0, 1), 40, 128, 128, 0.01f, 100);
  RenderOptions o;
  o.cutoffRadius = cutoff;
  o.prefilterVariance = 1.0f;  // the tolerances below were measured at the thesis's identity prefilter
  o.backfaceCulling = false;
  const FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
  PreparedSegment ps;
  LodError e;
  const PrimitiveStatus st = prepareSegment(s, 0, frame, ps);
  if (st != PrimitiveStatus::Drawn) return e;
  e.lambda = double(ps.raster.length) / std::sqrt(double(ps.raster.invM00));
  PreparedPoint hot;
  PixelRect bounds;
  PointCold cold;
  PointGouraud gouraud;
  e.converted = segmentLodPoint(ps, frame, lodMax, PointSlots{&hot, &bounds, &cold, &gouraud});
  if (!e.converted) return e;
  double peak = 0, sumA = 0, sumB = 0, sumD = 0, maxD = 0, lost = 0;
  int nA = 0, nLost = 0, nExtra = 0;
  for (int y = 0; y < cam.height(); ++y)
    for (int x = 0; x < cam.width(); ++x) {
      const float px = x + 0.5f, py = y + 0.5f;
      const double a = segmentWeightAt(ps, frame, Vec2f(px, py));
      const double b = pointWeightAt(hot, frame.cutoffQ, px, py);
      // the ellipse's fragments lie in its bounds (the rows visit nothing else)
      if (b > 0) {
        EXPECT_TRUE(x >= bounds.x0 && x < bounds.x1 && y >= bounds.y0 && y < bounds.y1) << x << " " << y;
      }
      peak = std::max(peak, a);
      sumA += a, sumB += b, sumD += std::abs(a - b), maxD = std::max(maxD, std::abs(a - b));
      nA += a > 0;
      if (a > 0 && b > 0) e.maxRelBoth = std::max(e.maxRelBoth, std::abs(a - b));
      if (a > 0 && b == 0) ++nLost, lost = std::max(lost, a);
      if (b > 0 && a == 0) ++nExtra;
    }
  e.maxRel = maxD / peak;
  e.maxRelBoth /= peak;
  e.meanRel = sumD / sumA;
  e.massRatio = sumB / sumA;
  e.lostPeak = lost / peak;
  e.lostFraction = double(nLost) / nA;
  e.extraFraction = double(nExtra) / nA;
  return e;
}

// Views of segments of a growing length (radius 0.05, kernel about 3-8 pixels wide): from the
// front, oblique, close to grazing, minified.
std::vector<LodCase> lodCases() {
  std::vector<LodCase> cases;
  for (float len : {0.005f, 0.01f, 0.02f, 0.03f, 0.04f, 0.05f, 0.06f, 0.08f, 0.1f, 0.12f})
    for (Vec3f eye : {Vec3f(0.1f, -0.2f, 1.5f), Vec3f(0.5f, -1.2f, 0.8f), Vec3f(0.2f, -2.0f, 0.3f),
                      Vec3f(1.0f, 0.3f, 0.6f), Vec3f(0.2f, -1.0f, 6.0f)})
      cases.push_back({len, 0.05f, eye});
  return cases;
}

// Up to two kernel sigmas the ellipse keeps the segment's mass (within 7%, as sampled at the
// pixels) and lies inside the exact kernel's cutoff region; its weights differ from the exact ones by at most 11% of the peak
// (8% where both have a weight): the exact kernel truncates every point kernel along the segment
// at the cutoff, so it fades out towards its capsule's border, where the ellipse's cutoff cuts at
// exp(-R^2/2) of its peak; its capsule's ends reach past the ellipse (weights below 11% of the
// peak, 20-35% of its pixels: docs/segment-splatting.md).
TEST(SegmentLod, EllipseAgreesWithTheSegmentKernelUpToTwoSigmas) {
  int converted = 0;
  for (float cutoff : {2.0f, 2.5f})
    for (const LodCase& c : lodCases()) {
      const LodError e = lodError(c, cutoff);
      if (!e.converted || e.lambda > 2.0) continue;
      ++converted;
      const std::string what = "length " + std::to_string(c.length) + " lambda " + std::to_string(e.lambda) +
                               " cutoff " + std::to_string(cutoff);
      EXPECT_LT(e.maxRel, 0.11) << what;
      EXPECT_LT(e.maxRelBoth, 0.08) << what;
      EXPECT_LT(e.meanRel, 0.09) << what;
      EXPECT_NEAR(e.massRatio, 1.0, 0.07) << what;
      EXPECT_LT(e.lostPeak, 0.11) << what;
      EXPECT_EQ(e.extraFraction, 0.0) << what;
    }
  EXPECT_GT(converted, 40);
}

// The table of docs/segment-splatting.md ("Segment level of detail"): error against lambda.
TEST(SegmentLodDocs, ErrorTable) {
  std::printf("cutoff lambda maxRel maxRelBoth meanRel mass lostPeak lost%% extra%%\n");
  for (float cutoff : {2.0f})
    for (const LodCase& c : lodCases()) {
      const LodError e = lodError(c, cutoff);
      if (!e.converted) continue;
      std::printf("%.1f %.2f %.4f %.4f %.4f %.4f %.4f %.2f %.2f\n", cutoff, e.lambda, e.maxRel, e.maxRelBoth, e.meanRel, e.massRatio,
                  e.lostPeak, 100 * e.lostFraction, 100 * e.extraFraction);
    }
}

// A unit sphere as latitude rings of short segments (a contour line model: rings `spacing` apart,
// segments about `length` long, radius = spacing), outward normals.
HybridModel ringSphere(float spacing, float length) {
  HybridModel m;
  m.attributes.normals = m.attributes.radii = true;
  const float pi = 3.14159265f;
  const int rings = int(std::ceil(pi / spacing));
  for (int i = 0; i < rings; ++i) {
    const float th = pi * (i + 0.5f) / rings, z = std::cos(th), r = std::sin(th);
    const int n = std::max(3, int(std::ceil(2 * pi * r / length)));
    for (int j = 0; j < n; ++j) {
      const float p0 = 2 * pi * j / n, p1 = 2 * pi * (j + 1) / n;
      Segment s;
      s.p0 = Vec3f(r * std::cos(p0), r * std::sin(p0), z);
      s.p1 = Vec3f(r * std::cos(p1), r * std::sin(p1), z);
      s.normal = (0.5f * (s.p0 + s.p1)).normalized();
      s.radius = spacing;
      m.segments.push_back(s);
    }
  }
  return m;
}

// Background pixels whose centre ray passes at least marginPx pixels inside the unit sphere's
// silhouette.
int sphereHoles(const Image& alpha, const Camera& cam, float marginPx) {
  const Mat3f toWorld = cam.rotation().transpose();
  const Vec3f eye = cam.eye();
  const float d = eye.norm(), perPixel = d / cam.focalPixels();  // world units per pixel at the centre
  int holes = 0;
  for (int y = 0; y < cam.height(); ++y)
    for (int x = 0; x < cam.width(); ++x) {
      if (alpha.at(x, y).w() > 0) continue;
      const Vec3f dir = (toWorld * cam.rayThrough(x + 0.5f, y + 0.5f)).normalized();
      const float along = -eye.dot(dir);
      const float miss = (eye + along * dir).norm();  // the ray's distance to the centre
      if (along > 0 && miss < 1 - marginPx * perPixel) ++holes;
    }
  return holes;
}

void expectSameImage(const Image& a, const Image& b) {
  ASSERT_EQ(a.pixels.size(), b.pixels.size());
  for (size_t i = 0; i < a.pixels.size(); ++i) ASSERT_EQ(a.pixels[i], b.pixels[i]) << "pixel " << i;
}

RenderOptions lodOptions(float lod) {
  RenderOptions o;
  o.segmentLod = lod;
  o.alphaBuffer = true;
  // the kernels alone: tail coverage judges an LOD ellipse's tails by its own disc, an exact segment's by
  // its strip, so the two fringes fade differently
  o.tailCoverage = 0;
  return o;
}

// Renders m from `views` views of size^2 pixels with the level of detail at lodA and at lodB.
void renderPairs(const HybridModel& m, float lodA, float lodB, int views, int size,
                 const std::function<void(const Camera&, const RenderResult&, const RenderResult&)>& check) {
  const Renderer ra(m, lodOptions(lodA)), rb(m, lodOptions(lodB));
  for (const Camera& cam : Camera::spreadViews(ra.sphere(), views, size, size)) check(cam, ra.render(cam), rb.render(cam));
}

// Short segments: with the level of detail on nearly all are drawn as point splats, the image
// stays within 0.5 grey levels (mean) of the exact one and opens no hole.
TEST(SegmentLod, ShortSegmentModelRendersLikeTheExactOne) {
  renderPairs(ringSphere(0.02f, 0.02f), 0, 2, 3, 384, [](const Camera& cam, const RenderResult& a, const RenderResult& b) {
    EXPECT_EQ(a.stats.segmentsLod, 0u);
    EXPECT_GT(b.stats.segmentsLod, b.stats.segmentsDrawn * 9 / 10);
    EXPECT_EQ(a.stats.segmentsDrawn, b.stats.segmentsDrawn);
    const ImageMetrics e = compareImages(a.color, b.color);
    EXPECT_LT(e.meanAbsDiff, 0.5);
    EXPECT_GT(e.nccm, 0.9995);
    EXPECT_EQ(sphereHoles(*a.alpha, cam, 1.5f), 0);
    EXPECT_EQ(sphereHoles(*b.alpha, cam, 1.5f), 0);
    std::printf("ring sphere: %llu of %llu segments as points, mean abs diff %.3f, nccm %.6f\n",
                static_cast<unsigned long long>(b.stats.segmentsLod),
                static_cast<unsigned long long>(b.stats.segmentsDrawn), e.meanAbsDiff, e.nccm);
  });
}

// With the level of detail on, 1 and 2 threads give the same image.
TEST(SegmentLod, ThreadCountDoesNotChangeTheImage) {
  const HybridModel m = ringSphere(0.02f, 0.03f);
  const Renderer r(m, lodOptions(2));
  for (const Camera& cam : Camera::spreadViews(r.sphere(), 2, 256, 256)) {
    RenderResult one, two;
    {
      ThreadLimit limit(1);
      one = r.render(cam);
    }
    {
      ThreadLimit limit(2);
      two = r.render(cam);
    }
    EXPECT_GT(one.stats.segmentsLod, 0u);
    expectSameImage(one.color, two.color);
  }
}

// Long segments (far beyond the threshold) stay segments: the image is byte-identical to the one
// with the level of detail off (the LOD machinery leaves the exact path alone).
TEST(SegmentLod, LongSegmentsAndLodOffKeepTheExactImage) {
  renderPairs(ringSphere(0.02f, 0.3f), 0, 0.05f, 2, 256, [](const Camera&, const RenderResult& a, const RenderResult& b) {
    EXPECT_EQ(b.stats.segmentsLod, 0u);
    expectSameImage(a.color, b.color);
  });
}

TEST(SegmentLod, AbsurdThresholdIsRejected) {
  for (float v : {-1.0f, 4.5f, std::nanf("")}) {
    RenderOptions o;
    o.segmentLod = v;
    EXPECT_THROW(validate(o), Error) << v;
  }
  RenderOptions o;
  o.segmentLod = 0;
  EXPECT_NO_THROW(validate(o));
}

}  // namespace
}  // namespace linesurf
