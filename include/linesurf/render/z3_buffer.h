#pragma once
/// Visibility and blending by the modified Z^3 algorithm, thesis §6.2.3.1 (after Jouppi & Chang
/// 1999), on one screen tile. Every rasteriser (point splats, segment splats) produces Fragments
/// and calls Z3Tile::insert; the tile resolves its pixels back-to-front at the end.
///
/// Per pixel, up to `layers` fragment layers sorted front to back, each holding the weighted
/// sums  C = sum w c,  A = sum w a,  W = sum w,  N = sum w n  and a depth z with a z threshold:
///  a. insertion: a fragment within the z threshold of a layer is merged into it (sums added;
///     the layer keeps its depth, thesis step a);
///  b. allocation: otherwise it gets a new layer, kept sorted; an opaque layer frees (and from
///     then on rejects) everything farther than its own threshold (step b);
///  c. compression: when all layers are taken, the two nearest (front-most) layers are
///     composited into one (normalised colours, "over" operator, W = 1; step c);
///  2. resolve: layers normalised (C/W, A/W), lit when shading is deferred (C is then the
///     weighted albedo, lit once per layer with the normalised N), composited back to front.
/// Storage: a fixed number of layers per pixel, one 64-byte record per layer whose first eight
/// floats are the blended sums, so a merge is one 8-wide multiply-add (no allocation per fragment);
/// layer-major, so that the front layers of a tile (nearly every access) are dense.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "linesurf/core/image.h"
#include "linesurf/core/math.h"

namespace linesurf {

/// A rectangle of pixels [x0, x1) x [y0, y1).
struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  PixelRect intersect(const PixelRect& o) const {
    PixelRect r{x0 > o.x0 ? x0 : o.x0, y0 > o.y0 ? y0 : o.y0, x1 < o.x1 ? x1 : o.x1, y1 < o.y1 ? y1 : o.y1};
    return r;
  }
};

/// One fragment produced by a rasteriser at one pixel.
struct Fragment {
  float depth = 0;        ///< linear camera depth (camera.h), > 0
  float zThreshold = 0;   ///< merge tolerance in depth units (FrameContext::zThreshold)
  Vec3f color = Vec3f::Zero();   ///< linear RGB, straight: shaded, or the albedo when shading is deferred
  float alpha = 1;        ///< opacity in [0, 1]; 1 = opaque
  float weight = 0;       ///< resampling-filter weight (> 0; fragments with weight <= 0 are ignored)
  Vec3f normal = Vec3f::Zero();  ///< camera-space unit normal (deferred lighting, normal buffer; may be zero)
};

/// Counters of one tile (summed into RenderStats).
struct Z3Counters {
  uint64_t fragments = 0;   ///< insertions with positive weight
  uint64_t merged = 0;      ///< merged into an existing layer (step a)
  uint64_t allocated = 0;   ///< started a new layer (step b)
  uint64_t occluded = 0;    ///< rejected behind an opaque layer
  uint64_t compressed = 0;  ///< layer compressions (step c)
};

/// The resolved value of one pixel.
struct ResolvedPixel {
  Color color = Color(0, 0, 0, 0);  ///< premultiplied RGB and coverage alpha (before background)
  float depth = 0;                  ///< depth of the nearest layer, 0 when empty
  Vec3f normal = Vec3f::Zero();     ///< normalised weighted normal of the nearest layer
};

class Z3Tile {
 public:
  /// The blended attributes of a fragment, in the order a layer stores their weighted sums:
  /// colour (or albedo), alpha, 1 (the weight itself), normal.
  enum Attr { kR, kG, kB, kA, kW, kNx, kNy, kNz, kAttrs };
  /// A tile covering `rect` with `layers` layers per pixel (1..RenderOptions::kMaxLayers).
  Z3Tile(const PixelRect& rect, int layers);
  /// Clears the tile and moves it to `rect` (no reallocation when it is not larger).
  void reset(const PixelRect& rect);

  const PixelRect& rect() const { return rect_; }
  int layers() const { return layers_; }

  /// Inserts a fragment at absolute pixel (x, y), which must lie inside rect(): weight > 0 (else
  /// ignored), linear depth, z threshold, attr[kAttrs] = (r, g, b, alpha, 1, nx, ny, nz).
  /// The common case (merge into an existing layer, step a) is inline. The caller counts the
  /// fragments of positive weight it inserts (addFragments): no counter update per fragment.
  void insert(int x, int y, float depth, float zThreshold, float weight, const float* attr) {
    if (!(weight > 0)) return;
    const size_t p = index(x, y);
    float* px = block(p);
    const int n = count_[p];
    if (n == 0) {  // the pixel's first fragment opens its first layer (step b, inline)
      for (int k = 0; k < kAttrs; ++k) px[k] = weight * attr[k];
      px[kZ] = depth;
      px[kThr] = zThreshold;
      px[kOpaque] = attr[kA] >= 1.0f ? 1.0f : 0.0f;
      count_[p] = 1;
      ++counters_.allocated;
      return;
    }
    int hit = -1;
    float hitDz = INFINITY;
    for (int i = 0; i < n; ++i) {
      const float* ly = px + i * layerStride_;
      const float dz = std::abs(depth - ly[kZ]);
      const float t = zThreshold > ly[kThr] ? zThreshold : ly[kThr];
      if (dz <= t && dz < hitDz) { hit = i; hitDz = dz; }
    }
    if (hit < 0) return insertNew(p, depth, zThreshold, weight, attr);
    float* ly = px + hit * layerStride_;
#if defined(__SSE2__)
    const __m128 wv = _mm_set1_ps(weight);  // the sums: two 4-wide multiply-adds
    _mm_storeu_ps(ly, _mm_add_ps(_mm_loadu_ps(ly), _mm_mul_ps(wv, _mm_loadu_ps(attr))));
    _mm_storeu_ps(ly + 4, _mm_add_ps(_mm_loadu_ps(ly + 4), _mm_mul_ps(wv, _mm_loadu_ps(attr + 4))));
#else
    for (int k = 0; k < kAttrs; ++k) ly[k] += weight * attr[k];
#endif
    if (attr[kA] < 1.0f) ly[kOpaque] = 0;
  }
  void addFragments(uint64_t n) { fragments_ += n; }
  /// The same for one Fragment, counted.
  void insert(int x, int y, const Fragment& f) {
    const float attr[kAttrs] = {f.color.x(), f.color.y(), f.color.z(), f.alpha, 1.0f, f.normal.x(), f.normal.y(), f.normal.z()};
    insert(x, y, f.depth, f.zThreshold, f.weight, attr);
    if (f.weight > 0) addFragments(1);
  }

  /// Resolves pixel (x, y) (absolute, inside rect()): front-to-back "under" compositing of its
  /// normalised layers (== the thesis's back-to-front merge). Layer colours as stored.
  ResolvedPixel resolve(int x, int y) const {
    return resolve(x, y, [](const Vec3f& c, const Vec3f&, float) { return c; });
  }
  /// The same with deferred shading: each layer's colour is shade(albedo, normal sum (not
  /// normalised), layer depth).
  template <class Shade>
  ResolvedPixel resolve(int x, int y, Shade&& shade) const {
    ResolvedPixel out;
    const size_t p = index(x, y);
    const int n = count_[p];
    if (n == 0) return out;
    const float* px = block(p);
    Vec3f c = Vec3f::Zero();
    float a = 0;
    for (int i = 0; i < n && a < 1.0f; ++i) {
      const float* ly = px + i * layerStride_;
      const float iw = 1.0f / ly[kW];
      const float al = std::clamp(ly[kA] * iw, 0.0f, 1.0f);
      const float t = (1 - a) * al;
      c += t * shade(Vec3f(ly[kR] * iw, ly[kG] * iw, ly[kB] * iw), Vec3f(ly[kNx], ly[kNy], ly[kNz]), ly[kZ]);
      a += t;
    }
    out.color = Color(c.x(), c.y(), c.z(), a);
    out.depth = px[kZ];
    const Vec3f nrm(px[kNx], px[kNy], px[kNz]);
    const float nn = nrm.norm();
    out.normal = nn > 0 ? Vec3f(nrm / nn) : Vec3f::Zero();
    return out;
  }
  /// Number of layers in use at (x, y).
  int layerCount(int x, int y) const { return count_[index(x, y)]; }

  /// merged = fragments that neither opened a layer, nor were occluded, nor were composited
  /// directly into a single full layer.
  Z3Counters counters() const {
    Z3Counters c = counters_;
    c.fragments = fragments_;
    c.merged = fragments_ - c.allocated - c.occluded - direct_;
    return c;
  }

 private:
  // Layer record: the kAttrs sums, then depth, threshold and the opaque flag; 16 floats.
  enum Field { kZ = kAttrs, kThr, kOpaque, kStride = 16 };
  size_t index(int x, int y) const { return size_t(y - rect_.y0) * size_t(rect_.width()) + size_t(x - rect_.x0); }
  // Layer-major: the records of layer i of all pixels are contiguous (layerStride_ floats per
  // layer), so the front layers of neighbouring pixels share cache lines' neighbourhoods and pages.
  float* block(size_t pixel) { return data_.data() + pixel * kStride; }
  const float* block(size_t pixel) const { return data_.data() + pixel * kStride; }
  void compress(float* px, int& n);
  void insertNew(size_t pixel, float depth, float zThreshold, float weight, const float* attr);  // steps b and c
  PixelRect rect_;
  int layers_;
  size_t capacity_ = 0;     ///< pixels per layer the storage holds
  size_t layerStride_ = 0;  ///< kStride * capacity_
  std::vector<uint8_t> count_;
  std::vector<float> data_;
  Z3Counters counters_;  ///< allocated, occluded, compressed (fragments and merged: counters())
  uint64_t fragments_ = 0, direct_ = 0;
};

}  // namespace linesurf
