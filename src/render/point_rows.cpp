// The SIMD rows of object-space EWA point splats (thesis §4.2.2; point_rows.h): a splat's kernel
// per pixel through its tangent plane, straight into the Z^3 tile. Compiled once per x86 target
// (Google Highway); the best one the CPU runs is picked at run time.
#include "point_rows.h"

#include <algorithm>
#include <cmath>

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/point_rows.cpp"
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

// The prefilter tail of a point splat (beyond the thesis, Z3Tile::setTailLayers): a
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

// One point splat straight into the Z^3 tile (point_rows.h), in chunks of rows, two passes
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
        // the other fragments, one by one (as forEachRest, simd_rows-inl.h, which here changed the
        // rows' code and cost 7-12% on point frames, BM_ContourFrame/*/0)
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
        // the other fragments, one by one (as above)
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

// A run of point splats (point_rows.h): one dispatch for the run; each splat's hot record
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

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(PointFragments);
HWY_EXPORT(PointRowsZ3);
HWY_EXPORT(PointRunZ3);

int pointFragments(const PointRaster& p, int x0, int y0, int width, int k0, int n, bool withPlaneCoords,
                   FragmentBlock& out) {
  return HWY_DYNAMIC_DISPATCH(PointFragments)(p, x0, y0, width, k0, n, withPlaneCoords, out);
}
uint64_t pointRowsZ3(const PointRaster& p, const PointShade& shade, const PixelRect& r, Z3Tile& tile) {
  return HWY_DYNAMIC_DISPATCH(PointRowsZ3)(p, shade, r, tile);
}
uint64_t pointRunZ3(const PointRowsFrame& frame, const PointRunSlots& slots, const uint32_t* refs, int n, Z3Tile& tile) {
  return HWY_DYNAMIC_DISPATCH(PointRunZ3)(frame, slots, refs, n, tile);
}
}  // namespace linesurf::detail
#endif
