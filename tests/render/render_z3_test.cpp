// Modified Z^3 buffer (thesis §6.2.3.1): insertion, allocation, occlusion, compression, resolve.
#include <gtest/gtest.h>

#include "linesurf/render/z3_buffer.h"

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

}  // namespace
}  // namespace linesurf
