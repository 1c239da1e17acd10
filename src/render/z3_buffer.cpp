// Modified Z^3 visibility and blending, thesis §6.2.3.1 (see z3_buffer.h and docs/decisions.md).
#include "linesurf/render/z3_buffer.h"

#include <algorithm>
#include <cmath>

#include "linesurf/render/render_options.h"

namespace linesurf {

Z3Tile::Z3Tile(const PixelRect& rect, int layers) : layers_(std::clamp(layers, 1, RenderOptions::kMaxLayers)) {
  reset(rect);
}

void Z3Tile::reset(const PixelRect& rect) {
  rect_ = rect;
  size_t pixels = rect.empty() ? 0 : size_t(rect.width()) * size_t(rect.height());
  size_t slots = pixels * size_t(layers_);
  count_.assign(pixels, 0);
  if (z_.size() < slots) {
    for (auto* v : {&z_, &thr_, &r_, &g_, &b_, &a_, &w_, &nx_, &ny_, &nz_}) v->resize(slots);
    opaque_.resize(slots);
  }
  counters_ = {};
}

// Composites the adjacent pair of layers (i, i+1) with the smallest depth gap into one (step c).
// The merged layer keeps the pair's total weight W so that later fragments merge into it in
// proportion (the thesis sets w_m = 1, which makes later merges depend on the weight scale).
void Z3Tile::compress(size_t base, int& n) {
  int best = 0;
  float bestGap = INFINITY;
  for (int i = 0; i + 1 < n; ++i) {
    float gap = z_[base + i + 1] - z_[base + i];
    if (gap < bestGap) { bestGap = gap; best = i; }
  }
  size_t f = base + size_t(best), b = f + 1;
  float iwf = 1.0f / w_[f], iwb = 1.0f / w_[b];
  float af = a_[f] * iwf, ab = a_[b] * iwb;
  float tb = ab * (1 - af);
  float am = af + tb;
  float W = w_[f] + w_[b];
  float cr = r_[f] * iwf * af + r_[b] * iwb * tb;
  float cg = g_[f] * iwf * af + g_[b] * iwb * tb;
  float cb = b_[f] * iwf * af + b_[b] * iwb * tb;
  float s = am > 0 ? W / am : 0;  // store straight colour times W
  r_[f] = cr * s; g_[f] = cg * s; b_[f] = cb * s;
  a_[f] = am * W;
  // normal of the front layer, rescaled to the new weight
  nx_[f] *= W * iwf; ny_[f] *= W * iwf; nz_[f] *= W * iwf;
  z_[f] = 0.5f * (z_[f] + z_[b]);
  thr_[f] = std::max(thr_[f], thr_[b]);
  w_[f] = W;
  opaque_[f] = am >= 1.0f;
  // remove slot b
  for (int i = best + 1; i + 1 < n; ++i) {
    size_t d = base + size_t(i), s2 = d + 1;
    z_[d] = z_[s2]; thr_[d] = thr_[s2]; r_[d] = r_[s2]; g_[d] = g_[s2]; b_[d] = b_[s2];
    a_[d] = a_[s2]; w_[d] = w_[s2]; nx_[d] = nx_[s2]; ny_[d] = ny_[s2]; nz_[d] = nz_[s2];
    opaque_[d] = opaque_[s2];
  }
  --n;
  if (opaque_[f]) n = best + 1;  // an opaque merged layer hides everything behind it
  ++counters_.compressed;
}

void Z3Tile::insert(int x, int y, const Fragment& fr) {
  if (!(fr.weight > 0)) return;
  ++counters_.fragments;
  const size_t p = index(x, y);
  const size_t base = p * size_t(layers_);
  int n = count_[p];
  const float w = fr.weight;

  // a. insertion: merge into the layer nearest in depth among those within the threshold
  int hit = -1;
  float hitDz = INFINITY;
  for (int i = 0; i < n; ++i) {
    float dz = std::abs(fr.depth - z_[base + i]);
    float t = std::max(fr.zThreshold, thr_[base + i]);
    if (dz <= t && dz < hitDz) { hit = i; hitDz = dz; }
  }
  if (hit >= 0) {
    size_t s = base + size_t(hit);
    r_[s] += w * fr.color.x(); g_[s] += w * fr.color.y(); b_[s] += w * fr.color.z();
    a_[s] += w * fr.alpha; w_[s] += w;
    nx_[s] += w * fr.normal.x(); ny_[s] += w * fr.normal.y(); nz_[s] += w * fr.normal.z();
    if (fr.alpha < 1.0f) opaque_[s] = 0;
    ++counters_.merged;
    return;
  }
  // behind an opaque layer (always the last one): occluded
  if (n > 0 && opaque_[base + n - 1] && fr.depth > z_[base + n - 1]) {
    ++counters_.occluded;
    return;
  }
  // c. compression when every layer is taken
  if (n == layers_) {
    if (n == 1) {
      // One layer: composite the fragment with it directly, in depth order.
      size_t s = base;
      float wl = w_[s], al = a_[s] / wl, af = fr.alpha;
      Vec3f cl(r_[s] / wl, g_[s] / wl, b_[s] / wl);
      bool front = fr.depth < z_[s];
      float aFront = front ? af : al, aBack = front ? al : af;
      Vec3f cFront = front ? fr.color : cl, cBack = front ? cl : fr.color;
      float am = aFront + aBack * (1 - aFront);
      Vec3f cm = cFront * aFront + cBack * (aBack * (1 - aFront));
      float W = wl + w;
      float sc = am > 0 ? W / am : 0;
      r_[s] = cm.x() * sc; g_[s] = cm.y() * sc; b_[s] = cm.z() * sc;
      a_[s] = am * W;
      if (front) { nx_[s] = fr.normal.x() * W; ny_[s] = fr.normal.y() * W; nz_[s] = fr.normal.z() * W; }
      else { nx_[s] *= W / wl; ny_[s] *= W / wl; nz_[s] *= W / wl; }
      z_[s] = 0.5f * (z_[s] + fr.depth);
      thr_[s] = std::max(thr_[s], fr.zThreshold);
      w_[s] = W;
      opaque_[s] = am >= 1.0f;
      ++counters_.compressed;
      return;
    }
    compress(base, n);
    // the compression may have produced an opaque layer in front of the fragment
    if (opaque_[base + n - 1] && fr.depth > z_[base + n - 1] + std::max(fr.zThreshold, thr_[base + n - 1])) {
      count_[p] = uint8_t(n);
      ++counters_.occluded;
      return;
    }
  }
  // b. allocation, keeping the layers sorted front to back
  int pos = n;
  while (pos > 0 && z_[base + pos - 1] > fr.depth) --pos;
  const bool opaque = fr.alpha >= 1.0f;
  if (opaque) n = pos;  // everything behind an opaque fragment is occluded: free it
  for (int i = n; i > pos; --i) {
    size_t d = base + size_t(i), s2 = d - 1;
    z_[d] = z_[s2]; thr_[d] = thr_[s2]; r_[d] = r_[s2]; g_[d] = g_[s2]; b_[d] = b_[s2];
    a_[d] = a_[s2]; w_[d] = w_[s2]; nx_[d] = nx_[s2]; ny_[d] = ny_[s2]; nz_[d] = nz_[s2];
    opaque_[d] = opaque_[s2];
  }
  size_t s = base + size_t(pos);
  z_[s] = fr.depth; thr_[s] = fr.zThreshold;
  r_[s] = w * fr.color.x(); g_[s] = w * fr.color.y(); b_[s] = w * fr.color.z();
  a_[s] = w * fr.alpha; w_[s] = w;
  nx_[s] = w * fr.normal.x(); ny_[s] = w * fr.normal.y(); nz_[s] = w * fr.normal.z();
  opaque_[s] = opaque;
  count_[p] = uint8_t(n + 1);
  ++counters_.allocated;
}

ResolvedPixel Z3Tile::resolve(int x, int y) const {
  ResolvedPixel out;
  const size_t p = index(x, y);
  const size_t base = p * size_t(layers_);
  const int n = count_[p];
  if (n == 0) return out;
  // Front-to-back "under" compositing of the normalised layers == the thesis's back-to-front merge.
  Vec3f c = Vec3f::Zero();
  float a = 0;
  for (int i = 0; i < n && a < 1.0f; ++i) {
    size_t s = base + size_t(i);
    float iw = 1.0f / w_[s];
    float al = std::clamp(a_[s] * iw, 0.0f, 1.0f);
    float t = (1 - a) * al;
    c += t * Vec3f(r_[s] * iw, g_[s] * iw, b_[s] * iw);
    a += t;
  }
  out.color = Color(c.x(), c.y(), c.z(), a);
  out.depth = z_[base];
  Vec3f nrm(nx_[base], ny_[base], nz_[base]);
  float nn = nrm.norm();
  out.normal = nn > 0 ? Vec3f(nrm / nn) : Vec3f::Zero();
  return out;
}

}  // namespace linesurf
