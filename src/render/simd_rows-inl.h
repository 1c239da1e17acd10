// The SIMD code that the point rows (point_rows.cpp, §4.2.2) and the segment rows
// (segment_rows.cpp, §5.2) share: the reciprocal and exp of their kernels, the packing of a
// block's fragments, and the Z^3 fast path on a tile's planes (Z3Rows). Highway's per-target
// header: included once per target by each of those translation units (foreach_target).
#include "simd_rows.h"
#include "splat_rules.h"
#include "z3_buffer.h"

#if defined(LINESURF_RENDER_SIMD_ROWS_INL_H_) == defined(HWY_TARGET_TOGGLE)
#ifdef LINESURF_RENDER_SIMD_ROWS_INL_H_
#undef LINESURF_RENDER_SIMD_ROWS_INL_H_
#else
#define LINESURF_RENDER_SIMD_ROWS_INL_H_
#endif

#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>

HWY_BEFORE_NAMESPACE();
namespace linesurf::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;
using DF = hn::ScalableTag<float>;
using VF = hn::Vec<DF>;

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

// The lanes of `rest` that the fast path left (a new layer in front of or behind others,
// compression, occlusion), one by one in lane order: insert(i) calls Z3Tile::insert for lane i.
// The segment rows use it; the point rows spell the same loop out (through this helper their
// code changed and point frames cost 7-12% more).
template <class DZ, class Insert>
HWY_INLINE void forEachRest(DZ dz, hn::Mask<DZ> rest, Insert&& insert) {
  HWY_ALIGN float mk[kMaxLanes];
  hn::Store(hn::VecFromMask(dz, rest), dz, mk);
  for (int i = 0; i < int(hn::Lanes(dz)); ++i)
    if (mk[i] != 0) insert(i);
}

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#endif  // LINESURF_RENDER_SIMD_ROWS_INL_H_ toggle
