// Line-segment splats (thesis §5): points vs segments on the same surface, the three filter
// evaluations against each other, the Approx construction's cases, degenerate segments.
#include "render/segment_approx.h"
#include "render/segment_splat.h"
#include "render/segment_setup.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>

#include "linesurf/eval/image_metrics.h"
#include "linesurf/render/renderer.h"

namespace linesurf {
namespace {

Color rowColor(int j, int k) {
  return Color(0.5f + 0.35f * std::sin(0.9f * j), 0.5f + 0.35f * std::cos(1.7f * k + 0.3f * j), 0.55f, 1.0f);
}

// A plane z = 0 sampled on an nx x ny grid of spacing h, once as points and once as segments
// along x replacing `per` points each (a segment covers its points' cells: from half a spacing
// before the first point to half a spacing after the last, so neighbours share endpoints).
struct Pair {
  HybridModel points, segments;
};

Pair planePair(int nx, int ny, float h, int per) {
  Pair p;
  for (HybridModel* m : {&p.points, &p.segments}) m->attributes.normals = m->attributes.colors = m->attributes.radii = true;
  auto xAt = [&](float i) { return (i - 0.5f * (nx - 1)) * h; };
  for (int j = 0; j < ny; ++j) {
    const float y = (j - 0.5f * (ny - 1)) * h;
    for (int k = 0; k * per < nx; ++k) {
      const int i0 = k * per, i1 = std::min(nx, (k + 1) * per) - 1;
      for (int i = i0; i <= i1; ++i) p.points.points.push_back({Vec3f(xAt(i), y, 0), Vec3f(0, 0, 1), rowColor(j, k), h});
      Segment s;
      s.p0 = Vec3f(xAt(i0 - 0.5f), y, 0);
      s.p1 = Vec3f(xAt(i1 + 0.5f), y, 0);
      s.normal = Vec3f(0, 0, 1);
      s.color = rowColor(j, k);
      s.radius = h;
      p.segments.segments.push_back(s);
    }
  }
  return p;
}

// An open cylinder of radius r about z, nA columns around, nZ points per column at spacing h;
// segments are the columns (straight rulings of the surface), `per` points each.
Pair cylinderPair(float r, int nA, int nZ, int per) {
  Pair p;
  for (HybridModel* m : {&p.points, &p.segments}) m->attributes.normals = m->attributes.colors = m->attributes.radii = true;
  const float h = 2 * 3.14159265f * r / nA;
  auto zAt = [&](float i) { return (i - 0.5f * (nZ - 1)) * h; };
  for (int j = 0; j < nA; ++j) {
    const float phi = 2 * 3.14159265f * j / nA;
    const Vec3f n(std::cos(phi), std::sin(phi), 0);
    for (int k = 0; k * per < nZ; ++k) {
      const int i0 = k * per, i1 = std::min(nZ, (k + 1) * per) - 1;
      for (int i = i0; i <= i1; ++i) p.points.points.push_back({r * n + Vec3f(0, 0, zAt(i)), n, rowColor(j, k), h});
      Segment s;
      s.p0 = r * n + Vec3f(0, 0, zAt(i0 - 0.5f));
      s.p1 = r * n + Vec3f(0, 0, zAt(i1 + 0.5f));
      s.normal = n;
      s.color = rowColor(j, k);
      s.radius = h;
      p.segments.segments.push_back(s);
    }
  }
  return p;
}

// The filter settings of docs/segment-splatting.md, pinned so that the tests and the docs do not
// move with RenderOptions' defaults.
RenderOptions optionsFor(SegmentMethod m) {
  RenderOptions o;
  o.segmentMethod = m;
  o.segmentLod = 0;  // the segment kernel itself, never its point-splat level of detail
  o.cutoffRadius = 2.5f;
  o.prefilterVariance = 1.0f;
  o.reconstructionScale = 0.5f;
  // The thesis's silhouettes: tail coverage fades only the ScreenSpace method's (and the points')
  // tails, which would make the methods differ at the plane's edge for a reason this file is not about.
  o.tailCoverage = 0;
  return o;
}

const SegmentMethod kMethods[] = {SegmentMethod::ScreenSpace, SegmentMethod::Approx, SegmentMethod::Reference};
const char* name(SegmentMethod m) {
  return m == SegmentMethod::ScreenSpace ? "ScreenSpace" : m == SegmentMethod::Approx ? "Approx" : "Reference";
}

TEST(SegmentSplat, WeightTexturesMatchTheErfFormulas) {
  const float R = 2.5f;
  const double sq = std::sqrt(3.14159265358979 / 2);
  for (float y : {0.0f, 0.7f, 1.9f, 2.4f})
    for (float x : {-2.5f, -1.3f, 0.0f, 0.4f, 2.0f, 2.5f}) {
      const double w = std::sqrt(std::max(0.0, double(R * R - y * y)));
      const double xc = std::clamp(double(x), -w, w);
      const double t1 = sq * std::exp(-0.5 * y * y) * (std::erf(w / std::sqrt(2.0)) + std::erf(xc / std::sqrt(2.0)));
      EXPECT_NEAR(weightTextureT1(R, x, y), t1, 2e-3) << x << " " << y;
    }
  for (float y : {0.0f, 1.0f, 2.0f}) {
    EXPECT_NEAR(weightTextureT1(R, R, y), weightTextureT2(R, y), 1e-6);   // T1 joins T2 at x = R
    EXPECT_NEAR(weightTextureT1(R, -R, y), 0.0f, 1e-6);                   // and vanishes at x = -R
    EXPECT_NEAR(weightTextureT1(R, 0, y), 0.5f * weightTextureT2(R, y), 1e-4);
  }
  EXPECT_EQ(weightTextureT2(R, R), 0.0f);
}

// The must-show: the same plane as points and as segments renders alike (< 1 grey level mean
// absolute difference), for every method, in a perspective close view and a minified one.
TEST(SegmentSplat, PlaneAsPointsAndAsSegmentsRenderAlike) {
  const Pair pair = planePair(90, 90, 0.05f, 6);
  for (int view = 0; view < 2; ++view) {
    const Vec3f eye = view == 0 ? Vec3f(0.2f, -1.1f, 1.2f) : Vec3f(0.3f, -3.0f, 5.0f);
    const Camera cam = Camera::lookAt(eye, Vec3f(0, 0.2f, 0), Vec3f(0, 0, 1), 40, 128, 128, 0.05f, 50);
    const Image ref = renderImage(pair.points, cam, optionsFor(SegmentMethod::ScreenSpace)).color;
    for (SegmentMethod m : kMethods) {
      const RenderResult r = renderImage(pair.segments, cam, optionsFor(m));
      EXPECT_EQ(r.stats.segmentsDegenerate, 0u);
      const ImageMetrics im = compareImages(ref, r.color);
      EXPECT_LT(im.meanAbsDiff, 1.0) << name(m) << " view " << view << " psnr " << im.psnr;
    }
  }
}

TEST(SegmentSplat, CylinderAsPointsAndAsSegmentsRenderAlike) {
  const Pair pair = cylinderPair(1.0f, 96, 60, 10);
  const Camera cam = Camera::lookAt(Vec3f(0.3f, -4.2f, 0.8f), Vec3f(0, 0, 0), Vec3f(0, 0, 1), 40, 128, 128, 0.1f, 50);
  for (SegmentMethod m : kMethods) {
    // the same frame options for both (tail layers only with the ScreenSpace method: RenderOptions)
    const Image ref = renderImage(pair.points, cam, optionsFor(m)).color;
    const ImageMetrics im = compareImages(ref, renderImage(pair.segments, cam, optionsFor(m)).color);
    EXPECT_LT(im.meanAbsDiff, 1.0) << name(m) << " psnr " << im.psnr;
  }
}

// A hybrid model: half the plane's rows as points, half as segments, interleaved; it must
// render like the pure point model (one surface through Z^3, no seams between the kinds).
TEST(SegmentSplat, HybridRowsBlendWithPoints) {
  const Pair pair = planePair(80, 80, 0.05f, 8);
  HybridModel hybrid = pair.points;
  hybrid.points.clear();
  const size_t perRow = pair.segments.segments.size() / 80;
  for (int j = 0; j < 80; ++j) {
    if (j % 2 == 0) {
      for (size_t k = 0; k < perRow; ++k) hybrid.segments.push_back(pair.segments.segments[j * perRow + k]);
    } else {
      for (int i = 0; i < 80; ++i) hybrid.points.push_back(pair.points.points[size_t(j) * 80 + i]);
    }
  }
  const Camera cam = Camera::lookAt(Vec3f(0.1f, -1.3f, 1.4f), Vec3f(0, 0.1f, 0), Vec3f(0, 0, 1), 40, 128, 128, 0.05f, 50);
  const Image ref = renderImage(pair.points, cam, optionsFor(SegmentMethod::ScreenSpace)).color;
  for (SegmentMethod m : {SegmentMethod::ScreenSpace, SegmentMethod::Approx}) {
    const ImageMetrics im = compareImages(ref, renderImage(hybrid, cam, optionsFor(m)).color);
    EXPECT_LT(im.meanAbsDiff, 1.0) << name(m);
  }
}

}  // namespace
}  // namespace linesurf

namespace linesurf {
namespace {

// Weight image of one segment under one method, via segmentWeightAt.
struct WeightImage {
  std::vector<float> w;
  float peak = 0;
  PrimitiveStatus status{};
  bool fallback = false, longCase = true;
  size_t quads = 0;
};

WeightImage weightImage(const Segment& s, const Camera& cam, SegmentMethod m) {
  RenderOptions o = optionsFor(m);
  o.backfaceCulling = false;
  const FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
  PreparedSegment ps;
  WeightImage out;
  out.status = prepareSegment(s, 0, frame, ps);
  out.fallback = ps.fallback;
  out.longCase = ps.extra && ps.extra->longCase;
  out.quads = ps.extra ? ps.extra->quads.size() : 0;
  out.w.assign(size_t(cam.width()) * cam.height(), 0.0f);
  if (out.status != PrimitiveStatus::Drawn && out.status != PrimitiveStatus::Clipped) return out;
  for (int y = ps.bounds.y0; y < ps.bounds.y1; ++y)
    for (int x = ps.bounds.x0; x < ps.bounds.x1; ++x) {
      const float w = segmentWeightAt(ps, frame, Vec2f(x + 0.5f, y + 0.5f));
      EXPECT_TRUE(std::isfinite(w));
      out.w[size_t(y) * cam.width() + x] = w;
      out.peak = std::max(out.peak, w);
    }
  return out;
}

// Error of `a` against the reference `r`, relative to the reference's peak weight.
struct WeightError {
  double psnr = 0, maxRel = 0;
};
WeightError weightError(const WeightImage& a, const WeightImage& r) {
  double se = 0, mx = 0;
  for (size_t i = 0; i < a.w.size(); ++i) {
    const double d = (a.w[i] - r.w[i]) / r.peak;
    se += d * d;
    mx = std::max(mx, std::abs(d));
  }
  const double mse = se / double(a.w.size());
  return {mse > 0 ? 10 * std::log10(1 / mse) : 999, mx};
}

Segment unitSegment(float length, float radius) {
  Segment s;
  s.p0 = Vec3f(-0.5f * length, 0, 0);
  s.p1 = Vec3f(0.5f * length, 0, 0);
  s.normal = Vec3f(0, 0, 1);
  s.radius = radius;
  return s;
}

TEST(SegmentSplat, MethodsAgreeWithReferenceOnSimpleViews) {
  struct View {
    const char* name;
    Vec3f eye;
    float length;
  };
  const View views[] = {
      {"front long", Vec3f(0.1f, -0.2f, 3.0f), 1.0f},      {"front short", Vec3f(0.1f, -0.2f, 3.0f), 0.08f},
      {"oblique long", Vec3f(0.5f, -2.0f, 1.5f), 1.0f},    {"grazing", Vec3f(0.3f, -3.0f, 0.15f), 1.0f},
      {"close-up", Vec3f(0.05f, -0.3f, 0.35f), 1.0f},      {"along the axis", Vec3f(2.5f, -0.3f, 1.0f), 1.0f},
      {"minified", Vec3f(0.2f, -4.0f, 25.0f), 1.0f},
  };
  for (const View& v : views) {
    const Segment s = unitSegment(v.length, 0.05f);
    const Camera cam = Camera::lookAt(v.eye, Vec3f(0, 0, 0), Vec3f(0, 0, 1), 40, 96, 96, 0.01f, 100);
    const WeightImage ref = weightImage(s, cam, SegmentMethod::Reference);
    ASSERT_GT(ref.peak, 0) << v.name;
    for (SegmentMethod m : {SegmentMethod::ScreenSpace, SegmentMethod::Approx}) {
      const WeightImage img = weightImage(s, cam, m);
      const WeightError e = weightError(img, ref);
      if (m == SegmentMethod::ScreenSpace) {
        EXPECT_GT(e.psnr, 45) << v.name;
        EXPECT_LT(e.maxRel, 0.05) << v.name;
      } else {
        EXPECT_GT(e.psnr, 25) << v.name;
      }
    }
  }
}

}  // namespace
}  // namespace linesurf

namespace linesurf {
namespace {

PrimitiveStatus prepareWith(const Segment& s, const Camera& cam, SegmentMethod m, PreparedSegment& ps,
                            bool culling = true) {
  static RenderOptions o;  // FrameContext keeps a pointer to it
  o = optionsFor(m);
  o.backfaceCulling = culling;
  const FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
  return prepareSegment(s, 0, frame, ps);
}

TEST(SegmentSplat, ApproxLongAndShortCases) {
  const Camera cam = Camera::lookAt(Vec3f(0.1f, -0.2f, 3.0f), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 96, 96);
  PreparedSegment ps;
  ASSERT_EQ(prepareWith(unitSegment(1.0f, 0.05f), cam, SegmentMethod::Approx, ps), PrimitiveStatus::Drawn);
  EXPECT_FALSE(ps.fallback);
  ASSERT_TRUE(ps.extra);
  EXPECT_TRUE(ps.extra->longCase);
  EXPECT_EQ(ps.extra->quads.size(), 10u);
  // shorter than the cutoff diameter: the endpoint ellipses overlap
  ASSERT_EQ(prepareWith(unitSegment(0.05f, 0.05f), cam, SegmentMethod::Approx, ps), PrimitiveStatus::Drawn);
  EXPECT_FALSE(ps.fallback);
  ASSERT_TRUE(ps.extra);
  EXPECT_FALSE(ps.extra->longCase);
  EXPECT_EQ(ps.extra->quads.size(), 8u);
  // No seam between portions: along the axis the weight has no jump larger than its slope allows.
  ASSERT_EQ(prepareWith(unitSegment(1.0f, 0.05f), cam, SegmentMethod::Approx, ps), PrimitiveStatus::Drawn);
  RenderOptions o = optionsFor(SegmentMethod::Approx);
  const FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
  const Vec3f a = cam.project(cam.toCamera(Vec3f(-0.7f, 0.01f, 0))), b = cam.project(cam.toCamera(Vec3f(0.7f, 0.01f, 0)));
  float prev = -1, maxJump = 0, peak = 0;
  for (int i = 0; i <= 2000; ++i) {
    const Vec2f p = a.head<2>() + (b.head<2>() - a.head<2>()) * (i / 2000.0f);
    const float w = segmentWeightAt(ps, frame, p);
    ASSERT_TRUE(std::isfinite(w));
    if (prev >= 0) maxJump = std::max(maxJump, std::abs(w - prev));
    prev = w;
    peak = std::max(peak, w);
  }
  EXPECT_GT(peak, 0);
  EXPECT_LT(maxJump, 0.02f * peak);
}

TEST(SegmentSplat, DegenerateSegmentsAreCountedNotDrawn) {
  const Camera cam = Camera::lookAt(Vec3f(0, -0.5f, 3.0f), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 64, 64, 0.1f, 100);
  PreparedSegment ps;
  Segment s = unitSegment(0.0f, 0.05f);  // zero length: zero weight
  EXPECT_EQ(prepareWith(s, cam, SegmentMethod::ScreenSpace, ps), PrimitiveStatus::Degenerate);
  s = unitSegment(1.0f, 0.0f);
  EXPECT_EQ(prepareWith(s, cam, SegmentMethod::ScreenSpace, ps), PrimitiveStatus::Degenerate);
  s = unitSegment(1.0f, 0.05f);
  s.p1.x() = NAN;
  EXPECT_EQ(prepareWith(s, cam, SegmentMethod::Approx, ps), PrimitiveStatus::Degenerate);
  // behind the camera
  s = unitSegment(1.0f, 0.05f);
  s.p0.z() = s.p1.z() = 10;
  s.normal = Vec3f(0, 1, 0);
  EXPECT_EQ(prepareWith(s, cam, SegmentMethod::ScreenSpace, ps, false), PrimitiveStatus::Outside);
  // edge-on: the eye lies in the strip's plane
  s = unitSegment(1.0f, 0.05f);
  s.p0 += Vec3f(0, -0.5f, 3.0f) * 0;
  s.normal = Vec3f(1, 0, 0).cross(Vec3f(0, -0.5f, 3.0f)).normalized();
  EXPECT_EQ(prepareWith(s, cam, SegmentMethod::Approx, ps, false), PrimitiveStatus::Culled);
  // back-facing
  s = unitSegment(1.0f, 0.05f);
  s.normal = Vec3f(0, 0, -1);
  EXPECT_EQ(prepareWith(s, cam, SegmentMethod::ScreenSpace, ps), PrimitiveStatus::Culled);
  // normal along the segment and zero normal: the strip facing the viewer is drawn
  s.normal = Vec3f::Zero();
  EXPECT_EQ(prepareWith(s, cam, SegmentMethod::ScreenSpace, ps), PrimitiveStatus::Drawn);
}

TEST(SegmentSplat, CrossingTheNearPlaneIsClippedAndFinite) {
  // a floor segment running from behind the eye to far ahead
  Segment s;
  s.p0 = Vec3f(0, -2, 0);
  s.p1 = Vec3f(0, 6, 0);
  s.normal = Vec3f(0, 0, 1);
  s.radius = 0.05f;
  const Camera cam = Camera::lookAt(Vec3f(0, -1, 0.3f), Vec3f(0, 1, 0), Vec3f(0, 0, 1), 60, 64, 64, 0.1f, 100);
  HybridModel m;
  m.segments.push_back(s);
  for (SegmentMethod meth : kMethods) {
    PreparedSegment ps;
    EXPECT_EQ(prepareWith(s, cam, meth, ps), PrimitiveStatus::Clipped) << name(meth);
    RenderOptions o = optionsFor(meth);
    o.alphaBuffer = true;
    const RenderResult r = renderImage(m, cam, o);
    double covered = 0;
    for (const Color& c : r.color.pixels) ASSERT_TRUE(c.allFinite());
    for (const Color& c : r.alpha->pixels) covered += c.x();
    EXPECT_GT(covered, 20) << name(meth);
  }
}

// Random segments and views (fixed seed), grazing and close ones included: every method gives a
// finite splat whose screen box is never wildly larger than the ScreenSpace one; Approx falls
// back (counted) rather than drawing a wild quad.
TEST(SegmentSplat, RandomViewsGiveSaneSplats) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> U(-1, 1);
  int fallbacks = 0, drawn = 0;
  for (int it = 0; it < 300; ++it) {
    Segment s;
    s.p0 = Vec3f(U(rng), U(rng), U(rng)) * 0.5f;
    const Vec3f dir = Vec3f(U(rng), U(rng), U(rng)).normalized();
    s.p1 = s.p0 + dir * (std::pow(10.0f, 2 * U(rng) - 1.5f));
    Vec3f n = Vec3f(U(rng), U(rng), U(rng)).cross(dir);
    if (n.norm() < 1e-3f) continue;
    s.normal = n.normalized();
    s.radius = std::pow(10.0f, U(rng) - 1.5f);
    const Vec3f eye = Vec3f(U(rng), U(rng), U(rng)).normalized() * std::pow(10.0f, U(rng) + 0.2f);
    const Camera cam = Camera::lookAt(eye, Vec3f::Zero(), Vec3f(0, 0, 1), 40, 64, 64, 0.01f, 100);
    PreparedSegment ss, ap;
    const PrimitiveStatus st = prepareWith(s, cam, SegmentMethod::ScreenSpace, ss, false);
    const PrimitiveStatus sa = prepareWith(s, cam, SegmentMethod::Approx, ap, false);
    EXPECT_EQ(st, sa);
    if (sa != PrimitiveStatus::Drawn && sa != PrimitiveStatus::Clipped) continue;
    ++drawn;
    fallbacks += ap.fallback;
    if (ap.extra) {
      for (const SegmentQuad& q : ap.extra->quads)
        for (const Vec2f& c : q.corner) ASSERT_TRUE(c.allFinite());
    }
    const RenderOptions o = optionsFor(SegmentMethod::Approx);
    const FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
    for (int y = ap.bounds.y0; y < ap.bounds.y1; y += 3)
      for (int x = ap.bounds.x0; x < ap.bounds.x1; x += 3)
        ASSERT_TRUE(std::isfinite(segmentWeightAt(ap, frame, Vec2f(x + 0.5f, y + 0.5f))));
    const auto area = [](const PixelRect& r) { return double(r.width()) * r.height(); };
    EXPECT_LE(area(ap.bounds), 4 * area(ss.bounds) + 64) << it;
  }
  EXPECT_GT(drawn, 100);
  std::printf("random views: %d drawn, %d Approx fallbacks\n", drawn, fallbacks);
}

// The fragments (pixel -> weight) the SIMD rows find over `spans`, in blocks of at most
// kBlock pixels (rows longer than that cut).
std::map<std::pair<int, int>, float> rowFragments(const PreparedSegment& ps, const std::vector<detail::RowSpan>& spans,
                                                  size_t& walked) {
  std::map<std::pair<int, int>, float> out;
  std::vector<detail::RowSpan> block;
  int pixels = 0;
  detail::FragmentBlock fb;
  auto flush = [&] {
    const int m = detail::segmentFragments(ps.raster, block.data(), int(block.size()), fb);
    for (int i = 0; i < m; ++i) out[{int(fb.x[i]), int(fb.y[i])}] = fb.weight[i];
    block.clear();
    pixels = 0;
  };
  for (const detail::RowSpan& s : spans)
    for (int x0 = s.x0; x0 < s.x1; x0 += detail::kBlock) {
      const int x1 = std::min(s.x1, x0 + detail::kBlock);
      if (pixels + (x1 - x0) > detail::kBlock) flush();
      block.push_back({s.y, x0, x1});
      pixels += x1 - x0;
      walked += size_t(x1 - x0);
    }
  if (!block.empty()) flush();
  return out;
}

// A random segment (any orientation, 0.1 to 3 units long, thin to wide) and a 96 x 80 camera
// looking near it from 10^(eyeLog - 1) to 10^(eyeLog + 1) away; false (nothing else drawn) when
// the draw gives no usable normal.
bool randomSegmentView(std::mt19937& rng, float eyeLog, Segment& s, Camera& cam) {
  std::uniform_real_distribution<float> U(-1, 1);
  s.p0 = Vec3f(U(rng), U(rng), U(rng)) * 0.5f;
  const Vec3f dir = Vec3f(U(rng), U(rng), U(rng)).normalized();
  s.p1 = s.p0 + dir * std::pow(10.0f, 1.5f * U(rng) - 1.0f);
  const Vec3f n = Vec3f(U(rng), U(rng), U(rng)).cross(dir);
  if (n.norm() < 1e-3f) return false;
  s.normal = n.normalized();
  s.radius = std::pow(10.0f, U(rng) - 1.5f);
  const Vec3f eye = Vec3f(U(rng), U(rng), U(rng)).normalized() * std::pow(10.0f, U(rng) + eyeLog);
  cam = Camera::lookAt(eye, 0.3f * Vec3f(U(rng), U(rng), U(rng)), Vec3f(0, 0, 1), 40, 96, 80, 0.05f, 100);
  return true;
}

// The tight walk (the rows' spans of the polygon around the cutoff region, detail::segmentSpans)
// finds every fragment of weight > 0 that the footprint-box walk finds, with the same weight, on
// random segments: any orientation, long (several sub-segments) and short, wide and thin,
// grazing, crossing the near plane, seen from close and far, cut by 16-pixel tiles at random
// offsets, prepared by the exact path and by the SIMD batches; and it walks fewer pixels.
TEST(SegmentSplat, TightRowSpansKeepEveryFragmentOfTheBoxWalk) {
  std::mt19937 rng(11);
  size_t fragments = 0, walkedBox = 0, walkedTight = 0, checked = 0, multiPiece = 0, clipped = 0, simdChecked = 0;
  for (int it = 0; it < 600; ++it) {
    Segment s;
    Camera cam;
    if (!randomSegmentView(rng, 0.1f, s, cam)) continue;
    // the exact prepare path and the renderer's SIMD batches (prepareSegments)
    PreparedSegment ps, simd;
    const PrimitiveStatus st = prepareWith(s, cam, SegmentMethod::ScreenSpace, ps, false);
    if (st != PrimitiveStatus::Drawn && st != PrimitiveStatus::Clipped) continue;
    static RenderOptions o;  // FrameContext keeps a pointer to it
    o = optionsFor(SegmentMethod::ScreenSpace);
    o.backfaceCulling = false;
    const FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
    PrimitiveStatus sst = PrimitiveStatus::Degenerate;
    prepareSegments(&s, 0, 1, frame, segmentSetupFrame(frame), &simd, &sst);
    multiPiece += ps.pieceCount() > 1;
    clipped += ps.raster.clipDepth;
    const int ox = int(rng() % 16), oy = int(rng() % 16);
    for (const PreparedSegment* p : {&ps, &simd}) {
      if (p == &simd && sst != PrimitiveStatus::Drawn && sst != PrimitiveStatus::Clipped) continue;
      simdChecked += p == &simd;
      for (int ty = -oy; ty < cam.height(); ty += 16)
        for (int tx = -ox; tx < cam.width(); tx += 16) {
          const PixelRect tile = PixelRect{tx, ty, tx + 16, ty + 16}.intersect(PixelRect{0, 0, cam.width(), cam.height()});
          const auto box = rowFragments(*p, segmentRowSpans(*p, tile, false), walkedBox);
          const auto tight = rowFragments(*p, segmentRowSpans(*p, tile, true), walkedTight);
          for (const auto& [px, w] : box) {
            ++checked;
            const auto f = tight.find(px);
            ASSERT_TRUE(f != tight.end()) << "segment " << it << (p == &simd ? " (SIMD prepare)" : "") << " drops pixel "
                                          << px.first << "," << px.second << " of weight " << w;
            EXPECT_EQ(f->second, w) << it;
          }
          fragments += tight.size();
        }
    }
  }
  EXPECT_GT(checked, 20000u);
  EXPECT_GT(multiPiece, 10u);
  EXPECT_GT(clipped, 3u);
  EXPECT_GT(simdChecked, 100u);
  EXPECT_LT(walkedTight, walkedBox);
  std::printf("tight spans: %zu fragments, %zu of them checked against the box walk; pixels walked %zu (box %zu); "
              "%zu segments with several sub-segments, %zu depth-clipped, %zu prepared by the SIMD batches too\n",
              fragments, checked, walkedTight, walkedBox, multiPiece, clipped, simdChecked);
}

// n random one-piece segments, prepared by the exact path for their random views
std::vector<PreparedSegment> randomOnePieceSegments(std::mt19937& rng, size_t n) {
  std::vector<PreparedSegment> segs(n);
  for (size_t i = 0; i < segs.size();) {
    Segment s;
    Camera cam;
    if (!randomSegmentView(rng, 0.1f, s, cam)) continue;
    PreparedSegment& ps = segs[i];
    const PrimitiveStatus st = prepareWith(s, cam, SegmentMethod::ScreenSpace, ps, false);
    if ((st != PrimitiveStatus::Drawn && st != PrimitiveStatus::Clipped) || ps.pieceCount() != 1) continue;
    ++i;
  }
  return segs;
}

// The span batch (detail::segmentSpansBatch, as rasterizeSegments calls it) reports each
// segment's widest span and its spans' pixels, which the rows take instead of counting them (the
// Z^3 pass's lane count is chosen by the widest span): on random one-piece segments in tiles at
// random offsets, both equal what its own spans hold, rows beyond a segment's rect left out.
TEST(SegmentSplat, SpanBatchReportsTheWidestSpanAndThePixels) {
  std::mt19937 rng(5);
  const std::vector<PreparedSegment> segs = randomOnePieceSegments(rng, 300);
  size_t checked = 0, wide = 0, shorter = 0;
  const int stride = 24;
  for (size_t g = 0; g < segs.size(); g += 16) {
    const int n = int(std::min<size_t>(16, segs.size() - g));
    const detail::SegmentRaster* batch[16];
    PixelRect rects[16];
    int m = 0;
    for (int i = 0; i < n; ++i) {
      const PreparedSegment& ps = segs[g + size_t(i)];
      const int ox = int(rng() % 24), oy = int(rng() % 24);  // a tile of 24 rows at most, cut at a random offset
      const PixelRect tile{ps.bounds.x0 + ox - 12, ps.bounds.y0 + oy - 12, ps.bounds.x0 + ox + 12,
                           ps.bounds.y0 + oy + 12};
      const PixelRect r = ps.bounds.intersect(tile);
      if (r.empty()) continue;
      batch[m] = &ps.raster, rects[m++] = r;
    }
    std::vector<detail::RowSpan> spans(size_t(16 * stride));
    int counts[16], widest[16], pixels[16];
    detail::segmentSpansBatch(batch, rects, m, 0.01f, spans.data(), stride, counts, widest, pixels);
    for (int i = 0; i < m; ++i) {
      if (counts[i] < 0) continue;
      int w = 0, p = 0;
      for (int k = 0; k < counts[i]; ++k) {
        const detail::RowSpan& sp = spans[size_t(i * stride + k)];
        ASSERT_GE(sp.y, rects[i].y0);
        ASSERT_LT(sp.y, rects[i].y1);
        w = std::max(w, sp.x1 - sp.x0), p += sp.x1 - sp.x0;
      }
      EXPECT_EQ(widest[i], w) << "segment " << g + size_t(i);
      EXPECT_EQ(pixels[i], p) << "segment " << g + size_t(i);
      ++checked, wide += w > 4, shorter += rects[i].height() < 24;
    }
  }
  EXPECT_GT(checked, 200u);
  EXPECT_GT(wide, 20u);
  EXPECT_GT(shorter, 50u);
}

// The span batch's rows take four constraints a side where every lane's opposite directions
// bound x from both sides, eight otherwise (the batch decides per vector): a segment's spans are
// the same alone as in any batch, so the same whichever of the two its batch took, on random
// one-piece segments (close and grazing views among them) in batches of 16 in random order.
TEST(SegmentSplat, SpanBatchGivesEachSegmentTheSameSpansInAnyBatch) {
  std::mt19937 rng(23);
  std::vector<PreparedSegment> segs = randomOnePieceSegments(rng, 480);
  const int stride = 24;
  size_t checked = 0, spansSeen = 0;
  for (int round = 0; round < 2; ++round) {
    std::shuffle(segs.begin(), segs.end(), rng);
    for (size_t g = 0; g < segs.size(); g += 16) {
      const detail::SegmentRaster* batch[16];
      PixelRect rects[16];
      int m = 0;
      for (size_t i = g; i < g + 16; ++i) {
        const PixelRect& b = segs[i].bounds;
        const PixelRect r = b.intersect(PixelRect{b.x0, b.y0, b.x0 + 24, b.y0 + stride});
        if (!r.empty()) batch[m] = &segs[i].raster, rects[m++] = r;
      }
      std::vector<detail::RowSpan> spans(size_t(16 * stride)), alone(static_cast<size_t>(stride));
      int counts[16], widest[16], pixels[16];
      detail::segmentSpansBatch(batch, rects, m, 0.01f, spans.data(), stride, counts, widest, pixels);
      for (int i = 0; i < m; ++i) {
        int count = 0, w = 0, p = 0;
        detail::segmentSpansBatch(&batch[i], &rects[i], 1, 0.01f, alone.data(), stride, &count, &w, &p);
        ASSERT_EQ(counts[i], count) << "segment " << g + size_t(i);
        if (count < 0) continue;
        EXPECT_EQ(widest[i], w);
        EXPECT_EQ(pixels[i], p);
        for (int k = 0; k < count; ++k) {
          const detail::RowSpan &a = spans[size_t(i * stride + k)], &b = alone[size_t(k)];
          ASSERT_TRUE(a.y == b.y && a.x0 == b.x0 && a.x1 == b.x1) << "segment " << g + size_t(i) << " span " << k;
        }
        ++checked, spansSeen += size_t(count);
      }
    }
  }
  EXPECT_GT(checked, 800u);
  EXPECT_GT(spansSeen, 2000u);
}

// The SIMD segment kernel (detail::segmentFragments: reciprocalNewton, the polynomial exp and erf
// at cutoff 2, hn::Exp and the rational erf at 3) against the ScreenSpace closed form in double
// (every sub-segment, std::erf, std::exp) on random segments: every fragment within 2e-4 of the
// segment's peak weight (measured 5.4e-5 at cutoff 2, 8.4e-5 at 3: the float plane coordinates),
// every pixel of reference weight above 1e-4 of the peak found; and a
// pixel's weight the same to the bit whether its row is evaluated alone or packed with the others
// (the uncut-vector shortcut must not depend on the lane's neighbours).
TEST(SegmentSplat, SimdKernelMatchesTheClosedFormInDouble) {
  for (const float cutoff : {2.0f, 3.0f}) {
    std::mt19937 rng(23);
    double worst = 0;
    size_t compared = 0, multiPiece = 0;
    for (int it = 0; it < 300; ++it) {
      Segment s;
      Camera cam;
      if (!randomSegmentView(rng, 0.3f, s, cam)) continue;
      static RenderOptions o;  // FrameContext keeps a pointer to it
      o = optionsFor(SegmentMethod::ScreenSpace);
      o.cutoffRadius = cutoff;
      o.backfaceCulling = false;
      const FrameContext frame = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
      PreparedSegment ps;
      const PrimitiveStatus st = prepareSegment(s, 0, frame, ps);
      if ((st != PrimitiveStatus::Drawn && st != PrimitiveStatus::Clipped) || ps.raster.clipDepth) continue;
      const detail::SegmentRaster& k = ps.raster;
      ASSERT_NEAR(k.R2, double(cutoff) * cutoff, 1e-5);
      std::vector<SegmentPiece> pieces;
      if (ps.pieceCount() > 1) {
        pieces = ps.extra->pieces;
        ++multiPiece;
      } else {
        SegmentPiece p;
        p.a0 = 0, p.a1 = k.length, p.skew = k.skew, p.across = k.across, p.invM00 = k.invM00, p.k = k.k;
        p.erfScale = k.erfScale, p.scale0 = k.scale0, p.slope = k.slope;
        pieces.push_back(p);
      }
      // the closed form in double at the pixel centre
      auto reference = [&](int x, int y) {
        const double px = x + 0.5, py = y + 0.5;
        const double nr = double(k.N.dx) * px + double(k.N.dy) * py + k.N.c;
        if (!(nr < 0)) return 0.0;
        const double a = (double(k.A.dx) * px + double(k.A.dy) * py + k.A.c) / nr - k.a0;
        const double b = (double(k.B.dx) * px + double(k.B.dy) * py + k.B.c) / nr - k.b0;
        if (std::abs(b) > k.bMax || a < k.aMin || a > k.aMax) return 0.0;
        double w = 0;
        for (const SegmentPiece& p : pieces) {
          const double tauStar = a - p.a0 + double(p.skew) * b, qmin = b * b * p.across;
          if (!(qmin < k.R2)) continue;
          const double delta = std::sqrt((k.R2 - qmin) * p.invM00);
          const double t0 = std::max(0.0, tauStar - delta), t1 = std::min(double(p.a1 - p.a0), tauStar + delta);
          if (!(t1 > t0)) continue;
          const double u0 = p.k * (t0 - tauStar), u1 = p.k * (t1 - tauStar);
          const detail::PieceScale sc = detail::pieceScale(p.scale0, p.slope, p.a1 - p.a0);  // flat if it barely changes
          w += (sc.scale0 + double(sc.slope) * tauStar) * p.erfScale * (std::erf(u1) - std::erf(u0)) * std::exp(-qmin / 2);
          w += double(sc.slope) * p.invM00 * (std::exp(-qmin / 2 - u0 * u0) - std::exp(-qmin / 2 - u1 * u1));
        }
        return w;
      };
      const PixelRect r = ps.bounds;
      if (double(r.width()) * r.height() > 4000) continue;
      double peak = 0;
      std::map<std::pair<int, int>, double> ref;
      for (int y = r.y0; y < r.y1; ++y)
        for (int x = r.x0; x < r.x1; ++x) peak = std::max(peak, ref[{x, y}] = reference(x, y));
      if (!(peak > 0)) continue;
      // the SIMD kernel over whole rows (packed), and each row alone
      std::vector<detail::RowSpan> rows;
      for (int y = r.y0; y < r.y1; ++y) rows.push_back({y, r.x0, r.x1});
      size_t walked = 0;
      const auto simd = rowFragments(ps, rows, walked);
      for (const detail::RowSpan& row : rows) {
        const auto alone = rowFragments(ps, {row}, walked);
        for (const auto& [px, w] : alone) {
          const auto f = simd.find(px);
          ASSERT_TRUE(f != simd.end()) << it;
          ASSERT_EQ(f->second, w) << "cutoff " << cutoff << " segment " << it << " pixel " << px.first << "," << px.second;
        }
      }
      for (const auto& [px, w] : simd) {
        const double e = std::abs(double(w) - ref[px]) / peak;
        worst = std::max(worst, e);
        ++compared;
        ASSERT_LT(e, 2e-4) << "cutoff " << cutoff << " segment " << it << " pixel " << px.first << "," << px.second
                           << ": SIMD " << w << " closed form " << ref[px] << " peak " << peak;
      }
      for (const auto& [px, w] : ref)
        if (w > 1e-4 * peak) { ASSERT_TRUE(simd.count(px)) << "cutoff " << cutoff << " segment " << it << " misses a pixel"; }
    }
    EXPECT_GT(compared, 20000u);
    EXPECT_GT(multiPiece, 5u);
    std::printf("cutoff %.1f: %zu fragments, largest difference %.2e of the peak; %zu segments with several pieces\n",
                double(cutoff), compared, worst, multiPiece);
  }
}

}  // namespace
}  // namespace linesurf

// Regenerates docs/images/segments/* and prints the error tables of docs/segment-splatting.md
// when LINESURF_SEGMENT_DOC_IMAGES names an output folder; skipped otherwise.
#include "linesurf/io/image_io.h"

namespace linesurf {
namespace {

Image weightToImage(const WeightImage& w, int width, int height, float peak) {
  Image img(width, height, Color(0, 0, 0, 1));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const float v = std::clamp(w.w[size_t(y) * width + x] / peak, 0.0f, 1.0f);
      img.at(x, y) = Color(v, v, v, 1);
    }
  return img;
}

TEST(SegmentSplatDocs, WriteImagesAndTables) {
  const char* dirEnv = std::getenv("LINESURF_SEGMENT_DOC_IMAGES");
  if (!dirEnv) GTEST_SKIP() << "set LINESURF_SEGMENT_DOC_IMAGES=<folder> to regenerate the docs images";
  const std::filesystem::path dir(dirEnv);
  std::filesystem::create_directories(dir);
  // 1. Weight of one segment per view: ScreenSpace and Approx against the Reference.
  struct View {
    const char* name;
    Vec3f eye;
    float length;
  };
  const View views[] = {
      {"front-long", Vec3f(0.1f, -0.2f, 3.0f), 1.0f},    {"front-short", Vec3f(0.1f, -0.2f, 3.0f), 0.08f},
      {"oblique", Vec3f(0.5f, -2.0f, 1.5f), 1.0f},       {"grazing", Vec3f(0.3f, -3.0f, 0.15f), 1.0f},
      {"grazing-10deg", Vec3f(0.2f, -3.0f, 0.5f), 1.0f}, {"close-up", Vec3f(0.05f, -0.3f, 0.35f), 1.0f},
      {"along-axis", Vec3f(2.5f, -0.3f, 1.0f), 1.0f},    {"minified", Vec3f(0.2f, -4.0f, 25.0f), 1.0f},
  };
  std::printf("\n| view | ScreenSpace PSNR | ScreenSpace max | Approx PSNR | Approx max | Approx case |\n|---|---|---|---|---|---|\n");
  for (const View& v : views) {
    const Segment s = unitSegment(v.length, 0.05f);
    const Camera cam = Camera::lookAt(v.eye, Vec3f(0, 0, 0), Vec3f(0, 0, 1), 40, 192, 192, 0.01f, 100);
    const WeightImage ref = weightImage(s, cam, SegmentMethod::Reference);
    const WeightImage ss = weightImage(s, cam, SegmentMethod::ScreenSpace);
    const WeightImage ap = weightImage(s, cam, SegmentMethod::Approx);
    const WeightError es = weightError(ss, ref), ea = weightError(ap, ref);
    std::printf("| %s | %.1f dB | %.4f | %.1f dB | %.4f | %s |\n", v.name, es.psnr, es.maxRel, ea.psnr, ea.maxRel,
                ap.fallback ? "fallback" : ap.longCase ? "long" : "short");
    writePng(dir / (std::string("weight-") + v.name + "-reference.png"), weightToImage(ref, 192, 192, ref.peak), false);
    writePng(dir / (std::string("weight-") + v.name + "-screenspace.png"), weightToImage(ss, 192, 192, ref.peak), false);
    writePng(dir / (std::string("weight-") + v.name + "-approx.png"), weightToImage(ap, 192, 192, ref.peak), false);
  }
  // 2. Shaded images of the plane and the cylinder: points vs segments, each method vs Reference.
  const Pair plane = planePair(90, 90, 0.05f, 6), cyl = cylinderPair(1.0f, 96, 60, 10);
  struct Scene {
    const char* name;
    const Pair* pair;
    Camera cam;
  };
  const Scene scenes[] = {
      {"plane-close", &plane, Camera::lookAt(Vec3f(0.2f, -1.1f, 1.2f), Vec3f(0, 0.2f, 0), Vec3f(0, 0, 1), 40, 256, 256, 0.05f, 50)},
      {"plane-grazing", &plane, Camera::lookAt(Vec3f(0.1f, -2.3f, 0.25f), Vec3f(0, 0.5f, 0), Vec3f(0, 0, 1), 40, 256, 256, 0.05f, 50)},
      {"plane-far", &plane, Camera::lookAt(Vec3f(0.3f, -3.0f, 5.0f), Vec3f(0, 0.2f, 0), Vec3f(0, 0, 1), 40, 256, 256, 0.05f, 50)},
      {"cylinder", &cyl, Camera::lookAt(Vec3f(0.3f, -4.2f, 0.8f), Vec3f(0, 0, 0), Vec3f(0, 0, 1), 40, 256, 256, 0.1f, 50)},
  };
  std::printf("\n| scene | points vs segments (ScreenSpace) MAD | ScreenSpace vs Reference PSNR / max | Approx vs Reference PSNR / max | Approx vs points MAD |\n|---|---|---|---|---|\n");
  for (const Scene& sc : scenes) {
    const Image pts = renderImage(sc.pair->points, sc.cam, optionsFor(SegmentMethod::ScreenSpace)).color;
    const Image ref = renderImage(sc.pair->segments, sc.cam, optionsFor(SegmentMethod::Reference)).color;
    const Image ss = renderImage(sc.pair->segments, sc.cam, optionsFor(SegmentMethod::ScreenSpace)).color;
    const Image ap = renderImage(sc.pair->segments, sc.cam, optionsFor(SegmentMethod::Approx)).color;
    const ImageMetrics a = compareImages(pts, ss), b = compareImages(ref, ss), c = compareImages(ref, ap),
                       d = compareImages(pts, ap);
    std::printf("| %s | %.3f | %.1f dB / %.0f | %.1f dB / %.0f | %.3f |\n", sc.name, a.meanAbsDiff, b.psnr, b.maxAbsDiff,
                c.psnr, c.maxAbsDiff, d.meanAbsDiff);
    const std::string base = std::string(sc.name);
    writePng(dir / (base + "-points.png"), pts, false);
    writePng(dir / (base + "-segments.png"), ss, false);
    writePng(dir / (base + "-approx.png"), ap, false);
    writePng(dir / (base + "-diff-points-segments.png"), differenceHeatmap(pts, ss, 8), false);
  }
}

}  // namespace
}  // namespace linesurf

namespace linesurf {
namespace {

// §5.2.4: uv interpolated between the endpoints, held at the endpoint's uv beyond them.
TEST(SegmentSplat, TextureCoordinatesInterpolatedAndClampedBeyondEndpoints) {
  auto tex = std::make_shared<Image>(64, 1);
  for (int i = 0; i < 64; ++i) {
    const float u = (i + 0.5f) / 64;
    tex->at(i, 0) = Color(1 - u, 0, u, 1);
  }
  HybridModel m;
  m.attributes.texcoords = m.attributes.normals = true;
  m.texture = tex;
  Segment s = unitSegment(1.0f, 0.1f);
  s.uv0 = Vec2f(0.25f, 0.5f);
  s.uv1 = Vec2f(0.75f, 0.5f);
  m.segments.push_back(s);
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 2.0f), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 50, 128, 128);
  for (SegmentMethod meth : kMethods) {
    RenderOptions o = optionsFor(meth);
    o.material.ambient = 1;
    o.material.diffuse = 0;
    o.material.specular = 0;
    const Image img = renderImage(m, cam, o).color;
    auto blueAt = [&](float x) {
      const Vec3f p = cam.project(cam.toCamera(Vec3f(x, 0, 0)));
      return img.at(int(p.x()), int(p.y())).z();
    };
    EXPECT_NEAR(blueAt(0.0f), 0.5f, 0.03f) << name(meth);
    EXPECT_NEAR(blueAt(-0.25f), 0.375f, 0.03f) << name(meth);
    EXPECT_NEAR(blueAt(0.54f), 0.75f, 0.03f) << name(meth);   // beyond p1: uv1
    EXPECT_NEAR(blueAt(-0.54f), 0.25f, 0.03f) << name(meth);  // beyond p0: uv0
  }
}

}  // namespace
}  // namespace linesurf

namespace linesurf {
namespace {

// Without the prefilter M = sigma_r^2 I is constant along the segment, so ScreenSpace's closed
// form is exact and the Reference must agree with it within its stated tolerance (2e-3 of the
// peak); both are checked against the analytic weight of the T1/T2 formulas on the axis.
TEST(SegmentSplat, ReferenceWithinToleranceOfTheClosedForm) {
  Segment s = unitSegment(1.0f, 0.05f);
  const Camera cam = Camera::lookAt(Vec3f(0.05f, -0.6f, 2.0f), Vec3f(0, 0, 0), Vec3f(0, 0, 1), 40, 96, 96, 0.01f, 100);
  RenderOptions o = optionsFor(SegmentMethod::Reference);
  o.prefilterVariance = 0;
  o.backfaceCulling = false;
  double maxRel = 0, peak = 0;
  PreparedSegment ref, ss;
  o.segmentMethod = SegmentMethod::Reference;
  const FrameContext fr = FrameContext::make(cam, o, BoundingSphere{Vec3f::Zero(), 1});
  ASSERT_EQ(prepareSegment(s, 0, fr, ref), PrimitiveStatus::Drawn);
  RenderOptions o2 = o;
  o2.segmentMethod = SegmentMethod::ScreenSpace;
  const FrameContext fs = FrameContext::make(cam, o2, BoundingSphere{Vec3f::Zero(), 1});
  ASSERT_EQ(prepareSegment(s, 0, fs, ss), PrimitiveStatus::Drawn);
  EXPECT_EQ(ss.pieceCount(), 1);
  for (int y = ref.bounds.y0; y < ref.bounds.y1; ++y)
    for (int x = ref.bounds.x0; x < ref.bounds.x1; ++x) {
      const Vec2f p(x + 0.5f, y + 0.5f);
      const double a = segmentWeightAt(ref, fr, p), b = segmentWeightAt(ss, fs, p);
      peak = std::max(peak, b);
      maxRel = std::max(maxRel, std::abs(a - b));
    }
  ASSERT_GT(peak, 0);
  EXPECT_LT(maxRel / peak, 2e-3);
  // On the axis in the middle: (1/h) * sigma * T2(0) / sigma^2 = T2(0) / (h sigma).
  const float sigma = 0.5f * s.radius;
  const Vec3f mid = cam.project(cam.toCamera(Vec3f(0, 0, 0)));
  const float expected = weightTextureT2(o.cutoffRadius, 0) / (s.radius * sigma);
  EXPECT_NEAR(segmentWeightAt(ss, fs, mid.head<2>()), expected, 2e-3f * expected);
}

}  // namespace
}  // namespace linesurf

namespace linesurf {
namespace {

// Smooth line models: with Attributes::endpointNormals a segment's shading normal is
// normalize(lerp(normal0, normal1, u)) along it; without the attribute (or with zero endpoint
// normals) the one-normal segment renders exactly as before.
TEST(SegmentSplat, EndpointNormalsInterpolateAlongTheSegment) {
  HybridModel m;
  m.attributes.normals = m.attributes.radii = true;
  Segment s;
  s.p0 = Vec3f(-1, 0, 0);
  s.p1 = Vec3f(1, 0, 0);
  s.normal = Vec3f(0, 0, 1);
  s.normal0 = Vec3f(-0.6f, 0, 0.8f);
  s.normal1 = Vec3f(0.6f, 0, 0.8f);
  s.radius = 0.1f;
  m.segments.push_back(s);
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 4), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 160, 96, 0.1f, 50);
  RenderOptions o;
  o.normalBuffer = true;
  o.perPixelLighting = false;
  const RenderResult flat = renderImage(m, cam, o);
  m.attributes.endpointNormals = true;
  const RenderResult smooth = renderImage(m, cam, o);
  ASSERT_TRUE(smooth.normal && flat.normal);
  for (float u : {0.0f, 0.25f, 0.5f, 0.75f, 1.0f}) {
    const Vec3f pc = cam.project(cam.toCamera(s.p0 + u * (s.p1 - s.p0)));
    const int x = std::clamp(int(pc.x()), 0, cam.width() - 1), y = int(pc.y());
    const Color nb = smooth.normal->at(x, y), nf = flat.normal->at(x, y);
    ASSERT_GT(nb.w(), 0) << "u " << u;
    const Vec3f got(2 * nb.x() - 1, 2 * nb.y() - 1, 2 * nb.z() - 1);
    // u of the pixel centre actually sampled
    const Vec3f ray = cam.rayThrough(x + 0.5f, y + 0.5f);
    const float uc = std::clamp((ray.x() * 4 / -ray.z() + 1) / 2, 0.0f, 1.0f);
    const Vec3f want = (cam.rotation() * (s.normal0 + uc * (s.normal1 - s.normal0))).normalized();
    EXPECT_LT((got - want).norm(), 2e-3f) << "u " << u << " got " << got.transpose() << " want " << want.transpose();
    EXPECT_NEAR(2 * nf.x() - 1, 0.0f, 1e-4f) << "one-normal segment: constant normal";
  }
  // Gouraud colour follows the interpolated normal: the two halves are lit differently.
  const Vec3f left = cam.project(cam.toCamera(Vec3f(-0.7f, 0, 0))), right = cam.project(cam.toCamera(Vec3f(0.7f, 0, 0)));
  EXPECT_GT(std::abs(smooth.color.at(int(left.x()), int(left.y())).x() - smooth.color.at(int(right.x()), int(right.y())).x()),
            0.02f);
  // Zero endpoint normals: the attribute changes nothing.
  m.segments[0].normal0 = m.segments[0].normal1 = Vec3f::Zero();
  const RenderResult zero = renderImage(m, cam, o);
  EXPECT_EQ(compareImages(flat.color, zero.color).maxAbsDiff, 0.0);
}

}  // namespace
}  // namespace linesurf
