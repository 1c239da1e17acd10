#pragma once
/// A rectangle of screen pixels: the unit of the pipeline's screen bookkeeping (a primitive's
/// bounds, a tile, a splat's rows). Internal to src/render.

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

}  // namespace linesurf
