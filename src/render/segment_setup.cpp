// SIMD set-up of segment splats (beyond the thesis, issue 13: the stages of thesis §5 / §6.2.2 that
// segment_splat.cpp runs per segment, for the common case, over a batch in float), and the batches
// around it (segment_setup.h). The exact path, which takes every lane this code marks for it, is
// prepareSegment (segment_splat.cpp).
#include "segment_setup.h"

#include <algorithm>
#include <cmath>

#include "detail/splat_math.h"
#include "point_setup.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/segment_setup.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace linesurf::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The margins below send a lane to the exact path wherever float rounding could decide a test
// otherwise than the double arithmetic of prepareSegment: relative 1e-4 on the culling and depth
// tests, 4% on the subdivision test (its float error is below 1e-4), a facing of 0.02 at the
// ends (below it the float covariance loses more than 1e-4 relative), covariances with an
// eigenvalue within 0.1% of the stretch clamp (beyond it the clamp is applied here).
constexpr float kPieceTolerance2 = float(segment::kPieceTolerance * segment::kPieceTolerance);
constexpr float kShort = float(segment::kShortSegment);
constexpr float kCosStationTurn = 0.99500417f;  // cos(segment::kStationTurn)

void SegmentSetup(const SegmentSetupFrame& F, SegmentSetupBatch& B, int n) {
  const PointSetupFrame& V = F.view;
  using DF = hn::ScalableTag<float>;
  using VF = hn::Vec<DF>;
  using MF = hn::Mask<DF>;
  using DI = hn::RebindToSigned<DF>;
  using VI = hn::Vec<DI>;
  const DF d;
  const DI di;
  const int lanes = int(hn::Lanes(d));
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f), half = hn::Set(d, 0.5f);
  auto S = [&](float v) { return hn::Set(d, v); };
  auto dot3 = [](VF ax, VF ay, VF az, VF bx, VF by, VF bz) { return hn::MulAdd(ax, bx, hn::MulAdd(ay, by, hn::Mul(az, bz))); };
  const VF inf = S(INFINITY);
  auto finite = [&](VF v) { return hn::Lt(hn::Abs(v), inf); };
  const VF f = S(V.f), R = S(V.cutoff), Vh = S(V.prefilter);
  for (int i = 0; i < n; i += lanes) {
    auto L = [&](const float* a) { return hn::LoadU(d, a + i); };
    auto St = [&](VF v, float* a) { hn::StoreU(v, d, a + i); };
    const VF px0 = L(B.p0x), py0 = L(B.p0y), pz0 = L(B.p0z), px1 = L(B.p1x), py1 = L(B.p1y), pz1 = L(B.p1z);
    const VF wx = L(B.wx), wy = L(B.wy), wz = L(B.wz), rad = L(B.radius);
    // stage 1: the strip (the batch holds camera-space input, rounded as Camera::toCamera rounds
    // for the exact path: a short segment far away gets its direction, not one of other rounding)
    const VF cx = px0, cy = py0, cz = pz0, qx1 = px1, qy1 = py1, qz1 = pz1;
    const VF dx = hn::Sub(qx1, cx), dy = hn::Sub(qy1, cy), dz = hn::Sub(qz1, cz);
    const VF len = hn::Sqrt(dot3(dx, dy, dz, dx, dy, dz));
    // three kinds of lanes for the exact path, in the order of its tests: unusual input (it may
    // be Degenerate), undecided before the culling tests, undecided after them
    MF badInput = hn::Not(hn::And(hn::Gt(rad, zero), finite(rad)));
    for (VF v : {px0, py0, pz0, px1, py1, pz1, wx, wy, wz}) badInput = hn::Or(badInput, hn::Not(finite(v)));
    badInput = hn::Or(badInput, hn::Not(hn::And(hn::Gt(len, hn::Mul(S(2e-6f), rad)), finite(len))));
    const VF iL = hn::Div(one, len);
    const VF ex = hn::Mul(dx, iL), ey = hn::Mul(dy, iL), ez = hn::Mul(dz, iL);
    // depth rejection with the largest possible footprint
    const VF reach = hn::Mul(S(F.reach), rad);
    const VF zmin = hn::Min(hn::Neg(cz), hn::Neg(qz1)), zmax = hn::Max(hn::Neg(cz), hn::Neg(qz1));
    const VF dmin = hn::Sub(zmin, reach), dmax = hn::Add(zmax, reach);
    const VF tolD = hn::Mul(S(1e-4f), hn::Add(hn::Add(hn::Abs(zmax), reach), S(V.nearD)));
    const MF outside = hn::Or(hn::Lt(hn::Add(dmax, tolD), S(V.nearD)), hn::Gt(hn::Sub(dmin, tolD), S(V.farD)));
    MF early = hn::AndNot(outside, hn::Or(hn::Lt(hn::Sub(dmax, tolD), S(V.nearD)), hn::Gt(hn::Add(dmin, tolD), S(V.farD))));
    // the plane normal perpendicular to e, facing the eye
    VF nx = wx, ny = wy, nz = wz;
    const VF ne = dot3(nx, ny, nz, ex, ey, ez);
    nx = hn::NegMulAdd(ne, ex, nx), ny = hn::NegMulAdd(ne, ey, ny), nz = hn::NegMulAdd(ne, ez, nz);
    const VF nn2 = dot3(nx, ny, nz, nx, ny, nz);
    early = hn::Or(early, hn::Not(hn::Gt(nn2, S(4e-6f))));  // |n| <= 2e-3: the exact stage decides
    const VF inn = hn::Div(one, hn::Sqrt(nn2));
    VF D = hn::Mul(hn::Neg(dot3(nx, ny, nz, cx, cy, cz)), inn);
    const MF back = hn::Lt(D, zero);
    const VF sgn = hn::IfThenElse(back, hn::Neg(inn), inn);
    nx = hn::Mul(nx, sgn), ny = hn::Mul(ny, sgn), nz = hn::Mul(nz, sgn);
    D = hn::Abs(D);
    MF culled = V.backfaceCulling ? back : hn::Lt(one, zero);
    {  // grazing everywhere: D / dist < kMinFacing at the point nearest to the eye
      const VF t = hn::Min(hn::Max(hn::Neg(dot3(cx, cy, cz, ex, ey, ez)), zero), len);
      const VF qx = hn::MulAdd(t, ex, cx), qy = hn::MulAdd(t, ey, cy), qz = hn::MulAdd(t, ez, cz);
      const VF g = hn::Mul(S(kMinFacing * kMinFacing), dot3(qx, qy, qz, qx, qy, qz)), D2 = hn::Mul(D, D);
      const MF graze = hn::Lt(D2, g);
      early = hn::Or(early, hn::AndNot(culled, hn::Lt(hn::Abs(hn::Sub(D2, g)), hn::Mul(S(1e-3f), g))));
      culled = hn::Or(culled, graze);
    }
    // near grazing at an end: the float covariance is not accurate enough there
    const VF end2 = hn::Max(dot3(cx, cy, cz, cx, cy, cz), dot3(qx1, qy1, qz1, qx1, qy1, qz1));
    MF exact = hn::Lt(hn::Mul(D, D), hn::Mul(S(4e-4f), end2));
    const VF sx = hn::MulSub(ey, nz, hn::Mul(ez, ny)), sy = hn::MulSub(ez, nx, hn::Mul(ex, nz)),
             sz = hn::MulSub(ex, ny, hn::Mul(ey, nx));
    // stage 2: the resampling covariance (segment::covariance) at both ends and the middle
    const VF sigma = hn::Mul(S(V.reconstructionScale), rad), s2 = hn::Mul(sigma, sigma);
    const VF hiX = hn::Mul(S(kMaxStretch * kMaxStretch), s2);
    struct Cov {
      VF a, b, c, det;
    };
    auto cov = [&](VF x, VF y, VF z, MF& bad) {
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
    };
    const Cov M0 = cov(cx, cy, cz, exact);
    const Cov M1 = cov(qx1, qy1, qz1, exact);
    Cov Mm{hn::Mul(half, hn::Add(M0.a, M1.a)), hn::Mul(half, hn::Add(M0.b, M1.b)), hn::Mul(half, hn::Add(M0.c, M1.c)), zero};
    auto norm2 = [&](VF a, VF b, VF c) { return hn::MulAdd(a, a, hn::MulAdd(hn::Add(b, b), b, hn::Mul(c, c))); };
    VF change2 = norm2(hn::Sub(M1.a, M0.a), hn::Sub(M1.b, M0.b), hn::Sub(M1.c, M0.c));
    // the middle's own covariance, unless the segment is short against its depth
    const MF isShort = hn::Lt(len, hn::Mul(S(kShort), zmin));
    exact = hn::Or(exact, hn::Lt(hn::Abs(hn::Sub(len, hn::Mul(S(kShort), zmin))), hn::Mul(S(1e-4f), len)));
    const MF active = hn::FirstN(d, size_t(n - i));
    if (!hn::AllTrue(d, hn::Or(isShort, hn::Not(active)))) {
      const VF hl = hn::Mul(half, len);
      MF badMid = hn::Lt(one, zero);
      const Cov Mc = cov(hn::MulAdd(hl, ex, cx), hn::MulAdd(hl, ey, cy), hn::MulAdd(hl, ez, cz), badMid);
      exact = hn::Or(exact, hn::AndNot(isShort, badMid));
      const VF c2 = hn::Mul(S(16.0f), norm2(hn::Sub(Mc.a, Mm.a), hn::Sub(Mc.b, Mm.b), hn::Sub(Mc.c, Mm.c)));
      change2 = hn::IfThenElse(isShort, change2, hn::Max(change2, c2));
      Mm.a = hn::IfThenElse(isShort, Mm.a, Mc.a), Mm.b = hn::IfThenElse(isShort, Mm.b, Mc.b);
      Mm.c = hn::IfThenElse(isShort, Mm.c, Mc.c);
    }
    const VF limit = hn::Mul(S(kPieceTolerance2), hn::Min(norm2(M0.a, M0.b, M0.c), norm2(M1.a, M1.b, M1.c)));
    exact = hn::Or(exact, hn::Not(hn::Lt(change2, hn::Mul(S(0.96f), limit))));  // K > 1 or near it
    // the only piece (segment::makePiece)
    const VF detm = hn::MulSub(Mm.a, Mm.c, hn::Mul(Mm.b, Mm.b));
    const VF ic = hn::Div(one, Mm.c);
    const VF invM00 = hn::Mul(detm, ic);
    const VF pieceReach = hn::Mul(R, hn::Sqrt(Mm.a));
    const VF scale0 = hn::Div(one, hn::Mul(rad, hn::Sqrt(M0.det))), scale1 = hn::Div(one, hn::Mul(rad, hn::Sqrt(M1.det)));
    VF slope = hn::Mul(hn::Sub(scale1, scale0), iL);
    slope = hn::IfThenElseZero(hn::Gt(hn::Mul(hn::Abs(slope), len), hn::Mul(S(1e-4f), scale0)), slope);
    St(hn::Neg(hn::Mul(Mm.b, ic)), B.skew), St(ic, B.across), St(invM00, B.invM00);
    St(hn::Sqrt(hn::Div(half, invM00)), B.k), St(hn::Sqrt(hn::Mul(S(0.5f * float(kPi)), invM00)), B.erfScale);
    St(scale0, B.scale0), St(slope, B.slope);
    const VF aMin = hn::Neg(pieceReach), aMax = hn::Add(len, pieceReach), bMax = hn::Mul(R, hn::Sqrt(Mm.c));
    St(aMin, B.aMin), St(aMax, B.aMax), St(bMax, B.bMax), St(len, B.length);
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
    const MF cut = hn::RebindMask(d, hn::Not(hn::And(hn::And(hn::Eq(ix0, bx0), hn::Eq(iy0, by0)), hn::And(hn::Eq(ix1, bx1), hn::Eq(iy1, by1)))));
    const MF empty = hn::RebindMask(d, hn::Not(hn::And(hn::Gt(ix1, ix0), hn::Gt(iy1, iy0))));
    // stage 5: per-pixel constants; k.r(px, py) = k.x/f px - k.y/f py + (k.y cy - k.x cx)/f - k.z
    const VF invF = S(F.invF);
    const VF no = dot3(nx, ny, nz, cx, cy, cz);
    auto ray = [&](VF kx, VF ky, VF kz, VF c, float* ox, float* oy, float* oc) {
      const VF gx = hn::Mul(kx, invF), gy = hn::Mul(ky, invF);
      St(hn::Mul(c, gx), ox), St(hn::Neg(hn::Mul(c, gy)), oy);
      St(hn::Mul(c, hn::Sub(hn::MulSub(gy, S(V.cy), hn::Mul(gx, S(V.cx))), kz)), oc);
    };
    ray(nx, ny, nz, one, B.Nx, B.Ny, B.N0);
    ray(ex, ey, ez, no, B.Ax, B.Ay, B.A0);
    ray(sx, sy, sz, no, B.Bx, B.By, B.B0);
    St(no, B.depthNum), St(dot3(ex, ey, ez, cx, cy, cz), B.a0), St(dot3(sx, sy, sz, cx, cy, cz), B.b0);
    auto extent = [&](const Cov& M) {  // R sqrt(g.M g) + radius, g = (e.z, s.z)
      const VF q = hn::MulAdd(M.a, hn::Mul(ez, ez), hn::MulAdd(hn::Add(M.b, M.b), hn::Mul(ez, sz), hn::Mul(M.c, hn::Mul(sz, sz))));
      return hn::MulAdd(R, hn::Sqrt(hn::Max(q, zero)), rad);
    };
    St(extent(M0), B.extent0), St(extent(M1), B.extent1);
    St(nx, B.nx), St(ny, B.ny), St(nz, B.nz);
    St(qx1, B.p1cx), St(qy1, B.p1cy), St(qz1, B.p1cz);
    // stage 6: shading normals (smooth: the endpoint normals on the plane normal's side) and Phong
    VF n0x = nx, n0y = ny, n0z = nz, n1x = nx, n1y = ny, n1z = nz;
    if (F.smoothFrame) {
      const MF sm = hn::Gt(L(B.smooth), zero);
      VF ax = L(B.m0x), ay = L(B.m0y), az = L(B.m0z), bx = L(B.m1x), by = L(B.m1y), bz = L(B.m1z);
      const VF ia = hn::Div(one, hn::Sqrt(dot3(ax, ay, az, ax, ay, az))), ib = hn::Div(one, hn::Sqrt(dot3(bx, by, bz, bx, by, bz)));
      const MF flip = hn::Lt(dot3(nx, ny, nz, hn::MulAdd(ax, ia, hn::Mul(bx, ib)), hn::MulAdd(ay, ia, hn::Mul(by, ib)),
                                  hn::MulAdd(az, ia, hn::Mul(bz, ib))), zero);
      const VF sa = hn::IfThenElse(flip, hn::Neg(ia), ia), sb = hn::IfThenElse(flip, hn::Neg(ib), ib);
      ax = hn::Mul(ax, sa), ay = hn::Mul(ay, sa), az = hn::Mul(az, sa);
      bx = hn::Mul(bx, sb), by = hn::Mul(by, sb), bz = hn::Mul(bz, sb);
      // turning by more than kStationTurn (0.1 rad): several lighting stations (prepareSegments
      // lights them per lane); near that threshold the exact path decides
      const VF cosTurn = dot3(ax, ay, az, bx, by, bz);
      exact = hn::Or(exact, hn::And(sm, hn::Not(hn::Gt(hn::Abs(hn::Sub(cosTurn, S(kCosStationTurn))), S(1e-5f)))));
      exact = hn::Or(exact, hn::And(sm, hn::Not(hn::And(finite(ax), finite(bx)))));
      n0x = hn::IfThenElse(sm, ax, nx), n0y = hn::IfThenElse(sm, ay, ny), n0z = hn::IfThenElse(sm, az, nz);
      n1x = hn::IfThenElse(sm, bx, nx), n1y = hn::IfThenElse(sm, by, ny), n1z = hn::IfThenElse(sm, bz, nz);
    }
    St(n0x, B.n0x), St(n0y, B.n0y), St(n0z, B.n0z), St(n1x, B.n1x), St(n1y, B.n1y), St(n1z, B.n1z);
    if (F.light) {
      const VF lx = S(V.lightDir[0]), ly = S(V.lightDir[1]), lz = S(V.lightDir[2]);
      auto phong = [&](VF mx, VF my, VF mz, VF qx, VF qy, VF qz, float* dif, float* spec) {
        const VF ndl = hn::Max(zero, dot3(mx, my, mz, lx, ly, lz));
        St(hn::MulAdd(S(V.diffuse), ndl, S(V.ambient)), dif);
        VF sp = zero;
        if (V.specular > 0) {
          const VF q2 = dot3(qx, qy, qz, qx, qy, qz);
          const VF iq = hn::Neg(hn::Div(one, hn::Sqrt(q2)));  // view vector -q / |q|
          const VF hx = hn::MulAdd(qx, iq, lx), hy = hn::MulAdd(qy, iq, ly), hz = hn::MulAdd(qz, iq, lz);
          const VF h2 = dot3(hx, hy, hz, hx, hy, hz);
          const VF ndh = hn::Min(one, hn::Max(zero, hn::Div(dot3(mx, my, mz, hx, hy, hz), hn::Sqrt(h2))));
          // lanes the exact path takes may hold NaN here: the index stays inside the table
          VF x = hn::Mul(ndh, S(float(FrameContext::kSpecularTable)));
          x = hn::Min(hn::Max(hn::IfThenElseZero(hn::Eq(x, x), x), zero), S(float(FrameContext::kSpecularTable)));
          const VF xi = hn::Floor(x);
          const VI k = hn::ConvertTo(di, xi);
          const VF t0 = hn::GatherIndex(d, F.specularTable, k), t1 = hn::GatherIndex(d, F.specularTable + 1, k);
          const VF pw = hn::MulAdd(hn::Sub(x, xi), hn::Sub(t1, t0), t0);
          const MF lit = hn::And(hn::And(hn::Gt(ndl, zero), hn::Gt(h2, zero)), hn::Gt(q2, zero));
          sp = hn::IfThenElseZero(lit, hn::Mul(S(V.specular), pw));
        }
        St(sp, spec);
      };
      phong(n0x, n0y, n0z, cx, cy, cz, B.diffuse0, B.specular0);
      phong(n1x, n1y, n1z, qx1, qy1, qz1, B.diffuse1, B.specular1);
    }
    const VF status = hn::IfThenElse(empty, S(4.0f), hn::IfThenElseZero(cut, S(3.0f)));
    const VF two = S(2.0f);
    St(hn::IfThenElse(badInput, two, hn::IfThenElse(outside, S(4.0f), hn::IfThenElse(early, two,
        hn::IfThenElse(culled, one, hn::IfThenElse(exact, two, status))))), B.status);
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(SegmentSetup);
void segmentSetup(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n) {
  HWY_DYNAMIC_DISPATCH(SegmentSetup)(frame, batch, n);
}
}  // namespace linesurf::detail

namespace linesurf {

detail::SegmentSetupFrame segmentSetupFrame(const FrameContext& frame) {
  const RenderOptions& opt = frame.opt();
  detail::SegmentSetupFrame f;
  f.view = pointSetupFrame(frame);  // the camera, filter and material constants points use
  f.invF = 1 / f.view.f;
  f.reach = float(double(opt.cutoffRadius) * opt.reconstructionScale * detail::kMaxStretch);
  f.smoothFrame = frame.endpointNormals;
  f.perPixelLighting = opt.perPixelLighting;
  f.specularTable = frame.specularPow ? frame.specularPow->data() : nullptr;
  f.light = !opt.perPixelLighting && (f.specularTable || !(opt.material.specular > 0));
  // the common case the SIMD code handles: the ScreenSpace method, untextured, with a prefilter
  f.simd = opt.segmentMethod == SegmentMethod::ScreenSpace && !frame.texture && opt.prefilterVariance > 0;
  return f;
}

namespace {

bool visible(PrimitiveStatus s) { return s == PrimitiveStatus::Drawn || s == PrimitiveStatus::Clipped; }

// A smooth lane whose shading normals turn by more than kStationTurn gets shade Stations, as in
// prepareSegment's stage 6 (segment_splat.cpp): Gouraud at ceil(turn / kStationTurn) + 1 stations,
// or none when lighting is deferred. Returns the number of station intervals (0 deferred), -1 for
// a lane that does not turn, -2 for one whose count the float turn cannot decide (the exact path).
int turningStations(const detail::SegmentSetupBatch& b, int j, const detail::SegmentSetupFrame& F) {
  if (!(b.smooth[j] > 0)) return -1;
  const Vec3f n0(b.n0x[j], b.n0y[j], b.n0z[j]), n1(b.n1x[j], b.n1y[j], b.n1z[j]);
  const float cosTurn = n0.dot(n1);  // the SIMD code left lanes within 1e-5 of the threshold
  if (!(cosTurn < std::cos(segment::kStationTurn))) return -1;
  if (F.perPixelLighting) return 0;
  const float turn = std::acos(std::clamp(cosTurn, -1.0f, 1.0f));
  const float x = turn / segment::kStationTurn;
  if (std::abs(x - std::round(x)) < 1e-3f) return -2;  // ceil(x) undecided
  return stationIntervals(turn, 1);
}

// Lane j of the batch into its PreparedSegment (what prepareSegment's stages 4-6 write);
// stations as turningStations gives it.
void pack(const detail::SegmentSetupBatch& b, int j, const Segment& seg, uint32_t index, const FrameContext& frame,
          const detail::SegmentSetupFrame& F, int stations, PreparedSegment& out) {
  out.index = index;
  out.fallback = false;
  resetExtra(out.extra);
  out.bounds = {b.x0[j], b.y0[j], b.x1[j], b.y1[j]};
  out.method = SegmentMethod::ScreenSpace;
  out.useSpans = true;
  for (int k = 0; k < 4; ++k) out.screenQuad[k] = Vec2f(b.qx[k][j], b.qy[k][j]);
  detail::SegmentRaster& k = out.raster;
  k.N = {b.Nx[j], b.Ny[j], b.N0[j]};
  k.A = {b.Ax[j], b.Ay[j], b.A0[j]};
  k.B = {b.Bx[j], b.By[j], b.B0[j]};
  k.depthNum = b.depthNum[j], k.a0 = b.a0[j], k.b0 = b.b0[j];
  k.length = b.length[j], k.R2 = frame.cutoffQ;
  k.aMin = b.aMin[j], k.aMax = b.aMax[j], k.bMax = b.bMax[j];
  k.skew = b.skew[j], k.across = b.across[j], k.invM00 = b.invM00[j], k.k = b.k[j], k.erfScale = b.erfScale[j];
  k.scale0 = b.scale0[j], k.slope = b.slope[j];
  k.zThreshold0 = frame.zThreshold(b.extent0[j]);
  k.zThreshold1 = frame.zThreshold(b.extent1[j]);
  k.nearD = F.view.nearD, k.farD = F.view.farD;
  k.clipDepth = false;
  k.pieceCount = 1;
  k.pieces = nullptr;
  k.pieceInvLength = 0, k.pieceMaxReach = 0;
  // shading (segment_splat.cpp, stage 6, for one or no lighting station interval)
  const bool smooth = b.smooth[j] > 0;
  out.smooth = smooth;
  const Vec3f n0(b.n0x[j], b.n0y[j], b.n0z[j]), n1(b.n1x[j], b.n1y[j], b.n1z[j]);
  if (smooth) out.n0 = n0, out.dn = n1 - n0;
  const Color col = frame.primitiveColor(seg.color);
  setBaseAttributes(out, col, n0);
  float* a = out.attr;
  if (F.perPixelLighting) {
    out.shade = smooth ? SegmentShade::Smooth : SegmentShade::Constant;
    if (stations == 0) {  // turning: the rows normalise n0 + u dn exactly
      out.shade = SegmentShade::Stations;
      stationsExtra(out, seg, false, 0);
    }
    return;
  }
  out.shade = smooth ? SegmentShade::Smooth : SegmentShade::Linear;
  Vec3f k0, k1;
  if (stations > 0) {  // Gouraud at stations + 1 evenly spaced stations (segment_splat.cpp, stage 6)
    out.shade = SegmentShade::Stations;
    SegmentExtra& x = stationsExtra(out, seg, false, stations);
    const Vec3f p0(b.p0x[j], b.p0y[j], b.p0z[j]), p1(b.p1cx[j], b.p1cy[j], b.p1cz[j]);
    const Vec3f albedo = col.head<3>(), dn = n1 - n0;
    for (int s = 0; s <= stations; ++s) {
      const float u = float(s) / float(stations);
      Vec3f c;
      if (F.light && (s == 0 || s == stations)) {  // the batch's Phong factors at the ends
        const float dif = s == 0 ? b.diffuse0[j] : b.diffuse1[j], spec = s == 0 ? b.specular0[j] : b.specular1[j];
        c = (albedo * dif + Vec3f::Constant(spec)).cwiseProduct(frame.opt().light.color);
      } else {
        const Vec3f m = n0 + u * dn;
        c = frame.shade(albedo, m / m.norm(), p0 + u * (p1 - p0));
      }
      for (int ch = 0; ch < 3; ++ch) x.colour[size_t(ch * (stations + 1) + s)] = c[ch];
    }
    return;
  }
  if (F.light) {
    const Vec3f& lc = frame.opt().light.color;
    for (int c = 0; c < 3; ++c) {
      k0[c] = (col[c] * b.diffuse0[j] + b.specular0[j]) * lc[c];
      k1[c] = (col[c] * b.diffuse1[j] + b.specular1[j]) * lc[c];
    }
  } else {
    k0 = frame.shade(col.head<3>(), n0, frame.cam().toCamera(seg.p0));
    k1 = frame.shade(col.head<3>(), n1, Vec3f(b.p1cx[j], b.p1cy[j], b.p1cz[j]));
  }
  a[Z3Tile::kR] = k0.x(), a[Z3Tile::kG] = k0.y(), a[Z3Tile::kB] = k0.z();
  out.dc = k1 - k0;
}

}  // namespace

size_t prepareSegments(const Segment* segments, uint32_t first, size_t count, const FrameContext& frame,
                       const detail::SegmentSetupFrame& F, PreparedSegment* out, PrimitiveStatus* status) {
  if (!F.simd) {
    for (size_t j = 0; j < count; ++j) status[j] = prepareSegment(segments[first + j], uint32_t(first + j), frame, out[j]);
    return count;
  }
  size_t scalar = 0;
  const Camera& cam = frame.cam();
  detail::SegmentSetupBatch b;
  for (size_t base = 0; base < count; base += detail::kSegmentBatch) {
    const int n = int(std::min<size_t>(detail::kSegmentBatch, count - base));
    for (int j = 0; j < n; ++j) {  // AoS -> SoA
      const Segment& s = segments[first + base + size_t(j)];
      // the input a batch ahead (a hint: an address past the array is harmless)
      const char* next = reinterpret_cast<const char*>(&s + detail::kSegmentBatch);
      __builtin_prefetch(next);
      __builtin_prefetch(next + 64);
      const Vec3f c0 = cam.toCamera(s.p0), c1 = cam.toCamera(s.p1);
      b.p0x[j] = c0.x(), b.p0y[j] = c0.y(), b.p0z[j] = c0.z();
      b.p1x[j] = c1.x(), b.p1y[j] = c1.y(), b.p1z[j] = c1.z();
      b.radius[j] = s.radius;
      const bool smooth = F.smoothFrame && s.normal0.allFinite() && s.normal1.allFinite() &&
                          s.normal0.squaredNorm() > 0 && s.normal1.squaredNorm() > 0;
      const Vec3f w = cam.rotation() * (smooth && !(s.normal.squaredNorm() > 0) ? Vec3f(s.normal0 + s.normal1) : s.normal);
      b.wx[j] = w.x(), b.wy[j] = w.y(), b.wz[j] = w.z();
      b.smooth[j] = smooth ? 1.0f : 0.0f;
      if (F.smoothFrame) {
        const Vec3f m0 = smooth ? Vec3f(cam.rotation() * s.normal0) : Vec3f::UnitZ();
        const Vec3f m1 = smooth ? Vec3f(cam.rotation() * s.normal1) : Vec3f::UnitZ();
        b.m0x[j] = m0.x(), b.m0y[j] = m0.y(), b.m0z[j] = m0.z();
        b.m1x[j] = m1.x(), b.m1y[j] = m1.y(), b.m1z[j] = m1.z();
      }
    }
    for (int j = n; j < detail::kSegmentBatch && j < ((n + 15) & ~15); ++j) {  // harmless padding lanes
      b.p0x[j] = b.p0y[j] = b.p0z[j] = b.p1y[j] = b.p1z[j] = b.wx[j] = b.wy[j] = 0;
      b.p1x[j] = b.wz[j] = b.radius[j] = 1;
      b.smooth[j] = 0;
      b.m0x[j] = b.m0y[j] = b.m1x[j] = b.m1y[j] = 0;
      b.m0z[j] = b.m1z[j] = 1;
    }
    detail::segmentSetup(F, b, n);
    // the records of the segments drawn, a few lanes ahead of their writing (they stream
    // through memory once per frame)
    constexpr int kAhead = 24;
    auto prefetchRecord = [&](int j) {
      if (j >= n || b.status[j] == 1.0f || b.status[j] == 4.0f) return;
      const char* rec = reinterpret_cast<const char*>(out + base + size_t(j));
      for (size_t o = 0; o < sizeof(PreparedSegment); o += 64) __builtin_prefetch(rec + o, 1);
    };
    for (int j = 0; j < kAhead; ++j) prefetchRecord(j);
    for (int j = 0; j < n; ++j) {
      prefetchRecord(j + kAhead);
      const size_t i = base + size_t(j);
      const uint32_t index = uint32_t(first + i);
      int stations = -1;
      switch (int(b.status[j])) {
        case 0: status[i] = PrimitiveStatus::Drawn; break;
        case 1: status[i] = PrimitiveStatus::Culled; break;
        case 3: status[i] = PrimitiveStatus::Clipped; break;
        case 4: status[i] = PrimitiveStatus::Outside; break;
        default: stations = -2;
      }
      if (stations == -1 && visible(status[i])) stations = turningStations(b, j, F);
      if (stations == -2) {
        status[i] = prepareSegment(segments[index], index, frame, out[i]);
        ++scalar;
        continue;
      }
      if (visible(status[i])) pack(b, j, segments[index], index, frame, F, stations, out[i]);
    }
  }
  return scalar;
}

}  // namespace linesurf
#endif  // HWY_ONCE
