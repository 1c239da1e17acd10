// SIMD splat weights (thesis §4.2.2 EWA point kernel, §5.2 segment kernel in closed form) over pixel blocks with Google Highway's runtime dispatch (see
// detail/splat_rows.h). Compiled once per x86 target; hwy picks the best the CPU runs.
#include "detail/splat_rows.h"
#include "coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/splat_rows.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>

HWY_BEFORE_NAMESPACE();
namespace linesurf::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;
using DF = hn::ScalableTag<float>;
using VF = hn::Vec<DF>;

// Pixel centres of lanes k .. k + lanes - 1 of a row-major rectangle of `width` pixels.
struct BlockWalker {
  DF d;
  VF iota = hn::Iota(d, 0.0f), half = hn::Set(d, 0.5f), w, x0, y0;
  BlockWalker(int width, int px0, int py0)
      : w(hn::Set(d, float(width))), x0(hn::Set(d, float(px0) + 0.5f)), y0(hn::Set(d, float(py0) + 0.5f)) {}
  void at(int k, VF& px, VF& py) const {
    const VF kk = hn::Add(iota, hn::Set(d, float(k)));
    const VF row = hn::Floor(hn::Div(hn::Add(kk, half), w));
    px = hn::Add(hn::NegMulAdd(row, w, kk), x0);
    py = hn::Add(row, y0);
  }
};

HWY_INLINE VF affine(DF d, const Affine2& f, VF px, VF py) {
  return hn::MulAdd(hn::Set(d, f.dx), px, hn::MulAdd(hn::Set(d, f.dy), py, hn::Set(d, f.c)));
}

// --- points (§4.2.2: the object-space EWA kernel, evaluated per pixel through the tangent plane) --

// 1 / n by the reciprocal estimate and one Newton step (beyond the thesis): within about an ulp of
// the division (AVX-512's estimate has 14 bits, AVX2's 12; the step squares the error) at a third
// of its latency: the point kernel's only division.
HWY_INLINE VF reciprocalNewton(DF d, VF n) {
  const VF r = hn::ApproximateReciprocal(n);
  return hn::MulAdd(r, hn::NegMulAdd(n, r, hn::Set(d, 1.0f)), r);
}

// exp(-q/2) for 0 <= q <= kPolyExpMaxQ (the default cutoff of 2 standard deviations gives q <= 4)
// by a polynomial of degree 6 in Estrin's scheme (beyond the thesis: Chebyshev interpolation on
// [0, 4], absolute error 1.4e-6, relative 9e-6 in float, far below the 8-bit output), about half
// of hn::Exp's instructions and latency; wider cutoffs keep hn::Exp (kPoly false).
inline constexpr float kPolyExpMaxQ = 4.0f;
template <bool kPoly>
HWY_INLINE VF expHalfNeg(DF d, VF q) {
  if (!kPoly) return hn::Exp(d, hn::Mul(q, hn::Set(d, -0.5f)));
  const VF q2 = hn::Mul(q, q), q4 = hn::Mul(q2, q2);
  const VF a = hn::MulAdd(hn::Set(d, -0.4999672770500183f), q, hn::Set(d, 0.9999986886978149f));
  const VF b = hn::MulAdd(hn::Set(d, -0.020628463476896286f), q, hn::Set(d, 0.12486723810434341f));
  const VF c = hn::MulAdd(hn::Set(d, -0.00019870136748068035f), q, hn::Set(d, 0.002450336469337344f));
  return hn::MulAdd(q4, hn::MulAdd(hn::Set(d, 8.236473149736412e-06f), q2, c), hn::MulAdd(q2, b, a));
}

// One point splat's per-pixel constants in vectors (PointRaster / PointHot) and its kernel at the
// pixel centres (px, py) of the lanes: the ray meets the splat's plane at depth z = depthNum / N
// with plane coordinates (s, t) = (S, T) / N, q = s^2 + t^2, weight exp(-q/2) * scale; `hit`: in
// front of the eye (N < 0) and q <= cutoffQ. Shared by pointFragments and the rows (they agree).
struct PointKernel {
  VF Ndx, Ndy, N0, Sdx, Sdy, S0, Tdx, Tdy, T0, depthNum, scale;
  PointKernel(DF d, const Affine2& N, const Affine2& S, const Affine2& T, float dn, float sc)
      : Ndx(hn::Set(d, N.dx)), Ndy(hn::Set(d, N.dy)), N0(hn::Set(d, N.c)), Sdx(hn::Set(d, S.dx)),
        Sdy(hn::Set(d, S.dy)), S0(hn::Set(d, S.c)), Tdx(hn::Set(d, T.dx)), Tdy(hn::Set(d, T.dy)),
        T0(hn::Set(d, T.c)), depthNum(hn::Set(d, dn)), scale(hn::Set(d, sc)) {}
  struct At {
    VF z, s, t, w;
    hn::Mask<DF> hit;
  };
  template <bool kPoly>
  HWY_INLINE At at(DF d, VF px, VF py, VF cutoff) const {
    const VF n = hn::MulAdd(Ndx, px, hn::MulAdd(Ndy, py, N0));
    const VF iN = reciprocalNewton(d, n);
    At a;
    a.z = hn::Mul(depthNum, iN);
    a.s = hn::Mul(hn::MulAdd(Sdx, px, hn::MulAdd(Sdy, py, S0)), iN);
    a.t = hn::Mul(hn::MulAdd(Tdx, px, hn::MulAdd(Tdy, py, T0)), iN);
    const VF q = hn::MulAdd(a.s, a.s, hn::Mul(a.t, a.t));
    a.hit = hn::And(hn::Lt(n, hn::Zero(d)), hn::Le(q, cutoff));
    a.w = hn::Mul(expHalfNeg<kPoly>(d, hn::Min(q, cutoff)), scale);
    return a;
  }
};

// The prefilter tail of a point splat (beyond the thesis, issue 14; Z3Tile::setTailLayers): a
// fragment whose ray meets the splat's plane outside kTailDisc times its own disc |p - c| <=
// cutoff sigma_r, i.e. g0 s^2 + g1 s t + g2 t^2 > 1 with p - c = s B0 + t B1 (PointCold::disc):
// only the screen prefilter put it there, and its depth is the plane's, extrapolated. Its depth
// is returned negated (the rows' pass 2 reads the sign back).
struct PointTail {
  VF g0, g1, g2;
  PointTail(DF d, const float* disc) : g0(hn::Set(d, disc[0])), g1(hn::Set(d, disc[1])), g2(hn::Set(d, disc[2])) {}
  HWY_INLINE VF z(DF d, VF s, VF t, VF z) const {
    const VF Q = hn::MulAdd(g0, hn::Mul(s, s), hn::MulAdd(g1, hn::Mul(s, t), hn::Mul(g2, hn::Mul(t, t))));
    return hn::IfThenElse(hn::Gt(Q, hn::Set(d, 1.0f)), hn::Neg(z), z);
  }
};

// Packs the lanes of `keep` into the block at `at`; returns how many. Compress in registers and
// store whole vectors (the arrays are padded): a compressing store to memory is microcoded on
// some CPUs (Zen 4).
HWY_INLINE int pack(DF d, hn::Mask<DF> keep, VF x, VF y, VF w, VF z, VF p, VF q, bool withPQ, FragmentBlock& out, int at) {
  hn::StoreU(hn::Compress(x, keep), d, out.x + at);
  hn::StoreU(hn::Compress(y, keep), d, out.y + at);
  hn::StoreU(hn::Compress(w, keep), d, out.weight + at);
  hn::StoreU(hn::Compress(z, keep), d, out.depth + at);
  if (withPQ) {
    hn::StoreU(hn::Compress(p, keep), d, out.p + at);
    hn::StoreU(hn::Compress(q, keep), d, out.q + at);
  }
  return int(hn::CountTrue(d, keep));
}

template <bool kPoly>
int PointFragmentsT(const PointRaster& P, int x0, int y0, int width, int k0, int n, bool withPlaneCoords,
                    FragmentBlock& out) {
  const BlockWalker walk(width, x0, y0);
  const DF d;
  const int L = int(hn::Lanes(d));
  const PointKernel K(d, P.N, P.S, P.T, P.depthNum, P.weightScale);
  const VF cutoff = hn::Set(d, P.cutoffQ), nearD = hn::Set(d, P.nearD), farD = hn::Set(d, P.farD);
  const VF lane = hn::Iota(d, 0.0f), count = hn::Set(d, float(n));
  int m = 0;
  for (int i = 0; i < n; i += L) {
    VF px, py;
    walk.at(k0 + i, px, py);
    const auto a = K.at<kPoly>(d, px, py, cutoff);
    auto inside = hn::And(a.hit, hn::Lt(hn::Add(lane, hn::Set(d, float(i))), count));
    if (P.clipDepth) inside = hn::And(inside, hn::And(hn::Ge(a.z, nearD), hn::Le(a.z, farD)));
    inside = hn::And(inside, hn::Gt(a.w, hn::Zero(d)));
    m += pack(d, inside, px, py, a.w, a.z, a.s, a.t, withPlaneCoords, out, m);
  }
  return m;
}

int PointFragments(const PointRaster& P, int x0, int y0, int width, int k0, int n, bool withPlaneCoords,
                   FragmentBlock& out) {
  return P.cutoffQ <= kPolyExpMaxQ ? PointFragmentsT<true>(P, x0, y0, width, k0, n, withPlaneCoords, out)
                                   : PointFragmentsT<false>(P, x0, y0, width, k0, n, withPlaneCoords, out);
}

// --- segments (§5: the ScreenSpace closed form of segment_methods.cpp) ----------------------

// erf(x) without exp (Abramowitz & Stegun 7.1.28: 1 - (1 + a1 x + ... + a6 x^6)^-16, absolute
// error < 3e-7; about 1e-6 in float); 1 / p by reciprocalNewton (p >= 1), as the point kernel.
HWY_INLINE VF erfRational(DF d, VF x) {
  using V = VF;
  const V ax = hn::Abs(x);
  V p = hn::Set(d, 0.0000430638f);
  p = hn::MulAdd(p, ax, hn::Set(d, 0.0002765672f));
  p = hn::MulAdd(p, ax, hn::Set(d, 0.0001520143f));
  p = hn::MulAdd(p, ax, hn::Set(d, 0.0092705272f));
  p = hn::MulAdd(p, ax, hn::Set(d, 0.0422820123f));
  p = hn::MulAdd(p, ax, hn::Set(d, 0.0705230784f));
  p = hn::MulAdd(p, ax, hn::Set(d, 1.0f));
  p = hn::Mul(p, p);  // ^2
  p = hn::Mul(p, p);  // ^4
  p = hn::Mul(p, p);  // ^8
  p = hn::Mul(p, p);  // ^16
  const V r = hn::Sub(hn::Set(d, 1.0f), reciprocalNewton(d, p));
  return hn::CopySign(r, x);
}

// erf(x) for |x| <= kPolyErfMaxX as x P(x^2), P of degree 6 in Estrin's scheme (beyond the thesis:
// least squares on Chebyshev nodes, absolute error 3.1e-7 in float, as erfRational's; about half
// its instructions, no reciprocal). The segment kernel's erf arguments are u = k (t - tau*) with
// |t - tau*| <= delta, so |u| <= sqrt((R^2 - qmin) / 2) <= R / sqrt(2): within range whenever
// the Gaussian takes expHalfNeg's polynomial (R^2 <= kPolyExpMaxQ = 4 gives |u| <= 1.42).
inline constexpr float kPolyErfMaxX = 1.5f;
static_assert(kPolyExpMaxQ <= 2 * kPolyErfMaxX * kPolyErfMaxX);
template <bool kPoly>
HWY_INLINE VF erfKernel(DF d, VF x) {
  if (!kPoly) return erfRational(d, x);
  const VF t = hn::Mul(x, x), t2 = hn::Mul(t, t), t4 = hn::Mul(t2, t2);
  const VF a = hn::MulAdd(hn::Set(d, -0.37610021233558655f), t, hn::Set(d, 1.1283776760101318f));
  const VF b = hn::MulAdd(hn::Set(d, -0.02658114954829216f), t, hn::Set(d, 0.11270857602357864f));
  const VF c = hn::MulAdd(hn::Set(d, -0.0006430802750401199f), t, hn::Set(d, 0.004894962068647146f));
  const VF p = hn::MulAdd(t4, hn::MulAdd(hn::Set(d, 4.422103666001931e-05f), t2, c), hn::MulAdd(t2, b, a));
  return hn::Mul(x, p);
}

// Pixel centres of the spans, packed: lanes are filled across rows, so a segment a few pixels
// wide costs as many vectors as its pixels fill, not one per row.
HWY_INLINE int expandSpans(DF d, const RowSpan* spans, int count, float* px, float* py) {
  const int L = int(hn::Lanes(d));
  const VF iota = hn::Iota(d, 0.5f);
  int n = 0;
  for (int r = 0; r < count; ++r) {
    const RowSpan& s = spans[r];
    const VF y = hn::Set(d, float(s.y) + 0.5f);
    const int w = s.x1 - s.x0;
    for (int i = 0; i < w; i += L) {  // the arrays are padded by kMaxLanes; the next span overwrites the excess
      hn::StoreU(hn::Add(iota, hn::Set(d, float(s.x0 + i))), d, px + n + i);
      hn::StoreU(y, d, py + n + i);
    }
    n += w;
  }
  return n;
}

// The frame's constants of the segment kernel (SegmentRaster's R2, nearD, farD: the same for every
// segment of a frame), set once per run of segments and again only when they change.
struct SegmentFrameV {
  DF d;
  VF one = hn::Set(d, 1.0f), zero = hn::Zero(d), mhalf = hn::Set(d, -0.5f);
  VF R2, halfR2, nearD, farD;
  VF gcut;  ///< exp(-R^2 / 2) (as expHalfNeg gives it): the slope term's ends where the cutoff bounds
  float r2 = std::numeric_limits<float>::quiet_NaN(), nd = 0, fd = 0;
  bool poly = false;  ///< R2 <= kPolyExpMaxQ: exp by the polynomial
  SegmentFrameV() = default;  ///< set() before use
  explicit SegmentFrameV(const SegmentRaster& S) { set(S); }
  HWY_INLINE void set(const SegmentRaster& S) {
    if (S.R2 == r2 && S.nearD == nd && S.farD == fd) return;
    r2 = S.R2, nd = S.nearD, fd = S.farD;
    R2 = hn::Set(d, r2), halfR2 = hn::Set(d, 0.5f * r2), nearD = hn::Set(d, nd), farD = hn::Set(d, fd);
    poly = r2 <= kPolyExpMaxQ;
    gcut = poly ? expHalfNeg<true>(d, R2) : expHalfNeg<false>(d, R2);
  }
};

// A segment's weight, depth and along-axis parameter u at the pixels (px, py) of the lanes in
// `valid`: the closed form of segment_methods.cpp (screenSpaceWeight), summed over the
// sub-segments that can reach the lanes. Returns the lanes with a fragment (w > 0). The economies
// of the point kernel (PointKernel): 1 / N and erf's 1 / p by reciprocalNewton, the Gaussian
// across the line exp(-qmin / 2) and the slope term's ends by expHalfNeg (kPoly: R^2 <= 4; both
// arguments are clamped to R^2). Shared by segmentFragments and the rows (they agree).
template <bool kPoly>
struct SegmentKernel {
  using D = DF;
  using V = VF;
  D d;
  const SegmentRaster& S;
  const SegmentFrameV& F;
  V a0 = hn::Set(d, S.a0), b0 = hn::Set(d, S.b0), invLen = hn::Set(d, S.length > 0 ? 1.0f / S.length : 0.0f);
  V aMin = hn::Set(d, S.aMin), aMax = hn::Set(d, S.aMax), bMax = hn::Set(d, S.bMax);
  V depthNum = hn::Set(d, S.depthNum);
  V Ndx = hn::Set(d, S.N.dx), Ndy = hn::Set(d, S.N.dy), N0 = hn::Set(d, S.N.c);
  V Adx = hn::Set(d, S.A.dx), Ady = hn::Set(d, S.A.dy), A0 = hn::Set(d, S.A.c);
  V Bdx = hn::Set(d, S.B.dx), Bdy = hn::Set(d, S.B.dy), B0 = hn::Set(d, S.B.c);
  // one sub-segment's constants
  struct Piece {
    V a0, len, skew, across, halfAcross, invM00, k, erfScale0, erfSlope, slope;
    bool flat;  ///< slope == 0
  };
  Piece first;
  static Piece piece(D d, float pa0, float len, float skew, float across, float invM00, float k, float erfScale,
                     float scale0, float slope) {
    const PieceScale s = pieceScale(scale0, slope, len);  // flat where the scale barely changes
    return {hn::Set(d, pa0),           hn::Set(d, len),          hn::Set(d, skew),
            hn::Set(d, across),        hn::Set(d, 0.5f * across), hn::Set(d, invM00),
            hn::Set(d, k),             hn::Set(d, erfScale * s.scale0), hn::Set(d, erfScale * s.slope),
            hn::Set(d, s.slope),       s.slope == 0};
  }
  static Piece piece(D d, const SegmentPiece& p) {
    return piece(d, p.a0, p.a1 - p.a0, p.skew, p.across, p.invM00, p.k, p.erfScale, p.scale0, p.slope);
  }
  SegmentKernel(const SegmentRaster& s, const SegmentFrameV& f)
      : S(s), F(f), first(piece(D(), 0, s.length, s.skew, s.across, s.invM00, s.k, s.erfScale, s.scale0, s.slope)) {}

  // The integral along one sub-segment at plane coordinates (a, b), zero outside `inside`.
  HWY_INLINE V pieceWeight(const Piece& p, V a, V b, hn::Mask<D> inside) const {
    const V zero = F.zero, R2 = F.R2;
    // with x = a - a0 - tau: q(tau) = m00 (tau - tau*)^2 + qmin, kernels count where q <= R^2,
    // i.e. u = k (tau - tau*) in [-kd, kd] with k = sqrt(m00 / 2), kd = sqrt((R^2 - qmin) / 2);
    // the sub-segment [0, len] is u in [-k tau*, k (len - tau*)]. In u directly (beyond the
    // thesis, issue 13: no tau-space interval, a shorter dependency chain than clamping tau and
    // scaling back): the same integral, rounded differently
    const V tauStar = hn::MulAdd(p.skew, b, hn::Sub(a, p.a0));
    const V bb = hn::Mul(b, b);
    const V qmin = hn::Mul(bb, p.across);
    const V kd = hn::Sqrt(hn::Max(hn::NegMulAdd(bb, p.halfAcross, F.halfR2), zero));  // (R^2 - qmin) / 2
    const V uS = hn::Mul(p.k, tauStar);                 // -u of the sub-segment's start
    const V uE = hn::MulSub(p.k, p.len, uS);            // u of its end
    const V nkd = hn::Neg(kd);
    // the ends of the sub-segment that cut the kernels' interval [-kd, kd]
    const auto cut0 = hn::Lt(uS, kd), cut1 = hn::Lt(uE, kd);
    const V u0 = hn::Max(hn::Neg(uS), nkd), u1 = hn::Min(uE, kd);
    inside = hn::And(inside, hn::And(hn::Lt(qmin, R2), hn::Gt(u1, u0)));
    if (hn::AllFalse(d, inside)) return zero;
    const V qc = hn::Min(qmin, R2);
    const V g = expHalfNeg<kPoly>(d, qc);  // exp(-qmin / 2)
    // integral of exp(-m00 (tau - tau*)^2 / 2) over the sub-segment = (erf(u1) - erf(u0)) / k
    // (erfScale = sqrt(pi) / 2 / k): erf without exp. At an uncut end u is -+kd exactly, so a
    // vector without cut lanes (the middle of a long segment) takes 2 erf(kd), the same value to
    // the bit (erfKernel is odd exactly): a pixel's weight does not depend on its lane's vector
    // w = (erf(u1) - erf(u0)) erfScale (scale0 + slope tau*) g, the factors beside the erfs first
    const V sg = hn::Mul(hn::MulAdd(p.erfSlope, tauStar, p.erfScale0), g);
    V w;
    if (hn::AllFalse(d, hn::And(inside, hn::Or(cut0, cut1)))) {
      const V e = erfKernel<kPoly>(d, kd);
      w = hn::Mul(hn::Add(e, e), sg);
    } else {
      w = hn::Mul(hn::Sub(erfKernel<kPoly>(d, u1), erfKernel<kPoly>(d, u0)), sg);
    }
    if (!p.flat) {
      // the scale's slope adds slope / m00 (g e0 - g e1), g e_i = exp(-qmin/2 - u_i^2): at an end
      // the cutoff bounds (not the sub-segment's end) that is exp(-R^2/2) at both, so only the
      // ends the sub-segment cuts need an exp (long segments: rarely a vector)
      V ge0 = F.gcut, ge1 = F.gcut;
      const V two = hn::Add(F.one, F.one);
      if (!hn::AllFalse(d, cut0))
        ge0 = hn::IfThenElse(cut0, expHalfNeg<kPoly>(d, hn::Min(hn::MulAdd(two, hn::Mul(u0, u0), qc), R2)), ge0);
      if (!hn::AllFalse(d, cut1))
        ge1 = hn::IfThenElse(cut1, expHalfNeg<kPoly>(d, hn::Min(hn::MulAdd(two, hn::Mul(u1, u1), qc), R2)), ge1);
      w = hn::MulAdd(hn::Mul(p.slope, p.invM00), hn::Sub(ge0, ge1), w);
    }
    return hn::IfThenElseZero(inside, w);
  }

  HWY_INLINE hn::Mask<D> operator()(V px, V py, hn::Mask<D> valid, V& w, V& z, V& u, V* bOut = nullptr,
                                    V* aOut = nullptr) const {
    const V zero = F.zero;
    // the ray through the pixel meets the strip's plane (in front of the eye) at depth z
    const V nr = hn::MulAdd(Ndx, px, hn::MulAdd(Ndy, py, N0));
    const V iN = reciprocalNewton(d, nr);
    z = hn::Mul(depthNum, iN);
    auto inside = hn::And(hn::Lt(nr, zero), valid);
    if (S.clipDepth) inside = hn::And(inside, hn::And(hn::Ge(z, F.nearD), hn::Le(z, F.farD)));
    const V a = hn::MulSub(hn::MulAdd(Adx, px, hn::MulAdd(Ady, py, A0)), iN, a0);
    const V b = hn::MulSub(hn::MulAdd(Bdx, px, hn::MulAdd(Bdy, py, B0)), iN, b0);
    if (bOut) *bOut = b;
    if (aOut) *aOut = a;
    if (S.pieceCount == 1) {
      // (no footprint box test: the sub-segment's own test, qmin < R^2 and a cut kernel interval,
      // is the capsule of the cutoff that the box holds)
      if (hn::AllFalse(d, inside)) return inside;
      w = pieceWeight(first, a, b, inside);
    } else {  // the pieces whose reach can contain the lanes' a (with a piece of margin each side)
      inside = hn::And(inside, hn::And(hn::Le(hn::Abs(b), bMax), hn::And(hn::Ge(a, aMin), hn::Le(a, aMax))));
      if (hn::AllFalse(d, inside)) return inside;
      w = zero;
      const float aLo = hn::GetLane(hn::MinOfLanes(d, hn::IfThenElse(inside, a, hn::Set(d, 1e30f))));
      const float aHi = hn::GetLane(hn::MaxOfLanes(d, hn::IfThenElse(inside, a, hn::Set(d, -1e30f))));
      const float K = float(S.pieceCount);
      const int k0 = int(std::clamp(std::floor((aLo - S.pieceMaxReach) * S.pieceInvLength) - 1.0f, 0.0f, K));
      const int k1 = int(std::clamp(std::floor((aHi + S.pieceMaxReach) * S.pieceInvLength) + 2.0f, 0.0f, K));
      for (int k = k0; k < k1; ++k) w = hn::Add(w, pieceWeight(piece(d, S.pieces[k]), a, b, inside));
    }
    u = hn::Min(F.one, hn::Max(zero, hn::Mul(a, invLen)));
    return hn::And(inside, hn::Gt(w, zero));
  }
};

template <bool kPoly>
int SegmentFragmentsT(const SegmentRaster& S, const SegmentFrameV& F, const RowSpan* spans, int spanCount,
                      FragmentBlock& out) {
  const SegmentKernel<kPoly> kernel(S, F);
  const DF d;
  const int L = int(hn::Lanes(d));
  alignas(64) float pxs[kBlock + kMaxLanes], pys[kBlock + kMaxLanes];
  const int n = expandSpans(d, spans, spanCount, pxs, pys);
  const VF lane = hn::Iota(d, 0.0f), count = hn::Set(d, float(n));
  const VF thr0 = hn::Set(d, S.zThreshold0), thrD = hn::Set(d, S.zThreshold1 - S.zThreshold0);
  int m = 0;
  for (int i = 0; i < n; i += L) {
    const VF px = hn::Load(d, pxs + i), py = hn::Load(d, pys + i);
    VF w, z, u;
    const auto keep = kernel(px, py, hn::Lt(hn::Add(lane, hn::Set(d, float(i))), count), w, z, u);
    if (hn::AllFalse(d, keep)) continue;
    m += pack(d, keep, px, py, w, z, u, hn::MulAdd(u, thrD, thr0), true, out, m);
  }
  return m;
}

int SegmentFragments(const SegmentRaster& S, const RowSpan* spans, int spanCount, FragmentBlock& out) {
  const SegmentFrameV F(S);
  return F.poly ? SegmentFragmentsT<true>(S, F, spans, spanCount, out) : SegmentFragmentsT<false>(S, F, spans, spanCount, out);
}

// The rows' spans of a segment's cutoff region (detail/splat_rows.h: segmentSpans). Eight
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

// SegmentSpans for a batch of one-piece segments with lanes = segments (detail/splat_rows.h):
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

// The Z^3 fast path of the point and segment rows: of the lanes `inside` at tile pixels
// p .. p + lanes - 1, those on an empty pixel open its first layer, those within the z threshold
// of a pixel's single layer merge into it (masked load-add-store per blended sum, attrAt(k) the
// lanes' attributes; the normal sums only when the tile blends them), those behind a single
// opaque layer are dropped; returns the lanes left for Z3Tile::insert.
template <class D>
struct Z3Rows {
  using V = hn::Vec<D>;
  D d;
  hn::RebindToSigned<D> di;
  // field f of layer 0 at pixel index p: base[f * stride + p] (one base and a stride, not a
  // pointer per field: fewer registers in the rows)
  float* base;
  size_t stride;
  int32_t* cnt;
  bool opaque;
  int nAttr;
  float coverage;  // Z3Tile::coverageScale(): a layer is opaque once its coverage reaches 1
  bool tails;      // Z3Tile::tailLayers(): a tail fragment occludes nothing (its layer's flag -1)
  float* behindBase;  // Z3Tile::behindPlane(0) (its planes `stride` apart), or null
  int32_t* behindCnt;
  // per-lane counts of the lanes opened and of those dropped behind (a vector subtract of the
  // mask per row, not a popcount); opened() / occluded() sum them
  hn::Vec<hn::RebindToSigned<D>> openedV = hn::Zero(di), occludedV = hn::Zero(di);
  uint64_t opened() const { return uint64_t(hn::GetLane(hn::SumOfLanes(di, openedV))); }
  uint64_t occluded() const { return uint64_t(hn::GetLane(hn::SumOfLanes(di, occludedV))); }
  // pass 1 hands a tail's depth on negated (PointTail, the segment rows): the tail lanes, with z
  // made positive again
  HWY_INLINE hn::Mask<D> takeTails(V& z) const {
    const auto tail = hn::Lt(z, hn::Zero(d));
    if (tails) z = hn::Abs(z);
    return tail;
  }
  Z3Rows(Z3Tile& z3, bool opaqueFragments)
      : base(z3.plane(0, 0)), stride(size_t(z3.plane(0, 1) - z3.plane(0, 0))), cnt(z3.counts()),
        opaque(opaqueFragments || !z3.coverageOccludes()), nAttr(z3.blendNormals() ? Z3Tile::kAttrs : Z3Tile::kW + 1),
        coverage(z3.coverageOccludes() ? z3.coverageScale() : 0.0f), tails(z3.tailLayers()),
        behindBase(z3.behindPlane(0)), behindCnt(z3.behindCounts()) {}
  HWY_INLINE float* field(int f, size_t p) const { return base + size_t(f) * stride + p; }
  template <class AttrAt>
  HWY_INLINE hn::Mask<D> operator()(size_t p, hn::Mask<D> inside, V w, V z, V thr, AttrAt&& attrAt) {
    return (*this)(p, inside, w, z, thr, attrAt, hn::FirstN(d, 0));
  }
  // tail: the lanes that are tail fragments (Z3Tile::setTailLayers; read only when `tails`)
  template <class AttrAt>
  HWY_INLINE hn::Mask<D> operator()(size_t p, hn::Mask<D> inside, V w, V z, V thr, AttrAt&& attrAt, hn::Mask<D> tail) {
    const V zero = hn::Zero(d);
    const auto count = hn::LoadU(di, cnt + p);
    const auto open = hn::And(inside, hn::RebindMask(d, hn::Eq(count, hn::Zero(di))));
    const auto single = hn::And(inside, hn::RebindMask(d, hn::Eq(count, hn::Set(di, 1))));
    const V z0 = hn::LoadU(d, field(Z3Tile::kZ, p));
    const auto within = hn::Le(hn::Abs(hn::Sub(z, z0)), hn::Max(thr, hn::LoadU(d, field(Z3Tile::kThr, p))));
    const auto fast = hn::Or(open, hn::And(single, within));
    const V flag0 = hn::LoadU(d, field(Z3Tile::kOpaque, p));
    // behind a single opaque layer; with tail layers in an opaque frame a tail in front of the
    // single layer (skipped) or behind it (occluded: every layer is opaque or tail-only) too
    auto drop = hn::And(hn::Gt(z, z0), hn::Gt(flag0, zero));
    if (tails && opaque) drop = hn::Or(drop, tail);
    const auto behind = hn::AndNot(within, hn::And(single, drop));
    if (!hn::AllFalse(d, fast)) {
      auto blend = [&](int k) {
        const V add = hn::Mul(w, attrAt(k));
        const V sum = hn::IfThenElse(open, add, hn::Add(hn::LoadU(d, field(k, p)), add));
        hn::BlendedStore(sum, fast, d, field(k, p));
      };
      for (int k = 0; k <= Z3Tile::kW; ++k) blend(k);  // unrolled: the colour, alpha and weight sums
      for (int k = Z3Tile::kW + 1; k < nAttr; ++k) blend(k);
      hn::BlendedStore(z, open, d, field(Z3Tile::kZ, p));
      hn::BlendedStore(thr, open, d, field(Z3Tile::kThr, p));
      if (coverage > 0) {  // (a single layer: nothing behind it to free)
        const auto covered = hn::Ge(hn::Mul(hn::LoadU(d, field(Z3Tile::kA, p)), hn::Set(d, coverage)), hn::Set(d, 1.0f));
        hn::BlendedStore(hn::IfThenElseZero(covered, hn::Set(d, 1.0f)), fast, d, field(Z3Tile::kOpaque, p));
      } else if (opaque && tails) {
        // a tail opens a tail-only layer (-1); a fragment that is not a tail makes one occlude
        const V one = hn::Set(d, 1.0f);
        const V flag = hn::IfThenElse(tail, hn::IfThenElse(open, hn::Neg(one), flag0), one);
        hn::BlendedStore(flag, fast, d, field(Z3Tile::kOpaque, p));
      } else if (opaque) {
        hn::BlendedStore(hn::Set(d, 1.0f), open, d, field(Z3Tile::kOpaque, p));
      } else {
        hn::BlendedStore(zero, fast, d, field(Z3Tile::kOpaque, p));
      }
      hn::BlendedStore(hn::Set(di, 1), hn::RebindMask(di, open), di, cnt + p);
      openedV = hn::Sub(openedV, hn::VecFromMask(di, hn::RebindMask(di, open)));
    }
    occludedV = hn::Sub(occludedV, hn::VecFromMask(di, hn::RebindMask(di, behind)));
    if (behindBase && !hn::AllFalse(d, behind)) {  // kept as the pixel's behind sums (Z3Tile::addBehind)
      const auto has = hn::RebindMask(d, hn::Ne(hn::LoadU(di, behindCnt + p), hn::Zero(di)));
      auto add = [&](int k, V v) {
        float* q = behindBase + size_t(k) * stride + p;
        hn::BlendedStore(hn::IfThenElse(has, hn::Add(hn::LoadU(d, q), v), v), behind, d, q);
      };
      for (int k = 0; k < Z3Tile::kAttrs; ++k) add(k, k < nAttr ? hn::Mul(w, attrAt(k)) : zero);
      add(Z3Tile::kBehindZ, hn::Mul(w, z));
      hn::BlendedStore(hn::Set(di, 1), hn::RebindMask(di, behind), di, behindCnt + p);
    }
    return hn::AndNot(hn::Or(fast, behind), inside);
  }
};

// One point splat straight into the Z^3 tile (detail/splat_rows.h), in chunks of rows, two passes
// per chunk, both branch-free in the common case:
//  1. weights and depths (the same operations as PointFragments) of the chunk's pixels into a
//     small buffer whose rows are Wp >= width lanes apart (Wp = 4, 8, 16 or a multiple of 16),
//     full vectors holding several rows of a narrow splat, and 0 weight outside the splat;
//  2. per row, the Z^3 fast path on the tile's planes (a row's pixels are contiguous there):
//     open a layer on an empty pixel, merge into the single layer the fragment lies within, or
//     drop a fragment behind a single opaque layer, as masked loads and stores; the rest (a new
//     layer next to others, compression) through Z3Tile::insert.
inline constexpr int kRowChunk = 1024;  // pixels (Wp x rows) per chunk

// kWp > 0: Wp known at compile time; kGouraud: Gouraud-shaded (the flat splats, nearly all small
// ones, hold no Gouraud constants in registers)
template <class DZ, int kWp, bool kGouraud>
HWY_NOINLINE uint64_t PointRowsT(DZ dz, int WpRun, const PointHot& P, const PointRowsFrame& F, const float* normal,
                                 const float* G, const float* disc, const PixelRect& r, Z3Tile& z3) {
  const DF d;
  const int Wp = kWp > 0 ? kWp : WpRun;
  const int L = int(hn::Lanes(d)), LZ = int(hn::Lanes(dz));
  const int W = r.width(), H = r.height();
  const VF cutoff = hn::Set(d, F.cutoffQ);
  const bool clipDepth = std::signbit(P.weightScaleSigned), poly = F.cutoffQ <= kPolyExpMaxQ;
  const VF zero = hn::Zero(d);
  const PointKernel K(d, P.N, P.S, P.T, P.depthNum, std::fabs(P.weightScaleSigned));
  const VF nearD = hn::Set(d, F.nearD), farD = hn::Set(d, F.farD);
  // lane offsets within a vector: several rows of Wp lanes when Wp < L, else a run of one row
  const int rowsPerVec = Wp < L ? L / Wp : 1;
  const hn::RebindToSigned<DF> di;
  const auto iota = hn::Iota(di, 0);
  const VF colLane = hn::ConvertTo(d, Wp < L ? hn::And(iota, hn::Set(di, Wp - 1)) : iota);
  const VF rowLane = Wp < L ? hn::Floor(hn::Mul(hn::ConvertTo(d, iota), hn::Set(d, 1.0f / float(Wp)))) : zero;
  HWY_ALIGN float bw[kRowChunk + kMaxLanes], bz[kRowChunk + kMaxLanes], bs[kRowChunk + kMaxLanes], bt[kRowChunk + kMaxLanes];
  // Z^3 pass constants
  using VZ = hn::Vec<DZ>;
  const VZ zeroZ = hn::Zero(dz), thr = hn::Set(dz, P.zThreshold);
  // the blended attributes (Z3Tile::Attr): colour, alpha, 1, normal (when the tile blends them)
  float fa[Z3Tile::kAttrs] = {P.color[0], P.color[1], P.color[2], P.color[3], 1.0f, 0.0f, 0.0f, 0.0f};
  if (normal) fa[Z3Tile::kNx] = normal[0], fa[Z3Tile::kNy] = normal[1], fa[Z3Tile::kNz] = normal[2];
  VZ attr[Z3Tile::kAttrs], c0[3], cs[3], ct[3], cst[3];
  for (int k = 0; k < Z3Tile::kAttrs; ++k) attr[k] = hn::Set(dz, fa[k]);
  for (int k = 0; k < 3; ++k) {
    c0[k] = hn::Set(dz, kGouraud ? G[k] : 0.0f), cs[k] = hn::Set(dz, kGouraud ? G[3 + k] : 0.0f);
    ct[k] = hn::Set(dz, kGouraud ? G[6 + k] : 0.0f), cst[k] = hn::Set(dz, kGouraud ? G[9 + k] : 0.0f);
  }
  Z3Rows<DZ> z3rows(z3, P.color[3] >= 1.0f);
  const bool tails = disc && (disc[0] > 0 || disc[2] > 0);  // (passed only with Z3Tile::tailLayers(); zero: none)
  const PointTail tailer(d, tails ? disc : F.noDisc);
  uint64_t inserted = 0;
  const int chunkRows = std::max(rowsPerVec, (kRowChunk / Wp) / rowsPerVec * rowsPerVec);
  const VF Wv = hn::Set(d, float(W));
  for (int cy = 0; cy < H; cy += chunkRows) {
    const int rows = std::min(chunkRows, H - cy);
    // 1. weights and depths
    for (int k = 0; k < rows * Wp; k += L) {
      const int row = k / Wp, col = k - row * Wp;  // of the vector's first lane
      const VF cx = hn::Add(colLane, hn::Set(d, float(col))), ry = hn::Add(rowLane, hn::Set(d, float(cy + row)));
      const VF px = hn::Add(cx, hn::Set(d, float(r.x0) + 0.5f)), py = hn::Add(ry, hn::Set(d, float(r.y0) + 0.5f));
      const auto a = poly ? K.at<true>(d, px, py, cutoff) : K.at<false>(d, px, py, cutoff);
      auto inside = hn::And(a.hit, hn::And(hn::Lt(cx, Wv), hn::Lt(ry, hn::Set(d, float(H)))));
      if (clipDepth) inside = hn::And(inside, hn::And(hn::Ge(a.z, nearD), hn::Le(a.z, farD)));
      hn::Store(hn::IfThenElseZero(inside, a.w), d, bw + k);
      hn::Store(tails ? tailer.z(d, a.s, a.t, a.z) : a.z, d, bz + k);
      if (kGouraud) hn::Store(a.s, d, bs + k), hn::Store(a.t, d, bt + k);
    }
    // 2. into the Z^3 tile
    for (int row = 0; row < rows; ++row) {
      const int y = r.y0 + cy + row;
      const size_t rowBase = z3.index(r.x0, y);
      for (int c = 0; c < W; c += LZ) {
        const int k = row * Wp + c;
        const VZ w = hn::LoadU(dz, bw + k);
        VZ z = hn::LoadU(dz, bz + k);
        const auto inside = hn::Gt(w, zeroZ);
        if (hn::AllFalse(dz, inside)) continue;  // a corner of the bounds the splat misses
        const size_t p = rowBase + size_t(c);
        VZ s = zeroZ, t = zeroZ;
        if (kGouraud) s = hn::LoadU(dz, bs + k), t = hn::LoadU(dz, bt + k);
        const auto tail = z3rows.takeTails(z);
        const auto rest = z3rows(p, inside, w, z, thr, [&](int a) {
          if (kGouraud && a < 3)  // bilinear Gouraud over the quad, in the plane coordinates (s, t)
            return hn::Add(hn::Add(hn::Add(c0[a], hn::Mul(s, cs[a])), hn::Mul(t, ct[a])), hn::Mul(hn::Mul(s, t), cst[a]));
          return attr[a];
        }, tail);
        inserted += hn::CountTrue(dz, inside);
        if (HWY_LIKELY(hn::AllFalse(dz, rest))) continue;
        // the other fragments (a new layer in front of or behind others, compression, occlusion)
        HWY_ALIGN float mk[kMaxLanes];
        hn::StoreU(hn::VecFromMask(dz, rest), dz, mk);
        for (int i = 0; i < LZ; ++i) {
          if (mk[i] == 0) continue;
          if (kGouraud) {
            const float si = bs[k + i], ti = bt[k + i];
            for (int a = 0; a < 3; ++a) fa[a] = G[a] + si * G[3 + a] + ti * G[6 + a] + (si * ti) * G[9 + a];
          }
          z3.insert(r.x0 + c + i, y, std::fabs(bz[k + i]), P.zThreshold, bw[k + i], fa, bz[k + i] < 0);
        }
      }
    }
  }
  z3.addFastCounts(z3rows.opened(), z3rows.occluded());
  return inserted;
}

template <bool kGouraud>
HWY_INLINE uint64_t PointRowsG(const PointHot& P, const PointRowsFrame& F, const float* normal, const float* G,
                               const float* disc, const PixelRect& r, Z3Tile& z3) {
  // rows Wp lanes apart in the weight buffer; the Z^3 pass runs on vectors of at most Wp lanes
  const int W = r.width();
  using D4 = hn::CappedTag<float, 4>;
  using D8 = hn::CappedTag<float, 8>;
  using D16 = hn::CappedTag<float, 16>;
  if (W <= 4) return PointRowsT<D4, 4, kGouraud>(D4(), 4, P, F, normal, G, disc, r, z3);
  if (W <= 8) return PointRowsT<D8, 8, kGouraud>(D8(), 8, P, F, normal, G, disc, r, z3);
  return PointRowsT<D16, 0, kGouraud>(D16(), (W + 15) / 16 * 16, P, F, normal, G, disc, r, z3);
}

// A small flat point splat: its rect r at most kWp pixels wide and kSmallRows tall (beyond the
// thesis; nearly every splat of a dense model: the dragon's rects are 4x4 to 5x5 pixels). The two
// passes of PointRowsT without its chunk loop and with the run's constants (PointRun): the kernel
// of all rows at once (rows kWp lanes apart, several per vector) into a small buffer, then the
// Z^3 fast path per row in kWp lanes.
inline constexpr int kSmallRows = 8;

// The constants of a run of point splats in one tile (PointRunZ3), set once per run, not per
// splat: the frame's, the lane layouts of the small rows, the Z^3 planes for 4 and 8 lanes.
template <bool kPoly>
struct PointRun {
  using D4 = hn::CappedTag<float, 4>;
  using D8 = hn::CappedTag<float, 8>;
  DF d;
  const PointRowsFrame& F;
  Z3Tile& z3;
  VF cutoff = hn::Set(d, F.cutoffQ), nearD = hn::Set(d, F.nearD), farD = hn::Set(d, F.farD);
  VF col4, row4, col8, row8;  ///< a lane's column and row in rows 4 (8) lanes apart
  Z3Rows<D4> z4{z3, true};
  Z3Rows<D8> z8{z3, true};
  uint64_t inserted = 0;

  PointRun(const PointRowsFrame& frame, Z3Tile& tile) : F(frame), z3(tile) {
    layout(4, col4, row4);
    layout(8, col8, row8);
  }
  void layout(int Wp, VF& col, VF& row) const {
    const hn::RebindToSigned<DF> di;
    const auto iota = hn::Iota(di, 0);
    const bool several = Wp < int(hn::Lanes(d));
    col = hn::ConvertTo(d, several ? hn::And(iota, hn::Set(di, Wp - 1)) : iota);
    row = several ? hn::Floor(hn::Mul(hn::ConvertTo(d, iota), hn::Set(d, 1.0f / float(Wp)))) : hn::Zero(d);
  }
  ~PointRun() { z3.addFastCounts(z4.opened() + z8.opened(), z4.occluded() + z8.occluded()); }

  // one splat; G: its Gouraud colours (C0, Cs, Ct, Cst), or null for a flat splat
  // disc: its tail form (PointTail), or null (no tail test)
  HWY_INLINE void splat(const PointHot& P, const float* normal, const float* G, const PixelRect& r,
                        const float* disc = nullptr) {
    const int W = r.width(), H = r.height();
    if (!G && H <= kSmallRows) {
      if (disc) {  // (passed only with Z3Tile::tailLayers())
        if (W <= 4) return small<4, true>(P, normal, r, col4, row4, z4, disc);
        if (W <= 8) return small<8, true>(P, normal, r, col8, row8, z8, disc);
      } else {
        if (W <= 4) return small<4, false>(P, normal, r, col4, row4, z4, disc);
        if (W <= 8) return small<8, false>(P, normal, r, col8, row8, z8, disc);
      }
    }
    inserted += G ? PointRowsG<true>(P, F, normal, G, disc, r, z3) : PointRowsG<false>(P, F, normal, nullptr, disc, r, z3);
  }

  template <int kWp, bool kTails, class DZ>
  HWY_INLINE void small(const PointHot& P, const float* normal, const PixelRect& r, VF colLane, VF rowLane,
                        Z3Rows<DZ>& zrun, const float* disc) {
    Z3Rows<DZ> copy = zrun;  // with tail layers, a local copy: its members stay in registers
    if (kTails) copy.tails = true, copy.coverage = 0, copy.behindBase = nullptr;  // (Z3Tile::tailLayers(): no coverage)
    Z3Rows<DZ>& zr = kTails ? copy : zrun;
    const DZ dz;
    using VZ = hn::Vec<DZ>;
    const int L = int(hn::Lanes(d)), LZ = int(hn::Lanes(dz));
    const int W = r.width(), H = r.height();
    const PointKernel K(d, P.N, P.S, P.T, P.depthNum, std::fabs(P.weightScaleSigned));
    const VF Wv = hn::Set(d, float(W)), Hv = hn::Set(d, float(H));
    const VF x0 = hn::Set(d, float(r.x0) + 0.5f), y0 = hn::Set(d, float(r.y0) + 0.5f);
    const bool clipDepth = std::signbit(P.weightScaleSigned);
    HWY_ALIGN float bw[kSmallRows * kWp + kMaxLanes], bz[kSmallRows * kWp + kMaxLanes];
    const bool tails = disc && (disc[0] > 0 || disc[2] > 0);  // (passed only with Z3Tile::tailLayers(); zero: none)
    const PointTail tailer(d, tails ? disc : F.noDisc);
    // 1. the kernel of all rows
    for (int k = 0; k < H * kWp; k += L) {
      const int row = k / kWp, col = k - row * kWp;  // of the vector's first lane
      const VF cx = hn::Add(colLane, hn::Set(d, float(col))), ry = hn::Add(rowLane, hn::Set(d, float(row)));
      const auto a = K.at<kPoly>(d, hn::Add(cx, x0), hn::Add(ry, y0), cutoff);
      auto inside = hn::And(a.hit, hn::And(hn::Lt(cx, Wv), hn::Lt(ry, Hv)));
      if (clipDepth) inside = hn::And(inside, hn::And(hn::Ge(a.z, nearD), hn::Le(a.z, farD)));
      const VF w = hn::IfThenElseZero(inside, a.w);
      hn::Store(w, d, bw + k);
      hn::Store(tails ? tailer.z(d, a.s, a.t, a.z) : a.z, d, bz + k);
      inserted += hn::CountTrue(d, hn::Gt(w, hn::Zero(d)));
    }
    // 2. into the Z^3 tile, row by row
    float fa[Z3Tile::kAttrs] = {P.color[0], P.color[1], P.color[2], P.color[3], 1.0f, 0.0f, 0.0f, 0.0f};
    if (normal) fa[Z3Tile::kNx] = normal[0], fa[Z3Tile::kNy] = normal[1], fa[Z3Tile::kNz] = normal[2];
    VZ attr[Z3Tile::kAttrs];
    for (int k = 0; k < Z3Tile::kAttrs; ++k) attr[k] = hn::Set(dz, fa[k]);
    const VZ thr = hn::Set(dz, P.zThreshold), zeroZ = hn::Zero(dz);
    zr.opaque = P.color[3] >= 1.0f || !z3.coverageOccludes();  // coverage at silhouettes: an opaque frame
    for (int row = 0; row < H; ++row) {
      const size_t rowBase = z3.index(r.x0, r.y0 + row);
      for (int c = 0; c < W; c += LZ) {
        const int k = row * kWp + c;
        const VZ w = hn::Load(dz, bw + k);
        VZ z = hn::Load(dz, bz + k);
        const auto inside = hn::Gt(w, zeroZ);
        if (hn::AllFalse(dz, inside)) continue;  // a corner of the bounds the splat misses
        const auto tail = zr.takeTails(z);
        const auto rest = zr(rowBase + size_t(c), inside, w, z, thr, [&](int a) { return attr[a]; }, tail);
        if (HWY_LIKELY(hn::AllFalse(dz, rest))) continue;
        // the other fragments (a new layer in front of or behind others, compression, occlusion)
        HWY_ALIGN float mk[kMaxLanes];
        hn::Store(hn::VecFromMask(dz, rest), dz, mk);
        for (int i = 0; i < LZ; ++i)
          if (mk[i] != 0) z3.insert(r.x0 + c + i, r.y0 + row, std::fabs(bz[k + i]), P.zThreshold, bw[k + i], fa, bz[k + i] < 0);
      }
    }
    if (kTails) zrun.openedV = copy.openedV, zrun.occludedV = copy.occludedV;
  }
};

uint64_t PointRowsZ3(const PointRaster& P, const PointShade& A, const PixelRect& r, Z3Tile& z3) {
  PointHot h;
  h.N = P.N, h.S = P.S, h.T = P.T, h.depthNum = P.depthNum;
  h.weightScaleSigned = P.clipDepth ? -P.weightScale : P.weightScale;
  h.zThreshold = A.zThreshold;
  for (int k = 0; k < 4; ++k) h.color[k] = A.attr[k];
  const PointRowsFrame F{P.cutoffQ, P.nearD, P.farD};
  float G[12] = {};
  if (A.gouraud)
    for (int k = 0; k < 3; ++k) G[k] = A.C0[k], G[3 + k] = A.Cs[k], G[6 + k] = A.Ct[k], G[9 + k] = A.Cst[k];
  auto one = [&](auto& run) {
    run.splat(h, A.attr + Z3Tile::kNx, A.gouraud ? G : nullptr, r);
    return run.inserted;
  };
  if (F.cutoffQ <= kPolyExpMaxQ) {
    PointRun<true> run(F, z3);
    return one(run);
  }
  PointRun<false> run(F, z3);
  return one(run);
}

// A run of point splats (detail/splat_rows.h): one dispatch for the run; each splat's hot record
// is fetched kRunAhead splats ahead (the bins visit slots in order with gaps: cold lines).
template <bool kPoly>
uint64_t PointRunT(const PointRowsFrame& F, const PointRunSlots& S, const uint32_t* refs, int n, Z3Tile& z3) {
  constexpr int kRunAhead = 4;
  const PixelRect tile = z3.rect();
  const bool blend = z3.blendNormals();
  PointRun<kPoly> run(F, z3);
  for (int i = 0; i < n; ++i) {
    if (i + kRunAhead < n) __builtin_prefetch(S.hot + refs[i + kRunAhead]);
    if (i + 2 * kRunAhead < n) __builtin_prefetch(S.bounds + refs[i + 2 * kRunAhead]);
    if (S.disc && i + kRunAhead < n) __builtin_prefetch(S.disc + size_t(refs[i + kRunAhead]) * S.discStride);
    const uint32_t j = refs[i];
    const PixelRect& b = S.bounds[j];
    const PixelRect r = b.intersect(tile);  // not empty: the bins hold the splats touching the tile
    const float* normal = blend ? S.normals + size_t(j) * S.normalStride : nullptr;
    const bool gouraud = S.gouraud && (b.width() > kPointFlatShadeSpan || b.height() > kPointFlatShadeSpan);
    run.splat(S.hot[j], normal, gouraud ? S.gouraud + size_t(j) * S.gouraudStride : nullptr, r,
              S.disc ? S.disc + size_t(j) * S.discStride : nullptr);
  }
  return run.inserted;
}

uint64_t PointRunZ3(const PointRowsFrame& F, const PointRunSlots& S, const uint32_t* refs, int n, Z3Tile& z3) {
  return F.cutoffQ <= kPolyExpMaxQ ? PointRunT<true>(F, S, refs, n, z3) : PointRunT<false>(F, S, refs, n, z3);
}

// One row of the resolve, pixels with one layer (detail/splat_rows.h): the formula of
// Z3Tile::resolve for n = 1 (keep the two alike), then the renderer's compositing over the
// background; every other pixel of the whole vectors gets the background itself. Stores of whole
// vectors only, so no other tile's pixels are touched; out is never read (it may be uninitialised).
// With frontZ (coverage at silhouettes only): the front depths of the whole vectors (+inf where
// empty) go there, the pixels are written opaque, and those partly covered are appended to cands
// with their coverage result.
int ResolveSingleLayerRow(Z3Tile& z3, int y, int x0, int n, const float* bg, float* out, bool& others, float* frontZ,
                          std::vector<SilhouettePixel>* cands) {
  const DF d;
  const hn::RebindToSigned<DF> di;
  const int L = int(hn::Lanes(d));
  const size_t p0 = z3.index(x0, y);
  const int32_t* cnt = z3.counts() + p0;
  const float *R = z3.plane(0, Z3Tile::kR) + p0, *G = z3.plane(0, Z3Tile::kG) + p0, *B = z3.plane(0, Z3Tile::kB) + p0;
  const float *A = z3.plane(0, Z3Tile::kA) + p0, *Wt = z3.plane(0, Z3Tile::kW) + p0;
  const float *Z = z3.plane(0, Z3Tile::kZ) + p0, *Thr = z3.plane(0, Z3Tile::kThr) + p0;
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f), inf = hn::Set(d, std::numeric_limits<float>::infinity());
  const float coverage = z3.coverageScale();
  const VF covS = hn::Set(d, coverage);
  const VF bgR = hn::Set(d, bg[0]), bgG = hn::Set(d, bg[1]), bgB = hn::Set(d, bg[2]), bgW = hn::Set(d, bg[3]);
  const int whole = n / L * L;
  auto several = hn::Lt(hn::Set(di, 1), hn::Zero(di));  // none yet
  // a layer of straight colour (r, g, b) and alpha a over the background, as the image stores it
  auto composite = [&](VF a, VF& r, VF& g, VF& b, VF& w) {
    r = hn::Mul(a, r), g = hn::Mul(a, g), b = hn::Mul(a, b);
    const VF rest = hn::Mul(hn::Sub(one, a), bgW);
    r = hn::Add(r, hn::Mul(rest, bgR)), g = hn::Add(g, hn::Mul(rest, bgG)), b = hn::Add(b, hn::Mul(rest, bgB));
    w = hn::Add(a, rest);
    if (bg[3] > 0) {  // straight colour for PNG
      const auto part = hn::And(hn::Gt(w, zero), hn::Lt(w, one));
      if (!hn::AllFalse(d, part))
        r = hn::IfThenElse(part, hn::Div(r, w), r), g = hn::IfThenElse(part, hn::Div(g, w), g), b = hn::IfThenElse(part, hn::Div(b, w), b);
    } else {
      const auto covered = hn::Gt(a, zero);
      r = hn::IfThenElse(covered, hn::Div(r, a), r), g = hn::IfThenElse(covered, hn::Div(g, a), g), b = hn::IfThenElse(covered, hn::Div(b, a), b);
    }
  };
  for (int i = 0; i < whole; i += L) {
    const auto count = hn::LoadU(di, cnt + i);
    several = hn::Or(several, hn::Gt(count, hn::Set(di, 1)));
    if (frontZ) hn::StoreU(hn::IfThenElse(hn::RebindMask(d, hn::Gt(count, hn::Zero(di))), hn::LoadU(d, Z + i), inf), d, frontZ + i);
    const auto single = hn::RebindMask(d, hn::Eq(count, hn::Set(di, 1)));
    if (hn::AllFalse(d, single)) {
      hn::StoreInterleaved4(bgR, bgG, bgB, bgW, d, out + 4 * i);
      continue;
    }
    const VF iw = hn::Div(one, hn::LoadU(d, Wt + i));
    // Z3Tile::layerAlpha: coverage min(1, s A), or the normalised alpha A/W
    const VF a = coverage > 0 ? hn::Min(hn::Mul(hn::LoadU(d, A + i), covS), one)
                              : hn::Min(hn::Max(hn::Mul(hn::LoadU(d, A + i), iw), zero), one);
    const VF r0 = hn::Mul(hn::LoadU(d, R + i), iw), g0 = hn::Mul(hn::LoadU(d, G + i), iw), b0 = hn::Mul(hn::LoadU(d, B + i), iw);
    VF r = r0, g = g0, b = b0, w;
    if (frontZ) {
      const auto partial = hn::And(single, hn::Lt(a, one));
      if (!hn::AllFalse(d, partial)) {
        composite(a, r, g, b, w);
        HWY_ALIGN float cr[kMaxLanes], cg[kMaxLanes], cb[kMaxLanes], cw[kMaxLanes], ca[kMaxLanes];
        hn::Store(r, d, cr), hn::Store(g, d, cg), hn::Store(b, d, cb), hn::Store(w, d, cw), hn::Store(a, d, ca);
        for (int j = 0; j < L; ++j)
          if (cnt[i + j] == 1 && ca[j] < 1.0f)
            cands->push_back({uint32_t(x0 + i + j), uint32_t(y), Thr[i + j], {cr[j], cg[j], cb[j], cw[j]}, ca[j]});
        r = r0, g = g0, b = b0;
      }
      composite(one, r, g, b, w);
    } else {
      composite(a, r, g, b, w);
    }
    // the other pixels get the background (whole vectors of this row only; out is not read)
    hn::StoreInterleaved4(hn::IfThenElse(single, r, bgR), hn::IfThenElse(single, g, bgG), hn::IfThenElse(single, b, bgB),
                          hn::IfThenElse(single, w, bgW), d, out + 4 * i);
  }
  others = !hn::AllFalse(di, several);
  return whole;
}


// One segment straight into the Z^3 tile over its rows' spans, in chunks of at most kSegChunk
// pixels, two passes per chunk (as PointRowsT; beyond the thesis):
//  1. the kernel, the z threshold and the attributes (colour from u, smooth normals, as
//     segment_splat.cpp's FragmentAttributes) of the chunk's pixels packed across rows: lanes
//     carry their own pixel centre, so a span of a few pixels does not start a vector of its own;
//     0 weight where there is no fragment;
//  2. per span, the Z^3 fast path of PointRowsT on the tile's planes (a span's pixels are
//     contiguous there), vectors of at most the widest span's lanes; the other fragments through
//     Z3Tile::insert.
// kOneChunk: the spans hold at most kSegChunk pixels (nearly always): one chunk, the spans are its
// runs as they are (no cutting, no runs copied; a short contour segment has ~5 spans in a tile,
// and the chunk's bookkeeping cost more instructions per span than its Z^3 pass: issue 13).
inline constexpr int kSegChunk = 512;

// The Z^3 pass's state of a run of segments for 4, 8 and 16 lanes (Z3Rows: the tile's planes and
// the fast path's counters), set up once per run; the counters go to the tile at its end.
struct SegmentZ3Sets {
  Z3Tile& z3;
  Z3Rows<hn::CappedTag<float, 4>> z4{z3, true};
  Z3Rows<hn::CappedTag<float, 8>> z8{z3, true};
  Z3Rows<hn::CappedTag<float, 16>> z16{z3, true};
  explicit SegmentZ3Sets(Z3Tile& tile) : z3(tile) {}
  ~SegmentZ3Sets() {
    z3.addFastCounts(z4.opened() + z8.opened() + z16.opened(), z4.occluded() + z8.occluded() + z16.occluded());
  }
  template <class DZ>  // (on narrower targets the tags are one type: its first set)
  Z3Rows<DZ>& rows() {
    if constexpr (std::is_same_v<DZ, hn::CappedTag<float, 4>>) return z4;
    else if constexpr (std::is_same_v<DZ, hn::CappedTag<float, 8>>) return z8;
    else return z16;
  }
};

template <bool kPoly, class DZ, bool kOneChunk>
HWY_NOINLINE uint64_t SegmentRowsT(DZ dz, const SegmentRaster& S, const SegmentFrameV& F, const SegmentShadeRows& A,
                                   const RowSpan* spans, int count, Z3Tile& z3, Z3Rows<DZ>& zset) {
  const DF d;
  const int L = int(hn::Lanes(d)), LZ = int(hn::Lanes(dz));
  // the smooth normals only when the tile blends normal sums (else nothing reads them: Z3Tile)
  const bool smooth = A.smooth && z3.blendNormals();
  const VF oneF = hn::Set(d, 1.0f), zero = hn::Zero(d), iota = hn::Iota(d, 0.0f), centre = hn::Iota(d, 0.5f);
  // (the kernel's, the colour's, the stations' and the smooth normals' constants are broadcast
  // where they are used: most segments need one vector, and hoisted they were spilled and
  // reloaded for every segment)
  const hn::RebindToSigned<DF> di;
  // at most L stations: their colours c_k and steps c_(k+1) - c_k as lane tables, looked up by a
  // lane permutation (one instruction) instead of gathered from memory (six per vector; the
  // same values to the bit)
  const int stations = A.stations;
  const bool stationTable = stations >= 2 && stations <= L;
  VF st0[3], stD[3];
  if (stationTable && A.stationPadded) {  // (lanes from `stations` on: the next channel or padding, never looked up)
    for (int c = 0; c < 3; ++c) {
      const float* sc = A.stationColour + c * stations;
      st0[c] = hn::LoadU(d, sc), stD[c] = hn::Sub(hn::LoadU(d, sc + 1), st0[c]);
    }
  } else if (stationTable) {  // the record's own (3) stations: the tables from broadcasts
    const auto laneI = hn::Iota(di, 0);
    for (int c = 0; c < 3; ++c) {
      const float* sc = A.stationColour + c * stations;
      VF t0 = hn::Set(d, sc[0]), t1 = hn::Set(d, sc[1]);
      for (int k = 1; k < stations; ++k) {
        const auto at = hn::RebindMask(d, hn::Eq(laneI, hn::Set(di, k)));
        t0 = hn::IfThenElse(at, hn::Set(d, sc[k]), t0);
        if (k + 1 < stations) t1 = hn::IfThenElse(at, hn::Set(d, sc[k + 1]), t1);
      }
      st0[c] = t0, stD[c] = hn::Sub(t1, t0);
    }
  }
  // the chunk's pixels (centres) and pass 1's results, kMaxLanes of padding for whole vectors
  constexpr int kPad = kSegChunk + kMaxLanes;
  HWY_ALIGN float px[kPad], py[kPad], bw[kPad], bz[kPad], bt[kPad], bc[3][kPad], bn[3][kPad];
  struct Run {
    int y, x0, x1, at;  ///< pixels [x0, x1) of row y, from `at` in the chunk
  };
  Run runs[kSegChunk];
  using VZ = hn::Vec<DZ>;
  const VZ zeroZ = hn::Zero(dz);
  VZ constAttr[Z3Tile::kAttrs];
  for (int k = 0; k < Z3Tile::kAttrs; ++k) constAttr[k] = hn::Set(dz, A.attr[k]);
  // (a local copy: the tile's stores would make the compiler reload the run's one)
  Z3Rows<DZ> z3rows = zset;
  z3rows.opaque = A.attr[Z3Tile::kA] >= 1.0f || !z3.coverageOccludes();  // (as Z3Rows sets it)
  // tail layers (Z3Tile::setTailLayers, SegmentRaster::tailB): a tail's depth goes negated to pass 2
  const bool tails = z3.tailLayers() && S.tailB > 0;
  uint64_t inserted = 0;
  int r = 0, rx = count > 0 ? spans[0].x0 : 0;  // the next span and where in it the next chunk starts
  while (r < count) {
    // gather up to kSegChunk pixels of runs (a span wider than that is cut)
    int n = 0, nRuns = 0;
    if (kOneChunk) {
      for (; r < count; ++r) {
        const RowSpan& sp = spans[r];
        const VF y = hn::Set(d, float(sp.y) + 0.5f);
        for (int i = 0; i < sp.x1 - sp.x0; i += L) {  // the next span overwrites the excess
          hn::StoreU(hn::Add(centre, hn::Set(d, float(sp.x0 + i))), d, px + n + i);
          hn::StoreU(y, d, py + n + i);
        }
        n += sp.x1 - sp.x0;
      }
    }
    while (!kOneChunk && r < count && n < kSegChunk) {
      const RowSpan& sp = spans[r];
      const int x1 = std::min(sp.x1, rx + (kSegChunk - n));
      if (x1 > rx) {
        runs[nRuns++] = {sp.y, rx, x1, n};
        const VF y = hn::Set(d, float(sp.y) + 0.5f);
        for (int i = 0; i < x1 - rx; i += L) {  // the next run overwrites the excess
          hn::StoreU(hn::Add(centre, hn::Set(d, float(rx + i))), d, px + n + i);
          hn::StoreU(y, d, py + n + i);
        }
        n += x1 - rx;
      }
      if (x1 < sp.x1) {
        rx = x1;
      } else if (++r < count) {
        rx = spans[r].x0;
      }
    }
    // 1. weights, depths, thresholds and attributes, lanes packed across rows
    const VF nv = hn::Set(d, float(n));
    for (int i = 0; i < n; i += L) {
      const VF x = hn::LoadU(d, px + i), y = hn::LoadU(d, py + i);
      VF w, z, u, b, a;
      // the record's constants through pointers the compiler cannot tell are the same in every
      // vector (beyond the thesis, issue 13): held for the segment, the kernel's ~25 broadcasts
      // and the colour's 8 were spilled to the stack and reloaded (a pair has ~1.2 vectors);
      // read here, they become broadcast operands of the arithmetic. The same values.
      const SegmentRaster* Sv = &S;
      const SegmentShadeRows* Av = &A;
      asm volatile("" : "+r"(Sv), "+r"(Av));
      const SegmentKernel<kPoly> kernel(*Sv, F);
      const auto keep = kernel(x, y, hn::Lt(hn::Add(iota, hn::Set(d, float(i))), nv), w, z, u, &b, &a);
      if (hn::AllFalse(d, keep)) {
        hn::Store(zero, d, bw + i);
        continue;
      }
      hn::Store(hn::IfThenElseZero(keep, w), d, bw + i);
      inserted += hn::CountTrue(d, keep);  // every one is a fragment pass 2 inserts
      u = hn::IfThenElseZero(keep, u);  // the other lanes' u may be anything (the station gather's index)
      const VF thr = hn::MulAdd(u, hn::Set(d, Sv->zThreshold1 - Sv->zThreshold0), hn::Set(d, Sv->zThreshold0));
      if (tails) {  // outside the strip's own capsule [0, length] x [-tailB, tailB] (with its caps' box)
        const VF tailB = hn::Set(d, Sv->tailB);
        const auto tl = hn::Or(hn::Gt(hn::Abs(b), tailB),
                               hn::Or(hn::Lt(a, hn::Neg(tailB)), hn::Gt(a, hn::Add(hn::Set(d, Sv->length), tailB))));
        z = hn::IfThenElse(tl, hn::Neg(z), z);
      }
      hn::Store(z, d, bz + i);
      hn::Store(thr, d, bt + i);
      if (stations >= 2) {  // piecewise linear between the lighting stations
        const VF fs = hn::Mul(u, hn::Set(d, float(stations - 1)));
        const auto k = hn::Min(hn::ConvertTo(di, hn::Floor(fs)), hn::Set(di, stations - 2));
        const VF v = hn::Sub(fs, hn::ConvertTo(d, k));
        if (stationTable) {
          const auto idx = hn::IndicesFromVec(d, k);
          for (int c = 0; c < 3; ++c)
            hn::Store(hn::MulAdd(v, hn::TableLookupLanes(stD[c], idx), hn::TableLookupLanes(st0[c], idx)), d, bc[c] + i);
        } else {
          for (int c = 0; c < 3; ++c) {
            const float* sc = A.stationColour + c * stations;
            const VF c0 = hn::GatherIndex(d, sc, k), c1 = hn::GatherIndex(d, sc + 1, k);
            hn::Store(hn::MulAdd(v, hn::Sub(c1, c0), c0), d, bc[c] + i);
          }
        }
      } else {
        for (int c = 0; c < 3; ++c) hn::Store(hn::MulAdd(u, hn::Set(d, Av->dc[c]), hn::Set(d, Av->attr[c])), d, bc[c] + i);
      }
      if (smooth) {
        VF m[3];
        for (int c = 0; c < 3; ++c) m[c] = hn::MulAdd(u, hn::Set(d, A.dn[c]), hn::Set(d, A.n0[c]));
        VF inv;
        if (A.exactNormal) {
          const VF len2 = hn::MulAdd(m[0], m[0], hn::MulAdd(m[1], m[1], hn::Mul(m[2], m[2])));
          inv = hn::IfThenElseZero(hn::Gt(len2, zero), hn::Div(oneF, hn::Sqrt(len2)));
        } else {
          const VF xx = hn::Mul(hn::Mul(u, hn::Sub(oneF, u)), hn::Set(d, A.dn2));
          inv = hn::MulAdd(xx, hn::MulAdd(xx, hn::Set(d, 0.375f), hn::Set(d, 0.5f)), oneF);
        }
        for (int c = 0; c < 3; ++c) hn::Store(hn::Mul(m[c], inv), d, bn[c] + i);
      }
    }
    // 2. into the Z^3 tile, run by run (kOneChunk: the spans); lanes c .. c + LZ - 1 of a run:
    auto blend = [&](const Run& run, size_t rowBase, int width, int c) HWY_ATTR __attribute__((always_inline)) {
      const int k = run.at + c;
      const VZ w = hn::LoadU(dz, bw + k);
      const auto inside = hn::And(hn::Gt(w, zeroZ), hn::FirstN(dz, size_t(width - c)));
      if (hn::AllFalse(dz, inside)) return;
      VZ z = hn::LoadU(dz, bz + k);
      const VZ thr = hn::LoadU(dz, bt + k);
      const auto tail = z3rows.takeTails(z);
      const auto rest = z3rows(rowBase + size_t(c), inside, w, z, thr, [&](int a) {
        if (a < 3) return hn::LoadU(dz, bc[a] + k);
        if (smooth && a >= Z3Tile::kNx) return hn::LoadU(dz, bn[a - Z3Tile::kNx] + k);
        return constAttr[a];
      }, tail);
      if (HWY_LIKELY(hn::AllFalse(dz, rest))) return;
      // the other fragments (a new layer in front of or behind others, compression, occlusion)
      HWY_ALIGN float mk[kMaxLanes];
      hn::StoreU(hn::VecFromMask(dz, rest), dz, mk);
      for (int i = 0; i < LZ; ++i) {
        if (mk[i] == 0) continue;
        float fa[Z3Tile::kAttrs];
        for (int a = 0; a < Z3Tile::kAttrs; ++a) fa[a] = A.attr[a];
        for (int a = 0; a < 3; ++a) fa[a] = bc[a][k + i];
        if (smooth)
          for (int a = 0; a < 3; ++a) fa[Z3Tile::kNx + a] = bn[a][k + i];
        z3.insert(run.x0 + c + i, run.y, std::fabs(bz[k + i]), bt[k + i], bw[k + i], fa, bz[k + i] < 0);
      }
    };
    for (int q = 0, at = 0; q < (kOneChunk ? count : nRuns); ++q) {
      const Run run = kOneChunk ? Run{spans[q].y, spans[q].x0, spans[q].x1, at} : runs[q];
      const size_t rowBase = z3.index(run.x0, run.y);
      const int width = run.x1 - run.x0;
      at += width;
      if (width <= LZ) {  // one vector (DZ fits the widest span unless it is wider than 16)
        blend(run, rowBase, width, 0);
        continue;
      }
      for (int c = 0; c < width; c += LZ) blend(run, rowBase, width, c);
    }
  }
  zset.openedV = z3rows.openedV, zset.occludedV = z3rows.occludedV;
  return inserted;
}

// One segment's rows (SegmentRowsZ3, SegmentRowsRunZ3) with the frame's constants F (set here);
// widest, pixels: of the spans, or pixels < 0 to count them here.
HWY_INLINE uint64_t SegmentRowsF(SegmentFrameV& F, SegmentZ3Sets& Z, const SegmentRaster& S, const SegmentShadeRows& A,
                                 const RowSpan* spans, int count, Z3Tile& z3, int widest = 0, int pixels = -1) {
  if (pixels < 0) {  // the Z^3 pass runs on vectors of at most the widest span's lanes
    pixels = 0;
    for (int r = 0; r < count; ++r) {
      const int w = spans[r].x1 - spans[r].x0;
      widest = std::max(widest, w), pixels += w;
    }
  }
  if (pixels <= 0) return 0;
  F.set(S);
  auto rows = [&](auto dz) {
    using DZ = decltype(dz);
    Z3Rows<DZ>& zr = Z.template rows<DZ>();
    if (pixels <= kSegChunk)
      return F.poly ? SegmentRowsT<true, DZ, true>(dz, S, F, A, spans, count, z3, zr)
                    : SegmentRowsT<false, DZ, true>(dz, S, F, A, spans, count, z3, zr);
    return F.poly ? SegmentRowsT<true, DZ, false>(dz, S, F, A, spans, count, z3, zr)
                  : SegmentRowsT<false, DZ, false>(dz, S, F, A, spans, count, z3, zr);
  };
  if (widest <= 4) return rows(hn::CappedTag<float, 4>());
  if (widest <= 8) return rows(hn::CappedTag<float, 8>());
  return rows(hn::CappedTag<float, 16>());
}

uint64_t SegmentRowsZ3(const SegmentRaster& S, const SegmentShadeRows& A, const RowSpan* spans, int count, Z3Tile& z3) {
  SegmentFrameV F;
  SegmentZ3Sets Z(z3);
  return SegmentRowsF(F, Z, S, A, spans, count, z3);
}

// SegmentRowsZ3 for a run of segments (detail/splat_rows.h): one dispatch, the frame's constants
// set again only when they change, the Z^3 pass's state once.
uint64_t SegmentRowsRunZ3(const SegmentRowsItem* items, int n, Z3Tile& z3) {
  SegmentFrameV F;
  SegmentZ3Sets Z(z3);
  uint64_t inserted = 0;
  for (int i = 0; i < n; ++i) {
    const SegmentRowsItem& it = items[i];
    inserted += SegmentRowsF(F, Z, *it.raster, it.shade, it.spans, it.count, z3, it.widest, it.pixels);
  }
  return inserted;
}

int64_t Target() { return HWY_TARGET; }

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(PointFragments);
HWY_EXPORT(SegmentFragments);
HWY_EXPORT(SegmentRowsZ3);
HWY_EXPORT(SegmentRowsRunZ3);
HWY_EXPORT(SegmentSpans);
HWY_EXPORT(SegmentSpansBatch);
HWY_EXPORT(Target);
HWY_EXPORT(PointRowsZ3);
HWY_EXPORT(PointRunZ3);
HWY_EXPORT(ResolveSingleLayerRow);

int pointFragments(const PointRaster& p, int x0, int y0, int width, int k0, int n, bool withPlaneCoords,
                   FragmentBlock& out) {
  return HWY_DYNAMIC_DISPATCH(PointFragments)(p, x0, y0, width, k0, n, withPlaneCoords, out);
}
int segmentFragments(const SegmentRaster& s, const RowSpan* spans, int count, FragmentBlock& out) {
  return HWY_DYNAMIC_DISPATCH(SegmentFragments)(s, spans, count, out);
}
uint64_t pointRowsZ3(const PointRaster& p, const PointShade& shade, const PixelRect& r, Z3Tile& tile) {
  return HWY_DYNAMIC_DISPATCH(PointRowsZ3)(p, shade, r, tile);
}
uint64_t pointRunZ3(const PointRowsFrame& frame, const PointRunSlots& slots, const uint32_t* refs, int n, Z3Tile& tile) {
  return HWY_DYNAMIC_DISPATCH(PointRunZ3)(frame, slots, refs, n, tile);
}
int resolveSingleLayerRow(Z3Tile& tile, int y, int x0, int n, const float* bg, float* out, bool& others, float* frontZ,
                          std::vector<SilhouettePixel>* cands) {
  return HWY_DYNAMIC_DISPATCH(ResolveSingleLayerRow)(tile, y, x0, n, bg, out, others, frontZ, cands);
}
uint64_t segmentRowsZ3(const SegmentRaster& s, const SegmentShadeRows& shade, const RowSpan* spans, int count,
                       Z3Tile& tile) {
  return HWY_DYNAMIC_DISPATCH(SegmentRowsZ3)(s, shade, spans, count, tile);
}
uint64_t segmentRowsRunZ3(const SegmentRowsItem* items, int n, Z3Tile& tile) {
  return HWY_DYNAMIC_DISPATCH(SegmentRowsRunZ3)(items, n, tile);
}
int segmentSpans(const SegmentRaster& s, const PixelRect& r, float slack, RowSpan* out) {
  return HWY_DYNAMIC_DISPATCH(SegmentSpans)(s, r, slack, out);
}
void segmentSpansBatch(const SegmentRaster* const* segs, const PixelRect* rects, int n, float slack, RowSpan* out,
                       int stride, int* counts, int* widest, int* pixels) {
  HWY_DYNAMIC_DISPATCH(SegmentSpansBatch)(segs, rects, n, slack, out, stride, counts, widest, pixels);
}
const char* simdTargetName() { return hwy::TargetName(HWY_DYNAMIC_DISPATCH(Target)()); }
}  // namespace linesurf::detail
#endif
