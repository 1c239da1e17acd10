// Modified Z^3 visibility and blending, thesis §6.2.3.1 (see z3_buffer.h and docs/decisions.md).
#include "linesurf/render/z3_buffer.h"

#include <algorithm>
#include <cmath>

#include "linesurf/render/render_options.h"

namespace linesurf {

Z3Tile::Z3Tile(const PixelRect& rect, int layers, bool keepNormals)
    : layers_(std::clamp(layers, 1, RenderOptions::kMaxLayers)), keepNormals_(keepNormals),
      stride_(size_t(kFields) * size_t(layers_)) {
  reset(rect);
}

void Z3Tile::reset(const PixelRect& rect) {
  rect_ = rect;
  size_t pixels = rect.empty() ? 0 : size_t(rect.width()) * size_t(rect.height());
  count_.assign(pixels, 0);
  if (data_.size() < pixels * stride_) data_.resize(pixels * stride_);
  counters_ = {};
}

namespace {
// Moves layer s to slot d (all fields) within one pixel block.
inline void moveLayer(float* px, int L, int d, int s) {
  for (int f = 0; f < 11; ++f) px[f * L + d] = px[f * L + s];
}
}  // namespace

// Composites the adjacent pair of layers (i, i+1) with the smallest depth gap into one (step c).
// The merged layer keeps the pair's total weight W so that later fragments merge into it in
// proportion (the thesis sets w_m = 1, which makes later merges depend on the weight scale).
void Z3Tile::compress(float* px, int& n) {
  const int L = layers_;
  float* z = px + kZ * L;
  int best = 0;
  float bestGap = INFINITY;
  for (int i = 0; i + 1 < n; ++i) {
    float gap = z[i + 1] - z[i];
    if (gap < bestGap) { bestGap = gap; best = i; }
  }
  const int f = best, b = best + 1;
  float* w = px + kW * L;
  float* a = px + kA * L;
  const float iwf = 1.0f / w[f], iwb = 1.0f / w[b];
  const float af = a[f] * iwf, ab = a[b] * iwb;
  const float tb = ab * (1 - af);
  const float am = af + tb;
  const float W = w[f] + w[b];
  const float s = am > 0 ? W / am : 0;  // store straight colour times W
  for (int c = kR; c <= kB; ++c) {
    float* ch = px + c * L;
    ch[f] = (ch[f] * iwf * af + ch[b] * iwb * tb) * s;
  }
  a[f] = am * W;
  for (int c = kNx; c <= kNz; ++c) px[c * L + f] *= W * iwf;  // normal of the front layer
  z[f] = 0.5f * (z[f] + z[b]);
  px[kThr * L + f] = std::max(px[kThr * L + f], px[kThr * L + b]);
  w[f] = W;
  px[kOpaque * L + f] = am >= 1.0f ? 1.0f : 0.0f;
  for (int i = b; i + 1 < n; ++i) moveLayer(px, L, i, i + 1);
  --n;
  if (px[kOpaque * L + f] != 0) n = f + 1;  // an opaque merged layer hides everything behind it
  ++counters_.compressed;
}

void Z3Tile::insertNew(size_t p, const Fragment& fr) {
  ++counters_.fragments;
  float* px = block(p);
  const int L = layers_;
  int n = count_[p];
  const float w = fr.weight;
  float* z = px + kZ * L;
  float* thr = px + kThr * L;
  // behind an opaque layer (always the last one): occluded
  if (n > 0 && px[kOpaque * L + n - 1] != 0 && fr.depth > z[n - 1]) {
    ++counters_.occluded;
    return;
  }
  // c. compression when every layer is taken
  if (n == L) {
    if (n == 1) {
      // One layer: composite the fragment with it directly, in depth order.
      const float wl = px[kW], al = px[kA] / wl, af = fr.alpha;
      const Vec3f cl(px[kR] / wl, px[kG] / wl, px[kB] / wl);
      const bool front = fr.depth < z[0];
      const float aFront = front ? af : al, aBack = front ? al : af;
      const Vec3f cFront = front ? fr.color : cl, cBack = front ? cl : fr.color;
      const float am = aFront + aBack * (1 - aFront);
      const Vec3f cm = cFront * aFront + cBack * (aBack * (1 - aFront));
      const float W = wl + w;
      const float sc = am > 0 ? W / am : 0;
      px[kR] = cm.x() * sc; px[kG] = cm.y() * sc; px[kB] = cm.z() * sc;
      px[kA] = am * W;
      if (front) { px[kNx] = fr.normal.x() * W; px[kNy] = fr.normal.y() * W; px[kNz] = fr.normal.z() * W; }
      else { px[kNx] *= W / wl; px[kNy] *= W / wl; px[kNz] *= W / wl; }
      z[0] = 0.5f * (z[0] + fr.depth);
      thr[0] = std::max(thr[0], fr.zThreshold);
      px[kW] = W;
      px[kOpaque] = am >= 1.0f ? 1.0f : 0.0f;
      ++counters_.compressed;
      return;
    }
    compress(px, n);
    // the compression may have produced an opaque layer in front of the fragment
    if (px[kOpaque * L + n - 1] != 0 && fr.depth > z[n - 1] + std::max(fr.zThreshold, thr[n - 1])) {
      count_[p] = uint8_t(n);
      ++counters_.occluded;
      return;
    }
  }
  // b. allocation, keeping the layers sorted front to back
  int pos = n;
  while (pos > 0 && z[pos - 1] > fr.depth) --pos;
  const bool opaque = fr.alpha >= 1.0f;
  if (opaque) n = pos;  // everything behind an opaque fragment is occluded: free it
  for (int i = n; i > pos; --i) moveLayer(px, L, i, i - 1);
  z[pos] = fr.depth;
  thr[pos] = fr.zThreshold;
  px[kR * L + pos] = w * fr.color.x();
  px[kG * L + pos] = w * fr.color.y();
  px[kB * L + pos] = w * fr.color.z();
  px[kA * L + pos] = w * fr.alpha;
  px[kW * L + pos] = w;
  px[kNx * L + pos] = w * fr.normal.x();
  px[kNy * L + pos] = w * fr.normal.y();
  px[kNz * L + pos] = w * fr.normal.z();
  px[kOpaque * L + pos] = opaque ? 1.0f : 0.0f;
  count_[p] = uint8_t(n + 1);
  ++counters_.allocated;
}

ResolvedPixel Z3Tile::resolve(int x, int y) const {
  ResolvedPixel out;
  const size_t p = index(x, y);
  const int n = count_[p];
  if (n == 0) return out;
  const float* px = block(p);
  const int L = layers_;
  // Front-to-back "under" compositing of the normalised layers == the thesis's back-to-front merge.
  Vec3f c = Vec3f::Zero();
  float a = 0;
  for (int i = 0; i < n && a < 1.0f; ++i) {
    const float iw = 1.0f / px[kW * L + i];
    const float al = std::clamp(px[kA * L + i] * iw, 0.0f, 1.0f);
    const float t = (1 - a) * al;
    c += t * iw * Vec3f(px[kR * L + i], px[kG * L + i], px[kB * L + i]);
    a += t;
  }
  out.color = Color(c.x(), c.y(), c.z(), a);
  out.depth = px[kZ * L];
  Vec3f nrm(px[kNx * L], px[kNy * L], px[kNz * L]);
  const float nn = nrm.norm();
  out.normal = nn > 0 ? Vec3f(nrm / nn) : Vec3f::Zero();
  return out;
}

}  // namespace linesurf
