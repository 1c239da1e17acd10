// SIMD splat weights (thesis §4.2.2 EWA point kernel, §5.2 segment kernel in closed form) over pixel blocks with Google Highway's runtime dispatch (see
// detail/splat_rows.h). Compiled once per x86 target; hwy picks the best the CPU runs.
#include "detail/splat_rows.h"

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

// The rays through lanes k.. meet a primitive's plane: pixel centres, 1 / N, depth, and the mask
// of the lanes where the plane is hit in front of the eye (and within [near, far] when clipDepth).
struct PlaneHit {
  VF px, py, iN, z;
  hn::Mask<DF> front;
  PlaneHit(const BlockWalker& walk, int k, const Affine2& N, float depthNum, bool clipDepth, float nearD, float farD) {
    const DF d;
    walk.at(k, px, py);
    const VF n = affine(d, N, px, py);
    iN = hn::Div(hn::Set(d, 1.0f), n);
    z = hn::Mul(hn::Set(d, depthNum), iN);
    front = hn::Lt(n, hn::Zero(d));
    if (clipDepth) front = hn::And(front, hn::And(hn::Ge(z, hn::Set(d, nearD)), hn::Le(z, hn::Set(d, farD))));
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

int PointFragments(const PointRaster& P, int x0, int y0, int width, int k0, int n, bool withPlaneCoords,
                   FragmentBlock& out) {
  const BlockWalker walk(width, x0, y0);
  const DF d;
  const int L = int(hn::Lanes(d));
  const VF cutoff = hn::Set(d, P.cutoffQ), scale = hn::Set(d, P.weightScale), mhalf = hn::Set(d, -0.5f);
  const VF lane = hn::Iota(d, 0.0f), count = hn::Set(d, float(n));
  int m = 0;
  for (int i = 0; i < n; i += L) {
    const PlaneHit h(walk, k0 + i, P.N, P.depthNum, P.clipDepth, P.nearD, P.farD);
    const VF s = hn::Mul(affine(d, P.S, h.px, h.py), h.iN), t = hn::Mul(affine(d, P.T, h.px, h.py), h.iN);
    const VF q = hn::MulAdd(s, s, hn::Mul(t, t));
    auto inside = hn::And(hn::And(h.front, hn::Le(q, cutoff)), hn::Lt(hn::Add(lane, hn::Set(d, float(i))), count));
    const VF w = hn::Mul(hn::Exp(d, hn::Mul(hn::Min(q, cutoff), mhalf)), scale);
    inside = hn::And(inside, hn::Gt(w, hn::Zero(d)));
    m += pack(d, inside, h.px, h.py, w, h.z, s, t, withPlaneCoords, out, m);
  }
  return m;
}

// erf(x) from exp(-x^2) (Abramowitz & Stegun 7.1.26, absolute error < 1.5e-7).
HWY_INLINE VF erfFromExp(DF d, VF x, VF expMinusX2) {
  const VF ax = hn::Abs(x);
  const VF t = hn::Div(hn::Set(d, 1.0f), hn::MulAdd(hn::Set(d, 0.3275911f), ax, hn::Set(d, 1.0f)));
  VF p = hn::Set(d, 1.061405429f);
  p = hn::MulAdd(p, t, hn::Set(d, -1.453152027f));
  p = hn::MulAdd(p, t, hn::Set(d, 1.421413741f));
  p = hn::MulAdd(p, t, hn::Set(d, -0.284496736f));
  p = hn::MulAdd(p, t, hn::Set(d, 0.254829592f));
  p = hn::Mul(p, t);
  const VF r = hn::NegMulAdd(p, expMinusX2, hn::Set(d, 1.0f));
  return hn::CopySign(r, x);
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

int SegmentFragments(const SegmentRaster& S, const RowSpan* spans, int spanCount, FragmentBlock& out) {
  const DF d;
  const int L = int(hn::Lanes(d));
  alignas(64) float pxs[kBlock + kMaxLanes], pys[kBlock + kMaxLanes];
  const int n = expandSpans(d, spans, spanCount, pxs, pys);
  const VF one = hn::Set(d, 1.0f), zero = hn::Zero(d), mhalf = hn::Set(d, -0.5f);
  const VF a0 = hn::Set(d, S.a0), b0 = hn::Set(d, S.b0);
  const VF len = hn::Set(d, S.length), invLen = hn::Set(d, S.length > 0 ? 1.0f / S.length : 0.0f), R2 = hn::Set(d, S.R2);
  const VF aMin = hn::Set(d, S.aMin), aMax = hn::Set(d, S.aMax), bMax = hn::Set(d, S.bMax);
  const VF skew = hn::Set(d, S.skew), across = hn::Set(d, S.across), invM00 = hn::Set(d, S.invM00);
  const VF kk = hn::Set(d, S.k), erfScale = hn::Set(d, S.erfScale), scale0 = hn::Set(d, S.scale0),
           slope = hn::Set(d, S.slope);
  const VF thr0 = hn::Set(d, S.zThreshold0), thrD = hn::Set(d, S.zThreshold1 - S.zThreshold0);
  const VF depthNum = hn::Set(d, S.depthNum), nearD = hn::Set(d, S.nearD), farD = hn::Set(d, S.farD);
  const VF lane = hn::Iota(d, 0.0f), count = hn::Set(d, float(n));
  int m = 0;
  for (int i = 0; i < n; i += L) {
    const VF px = hn::Load(d, pxs + i), py = hn::Load(d, pys + i);
    // the ray through the pixel meets the strip's plane (in front of the eye) at depth z
    const VF nr = affine(d, S.N, px, py);
    const VF iN = hn::Div(one, nr);
    const VF z = hn::Mul(depthNum, iN);
    auto inside = hn::And(hn::Lt(nr, zero), hn::Lt(hn::Add(lane, hn::Set(d, float(i))), count));
    if (S.clipDepth) inside = hn::And(inside, hn::And(hn::Ge(z, nearD), hn::Le(z, farD)));
    const VF a = hn::MulSub(affine(d, S.A, px, py), iN, a0), b = hn::MulSub(affine(d, S.B, px, py), iN, b0);
    inside = hn::And(inside, hn::And(hn::Le(hn::Abs(b), bMax), hn::And(hn::Ge(a, aMin), hn::Le(a, aMax))));
    // the integral along the sub-segment in closed form (segment_methods.cpp, screenSpaceWeight)
    const VF tauStar = hn::MulAdd(skew, b, a);
    const VF qmin = hn::Mul(hn::Mul(b, b), across);
    inside = hn::And(inside, hn::Lt(qmin, R2));
    const VF delta = hn::Sqrt(hn::Mul(hn::Max(hn::Sub(R2, qmin), zero), invM00));
    const VF t0 = hn::Max(zero, hn::Sub(tauStar, delta)), t1 = hn::Min(len, hn::Add(tauStar, delta));
    inside = hn::And(inside, hn::Gt(t1, t0));
    const VF u0 = hn::Mul(kk, hn::Sub(t0, tauStar)), u1 = hn::Mul(kk, hn::Sub(t1, tauStar));
    const VF g = hn::Exp(d, hn::Mul(hn::Min(qmin, R2), mhalf));
    const VF e0 = hn::Exp(d, hn::Neg(hn::Min(hn::Mul(u0, u0), R2))),
             e1 = hn::Exp(d, hn::Neg(hn::Min(hn::Mul(u1, u1), R2)));
    const VF i0 = hn::Mul(erfScale, hn::Sub(erfFromExp(d, u1, e1), erfFromExp(d, u0, e0)));
    VF w = hn::Mul(hn::Mul(hn::MulAdd(slope, tauStar, scale0), i0), g);
    w = hn::MulAdd(hn::Mul(hn::Mul(slope, invM00), g), hn::Sub(e0, e1), w);
    const VF u = hn::Min(one, hn::Max(zero, hn::Mul(a, invLen)));
    inside = hn::And(inside, hn::Gt(w, zero));
    m += pack(d, inside, px, py, w, z, u, hn::MulAdd(u, thrD, thr0), true, out, m);
  }
  return m;
}

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

template <class DZ>
HWY_NOINLINE uint64_t PointRowsT(DZ dz, int Wp, const PointRaster& P, const PointShade& A, const PixelRect& r, Z3Tile& z3) {
  const DF d;
  const int L = int(hn::Lanes(d)), LZ = int(hn::Lanes(dz));
  const int W = r.width(), H = r.height();
  const VF cutoff = hn::Set(d, P.cutoffQ), scale = hn::Set(d, P.weightScale), mhalf = hn::Set(d, -0.5f);
  const VF zero = hn::Zero(d), oneF = hn::Set(d, 1.0f);
  const VF Ndx = hn::Set(d, P.N.dx), Ndy = hn::Set(d, P.N.dy), N0 = hn::Set(d, P.N.c);
  const VF Sdx = hn::Set(d, P.S.dx), Sdy = hn::Set(d, P.S.dy), S0 = hn::Set(d, P.S.c);
  const VF Tdx = hn::Set(d, P.T.dx), Tdy = hn::Set(d, P.T.dy), T0 = hn::Set(d, P.T.c);
  const VF depthNum = hn::Set(d, P.depthNum), nearD = hn::Set(d, P.nearD), farD = hn::Set(d, P.farD);
  // lane offsets within a vector: several rows of Wp lanes when Wp < L, else a run of one row
  const int rowsPerVec = Wp < L ? L / Wp : 1;
  const hn::RebindToSigned<DF> di;
  const auto iota = hn::Iota(di, 0);
  const VF colLane = hn::ConvertTo(d, Wp < L ? hn::And(iota, hn::Set(di, Wp - 1)) : iota);
  const VF rowLane = Wp < L ? hn::Floor(hn::Mul(hn::ConvertTo(d, iota), hn::Set(d, 1.0f / float(Wp)))) : zero;
  HWY_ALIGN float bw[kRowChunk + kMaxLanes], bz[kRowChunk + kMaxLanes], bs[kRowChunk + kMaxLanes], bt[kRowChunk + kMaxLanes];
  // Z^3 pass constants
  using VZ = hn::Vec<DZ>;
  const hn::RebindToSigned<DZ> diz;
  const VZ zeroZ = hn::Zero(dz), oneZ = hn::Set(dz, 1.0f), thr = hn::Set(dz, A.zThreshold);
  const bool normals = z3.blendNormals();
  const int nAttr = normals ? Z3Tile::kAttrs : Z3Tile::kW + 1;
  VZ attr[Z3Tile::kAttrs], c0[3], cs[3], ct[3], cst[3];
  for (int k = 0; k < Z3Tile::kAttrs; ++k) attr[k] = hn::Set(dz, A.attr[k]);
  for (int k = 0; k < 3; ++k) {
    c0[k] = hn::Set(dz, A.gouraud ? A.C0[k] : 0.0f), cs[k] = hn::Set(dz, A.gouraud ? A.Cs[k] : 0.0f);
    ct[k] = hn::Set(dz, A.gouraud ? A.Ct[k] : 0.0f), cst[k] = hn::Set(dz, A.gouraud ? A.Cst[k] : 0.0f);
  }
  const bool opaque = A.attr[Z3Tile::kA] >= 1.0f;
  float* pl[Z3Tile::kFields];
  for (int f = 0; f < Z3Tile::kFields; ++f) pl[f] = z3.plane(0, f);
  int32_t* cnt = z3.counts();
  const auto iZero = hn::Zero(diz), iOne = hn::Set(diz, 1);
  uint64_t inserted = 0, opened = 0, occluded = 0;
  const int chunkRows = std::max(rowsPerVec, (kRowChunk / Wp) / rowsPerVec * rowsPerVec);
  const VF Wv = hn::Set(d, float(W));
  for (int cy = 0; cy < H; cy += chunkRows) {
    const int rows = std::min(chunkRows, H - cy);
    // 1. weights and depths
    for (int k = 0; k < rows * Wp; k += L) {
      const int row = k / Wp, col = k - row * Wp;  // of the vector's first lane
      const VF cx = hn::Add(colLane, hn::Set(d, float(col))), ry = hn::Add(rowLane, hn::Set(d, float(cy + row)));
      const VF px = hn::Add(cx, hn::Set(d, float(r.x0) + 0.5f)), py = hn::Add(ry, hn::Set(d, float(r.y0) + 0.5f));
      const VF n = hn::MulAdd(Ndx, px, hn::MulAdd(Ndy, py, N0));
      const VF iN = hn::Div(oneF, n);
      const VF z = hn::Mul(depthNum, iN);
      auto inside = hn::And(hn::Lt(n, zero), hn::And(hn::Lt(cx, Wv), hn::Lt(ry, hn::Set(d, float(H)))));
      if (P.clipDepth) inside = hn::And(inside, hn::And(hn::Ge(z, nearD), hn::Le(z, farD)));
      const VF s = hn::Mul(hn::MulAdd(Sdx, px, hn::MulAdd(Sdy, py, S0)), iN);
      const VF t = hn::Mul(hn::MulAdd(Tdx, px, hn::MulAdd(Tdy, py, T0)), iN);
      const VF q = hn::MulAdd(s, s, hn::Mul(t, t));
      inside = hn::And(inside, hn::Le(q, cutoff));
      hn::Store(hn::IfThenElseZero(inside, hn::Mul(hn::Exp(d, hn::Mul(hn::Min(q, cutoff), mhalf)), scale)), d, bw + k);
      hn::Store(z, d, bz + k);
      if (A.gouraud) hn::Store(s, d, bs + k), hn::Store(t, d, bt + k);
    }
    // 2. into the Z^3 tile
    for (int row = 0; row < rows; ++row) {
      const int y = r.y0 + cy + row;
      const size_t rowBase = z3.index(r.x0, y);
      for (int c = 0; c < W; c += LZ) {
        const int k = row * Wp + c;
        const VZ w = hn::LoadU(dz, bw + k), z = hn::LoadU(dz, bz + k);
        const auto inside = hn::Gt(w, zeroZ);
        const size_t p = rowBase + size_t(c);
        const auto count = hn::LoadU(diz, cnt + p);
        const auto open = hn::And(inside, hn::RebindMask(dz, hn::Eq(count, iZero)));
        const auto single = hn::And(inside, hn::RebindMask(dz, hn::Eq(count, iOne)));
        const VZ z0 = hn::LoadU(dz, pl[Z3Tile::kZ] + p);
        const auto within = hn::Le(hn::Abs(hn::Sub(z, z0)), hn::Max(thr, hn::LoadU(dz, pl[Z3Tile::kThr] + p)));
        const auto merge = hn::And(single, within);
        const auto fast = hn::Or(open, merge);
        // behind a single opaque layer (and not within its threshold): occluded
        const auto behind = hn::AndNot(within, hn::And(single, hn::And(hn::Gt(z, z0), hn::Gt(hn::LoadU(dz, pl[Z3Tile::kOpaque] + p), zeroZ))));
        VZ s = zeroZ, t = zeroZ;
        if (A.gouraud) s = hn::LoadU(dz, bs + k), t = hn::LoadU(dz, bt + k);
        for (int a = 0; a < nAttr; ++a) {
          VZ v = attr[a];
          if (A.gouraud && a < 3)  // bilinear Gouraud over the quad, in the plane coordinates (s, t)
            v = hn::Add(hn::Add(hn::Add(c0[a], hn::Mul(s, cs[a])), hn::Mul(t, ct[a])), hn::Mul(hn::Mul(s, t), cst[a]));
          const VZ add = hn::Mul(w, v);
          const VZ sum = hn::IfThenElse(open, add, hn::Add(hn::LoadU(dz, pl[a] + p), add));
          hn::BlendedStore(sum, fast, dz, pl[a] + p);
        }
        hn::BlendedStore(z, open, dz, pl[Z3Tile::kZ] + p);
        hn::BlendedStore(thr, open, dz, pl[Z3Tile::kThr] + p);
        if (opaque) hn::BlendedStore(oneZ, open, dz, pl[Z3Tile::kOpaque] + p);
        else hn::BlendedStore(zeroZ, fast, dz, pl[Z3Tile::kOpaque] + p);
        hn::BlendedStore(iOne, hn::RebindMask(diz, open), diz, cnt + p);
        inserted += hn::CountTrue(dz, inside);
        opened += hn::CountTrue(dz, open);
        occluded += hn::CountTrue(dz, behind);
        const auto rest = hn::AndNot(hn::Or(fast, behind), inside);
        if (HWY_LIKELY(hn::AllFalse(dz, rest))) continue;
        // the other fragments (a new layer in front of or behind others, compression, occlusion)
        HWY_ALIGN float mk[kMaxLanes];
        hn::StoreU(hn::VecFromMask(dz, rest), dz, mk);
        float fa[Z3Tile::kAttrs];
        for (int a = 0; a < Z3Tile::kAttrs; ++a) fa[a] = A.attr[a];
        for (int i = 0; i < LZ; ++i) {
          if (mk[i] == 0) continue;
          if (A.gouraud) {
            const float si = bs[k + i], ti = bt[k + i];
            for (int a = 0; a < 3; ++a) fa[a] = A.C0[a] + si * A.Cs[a] + ti * A.Ct[a] + (si * ti) * A.Cst[a];
          }
          z3.insert(r.x0 + c + i, y, bz[k + i], A.zThreshold, bw[k + i], fa);
        }
      }
    }
  }
  z3.addFastCounts(opened, occluded);
  return inserted;
}

uint64_t PointRowsZ3(const PointRaster& P, const PointShade& A, const PixelRect& r, Z3Tile& z3) {
  // rows Wp lanes apart in the weight buffer; the Z^3 pass runs on vectors of at most Wp lanes
  const int W = r.width();
  if (W <= 4) return PointRowsT(hn::CappedTag<float, 4>(), 4, P, A, r, z3);
  if (W <= 8) return PointRowsT(hn::CappedTag<float, 8>(), 8, P, A, r, z3);
  return PointRowsT(hn::CappedTag<float, 16>(), (W + 15) / 16 * 16, P, A, r, z3);
}

// One row of the resolve, pixels with one layer (detail/splat_rows.h): the formula of
// Z3Tile::resolve for n = 1 (keep the two alike), then the renderer's compositing over the
// background. Loads and stores of whole vectors only, so no other tile's pixels are touched.
int ResolveSingleLayerRow(Z3Tile& z3, int y, int x0, int n, const float* bg, float* out) {
  const DF d;
  const hn::RebindToSigned<DF> di;
  const int L = int(hn::Lanes(d));
  const size_t p0 = z3.index(x0, y);
  const int32_t* cnt = z3.counts() + p0;
  const float *R = z3.plane(0, Z3Tile::kR) + p0, *G = z3.plane(0, Z3Tile::kG) + p0, *B = z3.plane(0, Z3Tile::kB) + p0;
  const float *A = z3.plane(0, Z3Tile::kA) + p0, *Wt = z3.plane(0, Z3Tile::kW) + p0;
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  const VF bgR = hn::Set(d, bg[0]), bgG = hn::Set(d, bg[1]), bgB = hn::Set(d, bg[2]), bgW = hn::Set(d, bg[3]);
  const int whole = n / L * L;
  for (int i = 0; i < whole; i += L) {
    const auto single = hn::RebindMask(d, hn::Eq(hn::LoadU(di, cnt + i), hn::Set(di, 1)));
    if (hn::AllFalse(d, single)) continue;
    const VF iw = hn::Div(one, hn::LoadU(d, Wt + i));
    const VF a = hn::Min(hn::Max(hn::Mul(hn::LoadU(d, A + i), iw), zero), one);
    VF r = hn::Mul(a, hn::Mul(hn::LoadU(d, R + i), iw));
    VF g = hn::Mul(a, hn::Mul(hn::LoadU(d, G + i), iw));
    VF b = hn::Mul(a, hn::Mul(hn::LoadU(d, B + i), iw));
    const VF rest = hn::Mul(hn::Sub(one, a), bgW);
    r = hn::Add(r, hn::Mul(rest, bgR)), g = hn::Add(g, hn::Mul(rest, bgG)), b = hn::Add(b, hn::Mul(rest, bgB));
    const VF w = hn::Add(a, rest);
    if (bg[3] > 0) {  // straight colour for PNG
      const auto part = hn::And(hn::Gt(w, zero), hn::Lt(w, one));
      if (!hn::AllFalse(d, part))
        r = hn::IfThenElse(part, hn::Div(r, w), r), g = hn::IfThenElse(part, hn::Div(g, w), g), b = hn::IfThenElse(part, hn::Div(b, w), b);
    } else {
      const auto covered = hn::Gt(a, zero);
      r = hn::IfThenElse(covered, hn::Div(r, a), r), g = hn::IfThenElse(covered, hn::Div(g, a), g), b = hn::IfThenElse(covered, hn::Div(b, a), b);
    }
    // keep the other pixels as they are (whole vectors of this row only)
    VF r0, g0, b0, w0;
    hn::LoadInterleaved4(d, out + 4 * i, r0, g0, b0, w0);
    hn::StoreInterleaved4(hn::IfThenElse(single, r, r0), hn::IfThenElse(single, g, g0), hn::IfThenElse(single, b, b0),
                          hn::IfThenElse(single, w, w0), d, out + 4 * i);
  }
  return whole;
}

int64_t Target() { return HWY_TARGET; }

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(PointFragments);
HWY_EXPORT(SegmentFragments);
HWY_EXPORT(Target);
HWY_EXPORT(PointRowsZ3);
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
int resolveSingleLayerRow(Z3Tile& tile, int y, int x0, int n, const float* bg, float* out) {
  return HWY_DYNAMIC_DISPATCH(ResolveSingleLayerRow)(tile, y, x0, n, bg, out);
}
const char* simdTargetName() { return hwy::TargetName(HWY_DYNAMIC_DISPATCH(Target)()); }
}  // namespace linesurf::detail
#endif
