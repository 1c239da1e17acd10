// The rasterise stage of segment splats (thesis §5; segment_splat.h): the scalar per-pixel weights
// of the three methods, the row spans of a segment's footprint, and a tile's segments into the Z^3
// tile, the common case through the SIMD rows (segment_rows.h).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <new>

#include "segment_approx.h"
#include "segment_filter.h"
#include "segment_splat.h"
#include "splat_rules.h"

namespace linesurf {

namespace {

// Rasterisation visits the pixel centres within this distance (pixels) of the projected footprint
// box: the projection and the per-pixel ray-plane intersection differ by rounding only.
constexpr float kSpanSlack = 0.05f;
// Rectangles of at most this many pixels are rasterised whole (as point splats are), larger ones
// in the rows' spans of the projected footprint box: a span costs its set-up, a pixel outside the
// footprint only its share of a SIMD vector.
constexpr int kWholeRectArea = 96;

}  // namespace

// --- per-pixel weights (scalar path) ----------------------------------------------------------

namespace {

// The only sub-segment of a one-piece ScreenSpace segment, from the per-pixel constants.
SegmentPiece onlyPiece(const detail::SegmentRaster& k) {
  SegmentPiece p;
  p.a0 = 0, p.a1 = k.length;
  p.reach = INFINITY;  // the footprint box is tested before
  p.skew = k.skew, p.across = k.across, p.invM00 = k.invM00, p.k = k.k, p.erfScale = k.erfScale;
  p.scale0 = k.scale0, p.slope = k.slope;
  return p;
}

float weightAt(const PreparedSegment& sp, float a, float b) {
  const detail::SegmentRaster& k = sp.raster;
  if (std::abs(b) > k.bMax || a < k.aMin || a > k.aMax) return 0;
  switch (sp.method) {
    case SegmentMethod::ScreenSpace: {
      if (sp.pieceCount() == 1) {
        const SegmentPiece p = onlyPiece(k);
        return segment::screenSpaceWeight(&p, 1, 0, 0, a, b, k.R2);
      }
      const SegmentExtra& x = *sp.extra;
      return segment::screenSpaceWeight(x.pieces.data(), int(x.pieces.size()), x.pieceInvLength, x.pieceMaxReach, a,
                                        b, k.R2);
    }
    case SegmentMethod::Reference: return segment::referenceWeight(*sp.extra, a, b, k.R2);
    case SegmentMethod::Approx: return segment::approxWeight(*sp.extra, a, b);
  }
  return 0;
}

}  // namespace

float segmentWeightAt(const PreparedSegment& sp, const FrameContext&, const Vec2f& pixel) {
  const detail::SegmentRaster& k = sp.raster;
  if (!(k.length > 0)) return 0;
  const float nr = k.N.at(pixel.x(), pixel.y());
  if (!(nr < 0)) return 0;
  const float inr = 1.0f / nr;
  return weightAt(sp, k.A.at(pixel.x(), pixel.y()) * inr - k.a0, k.B.at(pixel.x(), pixel.y()) * inr - k.b0);
}

// --- rasterise -------------------------------------------------------------------------------

namespace {

// floor(v) for |v| < 2^31 (std::floor is a library call in the generic x86-64 build)
inline int floorInt(float v) {
  const int i = int(v);
  return i - (float(i) > v);
}

// The rows' spans of the projected footprint box (a convex quad): pixel centres of row y
// (py = y + 0.5) inside it, widened by kSpanSlack pixel against rounding (a centre farther out
// lies outside the footprint box, where the weight is zero).
struct QuadSpans {
  float ylo[4], yhi[4], xa[4], ya[4], slope[4];
  int edges = 0;
  bool full = false;  ///< no quad: whole rows
  explicit QuadSpans(const PreparedSegment& sp) {
    full = !sp.useSpans;
    for (int i = 0; i < 4 && !full; ++i) {
      const Vec2f& p = sp.screenQuad[i];
      const Vec2f& q = sp.screenQuad[(i + 1) % 4];
      if (p.y() == q.y()) continue;
      ylo[edges] = std::min(p.y(), q.y()), yhi[edges] = std::max(p.y(), q.y());
      xa[edges] = p.x(), ya[edges] = p.y();
      slope[edges] = (q.x() - p.x()) / (q.y() - p.y());
      ++edges;
    }
  }
  // [xb, xe) within r; false when the row misses the quad
  bool row(const PixelRect& r, float py, int& xb, int& xe) const {
    xb = r.x0, xe = r.x1;
    if (full) return true;
    float lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < edges; ++i) {
      if (!(ylo[i] <= py && py < yhi[i])) continue;
      const float x = xa[i] + (py - ya[i]) * slope[i];
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    if (!(hi >= lo)) return false;
    xb = std::max(r.x0, -floorInt(-(std::max(lo, -1e8f) - 0.5f - kSpanSlack)));
    xe = std::min(r.x1, floorInt(std::min(hi, 1e8f) - 0.5f + kSpanSlack) + 1);
    return xe > xb;
  }
};

// The rows' spans a segment's rasterisation walks over r: the cutoff region's (detail::segmentSpans) when tight,
// else those of the footprint box, whole rows when the rectangle is small or the box is clipped.
template <class Emit>
void forEachRowSpan(const PreparedSegment& sp, const PixelRect& r, bool tight, Emit&& emit) {
  if (tight && sp.method == SegmentMethod::ScreenSpace) {
    detail::RowSpan rows[detail::kBlock];
    for (int y0 = r.y0; y0 < r.y1; y0 += detail::kBlock) {  // bands of at most kBlock rows
      const PixelRect band{r.x0, y0, r.x1, std::min(r.y1, y0 + detail::kBlock)};
      int n;
      if (sp.raster.pieceCount == 1) {
        const detail::SegmentRaster* one = &sp.raster;
        detail::segmentSpansBatch(&one, &band, 1, kSpanSlack, rows, detail::kBlock, &n);
      } else {
        n = detail::segmentSpans(sp.raster, band, kSpanSlack, rows);
      }
      if (n < 0) break;  // degenerate constants (the first band already): the box
      for (int i = 0; i < n; ++i) emit(rows[i].y, rows[i].x0, rows[i].x1);
      if (y0 + detail::kBlock >= r.y1) return;
    }
  }
  const bool whole = r.width() * r.height() <= kWholeRectArea || !sp.useSpans;
  const QuadSpans quad(sp);
  for (int y = r.y0; y < r.y1; ++y) {
    int xb = r.x0, xe = r.x1;
    if (!whole && !quad.row(r, float(y) + 0.5f, xb, xe)) continue;
    emit(y, xb, xe);
  }
}

// The blended attributes of a segment fragment at along-parameter u (Z3Tile::Attr).
struct FragmentAttributes {
  const PreparedSegment& sp;
  const FrameContext& frame;
  float attr[Z3Tile::kAttrs];
  float dn2 = 0;  ///< |n1 - n0|^2 (Smooth)
  FragmentAttributes(const PreparedSegment& s, const FrameContext& f) : sp(s), frame(f), dn2(s.dn.squaredNorm()) {
    std::copy(sp.attr, sp.attr + Z3Tile::kAttrs, attr);
  }
  void at(float u) {
    switch (sp.shade) {
      case SegmentShade::Constant: return;
      case SegmentShade::Linear: return linearColour(u);
      case SegmentShade::Smooth: {
        // n0 and n1 are unit and at most kStationTurn apart, so |n0 + u dn|^2 = 1 - x with
        // x = u (1 - u) |dn|^2 <= 0.0025: 1 / sqrt(1 - x) to 5e-9 by its series
        linearColour(u);
        const float x = u * (1 - u) * dn2, inv = 1 + x * (0.5f + 0.375f * x);
        attr[Z3Tile::kNx] = (sp.n0.x() + u * sp.dn.x()) * inv;
        attr[Z3Tile::kNy] = (sp.n0.y() + u * sp.dn.y()) * inv;
        attr[Z3Tile::kNz] = (sp.n0.z() + u * sp.dn.z()) * inv;
        return;
      }
      case SegmentShade::Stations: return stations(u);
    }
  }
  void linearColour(float u) {
    attr[Z3Tile::kR] = sp.attr[Z3Tile::kR] + u * sp.dc.x();
    attr[Z3Tile::kG] = sp.attr[Z3Tile::kG] + u * sp.dc.y();
    attr[Z3Tile::kB] = sp.attr[Z3Tile::kB] + u * sp.dc.z();
  }
  // several lighting stations or a texture (§5.2.4: uv interpolated between the endpoints)
  void stations(float u) {
    Vec3f c(sp.attr[Z3Tile::kR], sp.attr[Z3Tile::kG], sp.attr[Z3Tile::kB]);
    if (sp.stationCount >= 0) {  // untextured, the stations in the record
      if (sp.stationCount >= 2) c = piecewise(sp.stationColour, sp.stationCount, u);
      return stationsDone(c, u);
    }
    const SegmentExtra& x = *sp.extra;
    if (x.textured) {
      const Vec2f uv = x.uv0 + u * (x.uv1 - x.uv0);
      c = frame.texture->sampleBilinear(uv.x(), uv.y()).head<3>();
    }
    if (!x.colour.empty()) {  // untextured: the stations' colours, piecewise linear
      c = piecewise(x.colour.data(), x.stations, u);
    } else if (!x.diffuse.empty()) {
      const int n = int(x.diffuse.size());
      const float fs = u * float(n - 1);
      const int k = std::min(int(fs), n - 2);
      const float v = fs - float(k);
      const Vec3f dif = (1 - v) * x.diffuse[k] + v * x.diffuse[k + 1];
      const Vec3f spec = (1 - v) * x.specular[k] + v * x.specular[k + 1];
      c = c.cwiseProduct(dif) + spec;
    }
    stationsDone(c, u);
  }
  // the colour of n stations (channel ch of station k at colour[ch * n + k]) at u, piecewise linear
  static Vec3f piecewise(const float* colour, int n, float u) {
    const float fs = u * float(n - 1);
    const int k = std::min(int(fs), n - 2);
    const float v = fs - float(k);
    Vec3f c;
    for (int ch = 0; ch < 3; ++ch) {
      const float* cc = colour + ch * n;
      c[ch] = cc[k] + v * (cc[k + 1] - cc[k]);
    }
    return c;
  }
  void stationsDone(const Vec3f& c, float u) {
    attr[Z3Tile::kR] = c.x(), attr[Z3Tile::kG] = c.y(), attr[Z3Tile::kB] = c.z();
    if (sp.smooth) {
      const Vec3f m = sp.n0 + u * sp.dn;
      const float len = m.norm();
      if (len > 0) attr[Z3Tile::kNx] = m.x() / len, attr[Z3Tile::kNy] = m.y() / len, attr[Z3Tile::kNz] = m.z() / len;
    }
  }
};

// Whether the SIMD rows shade the segment's fragments (all but textured ones). A segment's
// stations are textured exactly when the frame is (prepareSegment; the SIMD batches take only
// untextured frames), so the record's SegmentExtra (a cache miss) is not read for it.
bool shadedInRows(const PreparedSegment& sp, const FrameContext& frame) {
  return sp.shade != SegmentShade::Stations || !frame.texture;
}

// The rows' shading of an untextured segment (detail::SegmentShadeRows), written field by field
// into `shade` (a whole struct built on the stack and copied cost store-forwarding stalls per
// segment; see docs/decisions.md, "Segment rows").
void shadeRows(const PreparedSegment& sp, detail::SegmentShadeRows& shade) {
  const bool stations = sp.shade == SegmentShade::Stations;
  shade.attr = sp.attr;
  shade.dc = sp.dc.data(), shade.n0 = sp.n0.data(), shade.dn = sp.dn.data();
  shade.dn2 = sp.dn.squaredNorm();
  shade.smooth = sp.smooth && (sp.shade == SegmentShade::Smooth || stations);
  shade.exactNormal = stations;
  shade.stations = 0, shade.stationColour = nullptr, shade.stationPadded = false;
  if (stations && sp.stationCount >= 2) {  // in the record
    shade.stations = sp.stationCount;
    shade.stationColour = sp.stationColour;
  } else if (stations && sp.stationCount < 0 && sp.extra->stations >= 2) {  // padded (SegmentExtra::colour)
    shade.stationPadded = true;
    shade.stations = sp.extra->stations;
    shade.stationColour = sp.extra->colour.data();
  }
}

// ScreenSpace segments: the closed form evaluated in SIMD over the rows' spans of the cutoff
// region (`given`, else forEachRowSpan's), straight into the Z^3 tile (segment_rows.h).
void rasterizeRows(const PreparedSegment& sp, const SplatContext& ctx, const PixelRect& r,
                   const detail::RowSpan* given = nullptr, int givenCount = 0) {
  auto eachSpan = [&](auto&& emit) {
    if (!given) return forEachRowSpan(sp, r, true, emit);
    for (int i = 0; i < givenCount; ++i) emit(given[i].y, given[i].x0, given[i].x1);
  };
  detail::RowSpan spans[detail::kBlock];
  int spanCount = 0;
  uint64_t inserted = 0;
  if (shadedInRows(sp, ctx.frame)) {  // straight into the Z^3 tile, attributes in SIMD
    detail::SegmentShadeRows shade;
    shadeRows(sp, shade);
    if (given && givenCount <= detail::kBlock) {  // the batch's spans as they are (no copy)
      if (givenCount > 0) inserted = detail::segmentRowsZ3(sp.raster, shade, given, givenCount, ctx.tile);
      ctx.tile.addFragments(inserted);
      return;
    }
    auto flush = [&] {
      inserted += detail::segmentRowsZ3(sp.raster, shade, spans, spanCount, ctx.tile);
      spanCount = 0;
    };
    eachSpan([&](int y, int xb, int xe) {
      if (spanCount == detail::kBlock) flush();
      spans[spanCount++] = {y, xb, xe};
    });
    if (spanCount > 0) flush();
    ctx.tile.addFragments(inserted);
    return;
  }
  // textured: fragments in blocks, attributes per fragment
  FragmentAttributes shade(sp, ctx.frame);
  detail::FragmentBlock fb;
  int pixels = 0;
  auto flush = [&] {
    const int m = detail::segmentFragments(sp.raster, spans, spanCount, fb);
    for (int i = 0; i < m; ++i) {
      shade.at(fb.p[i]);
      ctx.tile.insert(int(fb.x[i]), int(fb.y[i]), fb.depth[i], fb.q[i], fb.weight[i], shade.attr);
    }
    inserted += uint64_t(m);
    spanCount = pixels = 0;
  };
  eachSpan([&](int y, int xb, int xe) {
    for (int x0 = xb; x0 < xe; x0 += detail::kBlock) {
      const int x1 = std::min(xe, x0 + detail::kBlock);
      if (pixels + (x1 - x0) > detail::kBlock) flush();
      spans[spanCount++] = {y, x0, x1};
      pixels += x1 - x0;
    }
  });
  if (spanCount > 0) flush();
  ctx.tile.addFragments(inserted);
}

// Approx and Reference: per pixel, scalar.
void rasterizeScalar(const PreparedSegment& sp, const SplatContext& ctx, const PixelRect& r) {
  const detail::SegmentRaster& k = sp.raster;
  FragmentAttributes shade(sp, ctx.frame);
  const QuadSpans quad(sp);
  uint64_t inserted = 0;
  for (int y = r.y0; y < r.y1; ++y) {
    const float py = float(y) + 0.5f;
    int xb, xe;
    if (!quad.row(r, py, xb, xe)) continue;
    for (int x = xb; x < xe; ++x) {
      const float px = float(x) + 0.5f;
      const float nr = k.N.at(px, py);
      if (!(nr < 0)) continue;  // ray parallel to or leaving the facing plane
      const float t = k.depthNum / nr;
      if (k.clipDepth && (t < k.nearD || t > k.farD)) continue;
      const float inr = 1.0f / nr;
      const float a = k.A.at(px, py) * inr - k.a0, b = k.B.at(px, py) * inr - k.b0;
      const float w = weightAt(sp, a, b);
      if (!(w > 0)) continue;
      const float u = std::clamp(a / k.length, 0.0f, 1.0f);
      shade.at(u);
      ctx.tile.insert(x, y, t, k.zThreshold0 + u * (k.zThreshold1 - k.zThreshold0), w, shade.attr);
      ++inserted;
    }
  }
  ctx.tile.addFragments(inserted);
}

}  // namespace

std::vector<detail::RowSpan> segmentRowSpans(const PreparedSegment& sp, const PixelRect& rect, bool tight) {
  std::vector<detail::RowSpan> out;
  const PixelRect r = sp.bounds.intersect(rect);
  if (!r.empty()) forEachRowSpan(sp, r, tight, [&](int y, int xb, int xe) { out.push_back({y, xb, xe}); });
  return out;
}

void rasterizeSegment(const PreparedSegment& sp, const SplatContext& ctx) {
  const PixelRect r = sp.bounds.intersect(ctx.rect);
  if (r.empty()) return;
  if (sp.method == SegmentMethod::ScreenSpace) return rasterizeRows(sp, ctx, r);
  rasterizeScalar(sp, ctx, r);
}

void rasterizeSegments(const PreparedSegment* const* segs, int n, const SplatContext& ctx) {
  // the rows' spans of the one-piece ScreenSpace segments at once (a band of at most kBlock
  // rows of the tile: taller tiles take the one-by-one path), then every segment in order
  const int stride = ctx.rect.height();
  const detail::SegmentRaster* batch[kRasterBatch];
  PixelRect rects[kRasterBatch];
  int slot[kRasterBatch], counts[kRasterBatch], widest[kRasterBatch], pixels[kRasterBatch];
  int m = 0;
  for (int i = 0; i < n; ++i) {
    const PreparedSegment& sp = *segs[i];
    slot[i] = -1;
    const PixelRect r = sp.bounds.intersect(ctx.rect);
    if (r.empty() || sp.method != SegmentMethod::ScreenSpace || sp.raster.pieceCount != 1 || stride > detail::kBlock)
      continue;
    slot[i] = m;
    batch[m] = &sp.raster;
    rects[m++] = r;
    if (sp.shade == SegmentShade::Stations) {  // its stations, read after the spans
      if (sp.stationCount >= 0) {
        __builtin_prefetch(sp.stationColour);  // (the record's cold line)
      } else {  // the SegmentExtra's fields (its colours when the item is built)
        const char* x = reinterpret_cast<const char*>(sp.extra.get());
        __builtin_prefetch(x + offsetof(SegmentExtra, colour));
        __builtin_prefetch(x + offsetof(SegmentExtra, stations));
      }
    }
  }
  thread_local std::vector<detail::RowSpan> spans;
  if (m > 0) {
    if (spans.size() < size_t(kRasterBatch * stride)) spans.resize(size_t(kRasterBatch * stride));
    detail::segmentSpansBatch(batch, rects, m, kSpanSlack, spans.data(), stride, counts, widest, pixels);
  }
  // runs of consecutive ones shaded in the rows in one call (detail::segmentRowsRunZ3)
  detail::SegmentRowsItem items[kRasterBatch];
  int runLength = 0;
  auto flush = [&] {
    if (runLength > 0) ctx.tile.addFragments(detail::segmentRowsRunZ3(items, runLength, ctx.tile));
    runLength = 0;
  };
  for (int i = 0; i < n; ++i) {
    const int k = slot[i];
    const PreparedSegment& sp = *segs[i];
    if (k >= 0 && counts[k] >= 0 && shadedInRows(sp, ctx.frame)) {
      if (counts[k] > 0) {
        detail::SegmentRowsItem& item = items[runLength++];
        item.raster = &sp.raster;
        shadeRows(sp, item.shade);
        item.spans = spans.data() + size_t(k) * size_t(stride);
        item.count = counts[k];
        item.widest = widest[k], item.pixels = pixels[k];
        if (item.shade.stationPadded) {  // read by the rows
          __builtin_prefetch(item.shade.stationColour);
          __builtin_prefetch(item.shade.stationColour + 3 * item.shade.stations - 1);
        }
      }
      continue;
    }
    flush();
    if (k >= 0 && counts[k] >= 0) rasterizeRows(sp, ctx, rects[k], spans.data() + size_t(k) * size_t(stride), counts[k]);
    else rasterizeSegment(sp, ctx);
  }
  flush();
}

}  // namespace linesurf
