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
///  2. resolve: layers normalised (C/W, A/W) and composited back to front.
/// Storage is SoA with a fixed number of layers per pixel (no allocation per fragment).
#include <cmath>
#include <cstdint>
#include <vector>

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
  Vec3f color = Vec3f::Zero();   ///< shaded linear RGB, straight (not weighted, not premultiplied)
  float alpha = 1;        ///< opacity in [0, 1]; 1 = opaque
  float weight = 0;       ///< resampling-filter weight (> 0; fragments with weight <= 0 are ignored)
  Vec3f normal = Vec3f::Zero();  ///< camera-space unit normal, for the normal buffer (may be zero)
};

/// Counters of one tile (summed into RenderStats).
struct Z3Counters {
  uint64_t fragments = 0;   ///< insert() calls with positive weight
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
  /// A tile covering `rect` with `layers` layers per pixel (1..RenderOptions::kMaxLayers).
  /// keepNormals = false skips the weighted normal sums of merged fragments (ResolvedPixel::normal
  /// is then the normal of the fragment that opened the layer).
  Z3Tile(const PixelRect& rect, int layers, bool keepNormals = true);
  /// Clears the tile and moves it to `rect` (no reallocation when it is not larger).
  void reset(const PixelRect& rect);

  const PixelRect& rect() const { return rect_; }
  int layers() const { return layers_; }

  bool keepsNormals() const { return keepNormals_; }

  /// Inserts a fragment at absolute pixel (x, y), which must lie inside rect().
  /// The common case (merge into an existing layer, step a) is inline.
  void insert(int x, int y, const Fragment& f) {
    if (!(f.weight > 0)) return;
    const size_t p = index(x, y);
    float* px = block(p);
    const int L = layers_, n = count_[p];
    int hit = -1;
    float hitDz = INFINITY;
    for (int i = 0; i < n; ++i) {
      const float dz = std::abs(f.depth - px[kZ * L + i]);
      const float t = f.zThreshold > px[kThr * L + i] ? f.zThreshold : px[kThr * L + i];
      if (dz <= t && dz < hitDz) { hit = i; hitDz = dz; }
    }
    if (hit < 0) return insertNew(p, f);
    const float w = f.weight;
    px[kR * L + hit] += w * f.color.x();
    px[kG * L + hit] += w * f.color.y();
    px[kB * L + hit] += w * f.color.z();
    px[kA * L + hit] += w * f.alpha;
    px[kW * L + hit] += w;
    if (keepNormals_) {
      px[kNx * L + hit] += w * f.normal.x();
      px[kNy * L + hit] += w * f.normal.y();
      px[kNz * L + hit] += w * f.normal.z();
    }
    if (f.alpha < 1.0f) px[kOpaque * L + hit] = 0;
    ++counters_.fragments;
    ++counters_.merged;
  }

  /// Resolves pixel (x, y) (absolute, inside rect()): back-to-front composite of its layers.
  ResolvedPixel resolve(int x, int y) const;
  /// Number of layers in use at (x, y).
  int layerCount(int x, int y) const { return count_[index(x, y)]; }

  const Z3Counters& counters() const { return counters_; }

 private:
  // One contiguous block per pixel: field-major arrays over the layers (SoA inside the pixel),
  // so an insertion touches a few adjacent cache lines.
  enum Field { kZ, kThr, kR, kG, kB, kA, kW, kNx, kNy, kNz, kOpaque, kFields };
  size_t index(int x, int y) const { return size_t(y - rect_.y0) * size_t(rect_.width()) + size_t(x - rect_.x0); }
  float* block(size_t pixel) { return data_.data() + pixel * stride_; }
  const float* block(size_t pixel) const { return data_.data() + pixel * stride_; }
  void compress(float* px, int& n);
  void insertNew(size_t pixel, const Fragment& f);  // steps b and c
  PixelRect rect_;
  int layers_;
  bool keepNormals_ = true;
  size_t stride_;  ///< kFields * layers_
  std::vector<uint8_t> count_;
  std::vector<float> data_;
  Z3Counters counters_;
};

}  // namespace linesurf
