// Modified Z^3 visibility and blending, thesis §6.2.3.1 (see z3_buffer.h and docs/decisions.md).
#include "linesurf/render/z3_buffer.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "linesurf/render/render_options.h"

namespace linesurf {

Z3Tile::Z3Tile(const PixelRect& rect, int layers)
    : layers_(std::clamp(layers, 1, RenderOptions::kMaxLayers)) {
  reset(rect);
}

void Z3Tile::reset(const PixelRect& rect) {
  rect_ = rect;
  size_t pixels = rect.empty() ? 0 : size_t(rect.width()) * size_t(rect.height());
  count_.assign(pixels, 0);
  if (pixels > capacity_) {
    capacity_ = pixels;
    layerStride_ = capacity_ * kStride;
    data_.resize(layerStride_ * size_t(layers_));
  }
  counters_ = {};
  fragments_ = direct_ = 0;
}

namespace {
constexpr int kRecord = 16;  // floats per layer record (Z3Tile::kStride)
// Moves layer s to slot d within one pixel (layers `stride` floats apart).
inline void moveLayer(float* px, size_t stride, int d, int s) {
  std::memcpy(px + d * stride, px + s * stride, sizeof(float) * kRecord);
}
}  // namespace

// Composites the adjacent pair of layers (i, i+1) with the smallest depth gap into one (step c).
// The merged layer keeps the pair's total weight W so that later fragments merge into it in
// proportion (the thesis sets w_m = 1, which makes later merges depend on the weight scale).
// With deferred shading the colour sums are albedos: they are composited alike.
void Z3Tile::compress(float* px, int& n) {
  int best = 0;
  float bestGap = INFINITY;
  for (int i = 0; i + 1 < n; ++i) {
    const float gap = px[(i + 1) * layerStride_ + kZ] - px[i * layerStride_ + kZ];
    if (gap < bestGap) { bestGap = gap; best = i; }
  }
  float* F = px + best * layerStride_;
  const float* B = F + layerStride_;
  const float iwf = 1.0f / F[kW], iwb = 1.0f / B[kW];
  const float af = F[kA] * iwf, ab = B[kA] * iwb;
  const float tb = ab * (1 - af);
  const float am = af + tb;
  const float W = F[kW] + B[kW];
  const float s = am > 0 ? W / am : 0;  // store straight colour times W
  for (int c = kR; c <= kB; ++c) F[c] = (F[c] * iwf * af + B[c] * iwb * tb) * s;
  F[kA] = am * W;
  for (int c = kNx; c <= kNz; ++c) F[c] *= W * iwf;  // normal of the front layer
  F[kZ] = 0.5f * (F[kZ] + B[kZ]);
  F[kThr] = std::max(F[kThr], B[kThr]);
  F[kW] = W;
  F[kOpaque] = am >= 1.0f ? 1.0f : 0.0f;
  for (int i = best + 1; i + 1 < n; ++i) moveLayer(px, layerStride_, i, i + 1);
  --n;
  if (F[kOpaque] != 0) n = best + 1;  // an opaque merged layer hides everything behind it
  ++counters_.compressed;
}

void Z3Tile::insertNew(size_t p, float depth, float zThreshold, float w, const float* attr) {
  float* px = block(p);
  const int L = layers_;
  int n = count_[p];
  const float alpha = attr[kA];
  // behind an opaque layer (always the last one): occluded
  if (n > 0 && px[(n - 1) * layerStride_ + kOpaque] != 0 && depth > px[(n - 1) * layerStride_ + kZ]) {
    ++counters_.occluded;
    return;
  }
  // c. compression when every layer is taken
  if (n == L) {
    if (n == 1) {
      // One layer: composite the fragment with it directly, in depth order.
      const float wl = px[kW], al = px[kA] / wl, af = alpha;
      const Vec3f cl(px[kR] / wl, px[kG] / wl, px[kB] / wl), cf(attr[kR], attr[kG], attr[kB]);
      const bool front = depth < px[kZ];
      const float aFront = front ? af : al, aBack = front ? al : af;
      const Vec3f cFront = front ? cf : cl, cBack = front ? cl : cf;
      const float am = aFront + aBack * (1 - aFront);
      const Vec3f cm = cFront * aFront + cBack * (aBack * (1 - aFront));
      const float W = wl + w;
      const float sc = am > 0 ? W / am : 0;
      px[kR] = cm.x() * sc; px[kG] = cm.y() * sc; px[kB] = cm.z() * sc;
      px[kA] = am * W;
      if (front) { px[kNx] = attr[kNx] * W; px[kNy] = attr[kNy] * W; px[kNz] = attr[kNz] * W; }
      else { px[kNx] *= W / wl; px[kNy] *= W / wl; px[kNz] *= W / wl; }
      px[kZ] = 0.5f * (px[kZ] + depth);
      px[kThr] = std::max(px[kThr], zThreshold);
      px[kW] = W;
      px[kOpaque] = am >= 1.0f ? 1.0f : 0.0f;
      ++counters_.compressed;
      ++direct_;
      return;
    }
    compress(px, n);
    // the compression may have produced an opaque layer in front of the fragment
    const float* last = px + (n - 1) * layerStride_;
    if (last[kOpaque] != 0 && depth > last[kZ] + std::max(zThreshold, last[kThr])) {
      count_[p] = uint8_t(n);
      ++counters_.occluded;
      return;
    }
  }
  // b. allocation, keeping the layers sorted front to back
  int pos = n;
  while (pos > 0 && px[(pos - 1) * layerStride_ + kZ] > depth) --pos;
  const bool opaque = alpha >= 1.0f;
  if (opaque) n = pos;  // everything behind an opaque fragment is occluded: free it
  for (int i = n; i > pos; --i) moveLayer(px, layerStride_, i, i - 1);
  float* ly = px + pos * layerStride_;
  for (int k = 0; k < kAttrs; ++k) ly[k] = w * attr[k];
  ly[kZ] = depth;
  ly[kThr] = zThreshold;
  ly[kOpaque] = opaque ? 1.0f : 0.0f;
  count_[p] = uint8_t(n + 1);
  ++counters_.allocated;
}

}  // namespace linesurf
