#pragma once
/// Where a segment splat can have fragments (beyond the thesis, §5.2): the row spans of the screen
/// region its cutoff capsule projects to, so that the rows (segment_rows.h) visit no pixel of the
/// footprint box that the kernel cannot reach. segment_spans.cpp, Highway runtime dispatch.
#include "segment_rows.h"

namespace linesurf::detail {

/// The rows' spans over r (at most r.height()) of the pixels where the segment can have a
/// fragment (beyond the thesis): a pixel's ray meets the strip's plane (N < 0) at (a, b) in the
/// union over the sub-segments k of [a0_k, a1_k] x {0} + {v : v^T M_k^-1 v < R^2} (the capsule
/// of the cutoff); its support lines in eight directions (the footprint box's sides and its
/// corners cut along the ellipse's diagonals) are, multiplied by N, half-planes of the screen.
/// Every bound is pushed `slack` pixel outward against rounding. Returns how many spans (empty
/// rows left out), or -1 for degenerate constants (walk the footprint box instead).
int segmentSpans(const SegmentRaster& s, const PixelRect& r, float slack, RowSpan* out);

/// segmentSpans for n one-piece segments at once (pieceCount == 1; SIMD lanes = segments):
/// segment i's spans over rects[i] (at most stride rows) go to out + i * stride, counts[i] their
/// number, or -1 for degenerate constants; with widest (and pixels), widest[i] the widest of
/// segment i's spans and pixels[i] their pixels (SegmentRowsItem).
void segmentSpansBatch(const SegmentRaster* const* segs, const PixelRect* rects, int n, float slack, RowSpan* out,
                       int stride, int* counts, int* widest = nullptr, int* pixels = nullptr);

}  // namespace linesurf::detail
