// The row spans of a segment splat's cutoff region in SIMD (segment_spans.h). Compiled once per
// x86 target (Google Highway); the best one the CPU runs is picked at run time.
#include "segment_spans.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/segment_spans.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace linesurf::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;
using DF = hn::ScalableTag<float>;
using VF = hn::Vec<DF>;

// The rows' spans of a segment's cutoff region (segment_spans.h: segmentSpans). Eight
// half-planes g(x, y) >= 0 of the pixel (the support lines of the footprint's capsules in the
// directions (+-1, 0), (0, +-1), (+-1/ra, +-1/rb)), each a lower or an upper bound on x affine
// in the row; the rows in SIMD lanes.
int SegmentSpans(const SegmentRaster& S, const PixelRect& r, float slack, RowSpan* out) {
  constexpr int kC = 8;
  float loY[kC], lo0[kC], hiY[kC], hi0[kC];
  const float R = std::sqrt(S.R2);
  float h[kC], ra, rb, ua, ub;
  // M = (M^-1)^-1 in (a, b); the support of {v : v^T M^-1 v <= R^2} in direction n is R sqrt(n^T M n)
  auto support = [&](float a0, float a1, float skew, float across, float invM00, bool first) {
    const float Mbb = 1 / across, Mab = -skew * Mbb, Maa = invM00 + skew * skew * Mbb;
    const float ea = R * std::sqrt(Maa), eb = R * std::sqrt(Mbb);
    if (first) ra = ea, rb = eb, ua = 1 / ea, ub = 1 / eb;
    const float cross = 2 * Mab * ua * ub, diag = Maa * ua * ua + Mbb * ub * ub;
    const float ep = R * std::sqrt(std::max(0.0f, diag + cross)), em = R * std::sqrt(std::max(0.0f, diag - cross));
    const float hs[kC] = {a1 + ea, -a0 + ea, eb, eb, ua * a1 + ep, ua * a1 + em, -ua * a0 + em, -ua * a0 + ep};
    for (int i = 0; i < kC; ++i) h[i] = first ? hs[i] : std::max(h[i], hs[i]);
  };
  if (S.pieceCount > 1 && S.pieces) {
    for (int k = 0; k < S.pieceCount; ++k) {
      const SegmentPiece& p = S.pieces[k];
      if (!(p.across > 0) || !(p.invM00 > 0)) return -1;
      support(p.a0, p.a1, p.skew, p.across, p.invM00, k == 0);
    }
  } else {
    if (!(S.across > 0) || !(S.invM00 > 0)) return -1;
    support(0, S.length, S.skew, S.across, S.invM00, true);
  }
  const float dirs[kC][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1}, {ua, ub}, {ua, -ub}, {-ua, ub}, {-ua, -ub}};
  // n.(a, b) <= h with a = A / N - a0, b = B / N - b0, times N < 0: g = n_a A + n_b B - K0 N >= 0,
  // pushed `slack` pixel outward (|gx| + |gy| >= |grad g|); a lower bound on x where gx > 0, an
  // upper one where gx < 0, none where gx = 0 (conservative). Where N > 0 no pixel meets both of
  // the opposite directions (+-1, 0): N < 0 needs no bound of its own.
  float sum = 0;
  for (int i = 0; i < kC; ++i) {
    const float na = dirs[i][0], nb = dirs[i][1];
    // the rows' float rounding of a and b is covered by the slack; this by far more
    const float K0 = na * S.a0 + nb * S.b0 + h[i] + 1e-5f * (std::abs(na) * ra + std::abs(nb) * rb);
    const float gx = na * S.A.dx + nb * S.B.dx - K0 * S.N.dx, gy = na * S.A.dy + nb * S.B.dy - K0 * S.N.dy;
    const float g0 = na * S.A.c + nb * S.B.c - K0 * S.N.c + slack * (std::abs(gx) + std::abs(gy));
    const float inv = -1.0f / (gx != 0 ? gx : 1.0f);
    const bool lower = gx > 0, upper = gx < 0;
    loY[i] = lower ? gy * inv : 0.0f, lo0[i] = lower ? g0 * inv : -1e8f;
    hiY[i] = upper ? gy * inv : 0.0f, hi0[i] = upper ? g0 * inv : 1e8f;
    sum += loY[i] + lo0[i] + hiY[i] + hi0[i];
  }
  if (!std::isfinite(sum)) return -1;
  // rows in lanes: pixel centres x + 0.5 in [max lower, min upper]
  const DF d;
  const hn::RebindToSigned<DF> di;
  const int L = int(hn::Lanes(d));
  const VF half = hn::Set(d, 0.5f), big = hn::Set(d, 1e8f);
  const auto rx0 = hn::Set(di, r.x0), rx1 = hn::Set(di, r.x1);
  HWY_ALIGN int32_t xb[kMaxLanes], xe[kMaxLanes];
  int count = 0;
  for (int y = r.y0; y < r.y1; y += L) {
    const VF py = hn::Iota(d, float(y) + 0.5f);
    VF lo[2] = {hn::Neg(big), hn::Neg(big)}, hi[2] = {big, big};
    for (int i = 0; i < kC; ++i) {
      lo[i & 1] = hn::Max(lo[i & 1], hn::MulAdd(hn::Set(d, loY[i]), py, hn::Set(d, lo0[i])));
      hi[i & 1] = hn::Min(hi[i & 1], hn::MulAdd(hn::Set(d, hiY[i]), py, hn::Set(d, hi0[i])));
    }
    const VF l = hn::Min(hn::Max(lo[0], lo[1]), big), u = hn::Max(hn::Min(hi[0], hi[1]), hn::Neg(big));
    hn::Store(hn::Max(hn::ConvertTo(di, hn::Ceil(hn::Sub(l, half))), rx0), di, xb);
    hn::Store(hn::Min(hn::Add(hn::ConvertTo(di, hn::Floor(hn::Sub(u, half))), hn::Set(di, 1)), rx1), di, xe);
    const int rows = std::min(L, r.y1 - y);
    for (int j = 0; j < rows; ++j) {
      out[count] = {y + j, xb[j], xe[j]};
      count += xe[j] > xb[j];
    }
  }
  return count;
}

// SegmentSpans for a batch of one-piece segments with lanes = segments (segment_spans.h):
// the same eight constraints, set up once per vector of segments, then one row of every
// segment per step.
void SegmentSpansBatch(const SegmentRaster* const* segs, const PixelRect* rects, int n, float slack, RowSpan* out,
                       int stride, int* counts, int* widest, int* pixels) {
  const DF d;
  const hn::RebindToSigned<DF> di;
  const int L = int(hn::Lanes(d));
  constexpr int kC = 8;
  for (int g0 = 0; g0 < n; g0 += L) {
    const int m = std::min(L, n - g0);
    // the segments' constants, structure of arrays (unused lanes copy the last)
    enum { kR2, kLen, kSkew, kAcross, kInvM00, kA0, kB0, kAx, kAy, kAc, kBx, kBy, kBc, kNx, kNy, kNc, kIn };
    HWY_ALIGN float in[kIn][kMaxLanes];
    HWY_ALIGN int32_t rx0[kMaxLanes], rx1[kMaxLanes], ry0[kMaxLanes], rh[kMaxLanes];
    int maxRows = 0;
    for (int j = 0; j < L; ++j) {
      const int i = g0 + std::min(j, m - 1);
      const SegmentRaster& S = *segs[i];
      const float v[kIn] = {S.R2,  S.length, S.skew, S.across, S.invM00, S.a0,  S.b0,  S.A.dx,
                            S.A.dy, S.A.c,   S.B.dx, S.B.dy,   S.B.c,    S.N.dx, S.N.dy, S.N.c};
      for (int f = 0; f < kIn; ++f) in[f][j] = v[f];
      rx0[j] = rects[i].x0, rx1[j] = rects[i].x1, ry0[j] = rects[i].y0, rh[j] = rects[i].height();
      if (j < m) maxRows = std::max(maxRows, rh[j]);
    }
    auto V = [&](int f) { return hn::Load(d, in[f]); };
    const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f);
    const VF across = V(kAcross), invM00 = V(kInvM00), skew = V(kSkew), len = V(kLen);
    const auto ok = hn::And(hn::Gt(across, zero), hn::Gt(invM00, zero));
    // M = (M^-1)^-1 in (a, b); support R sqrt(n^T M n) of the cutoff ellipse in direction n
    const VF Mbb = hn::Div(one, hn::IfThenElse(ok, across, one));
    const VF Mab = hn::Neg(hn::Mul(skew, Mbb)), Maa = hn::MulAdd(hn::Mul(skew, skew), Mbb, invM00);
    const VF R = hn::Sqrt(V(kR2));
    const VF ea = hn::Mul(R, hn::Sqrt(hn::Max(Maa, zero))), eb = hn::Mul(R, hn::Sqrt(Mbb));
    const VF ua = hn::Div(one, hn::IfThenElse(ok, ea, one)), ub = hn::Div(one, hn::IfThenElse(ok, eb, one));
    const VF cross = hn::Mul(hn::Add(Mab, Mab), hn::Mul(ua, ub));
    const VF diag = hn::MulAdd(hn::Mul(Maa, ua), ua, hn::Mul(hn::Mul(Mbb, ub), ub));
    const VF ep = hn::Mul(R, hn::Sqrt(hn::Max(hn::Add(diag, cross), zero)));
    const VF em = hn::Mul(R, hn::Sqrt(hn::Max(hn::Sub(diag, cross), zero)));
    const VF nua = hn::Neg(ua), nub = hn::Neg(ub), neg1 = hn::Neg(one);
    const VF na[kC] = {one, neg1, zero, zero, ua, ua, nua, nua}, nb[kC] = {zero, zero, one, neg1, ub, nub, ub, nub};
    const VF h[kC] = {hn::Add(len, ea), ea, eb, eb, hn::MulAdd(ua, len, ep), hn::MulAdd(ua, len, em), em, ep};
    // the constraints (as SegmentSpans): a lower bound x >= loY py + lo0 or an upper one
    VF loY[kC], lo0[kC], hiY[kC], hi0[kC], lowMask[kC], upMask[kC];
    const VF sl = hn::Set(d, slack), rel = hn::Set(d, 1e-5f), big = hn::Set(d, 1e8f);
    auto finite = ok;
    for (int c = 0; c < kC; ++c) {
      const VF margin = hn::Mul(rel, hn::MulAdd(hn::Abs(na[c]), ea, hn::Mul(hn::Abs(nb[c]), eb)));
      const VF K0 = hn::Add(hn::MulAdd(na[c], V(kA0), hn::Mul(nb[c], V(kB0))), hn::Add(h[c], margin));
      const VF gx = hn::NegMulAdd(K0, V(kNx), hn::MulAdd(na[c], V(kAx), hn::Mul(nb[c], V(kBx))));
      const VF gy = hn::NegMulAdd(K0, V(kNy), hn::MulAdd(na[c], V(kAy), hn::Mul(nb[c], V(kBy))));
      const VF g = hn::MulAdd(sl, hn::Add(hn::Abs(gx), hn::Abs(gy)),
                              hn::NegMulAdd(K0, V(kNc), hn::MulAdd(na[c], V(kAc), hn::Mul(nb[c], V(kBc)))));
      const auto lower = hn::Gt(gx, zero), upper = hn::Lt(gx, zero);
      const VF inv = hn::Neg(hn::Div(one, hn::IfThenElse(hn::Or(lower, upper), gx, one)));
      const VF by = hn::Mul(gy, inv), b0 = hn::Mul(g, inv);
      lowMask[c] = hn::IfThenElseZero(lower, one), upMask[c] = hn::IfThenElseZero(upper, one);
      loY[c] = hn::IfThenElseZero(lower, by), lo0[c] = hn::IfThenElse(lower, b0, hn::Neg(big));
      hiY[c] = hn::IfThenElseZero(upper, by), hi0[c] = hn::IfThenElse(upper, b0, big);
      finite = hn::And(finite, hn::Lt(hn::Abs(hn::Add(by, b0)), hn::Set(d, INFINITY)));
    }
    HWY_ALIGN int32_t okLane[kMaxLanes];
    hn::Store(hn::VecFromMask(di, hn::RebindMask(di, finite)), di, okLane);
    for (int j = 0; j < m; ++j) counts[g0 + j] = okLane[j] ? 0 : -1;
    const auto X0 = hn::Load(di, rx0), X1 = hn::Load(di, rx1);
    const VF half = hn::Set(d, 0.5f);
    VF py = hn::Add(hn::ConvertTo(d, hn::Load(di, ry0)), half);
    // the rows' bounds in vectors (row t of lane j at [t][j]), kRows rows at a time, then each
    // lane's spans in a run of its own rows (no per-row test of the other lanes' heights) from its
    // first to its last non-empty row so far (a segment's rect holds about twice its spans' rows)
    constexpr int kRows = 32;
    HWY_ALIGN int32_t xb[kRows][kMaxLanes], xe[kRows][kMaxLanes], firstRow[kMaxLanes], lastRow[kMaxLanes];
    auto first = hn::Set(di, kRows), last = hn::Set(di, -1);
    // the widest span and the pixels of each lane's rows within its rect (SegmentRowsItem)
    const auto RH = hn::Load(di, rh);
    auto wideV = hn::Zero(di), pixV = hn::Zero(di);
    // each opposite pair of directions (0, 1), (2, 3), (4, 7), (5, 6) bounds x from both sides where
    // one of its constraints is a lower and the other an upper bound (always in an affine frame):
    // then the rows take the pair's lower and upper one, four constraints a side instead of eight
    // (the same maxima and minima of the same values: the same spans), and fit in registers
    constexpr int kPair[4][2] = {{0, 1}, {2, 3}, {4, 7}, {5, 6}};
    VF pLoY[4], pLo0[4], pHiY[4], pHi0[4];
    auto paired = finite;
    for (int p = 0; p < 4; ++p) {
      const int c = kPair[p][0], c1 = kPair[p][1];
      const auto lowC = hn::Gt(lowMask[c], zero), upC = hn::Gt(upMask[c], zero);
      const auto lowC1 = hn::Gt(lowMask[c1], zero), upC1 = hn::Gt(upMask[c1], zero);
      paired = hn::And(paired, hn::Or(hn::And(lowC, upC1), hn::And(upC, lowC1)));
      pLoY[p] = hn::IfThenElse(lowC, loY[c], loY[c1]), pLo0[p] = hn::IfThenElse(lowC, lo0[c], lo0[c1]);
      pHiY[p] = hn::IfThenElse(lowC, hiY[c1], hiY[c]), pHi0[p] = hn::IfThenElse(lowC, hi0[c1], hi0[c]);
    }
    auto rowsOf = [&](const VF* LY, const VF* L0, const VF* HY, const VF* H0, auto ncTag) {
      constexpr int nc = decltype(ncTag)::value;
      for (int t0 = 0; t0 < maxRows; t0 += kRows) {
        const int rows = std::min(kRows, maxRows - t0);
        for (int t = 0; t < rows; ++t, py = hn::Add(py, one)) {
          VF lo = hn::Neg(big), hi = big;
          for (int c = 0; c < nc; ++c) {
            lo = hn::Max(lo, hn::MulAdd(LY[c], py, L0[c]));
            hi = hn::Min(hi, hn::MulAdd(HY[c], py, H0[c]));
          }
          lo = hn::Min(lo, big), hi = hn::Max(hi, hn::Neg(big));
          const auto b = hn::Max(hn::ConvertTo(di, hn::Ceil(hn::Sub(lo, half))), X0);
          const auto e = hn::Min(hn::Add(hn::ConvertTo(di, hn::Floor(hn::Sub(hi, half))), hn::Set(di, 1)), X1);
          hn::Store(b, di, xb[t]);
          hn::Store(e, di, xe[t]);
          const auto some = hn::Gt(e, b);
          const auto w = hn::IfThenElseZero(hn::And(some, hn::Lt(hn::Set(di, t0 + t), RH)), hn::Sub(e, b));
          wideV = hn::Max(wideV, w), pixV = hn::Add(pixV, w);
          first = hn::IfThenElse(hn::And(some, hn::Eq(first, hn::Set(di, kRows))), hn::Set(di, t), first);
          last = hn::IfThenElse(some, hn::Set(di, t), last);
        }
        hn::Store(first, di, firstRow);
        hn::Store(last, di, lastRow);
        first = hn::IfThenElse(hn::Eq(first, hn::Set(di, kRows)), first, hn::Zero(di));  // the next chunk from its row 0
        last = hn::Set(di, -1);
        for (int j = 0; j < m; ++j) {
          int c = counts[g0 + j];
          if (c < 0) continue;
          RowSpan* o = out + size_t(g0 + j) * size_t(stride);
          for (int t = firstRow[j], te = std::min(lastRow[j] + 1, rh[j] - t0); t < te; ++t) {
            o[c] = {ry0[j] + t0 + t, xb[t][j], xe[t][j]};
            c += xe[t][j] > xb[t][j];
          }
          counts[g0 + j] = c;
        }
      }
    };
    if (hn::AllTrue(d, hn::Or(paired, hn::Not(finite)))) {
      rowsOf(pLoY, pLo0, pHiY, pHi0, std::integral_constant<int, 4>());
    } else {
      rowsOf(loY, lo0, hiY, hi0, std::integral_constant<int, kC>());
    }
    if (widest) {
      HWY_ALIGN int32_t wa[kMaxLanes], pa[kMaxLanes];
      hn::Store(wideV, di, wa), hn::Store(pixV, di, pa);
      for (int j = 0; j < m; ++j) widest[g0 + j] = wa[j], pixels[g0 + j] = pa[j];
    }
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(SegmentSpans);
HWY_EXPORT(SegmentSpansBatch);

int segmentSpans(const SegmentRaster& s, const PixelRect& r, float slack, RowSpan* out) {
  return HWY_DYNAMIC_DISPATCH(SegmentSpans)(s, r, slack, out);
}
void segmentSpansBatch(const SegmentRaster* const* segs, const PixelRect* rects, int n, float slack, RowSpan* out,
                       int stride, int* counts, int* widest, int* pixels) {
  HWY_DYNAMIC_DISPATCH(SegmentSpansBatch)(segs, rects, n, slack, out, stride, counts, widest, pixels);
}
}  // namespace linesurf::detail
#endif
