// Placeholder line-segment splats (see segment_splat.h): ceil(l / r) + 1 EWA point splats along
// the segment, so that hybrid models render before the §5 rasteriser lands. To be replaced.
#include <algorithm>
#include <cmath>

#include "linesurf/render/segment_splat.h"

namespace linesurf {

PrimitiveStatus prepareSegment(const Segment& s, uint32_t index, const FrameContext& frame, PreparedSegment& out) {
  out.index = index;
  out.bounds = {};
  out.pieces.clear();
  const float len = s.length();
  if (!(s.radius > 0) || !std::isfinite(len) || !std::isfinite(s.radius)) return PrimitiveStatus::Degenerate;
  const int count = int(std::min(100000.0f, std::ceil(len / s.radius))) + 1;
  bool anyClipped = false, anyCulled = false;
  const bool textured = frame.texture != nullptr;
  for (int i = 0; i < count; ++i) {
    float t = count == 1 ? 0.5f : float(i) / float(count - 1);
    Point p;
    p.position = s.p0 + t * (s.p1 - s.p0);
    p.normal = s.normal;
    p.radius = s.radius;
    p.color = s.color;
    if (textured) {
      Vec2f uv = s.uv0 + t * (s.uv1 - s.uv0);
      Color tc = frame.texture->sampleBilinear(uv.x(), uv.y());
      p.color = Color(tc.x(), tc.y(), tc.z(), s.color.w());
    }
    PreparedPoint pp;
    PrimitiveStatus st = preparePoint(p, index, frame, pp);
    if (st == PrimitiveStatus::Drawn || st == PrimitiveStatus::Clipped) {
      anyClipped |= st == PrimitiveStatus::Clipped;
      out.bounds = out.pieces.empty() ? pp.bounds
                                      : PixelRect{std::min(out.bounds.x0, pp.bounds.x0), std::min(out.bounds.y0, pp.bounds.y0),
                                                  std::max(out.bounds.x1, pp.bounds.x1), std::max(out.bounds.y1, pp.bounds.y1)};
      out.pieces.push_back(pp);
    } else if (st == PrimitiveStatus::Culled) {
      anyCulled = true;
    } else if (st == PrimitiveStatus::Degenerate) {
      return st;
    }
  }
  if (out.pieces.empty()) return anyCulled ? PrimitiveStatus::Culled : PrimitiveStatus::Outside;
  return anyClipped ? PrimitiveStatus::Clipped : PrimitiveStatus::Drawn;
}

void rasterizeSegment(const PreparedSegment& s, const SplatContext& ctx) {
  for (const PreparedPoint& p : s.pieces) rasterizePoint(p, ctx);
}

}  // namespace linesurf
