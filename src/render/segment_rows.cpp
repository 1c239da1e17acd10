// The SIMD rows of segment splats (thesis §5.2, the ScreenSpace closed form of segment_filter.h;
// segment_rows.h): a segment's row spans, its kernel per pixel, straight into the Z^3 tile.
// Compiled once per x86 target (Google Highway); the best one the CPU runs is picked at run time.
#include "segment_rows.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <type_traits>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/segment_rows.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>
#include "simd_rows-inl.h"

HWY_BEFORE_NAMESPACE();
namespace linesurf::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;
using DF = hn::ScalableTag<float>;
using VF = hn::Vec<DF>;

// --- segments (§5: the ScreenSpace closed form of segment_filter.cpp) -----------------------

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
// `valid`: the closed form of segment_filter.cpp (screenSpaceWeight), summed over the
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
    // thesis, see docs/decisions.md, "Segment rows": no tau-space interval, a shorter dependency chain than clamping tau and
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
// and the chunk's bookkeeping cost more instructions per span than its Z^3 pass; see docs/decisions.md, "Segment rows").
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

// At most L stations of a segment's colour (SegmentShadeRows::stations, 2 <= stations <= L): their
// colours c_k and steps c_(k+1) - c_k as lane tables, looked up by a lane permutation (one
// instruction) instead of gathered from memory (six per vector; the same values to the bit).
HWY_INLINE void StationTables(DF d, const SegmentShadeRows& A, VF* st0, VF* stD) {
  const hn::RebindToSigned<DF> di;
  const int stations = A.stations;
  if (A.stationPadded) {  // (lanes from `stations` on: the next channel or padding, never looked up)
    for (int c = 0; c < 3; ++c) {
      const float* sc = A.stationColour + c * stations;
      st0[c] = hn::LoadU(d, sc), stD[c] = hn::Sub(hn::LoadU(d, sc + 1), st0[c]);
    }
  } else {  // the record's own (3) stations: the tables from broadcasts
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
}

// A run of a chunk: pixels [x0, x1) of row y, from `at` in the chunk.
struct ChunkRun {
  int y, x0, x1, at;
};

// The pixel centres (px, py; `centre` = the lanes' 0.5, 1.5, ...) of the next chunk of the spans,
// from span r at column rx on: kOneChunk, every span as it is (the spans hold at most kSegChunk
// pixels); else up to kSegChunk pixels, a span wider than that cut, in runs[0 .. nRuns). Advances
// r and rx past the chunk; returns its pixels. The arrays are padded by kMaxLanes: the next span
// overwrites a vector's excess.
template <bool kOneChunk>
HWY_INLINE int GatherChunk(DF d, VF centre, const RowSpan* spans, int count, int& r, int& rx, float* px, float* py,
                           ChunkRun* runs, int& nRuns) {
  const int L = int(hn::Lanes(d));
  int n = 0;
  if (kOneChunk) {
    for (; r < count; ++r) {
      const RowSpan& sp = spans[r];
      const VF y = hn::Set(d, float(sp.y) + 0.5f);
      for (int i = 0; i < sp.x1 - sp.x0; i += L) {
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
      for (int i = 0; i < x1 - rx; i += L) {
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
  return n;
}

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
  const int stations = A.stations;
  const bool stationTable = stations >= 2 && stations <= L;
  VF st0[3], stD[3];
  if (stationTable) StationTables(d, A, st0, stD);
  // the chunk's pixels (centres) and pass 1's results, kMaxLanes of padding for whole vectors
  constexpr int kPad = kSegChunk + kMaxLanes;
  HWY_ALIGN float px[kPad], py[kPad], bw[kPad], bz[kPad], bt[kPad], bc[3][kPad], bn[3][kPad];
  ChunkRun runs[kSegChunk];
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
    int nRuns = 0;
    const int n = GatherChunk<kOneChunk>(d, centre, spans, count, r, rx, px, py, runs, nRuns);
    // 1. weights, depths, thresholds and attributes, lanes packed across rows
    const VF nv = hn::Set(d, float(n));
    for (int i = 0; i < n; i += L) {
      const VF x = hn::LoadU(d, px + i), y = hn::LoadU(d, py + i);
      VF w, z, u, b, a;
      // the record's constants through pointers the compiler cannot tell are the same in every
      // vector (beyond the thesis, see docs/decisions.md, "Segment rows"): held for the segment, the kernel's ~25 broadcasts
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
    auto blend = [&](const ChunkRun& run, size_t rowBase, int width, int c) HWY_ATTR __attribute__((always_inline)) {
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
      forEachRest(dz, rest, [&](int i) {
        float fa[Z3Tile::kAttrs];
        for (int a = 0; a < Z3Tile::kAttrs; ++a) fa[a] = A.attr[a];
        for (int a = 0; a < 3; ++a) fa[a] = bc[a][k + i];
        if (smooth)
          for (int a = 0; a < 3; ++a) fa[Z3Tile::kNx + a] = bn[a][k + i];
        z3.insert(run.x0 + c + i, run.y, std::fabs(bz[k + i]), bt[k + i], bw[k + i], fa, bz[k + i] < 0);
      });
    };
    for (int q = 0, at = 0; q < (kOneChunk ? count : nRuns); ++q) {
      const ChunkRun run = kOneChunk ? ChunkRun{spans[q].y, spans[q].x0, spans[q].x1, at} : runs[q];
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

// SegmentRowsZ3 for a run of segments (segment_rows.h): one dispatch, the frame's constants
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

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(SegmentFragments);
HWY_EXPORT(SegmentRowsZ3);
HWY_EXPORT(SegmentRowsRunZ3);

int segmentFragments(const SegmentRaster& s, const RowSpan* spans, int count, FragmentBlock& out) {
  return HWY_DYNAMIC_DISPATCH(SegmentFragments)(s, spans, count, out);
}
uint64_t segmentRowsZ3(const SegmentRaster& s, const SegmentShadeRows& shade, const RowSpan* spans, int count,
                       Z3Tile& tile) {
  return HWY_DYNAMIC_DISPATCH(SegmentRowsZ3)(s, shade, spans, count, tile);
}
uint64_t segmentRowsRunZ3(const SegmentRowsItem* items, int n, Z3Tile& tile) {
  return HWY_DYNAMIC_DISPATCH(SegmentRowsRunZ3)(items, n, tile);
}
}  // namespace linesurf::detail
#endif
