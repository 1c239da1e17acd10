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
/// Coverage alpha (beyond the thesis, setCoverageScale; docs/decisions.md, "Coverage alpha (opt-in)"): A then sums each fragment's
/// coverage, weight times a per-primitive constant, and a layer's alpha is min(1, s A) (s the
/// tile's coverage scale) instead of the weighted mean A/W; a layer is opaque (step b) only once
/// that reaches 1, so a partly covered layer keeps what lies behind it; or, without coverage
/// occlusion (setCoverageOccludes(false), coverage at silhouettes only), at once as without
/// coverage, with what it hides summed per pixel (resolveBehind).
/// Tail layers (beyond the thesis, setTailLayers; docs/decisions.md, "Tail layers"): a prefilter tail fragment occludes
/// nothing (a tail-only layer has opaque flag -1) and is not composited in front of another layer.
/// Storage: a fixed number of layers per pixel in structure-of-arrays planes, one plane of
/// floats per (layer, field), row-major over the tile, so that the SIMD point rows
/// (point_rows.h, segment_rows.h) test and merge a whole row of pixels per instruction (the
/// fast path: a pixel with no layer or with one layer the fragment falls within); scalar insert()
/// handles the rest (no allocation per fragment).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "linesurf/core/image.h"
#include "linesurf/core/math.h"
#include "pixel_rect.h"

namespace linesurf {

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

/// A resolved pixel's colour (premultiplied, coverage alpha) composited over the background
/// `bg`, as the image stores it: straight colour where the result is partly transparent over a
/// visible background, the layer's own straight colour over a transparent one.
inline Color overBackground(const Color& px, const Color& bg) {
  const float a = px.w();
  Color c = px;
  c.head<3>() += (1 - a) * bg.w() * bg.head<3>();
  c.w() = a + (1 - a) * bg.w();
  if (bg.w() > 0 && c.w() > 0 && c.w() < 1) c.head<3>() /= c.w();  // straight colour for PNG
  if (bg.w() == 0 && a > 0) c.head<3>() /= a;
  return c;
}

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
  /// tail: the fragment lies in a splat's prefilter tail (outside the primitive's own disc or
  /// strip); with tailLayers() it occludes nothing (see setTailLayers).
  void insert(int x, int y, float depth, float zThreshold, float weight, const float* attr, bool tail = false) {
    if (!(weight > 0)) return;
    const size_t p = index(x, y);
    float* px = data_.data() + p;
    const int n = count_[p];
    const size_t fs = capacity_;  // field stride
    if (n == 0) {  // the pixel's first fragment opens its first layer (step b, inline)
      for (int k = 0; k < kAttrs; ++k) px[k * fs] = weight * attr[k];
      px[kZ * fs] = depth;
      px[kThr * fs] = zThreshold;
      px[kOpaque * fs] = fragmentOpaque(weight, attr[kA]) ? (tail && tailLayers() ? -1.0f : 1.0f) : 0.0f;
      count_[p] = 1;
      ++counters_.allocated;
      return;
    }
    int hit = -1;
    float hitDz = INFINITY;
    for (int i = 0; i < n; ++i) {
      const float* ly = px + i * layerStride_;
      const float dz = std::abs(depth - ly[kZ * fs]);
      const float t = zThreshold > ly[kThr * fs] ? zThreshold : ly[kThr * fs];
      if (dz <= t && dz < hitDz) { hit = i; hitDz = dz; }
    }
    if (hit < 0) return insertNew(p, depth, zThreshold, weight, attr, tail);
    float* ly = px + hit * layerStride_;
    for (int k = 0; k < kAttrs; ++k) ly[k * fs] += weight * attr[k];
    if (coverage_ > 0) {  // opaque once covered: what lies behind is freed (step b)
      if (coverageOccludes_ && ly[kA * fs] * coverage_ >= 1.0f) {
        ly[kOpaque * fs] = 1;
        count_[p] = hit + 1;
      }
    } else if (attr[kA] < 1.0f) {
      ly[kOpaque * fs] = 0;
    } else if (ly[kOpaque * fs] < 0 && !tail) {  // a tail-only layer gets a fragment of its own: it occludes (step b)
      ly[kOpaque * fs] = 1;
      count_[p] = hit + 1;
    }
  }
  void addFragments(uint64_t n) { fragments_ += n; }
  /// The same for one Fragment, counted.
  void insert(int x, int y, const Fragment& f) {
    const float attr[kAttrs] = {f.color.x(), f.color.y(), f.color.z(), f.alpha, 1.0f, f.normal.x(), f.normal.y(), f.normal.z()};
    insert(x, y, f.depth, f.zThreshold, f.weight, attr);
    if (f.weight > 0) addFragments(1);
  }

  /// Resolves pixel (x, y) (absolute, inside rect()): front-to-back "under" compositing of its
  /// normalised layers (== the thesis's back-to-front merge). Layer colours as stored. The
  /// renderer resolves one-layer pixels in SIMD rows with the same formula for n = 1
  /// (detail::resolveSingleLayerRow, resolve.cpp): a change here goes there too (the test
  /// EwaPoint.SimdResolveMatchesThePixelResolve compares them).
  ResolvedPixel resolve(int x, int y) const {
    return resolve(x, y, [](const Vec3f& c, const Vec3f&, float) { return c; });
  }
  /// The same with deferred shading: each layer's colour is shade(albedo, normal sum (not
  /// normalised), layer depth). frontOpaque: the front layer's alpha is 1 (coverage at
  /// silhouettes only, RenderOptions::coverageReach: an interior pixel keeps the opaque alpha).
  template <class Shade>
  ResolvedPixel resolve(int x, int y, Shade&& shade, bool frontOpaque = false) const {
    ResolvedPixel out;
    const size_t p = index(x, y);
    const int n = count_[p];
    if (n == 0) return out;
    const float* px = data_.data() + p;
    const size_t fs = capacity_;
    Vec3f c = Vec3f::Zero();
    float a = 0;
    int front = 0;  // the nearest layer composited (tail-only layers in front of others are skipped)
    for (int i = 0; i < n && a < 1.0f; ++i) {
      const float* ly = px + i * layerStride_;
      const float iw = 1.0f / ly[kW * fs];
      float al = frontOpaque && i == 0 ? 1.0f : layerAlpha(ly[kA * fs], iw);
      if (ly[kOpaque * fs] < 0 && i + 1 < n) {  // tail-only, over a layer behind it (setTailLayers)
        al = 0;
        if (front == i) ++front;
      }
      const float t = (1 - a) * al;
      c += t * shade(Vec3f(ly[kR * fs] * iw, ly[kG * fs] * iw, ly[kB * fs] * iw),
                     Vec3f(ly[kNx * fs], ly[kNy * fs], ly[kNz * fs]), ly[kZ * fs]);
      a += t;
    }
    out.color = Color(c.x(), c.y(), c.z(), a);
    const float* fl = px + std::min(front, n - 1) * layerStride_;
    out.depth = fl[kZ * fs];
    const Vec3f nrm(fl[kNx * fs], fl[kNy * fs], fl[kNz * fs]);
    const float nn = nrm.norm();
    out.normal = nn > 0 ? Vec3f(nrm / nn) : Vec3f::Zero();
    return out;
  }
  /// The alpha of the front layer at (x, y), which must hold a layer (layerAlpha), and its z
  /// threshold.
  float frontAlpha(int x, int y) const {
    const float* px = data_.data() + index(x, y);
    return layerAlpha(px[kA * capacity_], 1.0f / px[kW * capacity_]);
  }
  float frontThreshold(int x, int y) const { return data_[index(x, y) + kThr * capacity_]; }
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

  /// Fields of a layer beyond the blended sums: depth, z threshold, opaque flag (1 or 0).
  enum Field { kZ = kAttrs, kThr, kOpaque, kFields };
  /// Storage view for the SIMD rows (simd_rows-inl.h, Z3Rows): field f of layer l of pixel index(x, y)
  /// is plane(l, f)[index(x, y)], and its layer count counts()[index(x, y)]. The planes are padded
  /// by kPad elements, so a vector load or masked store starting at any pixel of the tile stays
  /// inside the storage.
  static constexpr int kPad = 64;
  size_t index(int x, int y) const { return size_t(y - rect_.y0) * size_t(rect_.width()) + size_t(x - rect_.x0); }
  float* plane(int layer, int field) { return data_.data() + size_t(layer) * layerStride_ + size_t(field) * capacity_; }
  int32_t* counts() { return count_.data(); }
  /// Counts what the SIMD rows did themselves: layers opened on empty pixels (step b) and
  /// fragments dropped behind a single opaque layer.
  void addFastCounts(uint64_t allocated, uint64_t occluded) {
    counters_.allocated += allocated;
    counters_.occluded += occluded;
  }
  /// Whether the SIMD rows blend the normal sums (true by default). The renderer turns it off
  /// when nothing reads them (no deferred lighting, no normal buffer): the normal of a layer
  /// (ResolvedPixel::normal, the shade argument) is then unspecified.
  bool blendNormals() const { return blendNormals_; }
  void setBlendNormals(bool on) { blendNormals_ = on; }
  /// Coverage alpha (see the top of this file): s > 0 turns it on, alpha = min(1, s A); 0 (the
  /// default) keeps the thesis's normalised alpha A/W. The renderer sets it per frame when every
  /// primitive is opaque, and the primitives' alpha attribute to their coverage constants.
  float coverageScale() const { return coverage_; }
  void setCoverageScale(float s) { coverage_ = s > 0 ? s : 0; }
  /// With coverage: whether a layer occludes only once covered (true, the default: a partly
  /// covered layer keeps the layers behind it) or at once, as an opaque layer does without
  /// coverage (false: coverage at silhouettes only, RenderOptions::coverageReach > 0, where the
  /// resolve composites a partly covered front over the farther neighbour instead; the layers
  /// are those of an opaque frame, so the frame costs what an opaque one does).
  bool coverageOccludes() const { return coverage_ <= 0 || coverageOccludes_; }
  void setCoverageOccludes(bool on) {
    coverageOccludes_ = on;
    if (on) return;
    if (behind_.size() < capacity_ * kBehindFields) behind_.resize(capacity_ * kBehindFields);
    behindCount_.assign(capacity_, 0);
  }
  /// Without coverage occlusion (setCoverageOccludes(false)) what the layers do not keep is summed
  /// per pixel instead of dropped: the fragments behind the front layer and the layers a nearer one
  /// frees, as one accumulation of the layer sums (kR..kNz) and of w z (kBehindZ), so that a
  /// silhouette pixel's partial front can be composited over what lay behind it (resolveBehind).
  /// The SIMD rows add to it through behindPlane / behindCounts (a pixel's sums are valid where its
  /// count is not 0). Null / empty otherwise.
  enum { kBehindZ = kAttrs, kBehindFields };
  float* behindPlane(int field) { return coverageOccludes() ? nullptr : behind_.data() + size_t(field) * capacity_; }
  int32_t* behindCounts() { return coverageOccludes() ? nullptr : behindCount_.data(); }
  /// What lay behind pixel (x, y)'s layers (premultiplied colour, shade(albedo, normal sum, depth)
  /// as resolve() lights a layer, and its coverage alpha); zero where nothing did or coverage
  /// occludes.
  template <class Shade>
  Color resolveBehind(int x, int y, Shade&& shade) const {
    if (coverageOccludes()) return Color(0, 0, 0, 0);
    const size_t p = index(x, y);
    if (behindCount_[p] == 0) return Color(0, 0, 0, 0);
    auto B = [&](int f) { return behind_[size_t(f) * capacity_ + p]; };
    const float W = B(kW);
    if (!(W > 0)) return Color(0, 0, 0, 0);
    const float iw = 1.0f / W, a = layerAlpha(B(kA), iw);
    const Vec3f c = shade(Vec3f(B(kR) * iw, B(kG) * iw, B(kB) * iw), Vec3f(B(kNx), B(kNy), B(kNz)), B(kBehindZ) * iw);
    return Color(a * c.x(), a * c.y(), a * c.z(), a);
  }
  /// Tail layers (beyond the thesis, RenderOptions::tailLayers): in an opaque frame
  /// without coverage, a tail fragment (insert's tail: only the screen prefilter put it there,
  /// outside the primitive's own disc or strip, so its depth is the plane's, extrapolated)
  /// occludes nothing. On an empty pixel it opens a tail-only layer (opaque flag -1), which a
  /// fragment that is not a tail turns opaque by merging into it; in front of a layer it is
  /// skipped (dropped: a tail-only layer over another is not composited), behind an opaque or
  /// tail-only one occluded; a fragment that is not a tail drops the tail-only layers in front of
  /// it. A tail-only layer with nothing behind it is resolved as any layer (the anti-aliasing of a
  /// silhouette against the background). Off (the default): every opaque fragment occludes.
  bool tailLayers() const { return tails_ && coverage_ <= 0; }
  void setTailLayers(bool on) { tails_ = on; }
  /// A layer's alpha from its sum A and 1/W (either mode).
  float layerAlpha(float A, float invW) const {
    return coverage_ > 0 ? std::min(A * coverage_, 1.0f) : std::clamp(A * invW, 0.0f, 1.0f);
  }
  /// Whether a lone fragment of this weight and alpha attribute is opaque (frees what is behind).
  bool fragmentOpaque(float weight, float alpha) const {
    if (coverage_ > 0 && !coverageOccludes_) return true;  // the renderer's coverage: opaque primitives only
    return coverage_ > 0 ? weight * alpha * coverage_ >= 1.0f : alpha >= 1.0f;
  }

 private:
  void compress(float* px, int& n);
  void addBehind(size_t p, float w, const float* attr, float depth);  // a fragment (see behindPlane)
  void layerBehind(size_t p, const float* layer);                     // a freed layer's sums
  void insertNew(size_t pixel, float depth, float zThreshold, float weight, const float* attr, bool tail);  // steps b and c
  PixelRect rect_;
  int layers_;
  size_t capacity_ = 0;     ///< elements per plane (pixels + kPad): the stride between fields
  size_t layerStride_ = 0;  ///< kFields * capacity_: the stride between layers
  std::vector<int32_t> count_;
  std::vector<float> data_;
  Z3Counters counters_;  ///< allocated, occluded, compressed (fragments and merged: counters())
  uint64_t fragments_ = 0, direct_ = 0;
  bool blendNormals_ = true;
  float coverage_ = 0;
  bool tails_ = false;
  bool coverageOccludes_ = true;
  std::vector<float> behind_;          ///< kBehindFields planes of capacity_ (setCoverageOccludes(false))
  std::vector<int32_t> behindCount_;   ///< per pixel: 0 = nothing behind yet
};

}  // namespace linesurf
