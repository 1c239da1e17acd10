// Line-segment splats (thesis §5): points vs segments on the same surface, the three filter
// evaluations against each other, the Approx construction's cases, degenerate segments.
#include "linesurf/render/segment_splat.h"

#include <gtest/gtest.h>

#include <cmath>

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

RenderOptions optionsFor(SegmentMethod m) {
  RenderOptions o;
  o.segmentMethod = m;
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
  const Image ref = renderImage(pair.points, cam, optionsFor(SegmentMethod::ScreenSpace)).color;
  for (SegmentMethod m : kMethods) {
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
  const Image ref = renderImage(pair.points, cam).color;
  for (SegmentMethod m : {SegmentMethod::ScreenSpace, SegmentMethod::Approx}) {
    const ImageMetrics im = compareImages(ref, renderImage(hybrid, cam, optionsFor(m)).color);
    EXPECT_LT(im.meanAbsDiff, 1.0) << name(m);
  }
}

}  // namespace
}  // namespace linesurf
