// The footprint of a segment splat in SIMD, stages 2 and 4 of the segment set-up
// (segment_setup.cpp; the exact path's are segment_splat.cpp's footprint and screenBounds): the
// resampling covariance along the segment (thesis §5.1.2; the scalar rule is segment::covariance,
// segment_filter.h), its sub-segments, and the footprint box projected to the screen. Highway's
// per-target header: included once per target by segment_setup.cpp (foreach_target).
#include <cmath>
#include <numbers>

#include "point_setup.h"
#include "segment_setup.h"
#include "splat_rules.h"

#if defined(LINESURF_RENDER_SEGMENT_SETUP_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef LINESURF_RENDER_SEGMENT_SETUP_INL_H_
#undef LINESURF_RENDER_SEGMENT_SETUP_INL_H_
#else
#define LINESURF_RENDER_SEGMENT_SETUP_INL_H_
#endif

#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace linesurf::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The resampling covariance M = (a b; b c) of a strip (segment::covariance) and its determinant.
template <class VF>
struct SegmentCov {
  VF a, b, c, det;
};

// segment::covariance for one vector of lanes: M at the camera-space points (x, y, z) of strips
// with unit axes e (along) and s (across), sigma_r^2 = s2, clamped to hiX = (kMaxStretch
// sigma_r)^2; lanes the float covariance cannot decide safely join `bad` (for the exact path).
template <class DF>
struct SegmentCovariance {
  using VF = hn::Vec<DF>;
  using MF = hn::Mask<DF>;
  DF d;
  const PointSetupFrame& V;
  VF f, Vh, s2, hiX, ex, ey, ez, sx, sy, sz;
  HWY_INLINE SegmentCov<VF> operator()(VF x, VF y, VF z, MF& bad) const {
    using Cov = SegmentCov<VF>;
    const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f), half = hn::Set(d, 0.5f);
    auto S = [&](float v) { return hn::Set(d, v); };
    const VF inf = S(INFINITY);
    auto finite = [&](VF v) { return hn::Lt(hn::Abs(v), inf); };
    const VF dd = hn::Neg(z);
    bad = hn::Or(bad, hn::Not(hn::Gt(dd, S(V.nearD))));
    const VF id = hn::Div(one, dd), fd = hn::Mul(f, id);
    const VF gx = hn::Mul(hn::Mul(fd, x), id), gy = hn::Neg(hn::Mul(hn::Mul(fd, y), id));
    const VF j00 = hn::MulAdd(fd, ex, hn::Mul(gx, ez)), j01 = hn::MulAdd(fd, sx, hn::Mul(gx, sz));
    const VF j10 = hn::MulSub(gy, ez, hn::Mul(fd, ey)), j11 = hn::MulSub(gy, sz, hn::Mul(fd, sy));
    const VF ja = hn::MulAdd(j00, j00, hn::Mul(j10, j10)), jb = hn::MulAdd(j00, j01, hn::Mul(j10, j11)),
             jc = hn::MulAdd(j01, j01, hn::Mul(j11, j11));
    const VF detJ = hn::MulSub(j00, j11, hn::Mul(j01, j10));
    const VF det = hn::Mul(detJ, detJ);
    bad = hn::Or(bad, hn::Not(hn::And(hn::Gt(det, zero), finite(det))));
    const VF v = hn::Div(Vh, det);
    Cov M;
    M.a = hn::MulAdd(v, jc, s2), M.b = hn::Neg(hn::Mul(v, jb)), M.c = hn::MulAdd(v, ja, s2);
    // det M without cancellation: s2^2 + s2 v (ja + jc) + Vh v
    M.det = hn::MulAdd(s2, hn::MulAdd(v, hn::Add(ja, jc), s2), hn::Mul(Vh, v));
    // the stretch clamp (segment::clampEigen): an eigenvalue beyond (kMaxStretch sigma_r)^2 is
    // clamped there (tiny far segments, whose prefilter dominates); one within 0.1% of the clamp
    // leaves the decision to the exact path
    const VF hm = hn::Mul(half, hn::Sub(M.a, M.c)), mean = hn::Mul(half, hn::Add(M.a, M.c));
    const VF rad = hn::Sqrt(hn::MulAdd(hm, hm, hn::Mul(M.b, M.b)));
    const VF l0 = hn::Add(mean, rad), l1 = hn::Div(M.det, l0);  // l1 without cancellation
    bad = hn::Or(bad, hn::Lt(hn::Abs(hn::Sub(l0, hiX)), hn::Mul(S(1e-3f), hiX)));
    bad = hn::Or(bad, hn::Lt(hn::Abs(hn::Sub(l1, hiX)), hn::Mul(S(1e-3f), hiX)));
    const MF over = hn::Gt(l0, hiX);
    if (!hn::AllFalse(d, over)) {
      // unit eigenvector of l0: (l0 - c, b) when a >= c, else (b, l0 - a) (no cancellation)
      const MF aBig = hn::Ge(M.a, M.c);
      VF ux = hn::IfThenElse(aBig, hn::Add(hm, rad), M.b), uy = hn::IfThenElse(aBig, M.b, hn::Sub(rad, hm));
      const VF u2 = hn::MulAdd(ux, ux, hn::Mul(uy, uy));
      const MF none = hn::Not(hn::Gt(u2, zero));  // M = l0 I
      const VF iu = hn::Div(one, hn::Sqrt(hn::IfThenElse(none, one, u2)));
      ux = hn::IfThenElse(none, one, hn::Mul(ux, iu)), uy = hn::IfThenElseZero(hn::Not(none), hn::Mul(uy, iu));
      const VF L0 = hn::Min(l0, hiX), L1 = hn::Min(l1, hiX);
      const VF xx = hn::Mul(ux, ux), yy = hn::Mul(uy, uy);
      M.a = hn::IfThenElse(over, hn::MulAdd(L0, xx, hn::Mul(L1, yy)), M.a);
      M.b = hn::IfThenElse(over, hn::Mul(hn::Sub(L0, L1), hn::Mul(ux, uy)), M.b);
      M.c = hn::IfThenElse(over, hn::MulAdd(L0, yy, hn::Mul(L1, xx)), M.c);
      M.det = hn::IfThenElse(over, hn::Mul(L0, L1), M.det);
    }
    return M;
  }
};

// The sub-segments of the lanes with K > 1 (hybrid models' long segments; see docs/decisions.md,
// "Segment prepare"): piece p over [L p / K, L (p + 1) / K] with the covariance at its middle, its
// weight scales from the covariances at its ends (M0, M1, the middle's Mm where 2 (p + 1) = K,
// else the covariance there), as the exact path's stage 2, to B.piece; the first piece's
// constants replace the one-piece ones (skew .. slope) and the footprint box grows around all
// pieces. Lanes whose covariance the floats cannot decide join `exact`.
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>>
HWY_INLINE void SegmentPieces(DF d, SegmentSetupBatch& B, int i, const SegmentCovariance<DF>& cov, VF R, VF rad,
                              VF len, VF iL, VF K, MF multi, MF active, VF cx, VF cy, VF cz, VF ex, VF ey, VF ez,
                              const SegmentCov<VF>& M0, const SegmentCov<VF>& M1, const SegmentCov<VF>& Mm, MF& exact,
                              VF& skew, VF& across, VF& invM00, VF& scale0, VF& slope, VF& aMin, VF& aMax, VF& bMax) {
  using Cov = SegmentCov<VF>;
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f), half = hn::Set(d, 0.5f);
  auto S = [&](float v) { return hn::Set(d, v); };
  auto St = [&](VF v, float* a) { hn::StoreU(v, d, a + i); };
  VF maxReach = zero, loDet = M0.det;
  aMin = hn::IfThenElse(multi, zero, aMin), aMax = hn::IfThenElse(multi, len, aMax);
  bMax = hn::IfThenElseZero(hn::Not(multi), bMax);
  const VF invK = hn::Div(one, K);
  const int maxK = int(hn::GetLane(hn::MaxOfLanes(d, hn::IfThenElseZero(hn::AndNot(exact, active), K))));
  for (int p = 0; p < maxK; ++p) {
    const MF live = hn::And(multi, hn::Lt(S(float(p)), K));
    const VF a0 = hn::Mul(hn::Mul(len, S(float(p))), invK), a1 = hn::Mul(hn::Mul(len, S(float(p + 1))), invK);
    const VF am = hn::Mul(half, hn::Add(a0, a1));
    MF bad = hn::Lt(one, zero);
    const Cov Mp = cov(hn::MulAdd(am, ex, cx), hn::MulAdd(am, ey, cy), hn::MulAdd(am, ez, cz), bad);
    const Cov Mh = cov(hn::MulAdd(a1, ex, cx), hn::MulAdd(a1, ey, cy), hn::MulAdd(a1, ez, cz), bad);
    const MF last = hn::Eq(S(float(p + 1)), K), middle = hn::Eq(S(float(2 * (p + 1))), K);
    const VF hiDet = hn::IfThenElse(last, M1.det, hn::IfThenElse(middle, Mm.det, Mh.det));
    exact = hn::Or(exact, hn::And(live, hn::Or(bad, hn::AndNot(hn::Or(last, middle), hn::Not(hn::Gt(hiDet, zero))))));
    const VF det = hn::MulSub(Mp.a, Mp.c, hn::Mul(Mp.b, Mp.b)), idet = hn::Div(one, det);
    const VF pic = hn::Div(one, Mp.c), pInv = hn::Mul(det, pic), reach = hn::Mul(R, hn::Sqrt(Mp.a));
    const VF s0 = hn::Div(one, hn::Mul(rad, hn::Sqrt(loDet))), s1 = hn::Div(one, hn::Mul(rad, hn::Sqrt(hiDet)));
    VF sl = hn::Div(hn::Sub(s1, s0), hn::Sub(a1, a0));
    sl = hn::IfThenElseZero(hn::Gt(hn::Mul(hn::Abs(sl), hn::Sub(a1, a0)), hn::Mul(S(1e-4f), s0)), sl);
    const VF pk = hn::Sqrt(hn::Div(half, pInv)), pErf = hn::Sqrt(hn::Mul(S(0.5f * float(std::numbers::pi)), pInv));
    const VF pSkew = hn::Neg(hn::Mul(Mp.b, pic));
    const VF fields[kPieceFields] = {a0, a1, hn::Mul(Mp.c, idet), hn::Neg(hn::Mul(Mp.b, idet)), hn::Mul(Mp.a, idet),
                                     s0, s1, reach, pSkew, pic, pInv, pk, pErf, sl};
    for (int q = 0; q < kPieceFields; ++q) St(fields[q], B.piece[q][p]);
    if (p == 0) {
      skew = hn::IfThenElse(multi, pSkew, skew), across = hn::IfThenElse(multi, pic, across);
      invM00 = hn::IfThenElse(multi, pInv, invM00), scale0 = hn::IfThenElse(multi, s0, scale0);
      slope = hn::IfThenElse(multi, sl, slope);
    }
    aMin = hn::IfThenElse(live, hn::Min(aMin, hn::Sub(a0, reach)), aMin);
    aMax = hn::IfThenElse(live, hn::Max(aMax, hn::Add(a1, reach)), aMax);
    bMax = hn::IfThenElse(live, hn::Max(bMax, hn::Mul(R, hn::Sqrt(Mp.c))), bMax);
    maxReach = hn::IfThenElse(live, hn::Max(maxReach, reach), maxReach);
    loDet = hiDet;
  }
  St(maxReach, B.pieceMaxReach), St(hn::Mul(K, iL), B.pieceInvLength);
    }

// Stage 4: the footprint box [aMin, aMax] x [-bMax, bMax] in the strip's plane (origin c, axes e,
// s) between the near and far planes, projected: its corners (B.qx, B.qy) and pixel bounds (B.x0
// .. B.y1; cut: the viewport clamped them; empty: no pixel). Lanes near a depth plane or with
// non-finite corners join `exact`.
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>>
HWY_INLINE void SegmentScreenBox(DF d, const SegmentSetupFrame& F, SegmentSetupBatch& B, int i, VF f, VF cx, VF cy,
                                 VF cz, VF ex, VF ey, VF ez, VF sx, VF sy, VF sz, VF aMin, VF aMax, VF bMax, MF& exact,
                                 MF& cut, MF& empty) {
  using DI = hn::RebindToSigned<DF>;
  using VI = hn::Vec<DI>;
  const DI di;
  const PointSetupFrame& V = F.view;
  const VF half = hn::Set(d, 0.5f);
  auto S = [&](float v) { return hn::Set(d, v); };
  auto St = [&](VF v, float* a) { hn::StoreU(v, d, a + i); };
  const VF inf = S(INFINITY);
  auto finite = [&](VF v) { return hn::Lt(hn::Abs(v), inf); };
  // stage 4: the footprint box between the near and far planes, projected
  VF x0 = inf, x1 = hn::Neg(inf), y0 = inf, y1 = hn::Neg(inf);
  for (int k = 0; k < 4; ++k) {
    const VF as = k == 0 || k == 3 ? aMin : aMax, bs = k < 2 ? hn::Neg(bMax) : bMax;
    const VF qx = hn::MulAdd(bs, sx, hn::MulAdd(as, ex, cx)), qy = hn::MulAdd(bs, sy, hn::MulAdd(as, ey, cy));
    const VF depth = hn::Neg(hn::MulAdd(bs, sz, hn::MulAdd(as, ez, cz)));
    exact = hn::Or(exact, hn::Not(hn::And(hn::Gt(depth, hn::Mul(S(1.0001f), S(V.nearD))),
                                          hn::Lt(depth, hn::Mul(S(0.9999f), S(V.farD))))));
    const VF id = hn::Div(f, depth);
    const VF X = hn::MulAdd(qx, id, S(V.cx)), Y = hn::NegMulAdd(qy, id, S(V.cy));
    St(X, B.qx[k]), St(Y, B.qy[k]);
    exact = hn::Or(exact, hn::Not(hn::And(finite(X), finite(Y))));
    x0 = hn::Min(x0, X), x1 = hn::Max(x1, X), y0 = hn::Min(y0, Y), y1 = hn::Max(y1, Y);
  }
  const VF lim = S(1e8f);
  auto pix = [&](VF v) {
    return hn::Add(hn::ConvertTo(di, hn::Floor(hn::Sub(hn::Min(hn::Max(v, hn::Neg(lim)), lim), half))), hn::Set(di, 1));
  };
  const VI bx0 = pix(x0), by0 = pix(y0), bx1 = pix(x1), by1 = pix(y1);
  const VI ix0 = hn::Max(bx0, hn::Zero(di)), iy0 = hn::Max(by0, hn::Zero(di));
  const VI ix1 = hn::Min(bx1, hn::Set(di, V.width)), iy1 = hn::Min(by1, hn::Set(di, V.height));
  hn::StoreU(ix0, di, B.x0 + i), hn::StoreU(ix1, di, B.x1 + i), hn::StoreU(iy0, di, B.y0 + i), hn::StoreU(iy1, di, B.y1 + i);
  cut = hn::RebindMask(d, hn::Not(hn::And(hn::And(hn::Eq(ix0, bx0), hn::Eq(iy0, by0)), hn::And(hn::Eq(ix1, bx1), hn::Eq(iy1, by1)))));
  empty = hn::RebindMask(d, hn::Not(hn::And(hn::Gt(ix1, ix0), hn::Gt(iy1, iy0))));
}

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#endif  // LINESURF_RENDER_SEGMENT_SETUP_INL_H_ toggle
