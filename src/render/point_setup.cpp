// SIMD set-up of point splats (thesis §4.2, §6.2: object-to-screen warp, culling, bounds) (see point_setup.h, pointSetup; the scalar reference is
// preparePoint in point_splat.cpp, which handles every lane this code marks for it), and the
// batches around it (point_setup.h: early culling, packing of the visible points).
#include "point_setup.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <new>

#include "splat_rules.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/point_setup.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>

HWY_BEFORE_NAMESPACE();
namespace linesurf::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The splats stretched past kMaxStretch (lanes `stretched`, some of them not slow yet): the
// thesis's construction, the exact path of preparePoint. V = Rot(theta) Lambda^2 Rot(theta)^T
// (V = (a b; b c) in the tangent frame u, v; eigenvalues mean +- eig) with both radii clamped to
// maxS = kMaxStretch sigma, bounds of the quadrilateral c +- R r0 E0 +- R r1 E1; in SIMD when no
// corner leaves [near, far] (else the lane turns slow: preparePoint clips it). The stretched
// lanes' plane vectors (a0, a1), weight scale, depth extent and Gouraud corners (b0, b1) are
// replaced; q*: their screen bounds.
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>>
HWY_INLINE void PointStretched(DF d, const PointSetupFrame& F, VF ux, VF uy, VF uz, VF vx, VF vy, VF vz, VF nx, VF ny,
                               VF nz, VF cx, VF cy, VF cz, VF a, VF b, VF c, VF mean, VF eig, VF maxS, VF R, VF f,
                               MF stretched, VF& a0x, VF& a0y, VF& a0z, VF& a1x, VF& a1y, VF& a1z, VF& wscale, VF& ext,
                               VF& b0x, VF& b0y, VF& b0z, VF& b1x, VF& b1y, VF& b1z, MF& slow, VF& qx0, VF& qx1,
                               VF& qy0, VF& qy1) {
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  auto S = [&](float v) { return hn::Set(d, v); };
  const VF l0 = hn::Add(mean, eig), l1 = hn::Max(hn::Sub(mean, eig), S(1e-30f));
  const auto useB = hn::And(hn::Gt(hn::Abs(b), hn::Mul(S(1e-30f), hn::Add(hn::Abs(a), hn::Abs(c)))), hn::Ne(b, zero));
  const VF gx = hn::Sub(l0, c), ie = hn::Div(one, hn::Sqrt(hn::MulAdd(gx, gx, hn::Mul(b, b))));
  const auto aGeC = hn::Ge(a, c);
  const VF e0x = hn::IfThenElse(useB, hn::Mul(gx, ie), hn::IfThenElseZero(aGeC, one));
  const VF e0y = hn::IfThenElse(useB, hn::Mul(b, ie), hn::IfThenZeroElse(aGeC, one));
  const VF r0 = hn::Min(hn::Sqrt(l0), maxS), r1 = hn::Min(hn::Sqrt(l1), maxS);
  const VF E0x = hn::MulAdd(e0x, ux, hn::Mul(e0y, vx)), E0y = hn::MulAdd(e0x, uy, hn::Mul(e0y, vy)),
           E0z = hn::MulAdd(e0x, uz, hn::Mul(e0y, vz));
  const VF E1x = hn::MulSub(ny, E0z, hn::Mul(nz, E0y)), E1y = hn::MulSub(nz, E0x, hn::Mul(nx, E0z)),
           E1z = hn::MulSub(nx, E0y, hn::Mul(ny, E0x));
  auto exSlow = hn::Not(hn::And(hn::Gt(r0, zero), hn::Gt(r1, zero)));
  const VF inf = S(INFINITY);
  exSlow = hn::Or(exSlow, hn::Not(hn::And(hn::Lt(hn::Abs(E0x), inf), hn::And(hn::Lt(hn::Abs(E0y), inf), hn::Lt(hn::Abs(E0z), inf)))));
  const VF ir0 = hn::Div(one, r0), ir1 = hn::Div(one, r1);
  const VF Rr0 = hn::Mul(R, r0), Rr1 = hn::Mul(R, r1);
  const VF hx0 = hn::Mul(Rr0, E0x), hy0 = hn::Mul(Rr0, E0y), hz0 = hn::Mul(Rr0, E0z);  // R r0 E0
  const VF hx1 = hn::Mul(Rr1, E1x), hy1 = hn::Mul(Rr1, E1y), hz1 = hn::Mul(Rr1, E1z);  // R r1 E1
  VF xmin = inf, xmax = hn::Neg(inf), ymin = inf, ymax = hn::Neg(inf);
  for (int k = 0; k < 4; ++k) {
    const VF ss = S(k & 1 ? 1.0f : -1.0f), tt = S(k & 2 ? 1.0f : -1.0f);
    const VF qx = hn::MulAdd(tt, hx1, hn::MulAdd(ss, hx0, cx)), qy = hn::MulAdd(tt, hy1, hn::MulAdd(ss, hy0, cy)),
             qz = hn::MulAdd(tt, hz1, hn::MulAdd(ss, hz0, cz));
    const VF qd = hn::Neg(qz);
    exSlow = hn::Or(exSlow, hn::Not(hn::And(hn::Ge(hn::Sub(qd, S(F.nearD)), zero), hn::Ge(hn::Add(S(F.farD), qz), zero))));
    const VF iqd = hn::Div(one, qd);
    const VF sx = hn::MulAdd(hn::Mul(f, qx), iqd, S(F.cx)), sy = hn::NegMulAdd(hn::Mul(f, qy), iqd, S(F.cy));
    xmin = hn::Min(xmin, sx), xmax = hn::Max(xmax, sx), ymin = hn::Min(ymin, sy), ymax = hn::Max(ymax, sy);
  }
  qx0 = xmin, qx1 = xmax, qy0 = ymin, qy1 = ymax;
  a0x = hn::IfThenElse(stretched, hn::Mul(E0x, ir0), a0x), a0y = hn::IfThenElse(stretched, hn::Mul(E0y, ir0), a0y),
  a0z = hn::IfThenElse(stretched, hn::Mul(E0z, ir0), a0z);
  a1x = hn::IfThenElse(stretched, hn::Mul(E1x, ir1), a1x), a1y = hn::IfThenElse(stretched, hn::Mul(E1y, ir1), a1y),
  a1z = hn::IfThenElse(stretched, hn::Mul(E1z, ir1), a1z);
  wscale = hn::IfThenElse(stretched, hn::Div(one, hn::Mul(r0, r1)), wscale);
  ext = hn::IfThenElse(stretched, hn::Mul(R, hn::Sqrt(hn::MulAdd(hn::Mul(r0, r0), hn::Mul(E0z, E0z), hn::Mul(hn::Mul(r1, r1), hn::Mul(E1z, E1z))))), ext);
  b0x = hn::IfThenElse(stretched, hx0, b0x), b0y = hn::IfThenElse(stretched, hy0, b0y), b0z = hn::IfThenElse(stretched, hz0, b0z);
  b1x = hn::IfThenElse(stretched, hx1, b1x), b1y = hn::IfThenElse(stretched, hy1, b1y), b1z = hn::IfThenElse(stretched, hz1, b1z);
  slow = hn::Or(slow, hn::And(stretched, exSlow));
}

// Phong factors (FrameContext::shade) of one vector of splats, lanes [i, n) of the batch: n.l is
// the same over a splat, the specular term is taken at the centre and at the Gouraud corners
// c +- R B0 +- R B1 (b0, b1), the corners only where some splat of the vector needs them.
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>, class VI = hn::Vec<hn::RebindToSigned<DF>>>
HWY_INLINE void PointPhong(DF d, const PointSetupFrame& F, PointSetupBatch& B, int i, int n, VF lx, VF ly, VF lz, VF cx,
                           VF cy, VF cz, VF b0x, VF b0y, VF b0z, VF b1x, VF b1y, VF b1z, VI ix0, VI ix1, VI iy0,
                           VI iy1, MF culled, MF slow, MF empty) {
  const hn::RebindToSigned<DF> di;
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  auto S = [&](float v) { return hn::Set(d, v); };
  auto dot3 = [&](VF ax, VF ay, VF az, VF bx, VF by, VF bz) { return hn::MulAdd(ax, bx, hn::MulAdd(ay, by, hn::Mul(az, bz))); };
  const VF ndl = hn::Max(zero, dot3(lx, ly, lz, S(F.lightDir[0]), S(F.lightDir[1]), S(F.lightDir[2])));
  hn::StoreU(hn::MulAdd(S(F.diffuse), ndl, S(F.ambient)), d, B.diffuseFactor + i);
  const float sgn[5][2] = {{0, 0}, {-1, -1}, {1, -1}, {-1, 1}, {1, 1}};
  // the corners only matter for Gouraud splats, wider or taller than kFlatShadeSpan pixels;
  // bounds of extent x1 - x0 <= kFlatShadeSpan - 1 hold at most kFlatShadeSpan pixel centres
  const VI span = hn::Set(di, PreparedPoint::kFlatShadeSpan);
  const auto flat = hn::RebindMask(d, hn::Not(hn::Or(hn::Gt(hn::Sub(ix1, ix0), span), hn::Gt(hn::Sub(iy1, iy0), span))));
  const auto needed = hn::AndNot(hn::Or(hn::Or(flat, culled), hn::Or(slow, empty)), hn::FirstN(d, size_t(n - i)));
  const int corners = hn::AllFalse(d, needed) ? 1 : 5;
  for (int k = 0; k < corners; ++k) {
    VF spec = zero;
    if (F.specular > 0) {
      const VF ss = S(sgn[k][0]), tt = S(sgn[k][1]);
      const VF qx = hn::MulAdd(tt, b1x, hn::MulAdd(ss, b0x, cx)), qy = hn::MulAdd(tt, b1y, hn::MulAdd(ss, b0y, cy)),
               qz = hn::MulAdd(tt, b1z, hn::MulAdd(ss, b0z, cz));
      const VF qn2 = dot3(qx, qy, qz, qx, qy, qz);
      const VF iq = hn::Neg(hn::Div(one, hn::Sqrt(qn2)));  // view vector -q / |q|
      const VF hx3 = hn::MulAdd(qx, iq, S(F.lightDir[0])), hy3 = hn::MulAdd(qy, iq, S(F.lightDir[1])),
               hz3 = hn::MulAdd(qz, iq, S(F.lightDir[2]));
      const VF hn2 = dot3(hx3, hy3, hz3, hx3, hy3, hz3);
      const VF ndh = hn::Min(one, hn::Max(zero, hn::Div(dot3(lx, ly, lz, hx3, hy3, hz3), hn::Sqrt(hn2))));
      const VF pw = hn::Exp(d, hn::Mul(S(F.shininess), hn::Log(d, hn::Max(ndh, S(1e-30f)))));
      spec = hn::IfThenElseZero(hn::And(hn::And(hn::Gt(ndl, zero), hn::Gt(hn2, zero)), hn::Gt(qn2, zero)),
                                hn::Mul(S(F.specular), pw));
    }
    hn::StoreU(spec, d, B.specular[k] + i);
  }
}

// The screen bounds of the common case's splats in closed form: the conic S^2 + T^2 <= cutoffQ N^2
// about the projected centre c (where S = T = 0 and N = nc / d, d the centre's depth) as
// detail::conicBounds computes it, in float: centre (bx, by) and half-extents (ex, ey) with its
// slack. Lanes whose conic is not a bounded ellipse join cfSlow.
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>>
HWY_INLINE void PointConicBounds(DF d, const PointSetupFrame& F, VF f, VF cx, VF cy, VF dd, VF nc, VF Nx, VF Ny, VF Sx,
                                 VF Sy, VF Tx, VF Ty, MF& cfSlow, VF& bx, VF& by, VF& ex, VF& ey) {
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  auto S = [&](float v) { return hn::Set(d, v); };
  // closed form: conic bounds about the projected centre, where S = T = 0 and N = nc / d
  const VF id = hn::Div(one, dd);
  const VF pcx = hn::MulAdd(hn::Mul(f, cx), id, S(F.cx)), pcy = hn::NegMulAdd(hn::Mul(f, cy), id, S(F.cy));
  const VF Nc = hn::Mul(nc, id), cq = S(F.cutoffQ);
  const VF A00 = hn::Sub(hn::MulAdd(Sx, Sx, hn::Mul(Tx, Tx)), hn::Mul(cq, hn::Mul(Nx, Nx)));
  const VF A01 = hn::Sub(hn::MulAdd(Sx, Sy, hn::Mul(Tx, Ty)), hn::Mul(cq, hn::Mul(Nx, Ny)));
  const VF A11 = hn::Sub(hn::MulAdd(Sy, Sy, hn::Mul(Ty, Ty)), hn::Mul(cq, hn::Mul(Ny, Ny)));
  const VF b0 = hn::Neg(hn::Mul(cq, hn::Mul(Nx, Nc))), b1 = hn::Neg(hn::Mul(cq, hn::Mul(Ny, Nc)));
  const VF m = hn::Neg(hn::Mul(cq, hn::Mul(Nc, Nc)));
  const VF det = hn::MulSub(A00, A11, hn::Mul(A01, A01));
  cfSlow = hn::Or(cfSlow, hn::Not(hn::And(hn::Gt(A00, zero), hn::Gt(det, zero))));
  const VF idt = hn::Div(one, det);
  const VF ox = hn::Mul(hn::MulSub(A01, b1, hn::Mul(A11, b0)), idt), oy = hn::Mul(hn::MulSub(A01, b0, hn::Mul(A00, b1)), idt);
  const VF kk = hn::Neg(hn::MulAdd(b0, ox, hn::MulAdd(b1, oy, m)));
  cfSlow = hn::Or(cfSlow, hn::Not(hn::Gt(kk, zero)));
  const VF hx = hn::Sqrt(hn::Mul(hn::Mul(kk, A11), idt)), hy = hn::Sqrt(hn::Mul(hn::Mul(kk, A00), idt));
  const VF slack = hn::MulAdd(S(1e-4f), hn::Add(hx, hy), S(0.01f));
  bx = hn::Add(pcx, ox), by = hn::Add(pcy, oy), ex = hn::Add(hx, slack), ey = hn::Add(hy, slack);
}

// The pixel bounds of splats whose screen bounds are [x0, x1] x [y0, y1] (pixel centres inside,
// within the viewport) to the batch's lanes [i, i + lanes), as detail::pixelBounds computes them;
// cut: the viewport clamped them; empty: no pixel.
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>, class VI = hn::Vec<hn::RebindToSigned<DF>>>
HWY_INLINE void PointPixelBounds(DF d, const PointSetupFrame& F, PointSetupBatch& B, int i, VF x0, VF x1, VF y0, VF y1,
                                 VI& ix0, VI& ix1, VI& iy0, VI& iy1, MF& cut, MF& empty) {
  const hn::RebindToSigned<DF> di;
  auto S = [&](float v) { return hn::Set(d, v); };
  // pixel bounds as detail::pixelBounds computes them (in float: the same integers while the
  // bounds lie within 2^22 pixels of the view; beyond, both are cut to the view)
  const VF lim = S(1e7f), half = S(0.5f);
  auto lo = [&](VF v) { return hn::ConvertTo(di, hn::Ceil(hn::Sub(hn::Min(hn::Max(v, hn::Neg(lim)), lim), half))); };
  auto hi = [&](VF v) { return hn::Add(hn::ConvertTo(di, hn::Floor(hn::Sub(hn::Min(hn::Max(v, hn::Neg(lim)), lim), half))), hn::Set(di, 1)); };
  const VI bx0 = lo(x0), by0 = lo(y0), bx1 = hi(x1), by1 = hi(y1);
  ix0 = hn::Max(bx0, hn::Zero(di)), iy0 = hn::Max(by0, hn::Zero(di));
  ix1 = hn::Min(bx1, hn::Set(di, F.width)), iy1 = hn::Min(by1, hn::Set(di, F.height));
  hn::StoreU(ix0, di, B.x0 + i), hn::StoreU(ix1, di, B.x1 + i), hn::StoreU(iy0, di, B.y0 + i), hn::StoreU(iy1, di, B.y1 + i);
  cut = hn::RebindMask(d, hn::Not(hn::And(hn::And(hn::Eq(ix0, bx0), hn::Eq(iy0, by0)), hn::And(hn::Eq(ix1, bx1), hn::Eq(iy1, by1)))));
  empty = hn::RebindMask(d, hn::Not(hn::And(hn::Gt(ix1, ix0), hn::Gt(iy1, iy0))));
}

// The tail form of the splats' own discs (PointCold::disc; tail layers, splat_rules.h kTailDisc):
// |s B0 + t B1|^2 / (kTailDisc R sigma)^2 with b = R B, to the batch's lanes [i, i + lanes).
template <class DF, class VF = hn::Vec<DF>>
HWY_INLINE void PointTailForm(DF d, PointSetupBatch& B, int i, VF R, VF s2, VF b0x, VF b0y, VF b0z, VF b1x, VF b1y,
                              VF b1z) {
  auto S = [&](float v) { return hn::Set(d, v); };
  auto dot3 = [&](VF ax, VF ay, VF az, VF bx, VF by, VF bz) { return hn::MulAdd(ax, bx, hn::MulAdd(ay, by, hn::Mul(az, bz))); };
  const VF k = hn::Div(S(1.0f / (kTailDisc * kTailDisc)), hn::Mul(hn::Mul(hn::Mul(R, R), hn::Mul(R, R)), s2));
  hn::StoreU(hn::Mul(k, dot3(b0x, b0y, b0z, b0x, b0y, b0z)), d, B.disc0 + i);
  hn::StoreU(hn::Mul(hn::Add(k, k), dot3(b0x, b0y, b0z, b1x, b1y, b1z)), d, B.disc1 + i);
  hn::StoreU(hn::Mul(k, dot3(b1x, b1y, b1z, b1x, b1y, b1z)), d, B.disc2 + i);
}

void PointSetup(const PointSetupFrame& F, PointSetupBatch& B, int n) {
  using DF = hn::ScalableTag<float>;
  using VF = hn::Vec<DF>;
  using VI = hn::Vec<hn::RebindToSigned<DF>>;
  const DF d;
  const int L = int(hn::Lanes(d));
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f), two = hn::Set(d, 2.0f);
  auto S = [&](float v) { return hn::Set(d, v); };
  const VF f = S(F.f);
  for (int i = 0; i < n; i += L) {
    const VF px = hn::LoadU(d, B.px + i), py = hn::LoadU(d, B.py + i), pz = hn::LoadU(d, B.pz + i);
    const VF wx = hn::LoadU(d, B.nx + i), wy = hn::LoadU(d, B.ny + i), wz = hn::LoadU(d, B.nz + i);
    const VF rad = hn::LoadU(d, B.radius + i);
    auto mat = [&](VF a, VF b, VF c, int row) {
      return hn::MulAdd(S(F.rot[3 * row]), a, hn::MulAdd(S(F.rot[3 * row + 1]), b, hn::Mul(S(F.rot[3 * row + 2]), c)));
    };
    // model-view transform; back-face culling before anything else
    const VF cx = hn::Add(mat(px, py, pz, 0), S(F.trans[0])), cy = hn::Add(mat(px, py, pz, 1), S(F.trans[1])),
             cz = hn::Add(mat(px, py, pz, 2), S(F.trans[2]));
    VF nx = mat(wx, wy, wz, 0), ny = mat(wx, wy, wz, 1), nz = mat(wx, wy, wz, 2);
    const VF nn2 = hn::MulAdd(nx, nx, hn::MulAdd(ny, ny, hn::Mul(nz, nz)));
    const VF nDotEye = hn::Neg(hn::MulAdd(nx, cx, hn::MulAdd(ny, cy, hn::Mul(nz, cz))));
    auto culled = hn::And(hn::Gt(nn2, zero), hn::Lt(nDotEye, zero));
    if (!F.backfaceCulling) culled = hn::Lt(one, zero);  // never
    // degenerate or unusual input (non-finite, radius <= 0, no normal): the scalar path decides
    const VF inf = S(INFINITY);
    auto bad = hn::Not(hn::And(hn::Gt(rad, zero), hn::Lt(rad, inf)));
    for (VF v : {px, py, pz, wx, wy, wz}) bad = hn::Or(bad, hn::Not(hn::Lt(hn::Abs(v), inf)));
    bad = hn::Or(bad, hn::Not(hn::Gt(nn2, zero)));
    auto slow = bad;
    const VF cn2 = hn::MulAdd(cx, cx, hn::MulAdd(cy, cy, hn::Mul(cz, cz)));
    const VF invN = hn::Div(one, hn::Sqrt(nn2)), invC = hn::Div(one, hn::Sqrt(cn2));
    nx = hn::Mul(nx, invN), ny = hn::Mul(ny, invN), nz = hn::Mul(nz, invN);
    VF facing = hn::Mul(hn::Mul(nDotEye, invN), invC);
    const auto flip = hn::Lt(facing, zero);  // two-sided: lit from the viewer's side
    nx = hn::IfThenElse(flip, hn::Neg(nx), nx), ny = hn::IfThenElse(flip, hn::Neg(ny), ny),
    nz = hn::IfThenElse(flip, hn::Neg(nz), nz);
    facing = hn::Abs(facing);
    slow = hn::Or(slow, hn::Not(hn::Ge(facing, S(kMinFacing))));
    // the lighting normal: the plane's, or the point's shading normal flipped with the plane (smooth contour models)
    VF lx = nx, ly = ny, lz = nz;
    if (F.shadingNormals) {
      const VF sx = hn::LoadU(d, B.snx + i), sy = hn::LoadU(d, B.sny + i), sz = hn::LoadU(d, B.snz + i);
      const VF mx = mat(sx, sy, sz, 0), my = mat(sx, sy, sz, 1), mz = mat(sx, sy, sz, 2);
      const VF m2 = hn::MulAdd(mx, mx, hn::MulAdd(my, my, hn::Mul(mz, mz)));
      const auto ok = hn::And(hn::Gt(m2, zero), hn::Lt(m2, inf));
      const VF im = hn::Div(one, hn::Sqrt(m2)), sg = hn::IfThenElse(flip, hn::Neg(im), im);
      lx = hn::IfThenElse(ok, hn::Mul(mx, sg), nx), ly = hn::IfThenElse(ok, hn::Mul(my, sg), ny),
      lz = hn::IfThenElse(ok, hn::Mul(mz, sg), nz);
    }
    const VF dd = hn::Neg(cz);
    slow = hn::Or(slow, hn::Not(hn::Gt(dd, zero)));
    // tangent frame u = normalize(X x n) (or Y x n), v = n x u
    const auto useX = hn::Lt(hn::Abs(nx), S(0.9f));
    VF ux = hn::IfThenElse(useX, zero, nz), uy = hn::IfThenElse(useX, hn::Neg(nz), zero),
       uz = hn::IfThenElse(useX, ny, hn::Neg(nx));
    const VF invU = hn::Div(one, hn::Sqrt(hn::MulAdd(ux, ux, hn::MulAdd(uy, uy, hn::Mul(uz, uz)))));
    ux = hn::Mul(ux, invU), uy = hn::Mul(uy, invU), uz = hn::Mul(uz, invU);
    const VF vx = hn::MulSub(ny, uz, hn::Mul(nz, uy)), vy = hn::MulSub(nz, ux, hn::Mul(nx, uz)),
             vz = hn::MulSub(nx, uy, hn::Mul(ny, ux));
    // warping: V = sigma_r^2 I + V_h (J^T J)^-1
    const VF sigma = hn::Mul(S(F.reconstructionScale), rad), s2 = hn::Mul(sigma, sigma);
    VF a = s2, b = zero, c = s2;
    if (F.prefilter > 0) {
      const VF id = hn::Div(one, dd), fd = hn::Mul(f, id);
      const VF gxz = hn::Mul(hn::Mul(fd, cx), id), gyz = hn::Neg(hn::Mul(hn::Mul(fd, cy), id));
      const VF j00 = hn::MulAdd(fd, ux, hn::Mul(gxz, uz)), j01 = hn::MulAdd(fd, vx, hn::Mul(gxz, vz));
      const VF j10 = hn::MulSub(gyz, uz, hn::Mul(fd, uy)), j11 = hn::MulSub(gyz, vz, hn::Mul(fd, vy));
      const VF p = hn::MulAdd(j00, j00, hn::Mul(j10, j10)), q = hn::MulAdd(j00, j01, hn::Mul(j10, j11)),
               r = hn::MulAdd(j01, j01, hn::Mul(j11, j11));
      const VF det = hn::MulSub(p, r, hn::Mul(q, q));
      slow = hn::Or(slow, hn::Not(hn::Gt(det, zero)));
      const VF k = hn::Div(S(F.prefilter), det);
      a = hn::MulAdd(k, r, a), b = hn::Neg(hn::Mul(k, q)), c = hn::MulAdd(k, p, c);
    }
    const VF mean = hn::Mul(S(0.5f), hn::Add(a, c)), diff = hn::Mul(S(0.5f), hn::Sub(a, c));
    const VF maxS = hn::Mul(S(kMaxStretch), sigma);
    const VF eig = hn::Sqrt(hn::MulAdd(diff, diff, hn::Mul(b, b)));  // eigenvalues mean +- eig
    // stretched past kMaxStretch: the thesis's construction (the exact path of preparePoint)
    const auto stretched = hn::Not(hn::Le(hn::Add(mean, eig), hn::Mul(maxS, maxS)));
    const VF R = S(F.cutoff);
    // closed form (common case): V^-1 = L L^T; its own limits in cfSlow
    const VF detV = hn::MulSub(a, c, hn::Mul(b, b));
    auto cfSlow = hn::Not(hn::Gt(detV, zero));
    const VF idet = hn::Div(one, detV);
    const VF l00 = hn::Sqrt(hn::Mul(c, idet)), l10 = hn::Div(hn::Neg(hn::Mul(b, idet)), l00);
    const VF l11 = hn::Sqrt(hn::Max(zero, hn::NegMulAdd(l10, l10, hn::Mul(a, idet))));
    cfSlow = hn::Or(cfSlow, hn::Not(hn::Gt(l11, zero)));
    VF a0x = hn::MulAdd(l00, ux, hn::Mul(l10, vx)), a0y = hn::MulAdd(l00, uy, hn::Mul(l10, vy)),
       a0z = hn::MulAdd(l00, uz, hn::Mul(l10, vz));
    VF a1x = hn::Mul(l11, vx), a1y = hn::Mul(l11, vy), a1z = hn::Mul(l11, vz);
    VF wscale = hn::Div(one, hn::Sqrt(detV));
    VF ext = hn::Mul(R, hn::Sqrt(hn::Max(zero, hn::MulAdd(a, hn::Mul(uz, uz), hn::MulAdd(hn::Mul(two, b), hn::Mul(uz, vz), hn::Mul(c, hn::Mul(vz, vz)))))));
    cfSlow = hn::Or(cfSlow, hn::Not(hn::And(hn::Ge(hn::Sub(dd, ext), S(F.nearD)), hn::Le(hn::Add(dd, ext), S(F.farD)))));
    // R B0, R B1 (B0, B1: plane vectors of unit plane coordinates; Gouraud corners c +- R B0 +- R B1)
    // closed form: B0 = u / l00, B1 = (v - (l10 / l00) u) / l11
    VF b0x, b0y, b0z, b1x, b1y, b1z;
    {
      const VF il00 = hn::Div(one, l00), il11 = hn::Div(one, l11), r = hn::Mul(l10, il00);
      b0x = hn::Mul(hn::Mul(ux, il00), R), b0y = hn::Mul(hn::Mul(uy, il00), R), b0z = hn::Mul(hn::Mul(uz, il00), R);
      b1x = hn::Mul(hn::Mul(hn::NegMulAdd(r, ux, vx), il11), R), b1y = hn::Mul(hn::Mul(hn::NegMulAdd(r, uy, vy), il11), R),
      b1z = hn::Mul(hn::Mul(hn::NegMulAdd(r, uz, vz), il11), R);
    }
    // exact path for the splats stretched past kMaxStretch (PointStretched)
    const auto exactLanes = hn::AndNot(slow, stretched);
    VF qx0 = zero, qx1 = zero, qy0 = zero, qy1 = zero;
    if (!hn::AllFalse(d, exactLanes)) {
      PointStretched(d, F, ux, uy, uz, vx, vy, vz, nx, ny, nz, cx, cy, cz, a, b, c, mean, eig, maxS, R, f, stretched, a0x,
                     a0y, a0z, a1x, a1y, a1z, wscale, ext, b0x, b0y, b0z, b1x, b1y, b1z, slow, qx0, qx1, qy0, qy1);
    } else {
      slow = hn::Or(slow, stretched);
    }
    // ray/plane constants: k.r(px, py) = k.x/f px - k.y/f py + (-k.x cx/f + k.y cy/f - k.z)
    const VF invf = S(1.0f / F.f);
    auto rayDx = [&](VF kx) { return hn::Mul(kx, invf); };
    auto rayDy = [&](VF ky) { return hn::Neg(hn::Mul(ky, invf)); };
    auto rayC = [&](VF kx, VF ky, VF kz) {
      return hn::Sub(hn::Mul(invf, hn::MulSub(ky, S(F.cy), hn::Mul(kx, S(F.cx)))), kz);
    };
    auto dot3 = [&](VF ax, VF ay, VF az, VF bx, VF by, VF bz) { return hn::MulAdd(ax, bx, hn::MulAdd(ay, by, hn::Mul(az, bz))); };
    const VF nc = dot3(nx, ny, nz, cx, cy, cz), a0c = dot3(a0x, a0y, a0z, cx, cy, cz), a1c = dot3(a1x, a1y, a1z, cx, cy, cz);
    const VF Nx = rayDx(nx), Ny = rayDy(ny), N0 = rayC(nx, ny, nz);
    const VF Sx = hn::MulSub(nc, rayDx(a0x), hn::Mul(a0c, Nx)), Sy = hn::MulSub(nc, rayDy(a0y), hn::Mul(a0c, Ny)),
             S0 = hn::MulSub(nc, rayC(a0x, a0y, a0z), hn::Mul(a0c, N0));
    const VF Tx = hn::MulSub(nc, rayDx(a1x), hn::Mul(a1c, Nx)), Ty = hn::MulSub(nc, rayDy(a1y), hn::Mul(a1c, Ny)),
             T0 = hn::MulSub(nc, rayC(a1x, a1y, a1z), hn::Mul(a1c, N0));
    // closed form: the conic bounds (PointConicBounds)
    VF bx, by, ex, ey;
    PointConicBounds(d, F, f, cx, cy, dd, nc, Nx, Ny, Sx, Sy, Tx, Ty, cfSlow, bx, by, ex, ey);
    slow = hn::Or(slow, hn::AndNot(stretched, cfSlow));
    const VF x0 = hn::IfThenElse(stretched, qx0, hn::Sub(bx, ex)), x1 = hn::IfThenElse(stretched, qx1, hn::Add(bx, ex));
    const VF y0 = hn::IfThenElse(stretched, qy0, hn::Sub(by, ey)), y1 = hn::IfThenElse(stretched, qy1, hn::Add(by, ey));
    VI ix0, ix1, iy0, iy1;
    hn::Mask<DF> cut, empty;
    PointPixelBounds(d, F, B, i, x0, x1, y0, y1, ix0, ix1, iy0, iy1, cut, empty);
    if (F.light)
      PointPhong(d, F, B, i, n, lx, ly, lz, cx, cy, cz, b0x, b0y, b0z, b1x, b1y, b1z, ix0, ix1, iy0, iy1, culled, slow,
                 empty);
    const VF status = hn::IfThenElse(empty, S(4.0f), hn::IfThenElseZero(cut, S(3.0f)));
    hn::StoreU(hn::IfThenElse(bad, S(2.0f), hn::IfThenElse(culled, one, hn::IfThenElse(slow, S(2.0f), status))), d, B.status + i);
    hn::StoreU(Nx, d, B.Nx + i), hn::StoreU(Ny, d, B.Ny + i), hn::StoreU(N0, d, B.N0 + i);
    hn::StoreU(Sx, d, B.Sx + i), hn::StoreU(Sy, d, B.Sy + i), hn::StoreU(S0, d, B.S0 + i);
    hn::StoreU(Tx, d, B.Tx + i), hn::StoreU(Ty, d, B.Ty + i), hn::StoreU(T0, d, B.T0 + i);
    hn::StoreU(nc, d, B.depthNum + i), hn::StoreU(wscale, d, B.weightScale + i), hn::StoreU(ext, d, B.depthExtent + i);
    PointTailForm(d, B, i, R, s2, b0x, b0y, b0z, b1x, b1y, b1z);
    hn::StoreU(lx, d, B.onx + i), hn::StoreU(ly, d, B.ony + i), hn::StoreU(lz, d, B.onz + i);
  }
}

// preparePoints' first step for the whole vectors among points[0 .. count): the early back-face
// test (clearlyBackFacing below, the same expressions) and the AoS -> SoA copy of the points it
// keeps into B (lane = their place), packed. Returns how many points it looked at (a multiple
// of the vector length); `kept` gets how many it kept.
int PointGather(const PointSetupFrame& F, const Point* points, int count, int pos, int nrm, int rad,
                PointSetupBatch& B, int& kept) {
  using DF = hn::ScalableTag<float>;
  using VF = hn::Vec<DF>;
  const DF d;
  const hn::RebindToSigned<DF> di;
  const int L = int(hn::Lanes(d));
  const float* base = reinterpret_cast<const float*>(points);
  constexpr int kStride = int(sizeof(Point) / sizeof(float));
  const auto iota = hn::Mul(hn::Iota(di, 0), hn::Set(di, kStride));
  const VF zero = hn::Zero(d), inf = hn::Set(d, INFINITY);
  const VF ex = hn::Set(d, F.eye[0]), ey = hn::Set(d, F.eye[1]), ez = hn::Set(d, F.eye[2]);
  const VF eye2 = hn::Set(d, F.eye[0] * F.eye[0] + F.eye[1] * F.eye[1] + F.eye[2] * F.eye[2]);
  int m = 0, j = 0;
  for (; j + L <= count; j += L) {
    // the next batch's points, a batch of work ahead (a hint: an address past the model is harmless)
    for (int k = 0; k < L; ++k)
      __builtin_prefetch(reinterpret_cast<const void*>(reinterpret_cast<uintptr_t>(points + j + k) + kSetupBatch * sizeof(Point)));
    const float* at = base + size_t(j) * kStride;
    auto g = [&](int field) { return hn::GatherIndex(d, at + field, iota); };
    const VF px = g(pos), py = g(pos + 1), pz = g(pos + 2), nx = g(nrm), ny = g(nrm + 1), nz = g(nrm + 2), r = g(rad);
    auto keep = hn::FirstN(d, size_t(L));
    if (F.backfaceCulling) {
      const VF dx = hn::Sub(px, ex), dy = hn::Sub(py, ey), dz = hn::Sub(pz, ez);
      const VF w = hn::Add(hn::Add(hn::Mul(nx, dx), hn::Mul(ny, dy)), hn::Mul(nz, dz));
      const VF nn2 = hn::Add(hn::Add(hn::Mul(nx, nx), hn::Mul(ny, ny)), hn::Mul(nz, nz));
      const VF d2 = hn::Add(hn::Add(hn::Mul(dx, dx), hn::Mul(dy, dy)), hn::Mul(dz, dz));
      const VF p2 = hn::Add(hn::Add(hn::Mul(px, px), hn::Mul(py, py)), hn::Mul(pz, pz));
      const VF scale2 = hn::Add(hn::Add(d2, p2), eye2), w2 = hn::Mul(w, w);
      auto back = hn::And(hn::Gt(w, zero), hn::Gt(w2, hn::Mul(hn::Mul(hn::Set(d, 3e-8f), nn2), scale2)));
      back = hn::And(back, hn::And(hn::Lt(w2, inf), hn::And(hn::Lt(nn2, inf), hn::Lt(scale2, inf))));
      back = hn::And(back, hn::And(hn::Gt(r, zero), hn::Lt(r, inf)));
      keep = hn::Not(back);
    }
    hn::StoreU(hn::Compress(hn::Add(hn::Iota(di, 0), hn::Set(di, j)), hn::RebindMask(di, keep)), di, B.lane + m);
    hn::StoreU(hn::Compress(px, keep), d, B.px + m), hn::StoreU(hn::Compress(py, keep), d, B.py + m);
    hn::StoreU(hn::Compress(pz, keep), d, B.pz + m), hn::StoreU(hn::Compress(nx, keep), d, B.nx + m);
    hn::StoreU(hn::Compress(ny, keep), d, B.ny + m), hn::StoreU(hn::Compress(nz, keep), d, B.nz + m);
    hn::StoreU(hn::Compress(r, keep), d, B.radius + m);
    m += int(hn::CountTrue(d, keep));
  }
  kept = m;
  return j;
}

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(PointSetup);
HWY_EXPORT(PointGather);
void pointSetup(const PointSetupFrame& frame, PointSetupBatch& batch, int n) {
  HWY_DYNAMIC_DISPATCH(PointSetup)(frame, batch, n);
}
static int pointGather(const PointSetupFrame& frame, const Point* points, int count, int pos, int nrm, int rad,
                       PointSetupBatch& batch, int& kept) {
  return HWY_DYNAMIC_DISPATCH(PointGather)(frame, points, count, pos, nrm, rad, batch, kept);
}
}  // namespace linesurf::detail

namespace linesurf {

detail::PointSetupFrame pointSetupFrame(const FrameContext& frame) {
  const Camera& cam = frame.cam();
  const RenderOptions& opt = frame.opt();
  detail::PointSetupFrame f;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) f.rot[3 * r + c] = cam.rotation()(r, c);
    f.trans[r] = cam.cameraFromWorld()(r, 3);
  }
  for (int c = 0; c < 3; ++c) {  // eye = -R^T t
    double e = 0;
    for (int r = 0; r < 3; ++r) e -= double(cam.rotation()(r, c)) * double(cam.cameraFromWorld()(r, 3));
    f.eye[c] = float(e);
  }
  f.f = cam.focalPixels();
  f.cx = cam.principalPoint().x(), f.cy = cam.principalPoint().y();
  f.nearD = cam.nearDepth(), f.farD = cam.farDepth();
  f.width = cam.width(), f.height = cam.height();
  f.prefilter = opt.prefilterVariance;
  f.reconstructionScale = opt.reconstructionScale;
  f.cutoff = opt.cutoffRadius;
  f.cutoffQ = frame.cutoffQ;
  f.backfaceCulling = opt.backfaceCulling;
  f.light = !opt.perPixelLighting;
  for (int k = 0; k < 3; ++k) f.lightDir[k] = frame.lightDirCamera[k];
  f.ambient = opt.material.ambient, f.diffuse = opt.material.diffuse, f.specular = opt.material.specular;
  f.shininess = opt.material.shininess;
  f.shadingNormals = frame.pointShadingNormals != nullptr;
  return f;
}

namespace {

// Early back-face test in world space: n.(p - eye) > 0 is the camera-space test -n'.c < 0 of
// pointSetup and preparePoint. Only points back-facing by a clear margin are taken (relative
// 1e-4 of |n| (|p - eye| + |p| + |eye|), far above the rounding of either test), and only with
// valid input, so that a point culled here is one the exact test culls too.
bool clearlyBackFacing(const detail::PointSetupFrame& F, const Point& p) {
  const float dx = p.position.x() - F.eye[0], dy = p.position.y() - F.eye[1], dz = p.position.z() - F.eye[2];
  const float w = p.normal.x() * dx + p.normal.y() * dy + p.normal.z() * dz;
  const float nn2 = p.normal.squaredNorm(), d2 = dx * dx + dy * dy + dz * dz;
  const float scale2 = d2 + p.position.squaredNorm() + (F.eye[0] * F.eye[0] + F.eye[1] * F.eye[1] + F.eye[2] * F.eye[2]);
  // bitwise, not short-circuit: no branch to mispredict on a coin-flip test
  return (w > 0) & (w * w > 3e-8f * nn2 * scale2) & (w * w < INFINITY) & (nn2 < INFINITY) & (scale2 < INFINITY) &
         (p.radius > 0) & (p.radius < INFINITY);
}

// how many output slots ahead preparePoints fetches the slot it will write
constexpr int kWriteAhead = 6;

}  // namespace

int preparePoints(const Point* points, uint32_t first, int count, const FrameContext& frame,
                  const detail::PointSetupFrame& setup, const PointSlots& out, PointSetupCounts& counts) {
  const RenderOptions& opt = frame.opt();
  detail::PointSetupBatch b;
  static_assert(sizeof(Point) % sizeof(float) == 0 && alignof(Point) >= alignof(float));
  // the fields' places in a Point, in floats (the SIMD gather's offsets)
  const Point& p0 = points[first];
  auto field = [&](const float* f) { return int(f - reinterpret_cast<const float*>(&p0)); };
  int m = 0;
  const int j0 = detail::pointGather(setup, points + first, count, field(p0.position.data()), field(p0.normal.data()),
                                     field(&p0.radius), b, m);
  for (int j = j0; j < count; ++j) {  // the rest (past the whole vectors): early culling; AoS -> SoA
    const Point& p = points[first + uint32_t(j)];
    // the next batch's point, a batch of work ahead (a hint: an address past the model is harmless)
    __builtin_prefetch(reinterpret_cast<const void*>(reinterpret_cast<uintptr_t>(&p) + detail::kSetupBatch * sizeof(Point)));
    b.lane[m] = j;
    b.px[m] = p.position.x(), b.py[m] = p.position.y(), b.pz[m] = p.position.z();
    b.nx[m] = p.normal.x(), b.ny[m] = p.normal.y(), b.nz[m] = p.normal.z();
    b.radius[m] = p.radius;
    m += !(setup.backfaceCulling & clearlyBackFacing(setup, p));
  }
  counts.culled += uint32_t(count - m);
  if (setup.shadingNormals) {  // the kept points' shading normals (smooth contour models)
    for (int j = 0; j < m; ++j) {
      const Vec3f& sn = frame.pointShadingNormals[first + uint32_t(b.lane[j])];
      b.snx[j] = sn.x(), b.sny[j] = sn.y(), b.snz[j] = sn.z();
    }
  }
  for (int j = m; j < std::min(detail::kSetupBatch, (m + detail::kMaxLanes - 1) / detail::kMaxLanes * detail::kMaxLanes); ++j) {
    // the last vector's spare lanes: defined values (radius 0 marks them degenerate), not stale ones
    b.px[j] = b.py[j] = b.pz[j] = b.nx[j] = b.ny[j] = b.nz[j] = b.radius[j] = 0;
    b.snx[j] = b.sny[j] = b.snz[j] = 0;
  }
  detail::pointSetup(setup, b, m);
  int k = 0;
  for (int j = 0; j < m; ++j) {
    // the hot record a few points ahead (one cache line; written, not read): its line is fetched
    // meanwhile (a hint: an address past the storage is harmless)
    __builtin_prefetch(out.hot + k + kWriteAhead, 1);
    const uint32_t index = first + uint32_t(b.lane[j]);
    const Point& point = points[index];
    if (b.status[j] == 1.0f) {
      ++counts.culled;
      continue;
    }
    PrimitiveStatus status;
    if (b.status[j] == 2.0f) {  // the exact path
      status = preparePoint(point, index, frame, out + k);
    } else if (b.status[j] == 4.0f) {
      ++counts.outside;
      continue;
    } else {
      const bool cut = b.status[j] == 3.0f;
      PreparedPoint& o = *new (out.hot + k) PreparedPoint;
      const PixelRect bounds{b.x0[j], b.y0[j], b.x1[j], b.y1[j]};
      out.bounds[k] = bounds;
      PointCold& cold = *new (out.cold + k) PointCold;
      cold.index = index;
      cold.normal[0] = b.onx[j], cold.normal[1] = b.ony[j], cold.normal[2] = b.onz[j];
      cold.disc[0] = b.disc0[j], cold.disc[1] = b.disc1[j], cold.disc[2] = b.disc2[j];
      o.N = {b.Nx[j], b.Ny[j], b.N0[j]};
      o.S = {b.Sx[j], b.Sy[j], b.S0[j]};
      o.T = {b.Tx[j], b.Ty[j], b.T0[j]};
      o.depthNum = b.depthNum[j];
      o.weightScaleSigned = b.weightScale[j];  // no depth clipping here
      if (frame.pointMasses) o.weightScaleSigned *= frame.pointMasses[index];
      o.zThreshold = frame.zThreshold(b.depthExtent[j] + point.radius);
      const Color col = frame.primitiveColor(point.color);
      Vec3f c = col.head<3>();
      if (!opt.perPixelLighting) {  // Phong, as preparePoint's light() does: flat at the centre or Gouraud
        const Vec3f& lc = opt.light.color;
        const Vec3f base = c * b.diffuseFactor[j];
        if (!PreparedPoint::gouraud(bounds, false)) {
          c = (base + Vec3f::Constant(b.specular[0][j])).cwiseProduct(lc);
        } else {
          const float s00 = b.specular[1][j], s10 = b.specular[2][j], s01 = b.specular[3][j], s11 = b.specular[4][j];
          const float inv2R = 0.5f / opt.cutoffRadius;
          PointGouraud& g = *new (out.gouraud + k) PointGouraud;
          g.C0 = (base + Vec3f::Constant(0.25f * (s00 + s10 + s01 + s11))).cwiseProduct(lc);
          g.Cs = (0.5f * inv2R * (s10 - s00 + s11 - s01)) * lc;
          g.Ct = (0.5f * inv2R * (s01 - s00 + s11 - s10)) * lc;
          g.Cst = (inv2R * inv2R * (s00 - s10 - s01 + s11)) * lc;
        }
      }
      // element by element: a local array copied out costs a store-forwarding stall per point
      static_assert(Z3Tile::kAttrs == 8);
      o.color[0] = c.x(), o.color[1] = c.y(), o.color[2] = c.z(), o.color[3] = std::clamp(col.w(), 0.0f, 1.0f);
      status = cut ? PrimitiveStatus::Clipped : PrimitiveStatus::Drawn;
    }
    switch (status) {
      case PrimitiveStatus::Drawn: ++counts.drawn, ++k; break;
      case PrimitiveStatus::Clipped: ++counts.clipped, ++k; break;
      case PrimitiveStatus::Culled: ++counts.culled; break;
      case PrimitiveStatus::Outside: ++counts.outside; break;
      case PrimitiveStatus::Degenerate: ++counts.degenerate; break;
    }
  }
  return k;
}

}  // namespace linesurf
#endif
