// Modified Z^3 visibility and blending, thesis §6.2.3.1 (see z3_buffer.h and docs/decisions.md).
#include "z3_buffer.h"

#include <algorithm>
#include <cmath>

#include "linesurf/render/render_options.h"

namespace linesurf {

Z3Tile::Z3Tile(const PixelRect& rect, int layers)
    : layers_(std::clamp(layers, 1, RenderOptions::kMaxLayers)) {
  reset(rect);
}

void Z3Tile::reset(const PixelRect& rect) {
  rect_ = rect;
  size_t pixels = rect.empty() ? 0 : size_t(rect.width()) * size_t(rect.height());
  count_.assign(pixels + kPad, 0);
  if (pixels + kPad > capacity_) {
    capacity_ = pixels + kPad;
    layerStride_ = capacity_ * kFields;
    data_.resize(layerStride_ * size_t(layers_));
  }
  counters_ = {};
  fragments_ = direct_ = 0;
  if (!coverageOccludes_) setCoverageOccludes(false);  // the behind sums sized and cleared
}

void Z3Tile::addBehind(size_t p, float w, const float* attr, float depth) {
  float* b = behind_.data() + p;
  const size_t fs = capacity_;
  const bool has = behindCount_[p] != 0;
  for (int k = 0; k < kAttrs; ++k) b[k * fs] = (has ? b[k * fs] : 0.0f) + w * attr[k];
  b[kBehindZ * fs] = (has ? b[kBehindZ * fs] : 0.0f) + w * depth;
  behindCount_[p] = 1;
}

void Z3Tile::layerBehind(size_t p, const float* layer) {
  float* b = behind_.data() + p;
  const size_t fs = capacity_;
  const bool has = behindCount_[p] != 0;
  for (int k = 0; k < kAttrs; ++k) b[k * fs] = (has ? b[k * fs] : 0.0f) + layer[k * fs];
  b[kBehindZ * fs] = (has ? b[kBehindZ * fs] : 0.0f) + layer[kZ * fs] * layer[kW * fs];
  behindCount_[p] = 1;
}

namespace {
// Moves layer s to slot d within one pixel (layers `stride` floats apart, fields `fs` apart).
inline void moveLayer(float* px, size_t stride, size_t fs, int d, int s) {
  for (int f = 0; f < Z3Tile::kFields; ++f) px[d * stride + f * fs] = px[s * stride + f * fs];
}
}  // namespace

// Composites the adjacent pair of layers (i, i+1) with the smallest depth gap into one (step c).
// The merged layer keeps the pair's total weight W so that later fragments merge into it in
// proportion (the thesis sets w_m = 1, which makes later merges depend on the weight scale).
// With deferred shading the colour sums are albedos: they are composited alike.
void Z3Tile::compress(float* px, int& n) {
  const size_t fs = capacity_;
  int best = 0;
  float bestGap = INFINITY;
  for (int i = 0; i + 1 < n; ++i) {
    const float gap = px[(i + 1) * layerStride_ + kZ * fs] - px[i * layerStride_ + kZ * fs];
    if (gap < bestGap) { bestGap = gap; best = i; }
  }
  float* F = px + best * layerStride_;
  const float* B = F + layerStride_;
  auto f = [&](int k) -> float& { return F[k * fs]; };
  auto b = [&](int k) { return B[k * fs]; };
  const float iwf = 1.0f / f(kW), iwb = 1.0f / b(kW);
  // coverage alpha: each layer's min(1, s A), the merged one stored as A = alpha / s
  const bool cov = coverage_ > 0;
  float af = cov ? layerAlpha(f(kA), iwf) : f(kA) * iwf, ab = cov ? layerAlpha(b(kA), iwb) : b(kA) * iwb;
  // tail-only layers (setTailLayers) in front of another layer: skipped, as the resolve does
  const bool tailF = f(kOpaque) < 0, tailB = b(kOpaque) < 0;
  if (tailF && !tailB) af = 0;
  if (tailB && best + 2 < n) ab = 0;
  const float tb = ab * (1 - af);
  const float am = af + tb;
  const float W = f(kW) + b(kW);
  const float s = am > 0 ? W / am : 0;  // store straight colour times W
  for (int c = kR; c <= kB; ++c) f(c) = (f(c) * iwf * af + b(c) * iwb * tb) * s;
  f(kA) = cov ? am / coverage_ : am * W;
  if (tailF && !tailB) {  // the normal of the layer behind the skipped tail
    for (int c = kNx; c <= kNz; ++c) f(c) = b(c) * W * iwb;
  } else {
    for (int c = kNx; c <= kNz; ++c) f(c) *= W * iwf;  // normal of the front layer
  }
  f(kZ) = 0.5f * (f(kZ) + b(kZ));
  f(kThr) = std::max(f(kThr), b(kThr));
  f(kW) = W;
  f(kOpaque) = tailF && tailB ? -1.0f : am >= 1.0f || !coverageOccludes() ? 1.0f : 0.0f;
  for (int i = best + 1; i + 1 < n; ++i) moveLayer(px, layerStride_, fs, i, i + 1);
  --n;
  if (f(kOpaque) > 0) {  // an opaque merged layer hides everything behind it
    if (!coverageOccludes())
      for (int i = best + 1; i < n; ++i) layerBehind(size_t(px - data_.data()), px + i * layerStride_);
    n = best + 1;
  }
  ++counters_.compressed;
}

void Z3Tile::insertNew(size_t p, float depth, float zThreshold, float w, const float* attr, bool tail) {
  float* px = data_.data() + p;
  const size_t fs = capacity_;
  auto at = [&](int layer, int k) -> float& { return px[layer * layerStride_ + k * fs]; };
  const int L = layers_;
  int n = count_[p];
  const bool cov = coverage_ > 0;
  const float alpha = cov ? std::min(w * attr[kA] * coverage_, 1.0f) : attr[kA];  // the fragment's own
  // behind an opaque layer (always the last one): occluded
  if (n > 0 && at(n - 1, kOpaque) > 0 && depth > at(n - 1, kZ)) {
    if (!coverageOccludes()) addBehind(p, w, attr, depth);
    ++counters_.occluded;
    return;
  }
  if (tailLayers() && alpha >= 1.0f && n > 0) {  // tail layers (setTailLayers)
    int pos = n;
    while (pos > 0 && at(pos - 1, kZ) > depth) --pos;
    if (tail) {  // in front of a layer: skipped; behind an opaque or tail-only one: occluded
      if (pos < n || at(n - 1, kOpaque) != 0) {
        ++counters_.occluded;
        return;
      }
    } else {  // the tail-only layers in front of it are skipped: dropped now
      int j = 0;
      for (int i = 0; i < n; ++i) {
        if (i < pos && at(i, kOpaque) < 0) continue;
        if (j != i) moveLayer(px, layerStride_, fs, j, i);
        ++j;
      }
      n = j;
      count_[p] = n;
    }
  }
  // c. compression when every layer is taken
  if (n == L) {
    if (n == 1) {
      // One layer: composite the fragment with it directly, in depth order.
      const float wl = at(0, kW), al = cov ? layerAlpha(at(0, kA), 1.0f / wl) : at(0, kA) / wl, af = alpha;
      const Vec3f cl(at(0, kR) / wl, at(0, kG) / wl, at(0, kB) / wl), cf(attr[kR], attr[kG], attr[kB]);
      const bool front = depth < at(0, kZ);
      float aFront = front ? af : al, aBack = front ? al : af;
      const bool tailL = at(0, kOpaque) < 0, tailF = tail && tailLayers() && alpha >= 1.0f;  // (setTailLayers)
      const bool skipFront = front ? tailF && !tailL : tailL && !tailF;  // a tail-only front: as the resolve
      if (skipFront) aFront = 0;
      const Vec3f cFront = front ? cf : cl, cBack = front ? cl : cf;
      const float am = aFront + aBack * (1 - aFront);
      const Vec3f cm = cFront * aFront + cBack * (aBack * (1 - aFront));
      const float W = wl + w;
      const float sc = am > 0 ? W / am : 0;
      at(0, kR) = cm.x() * sc; at(0, kG) = cm.y() * sc; at(0, kB) = cm.z() * sc;
      at(0, kA) = cov ? am / coverage_ : am * W;
      if (front != skipFront) {  // the normal of the front layer (of the one behind a skipped tail)
        at(0, kNx) = attr[kNx] * W; at(0, kNy) = attr[kNy] * W; at(0, kNz) = attr[kNz] * W;
      } else {
        at(0, kNx) *= W / wl; at(0, kNy) *= W / wl; at(0, kNz) *= W / wl;
      }
      at(0, kZ) = 0.5f * (at(0, kZ) + depth);
      at(0, kThr) = std::max(at(0, kThr), zThreshold);
      at(0, kW) = W;
      at(0, kOpaque) = tailF && tailL ? -1.0f : am >= 1.0f || !coverageOccludes() ? 1.0f : 0.0f;
      ++counters_.compressed;
      ++direct_;
      return;
    }
    compress(px, n);
    // the compression may have produced an opaque layer in front of the fragment
    if (at(n - 1, kOpaque) > 0 && depth > at(n - 1, kZ) + std::max(zThreshold, at(n - 1, kThr))) {
      count_[p] = n;
      if (!coverageOccludes()) addBehind(p, w, attr, depth);
      ++counters_.occluded;
      return;
    }
  }
  // b. allocation, keeping the layers sorted front to back
  int pos = n;
  while (pos > 0 && at(pos - 1, kZ) > depth) --pos;
  // coverage alpha: the fragment alone covers the pixel, or coverage does not decide occlusion
  const bool opaque = alpha >= 1.0f || !coverageOccludes();
  const bool tailOnly = opaque && tail && tailLayers();  // (setTailLayers) opens a layer that occludes nothing
  if (opaque && !tailOnly) {  // everything behind an opaque fragment is occluded: free it
    if (!coverageOccludes())
      for (int i = pos; i < n; ++i) layerBehind(p, px + i * layerStride_);
    n = pos;
  }
  for (int i = n; i > pos; --i) moveLayer(px, layerStride_, fs, i, i - 1);
  for (int k = 0; k < kAttrs; ++k) at(pos, k) = w * attr[k];
  at(pos, kZ) = depth;
  at(pos, kThr) = zThreshold;
  at(pos, kOpaque) = tailOnly ? -1.0f : opaque ? 1.0f : 0.0f;
  count_[p] = n + 1;
  ++counters_.allocated;
}

}  // namespace linesurf
