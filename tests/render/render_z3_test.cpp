// Modified Z^3 buffer (thesis §6.2.3.1): insertion, allocation, occlusion, compression, resolve.
#include <gtest/gtest.h>

#include "render/z3_buffer.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "render/point_rows.h"
#include "render/segment_rows.h"
#include "render/resolve.h"

namespace linesurf {
namespace {

Fragment frag(float depth, Vec3f color, float weight, float alpha = 1, float thr = 0.1f) {
  Fragment f;
  f.depth = depth;
  f.zThreshold = thr;
  f.color = color;
  f.weight = weight;
  f.alpha = alpha;
  f.normal = Vec3f(0, 0, 1);
  return f;
}

TEST(RenderZ3, FragmentsWithinThresholdBlendByWeight) {
  Z3Tile t({0, 0, 4, 4}, 4);
  t.insert(1, 2, frag(1.0f, Vec3f(1, 0, 0), 3));
  t.insert(1, 2, frag(1.05f, Vec3f(0, 0, 1), 1));
  EXPECT_EQ(t.layerCount(1, 2), 1);
  ResolvedPixel p = t.resolve(1, 2);
  EXPECT_NEAR(p.color.x(), 0.75f, 1e-6f);
  EXPECT_NEAR(p.color.z(), 0.25f, 1e-6f);
  EXPECT_NEAR(p.color.w(), 1.0f, 1e-6f);
  EXPECT_FLOAT_EQ(p.depth, 1.0f);  // the layer keeps its first depth (thesis step a)
  EXPECT_EQ(t.layerCount(0, 0), 0);
  EXPECT_EQ(t.resolve(0, 0).color.w(), 0.0f);
}

TEST(RenderZ3, OpaqueFrontFragmentHidesSurfacesBehindInAnyOrder) {
  for (int order = 0; order < 2; ++order) {
    Z3Tile t({0, 0, 1, 1}, 4);
    Fragment front = frag(1.0f, Vec3f(1, 0, 0), 1), back = frag(2.0f, Vec3f(0, 1, 0), 5);
    if (order == 0) { t.insert(0, 0, front); t.insert(0, 0, back); }
    else { t.insert(0, 0, back); t.insert(0, 0, front); }
    EXPECT_EQ(t.layerCount(0, 0), 1) << order;
    ResolvedPixel p = t.resolve(0, 0);
    EXPECT_NEAR((p.color - Color(1, 0, 0, 1)).norm(), 0.0f, 1e-6f) << order;
  }
}

// Tail layers (Z3Tile::setTailLayers, beyond the thesis; docs/decisions.md "Tail layers"): a
// prefilter tail occludes nothing. attr: colour c, alpha 1, weight 1, normal +z.
void insertTail(Z3Tile& t, float depth, Vec3f c, float w, bool tail, float thr = 0.1f) {
  const float attr[Z3Tile::kAttrs] = {c.x(), c.y(), c.z(), 1, 1, 0, 0, 1};
  t.insert(0, 0, depth, thr, w, attr, tail);
}

TEST(RenderZ3, TailInFrontOfASurfaceDoesNotHideItInAnyOrder) {
  for (int order = 0; order < 2; ++order) {
    for (bool tails : {false, true}) {
      Z3Tile t({0, 0, 1, 1}, 4);
      t.setTailLayers(tails);
      if (order == 0) {  // the tail first: it opens a tail-only layer, the surface behind drops it
        insertTail(t, 1.0f, Vec3f(1, 0, 0), 0.01f, true);
        insertTail(t, 3.0f, Vec3f(0, 0, 1), 2.0f, false);
      } else {  // the surface first: the tail in front of it is skipped
        insertTail(t, 3.0f, Vec3f(0, 0, 1), 2.0f, false);
        insertTail(t, 1.0f, Vec3f(1, 0, 0), 0.01f, true);
      }
      EXPECT_EQ(t.layerCount(0, 0), 1) << order << tails;
      const ResolvedPixel p = t.resolve(0, 0);
      // without tail layers the tail is the opaque front layer (the fold speckle)
      const Color want = tails ? Color(0, 0, 1, 1) : Color(1, 0, 0, 1);
      EXPECT_NEAR((p.color - want).norm(), 0.0f, 1e-6f) << order << tails;
      EXPECT_FLOAT_EQ(p.depth, tails ? 3.0f : 1.0f);
    }
  }
}

TEST(RenderZ3, TailOnlyLayerIsResolvedOverTheBackground) {
  // a silhouette's anti-aliasing: a pixel that only a tail reaches keeps it, as without tail layers
  for (bool tails : {false, true}) {
    Z3Tile t({0, 0, 1, 1}, 4);
    t.setTailLayers(tails);
    insertTail(t, 2.0f, Vec3f(0.2f, 0.4f, 0.6f), 0.05f, true);
    insertTail(t, 2.05f, Vec3f(0.6f, 0.4f, 0.2f), 0.05f, true);  // merges (step a)
    EXPECT_EQ(t.layerCount(0, 0), 1);
    const ResolvedPixel p = t.resolve(0, 0);
    EXPECT_NEAR((p.color - Color(0.4f, 0.4f, 0.4f, 1)).norm(), 0.0f, 1e-6f) << tails;
  }
}

TEST(RenderZ3, SurfaceMergingIntoATailLayerMakesItOcclude) {
  Z3Tile t({0, 0, 1, 1}, 4);
  t.setTailLayers(true);
  insertTail(t, 1.0f, Vec3f(1, 0, 0), 0.1f, true);
  insertTail(t, 4.0f, Vec3f(0, 1, 0), 1.0f, true);    // a tail behind a tail-only layer: occluded
  EXPECT_EQ(t.layerCount(0, 0), 1);
  insertTail(t, 1.05f, Vec3f(1, 0, 0), 1.0f, false);  // the surface itself: the layer occludes now
  insertTail(t, 3.0f, Vec3f(0, 0, 1), 5.0f, false);   // behind an opaque layer: occluded
  EXPECT_EQ(t.layerCount(0, 0), 1);
  EXPECT_NEAR((t.resolve(0, 0).color - Color(1, 0, 0, 1)).norm(), 0.0f, 1e-6f);
  // coverage alpha decides occlusion itself: no tail layers there
  t.setCoverageScale(1.0f);
  EXPECT_FALSE(t.tailLayers());
}

TEST(RenderZ3, TransparentLayersCompositeBackToFront) {
  Z3Tile t({0, 0, 1, 1}, 4);
  t.insert(0, 0, frag(3.0f, Vec3f(0, 0, 1), 1, 1.0f));   // opaque blue far
  t.insert(0, 0, frag(1.0f, Vec3f(1, 0, 0), 2, 0.5f));   // half red near
  t.insert(0, 0, frag(2.0f, Vec3f(0, 1, 0), 7, 0.5f));   // half green middle
  EXPECT_EQ(t.layerCount(0, 0), 3);
  ResolvedPixel p = t.resolve(0, 0);
  // red over green over blue: 0.5 red, 0.25 green, 0.25 blue
  EXPECT_NEAR(p.color.x(), 0.5f, 1e-6f);
  EXPECT_NEAR(p.color.y(), 0.25f, 1e-6f);
  EXPECT_NEAR(p.color.z(), 0.25f, 1e-6f);
  EXPECT_NEAR(p.color.w(), 1.0f, 1e-6f);
}

TEST(RenderZ3, CompressionKeepsCompositeWhenLayersRunOut) {
  // Three transparent layers in a 2-layer buffer: the closest pair in depth is composited.
  Z3Tile t({0, 0, 1, 1}, 2);
  t.insert(0, 0, frag(1.0f, Vec3f(1, 0, 0), 1, 0.5f));
  t.insert(0, 0, frag(1.5f, Vec3f(0, 1, 0), 1, 0.5f));
  t.insert(0, 0, frag(4.0f, Vec3f(0, 0, 1), 1, 1.0f));
  EXPECT_EQ(t.layerCount(0, 0), 2);
  EXPECT_EQ(t.counters().compressed, 1u);
  ResolvedPixel p = t.resolve(0, 0);
  EXPECT_NEAR(p.color.x(), 0.5f, 1e-6f);
  EXPECT_NEAR(p.color.y(), 0.25f, 1e-6f);
  EXPECT_NEAR(p.color.z(), 0.25f, 1e-6f);
}

TEST(RenderZ3, ZeroWeightIsIgnoredAndResetClears) {
  Z3Tile t({10, 20, 12, 22}, 3);
  t.insert(11, 21, frag(1.0f, Vec3f(1, 1, 1), 0));
  EXPECT_EQ(t.layerCount(11, 21), 0);
  t.insert(11, 21, frag(1.0f, Vec3f(1, 1, 1), 1));
  EXPECT_EQ(t.layerCount(11, 21), 1);
  t.reset({0, 0, 2, 2});
  EXPECT_EQ(t.layerCount(1, 1), 0);
  EXPECT_EQ(t.counters().fragments, 0u);
}

// The SIMD rows' Z^3 fast path (open / merge in SIMD, the rest through insert) leaves the same
// layers as inserting the same fragments one by one through the scalar insert: overlapping
// splats at several depths, opaque and translucent, flat and Gouraud, any layer count, so that
// merges, allocations in front and behind, occlusion and compression all occur.
TEST(RenderZ3, SimdFastPathGivesTheLayersOfTheScalarPath) {
  // cutoff^2 4: the rows' polynomial exp; 9: hn::Exp (simd_rows-inl.h, kPolyExpMaxQ)
  for (float cutoffQ : {4.0f, 9.0f})
  for (int layers : {1, 2, 4}) {
    std::mt19937 rng(7 + layers);
    std::uniform_real_distribution<float> U(0, 1);
    const PixelRect tile{16, 8, 16 + 37, 8 + 23};  // width not a multiple of any vector
    Z3Tile fast(tile, layers), scalar(tile, layers);
    uint64_t inserted = 0, reference = 0;
    for (int k = 0; k < 60; ++k) {
      const float cx = 12 + 45 * U(rng), cy = 5 + 30 * U(rng), R = 0.6f + 7 * U(rng);
      const float depth = 1 + 0.3f * float(k % 5) + 0.02f * U(rng), tilt = 0.004f * (U(rng) - 0.5f);
      detail::PointRaster P;  // a plane facing the camera, slightly tilted: N = -(1 + tilt x)
      P.N = {-tilt, 0, -1};
      P.S = {-1 / R, 0, cx / R};
      P.T = {0, -1 / R, cy / R};
      P.depthNum = -depth;
      P.cutoffQ = cutoffQ;
      P.weightScale = 0.5f + U(rng);
      float attr[Z3Tile::kAttrs] = {U(rng), U(rng), U(rng), k % 2 == 1 ? 0.5f : 1.0f, 1, 0, 0, 1};
      const float C0[3] = {U(rng), U(rng), U(rng)}, Cs[3] = {0.1f, -0.05f, 0.02f}, Ct[3] = {-0.03f, 0.04f, 0.1f},
                  Cst[3] = {0.01f, 0.02f, -0.01f};
      detail::PointShade shade{attr, 0.03f + 0.1f * U(rng), k % 3 == 0, C0, Cs, Ct, Cst};
      const PixelRect r = PixelRect{int(cx - 2 * R) - 1, int(cy - 2 * R) - 1, int(cx + 2 * R) + 2, int(cy + 2 * R) + 2}.intersect(tile);
      if (r.empty()) continue;
      inserted += detail::pointRowsZ3(P, shade, r, fast);
      detail::FragmentBlock fb;
      const int W = r.width(), total = W * r.height();
      for (int k0 = 0; k0 < total; k0 += detail::kBlock) {
        const int m = detail::pointFragments(P, r.x0, r.y0, W, k0, std::min(detail::kBlock, total - k0), true, fb);
        for (int i = 0; i < m; ++i) {
          float a[Z3Tile::kAttrs];
          std::copy(attr, attr + Z3Tile::kAttrs, a);
          if (shade.gouraud)
            for (int c = 0; c < 3; ++c) a[c] = C0[c] + fb.p[i] * Cs[c] + fb.q[i] * Ct[c] + (fb.p[i] * fb.q[i]) * Cst[c];
          scalar.insert(int(fb.x[i]), int(fb.y[i]), fb.depth[i], shade.zThreshold, fb.weight[i], a);
        }
        reference += uint64_t(m);
      }
    }
    EXPECT_EQ(inserted, reference);
    EXPECT_GT(reference, 2000u);
    fast.addFragments(inserted);
    scalar.addFragments(reference);
    const Z3Counters a = fast.counters(), b = scalar.counters();
    EXPECT_EQ(a.allocated, b.allocated) << layers;
    EXPECT_EQ(a.occluded, b.occluded) << layers;
    EXPECT_EQ(a.compressed, b.compressed) << layers;
    EXPECT_GT(a.merged, 500u) << layers;  // both paths ran
    EXPECT_GT(a.allocated, 0u);
    if (layers > 1) { EXPECT_GT(a.occluded, 0u) << layers; }
    EXPECT_GT(a.compressed, 0u) << layers;
    int multi = 0;
    for (int y = tile.y0; y < tile.y1; ++y)
      for (int x = tile.x0; x < tile.x1; ++x) {
        ASSERT_EQ(fast.layerCount(x, y), scalar.layerCount(x, y)) << x << "," << y;
        multi += fast.layerCount(x, y) > 1;
        for (int l = 0; l < fast.layerCount(x, y); ++l)
          for (int f = 0; f < Z3Tile::kFields; ++f) {
            const float u = fast.plane(l, f)[fast.index(x, y)], v = scalar.plane(l, f)[scalar.index(x, y)];
            EXPECT_NEAR(u, v, 1e-5f * std::max(1.0f, std::abs(v))) << x << "," << y << " layer " << l << " field " << f;
          }
      }
    if (layers > 1) { EXPECT_GT(multi, 10) << layers; }
  }
}

// The SIMD point kernel (pointFragments, shared with the rows: reciprocal estimate + Newton step
// for 1/N, a polynomial for exp(-q/2) when q <= 4) against the closed form in double on a tilted
// plane: every pixel centre with q clearly inside the cutoff and none clearly outside is a
// fragment, with the Gaussian weight, depth and plane coordinates to float accuracy.
TEST(RenderZ3, PointKernelIsTheGaussianOfThePlaneCoordinates) {
  for (float cutoffQ : {4.0f, 2.25f, 9.0f}) {
    detail::PointRaster P;
    P.N = {-0.004f, 0.002f, -1.1f};
    P.S = {-1 / 3.1f, 0.05f, 20 / 3.1f};
    P.T = {0.03f, -1 / 2.7f, 17 / 2.7f};
    P.depthNum = -2.3f;
    P.cutoffQ = cutoffQ;
    P.weightScale = 0.8f;
    const int x0 = 4, y0 = 3, W = 30, H = 30;
    detail::FragmentBlock fb;
    int inside = 0, found = 0;
    double maxWeightErr = 0, maxDepthErr = 0, maxPlaneErr = 0;
    for (int k0 = 0; k0 < W * H; k0 += detail::kBlock) {
      const int n = std::min(detail::kBlock, W * H - k0);
      const int m = detail::pointFragments(P, x0, y0, W, k0, n, true, fb);
      found += m;
      for (int i = 0; i < m; ++i) {
        const double x = fb.x[i], y = fb.y[i];
        const double N = double(P.N.dx) * x + double(P.N.dy) * y + double(P.N.c);
        const double s = (double(P.S.dx) * x + double(P.S.dy) * y + double(P.S.c)) / N;
        const double t = (double(P.T.dx) * x + double(P.T.dy) * y + double(P.T.c)) / N;
        const double q = s * s + t * t;
        ASSERT_LE(q, cutoffQ * (1 + 1e-4)) << x << "," << y;
        maxWeightErr = std::max(maxWeightErr, std::abs(fb.weight[i] - std::exp(-q / 2) * P.weightScale) / P.weightScale);
        maxDepthErr = std::max(maxDepthErr, std::abs(fb.depth[i] - P.depthNum / N) / std::abs(P.depthNum / N));
        maxPlaneErr = std::max(maxPlaneErr, std::max(std::abs(fb.p[i] - s), std::abs(fb.q[i] - t)));
      }
      for (int k = k0; k < k0 + n; ++k) {  // the pixels clearly inside
        const double x = x0 + k % W + 0.5, y = y0 + k / W + 0.5;
        const double N = double(P.N.dx) * x + double(P.N.dy) * y + double(P.N.c);
        const double s = (double(P.S.dx) * x + double(P.S.dy) * y + double(P.S.c)) / N;
        const double t = (double(P.T.dx) * x + double(P.T.dy) * y + double(P.T.c)) / N;
        inside += s * s + t * t <= cutoffQ * (1 - 1e-4);
      }
    }
    EXPECT_GT(inside, 60) << cutoffQ;
    EXPECT_GE(found, inside) << cutoffQ;
    EXPECT_LE(found, inside + 4) << cutoffQ;  // at most a few pixels on the cutoff's edge itself
    EXPECT_LT(maxWeightErr, 1e-5) << cutoffQ;
    EXPECT_LT(maxDepthErr, 1e-6) << cutoffQ;
    EXPECT_LT(maxPlaneErr, 1e-5) << cutoffQ;
  }
}

}  // namespace
}  // namespace linesurf
