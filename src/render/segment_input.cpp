// The input of the SIMD segment set-up (segment_setup.h): a batch of segments loaded into
// structure-of-arrays form and moved to camera space, rounded as the exact path rounds
// (prepareSegment, segment_splat.cpp). Compiled once per x86 target (Google Highway).
#include <cmath>
#include <cstddef>

#include "segment_setup.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/segment_input.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>

HWY_BEFORE_NAMESPACE();
namespace linesurf::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The batch's input from segments [0, n) (AoS -> SoA, world space) and the prefetches of the
// input a batch ahead and of the record slots whose plane faces the eye (see docs/decisions.md, "Segment prepare"):
// 16 segments at once, each 16-byte block of the Segment (p0x p0y p0z p1x | p1y p1z nx ny | nz
// n0x n0y n0z | n1x n1y n1z - | r g b a | radius ...) of 4 x 4 segments transposed to 4 field
// vectors. Only with 512-bit vectors; false elsewhere (the caller copies lane by lane).
bool SegmentLoad(const SegmentSetupFrame& F, SegmentSetupBatch& B, const Segment* seg, int n, const PreparedSegment* out) {
#if HWY_TARGET <= HWY_AVX3 && HWY_ARCH_X86
  static_assert(sizeof(Segment) == 112 && alignof(Segment) % 16 == 0 && offsetof(Segment, p0) == 0 &&
                    offsetof(Segment, p1) == 12 && offsetof(Segment, normal) == 24 && offsetof(Segment, normal0) == 36 &&
                    offsetof(Segment, normal1) == 48 && offsetof(Segment, color) == 64 && offsetof(Segment, radius) == 80,
                "the Segment's 16-byte blocks");
  const float* const base = reinterpret_cast<const float*>(seg);
  const __m512 eye[3] = {_mm512_set1_ps(F.view.eye[0]), _mm512_set1_ps(F.view.eye[1]), _mm512_set1_ps(F.view.eye[2])};
  for (int i = 0; i < n; i += 16) {
    {  // the input a batch ahead, every line it spans (a hint: an address past the array is harmless)
      const uintptr_t next = reinterpret_cast<uintptr_t>(seg + i) + kSegmentBatch * sizeof(Segment);
      for (size_t o = 0; o < 16 * sizeof(Segment); o += 64) __builtin_prefetch(reinterpret_cast<const void*>(next + o));
    }
    const float* at[16];  // lanes past n read segment 0 (their values are not used)
    for (int j = 0; j < 16; ++j) at[j] = base + 28 * (i + j < n ? i + j : 0);
    // block k of the 16 segments as 4 vectors of field 4 k .. 4 k + 3
    auto block = [&](int k, __m512* f) {
      __m512 t[4];
      for (int q = 0; q < 4; ++q) {
        __m512 v = _mm512_castps128_ps512(_mm_load_ps(at[q] + 4 * k));
        v = _mm512_insertf32x4(v, _mm_load_ps(at[4 + q] + 4 * k), 1);
        v = _mm512_insertf32x4(v, _mm_load_ps(at[8 + q] + 4 * k), 2);
        t[q] = _mm512_insertf32x4(v, _mm_load_ps(at[12 + q] + 4 * k), 3);
      }
      const __m512d l01 = _mm512_castps_pd(_mm512_unpacklo_ps(t[0], t[1])), l23 = _mm512_castps_pd(_mm512_unpacklo_ps(t[2], t[3]));
      const __m512d h01 = _mm512_castps_pd(_mm512_unpackhi_ps(t[0], t[1])), h23 = _mm512_castps_pd(_mm512_unpackhi_ps(t[2], t[3]));
      f[0] = _mm512_castpd_ps(_mm512_unpacklo_pd(l01, l23)), f[1] = _mm512_castpd_ps(_mm512_unpackhi_pd(l01, l23));
      f[2] = _mm512_castpd_ps(_mm512_unpacklo_pd(h01, h23)), f[3] = _mm512_castpd_ps(_mm512_unpackhi_pd(h01, h23));
    };
    __m512 f[4];
    block(0, f);
    _mm512_store_ps(B.p0x + i, f[0]), _mm512_store_ps(B.p0y + i, f[1]), _mm512_store_ps(B.p0z + i, f[2]);
    _mm512_store_ps(B.p1x + i, f[3]);
    const __m512 tx = _mm512_sub_ps(eye[0], f[0]), ty = _mm512_sub_ps(eye[1], f[1]), tz = _mm512_sub_ps(eye[2], f[2]);
    block(1, f);
    _mm512_store_ps(B.p1y + i, f[0]), _mm512_store_ps(B.p1z + i, f[1]), _mm512_store_ps(B.wx + i, f[2]);
    _mm512_store_ps(B.wy + i, f[3]);
    __m512 facing = _mm512_add_ps(_mm512_mul_ps(f[2], tx), _mm512_mul_ps(f[3], ty));
    block(2, f);
    _mm512_store_ps(B.wz + i, f[0]);
    facing = _mm512_add_ps(facing, _mm512_mul_ps(f[0], tz));
    if (F.smoothFrame) {
      _mm512_store_ps(B.m0x + i, f[1]), _mm512_store_ps(B.m0y + i, f[2]), _mm512_store_ps(B.m0z + i, f[3]);
      block(3, f);
      _mm512_store_ps(B.m1x + i, f[0]), _mm512_store_ps(B.m1y + i, f[1]), _mm512_store_ps(B.m1z + i, f[2]);
    }
    if (F.modelColors) {
      block(4, f);
    } else {
      for (int c = 0; c < 4; ++c) f[c] = _mm512_set1_ps(F.defaultColor[c]);
    }
    if (F.alphaOverride >= 0) f[3] = _mm512_set1_ps(F.alphaOverride);
    _mm512_store_ps(B.cr + i, f[0]), _mm512_store_ps(B.cg + i, f[1]), _mm512_store_ps(B.cb + i, f[2]);
    _mm512_store_ps(B.ca + i, f[3]);
    block(5, f);
    _mm512_store_ps(B.radius + i, f[0]);
    // the lanes' record slots, all their lines, into L2 unless the plane clearly faces away (the
    // records stream through memory once per frame; fetched a few lanes
    // before their writing, the writes stalled; from here the batch's set-up passes meanwhile)
    unsigned bits = F.view.backfaceCulling ? unsigned(_mm512_cmp_ps_mask(facing, _mm512_setzero_ps(), _CMP_NLT_UQ)) : 0xFFFFu;
    bits &= n - i >= 16 ? 0xFFFFu : (1u << (n - i)) - 1u;
    for (; bits; bits &= bits - 1) {
      const char* slot = reinterpret_cast<const char*>(out + i + std::countr_zero(bits));
      for (size_t o = 0; o < sizeof(PreparedSegment); o += 64) __builtin_prefetch(slot + o, 0, 2);
    }
  }
  return true;
#else
  (void)F, (void)B, (void)seg, (void)n, (void)out;
  return false;
#endif
}

// World to camera space in place over lanes [0, n) of the batch, rounded as the exact path's
// Camera::toCamera and rotation() products round (Eigen: r0 x + (r1 y + r2 z), then + t; separate
// products and sums: no contraction to fused multiply-adds here), and the smooth flags.
#if defined(__clang__)
#define LINESURF_NO_CONTRACT _Pragma("clang fp contract(off)")
#else
#define LINESURF_NO_CONTRACT
#pragma GCC push_options
#pragma GCC optimize("fp-contract=off")
#endif
HWY_NOINLINE void SegmentToCamera(const SegmentSetupFrame& F, SegmentSetupBatch& B, int n) {
  LINESURF_NO_CONTRACT
  const PointSetupFrame& V = F.view;
  using DF = hn::ScalableTag<float>;
  using VF = hn::Vec<DF>;
  const DF d;
  const int lanes = int(hn::Lanes(d));
  const VF zero = hn::Zero(d), inf = hn::Set(d, INFINITY);
  VF r[9], t[3];
  for (int k = 0; k < 9; ++k) r[k] = hn::Set(d, V.rot[k]);
  for (int k = 0; k < 3; ++k) t[k] = hn::Set(d, V.trans[k]);
  auto row = [&](int i, VF x, VF y, VF z) { return hn::Add(hn::Mul(r[3 * i], x), hn::Add(hn::Mul(r[3 * i + 1], y), hn::Mul(r[3 * i + 2], z))); };
  auto rotate = [&](float* x, float* y, float* z, int i, VF X, VF Y, VF Z) {
    hn::StoreU(row(0, X, Y, Z), d, x + i), hn::StoreU(row(1, X, Y, Z), d, y + i), hn::StoreU(row(2, X, Y, Z), d, z + i);
  };
  auto point = [&](float* x, float* y, float* z, int i) {
    const VF X = hn::LoadU(d, x + i), Y = hn::LoadU(d, y + i), Z = hn::LoadU(d, z + i);
    hn::StoreU(hn::Add(row(0, X, Y, Z), t[0]), d, x + i), hn::StoreU(hn::Add(row(1, X, Y, Z), t[1]), d, y + i);
    hn::StoreU(hn::Add(row(2, X, Y, Z), t[2]), d, z + i);
  };
  auto norm2 = [](VF x, VF y, VF z) { return hn::Add(hn::Add(hn::Mul(x, x), hn::Mul(y, y)), hn::Mul(z, z)); };
  // a vector of lanes whose p1 are all bit-equal to the next lanes' p0 (a chain's shared
  // endpoints; compared as bits: +0 and -0 may round apart) takes them from the p0 already in
  // camera space, the same arithmetic on the same bits; so p0 first, over the whole batch
  const hn::RebindToUnsigned<DF> du;
  uint64_t shared = 0;
  if (F.shareChainEnds)
    for (int i = 0, v = 0; i < n; i += lanes, ++v) {
      auto U = [&](const float* a, int at) { return hn::BitCast(du, hn::LoadU(d, a + at)); };
      const auto last = hn::FirstN(du, size_t(n - 1 - i));  // lanes with a next lane in the batch
      const auto eq = hn::And(hn::And(hn::Eq(U(B.p1x, i), U(B.p0x, i + 1)), hn::Eq(U(B.p1y, i), U(B.p0y, i + 1))),
                              hn::Eq(U(B.p1z, i), U(B.p0z, i + 1)));
      if (i + lanes < n && hn::AllTrue(du, hn::And(eq, last))) shared |= uint64_t(1) << v;
    }
  for (int i = 0; i < n; i += lanes) point(B.p0x, B.p0y, B.p0z, i);
  for (int i = 0, v = 0; i < n; i += lanes, ++v) {
    if (shared >> v & 1) {
      hn::StoreU(hn::LoadU(d, B.p0x + i + 1), d, B.p1x + i), hn::StoreU(hn::LoadU(d, B.p0y + i + 1), d, B.p1y + i);
      hn::StoreU(hn::LoadU(d, B.p0z + i + 1), d, B.p1z + i);
    } else {
      point(B.p1x, B.p1y, B.p1z, i);
    }
  }
  for (int i = 0; i < n; i += lanes) {
    VF wx = hn::LoadU(d, B.wx + i), wy = hn::LoadU(d, B.wy + i), wz = hn::LoadU(d, B.wz + i);
    if (F.smoothFrame) {
      const VF ax = hn::LoadU(d, B.m0x + i), ay = hn::LoadU(d, B.m0y + i), az = hn::LoadU(d, B.m0z + i);
      const VF bx = hn::LoadU(d, B.m1x + i), by = hn::LoadU(d, B.m1y + i), bz = hn::LoadU(d, B.m1z + i);
      auto finite3 = [&](VF x, VF y, VF z) {
        return hn::And(hn::And(hn::Lt(hn::Abs(x), inf), hn::Lt(hn::Abs(y), inf)), hn::Lt(hn::Abs(z), inf));
      };
      // a sum of squares is positive where one term is, whatever the order of the sums
      const auto sm = hn::And(hn::And(finite3(ax, ay, az), finite3(bx, by, bz)),
                              hn::And(hn::Gt(norm2(ax, ay, az), zero), hn::Gt(norm2(bx, by, bz), zero)));
      hn::StoreU(hn::IfThenElseZero(sm, hn::Set(d, 1.0f)), d, B.smooth + i);
      const auto sum = hn::AndNot(hn::Gt(norm2(wx, wy, wz), zero), sm);
      wx = hn::IfThenElse(sum, hn::Add(ax, bx), wx), wy = hn::IfThenElse(sum, hn::Add(ay, by), wy);
      wz = hn::IfThenElse(sum, hn::Add(az, bz), wz);
      const VF ux = hn::IfThenElseZero(sm, ax), uy = hn::IfThenElseZero(sm, ay), uz = hn::IfThenElse(sm, az, hn::Set(d, 1.0f));
      const VF vx = hn::IfThenElseZero(sm, bx), vy = hn::IfThenElseZero(sm, by), vz = hn::IfThenElse(sm, bz, hn::Set(d, 1.0f));
      rotate(B.m0x, B.m0y, B.m0z, i, ux, uy, uz);
      rotate(B.m1x, B.m1y, B.m1z, i, vx, vy, vz);
    } else {
      hn::StoreU(zero, d, B.smooth + i);
    }
    rotate(B.wx, B.wy, B.wz, i, wx, wy, wz);
  }
}
#if !defined(__clang__)
#pragma GCC pop_options
#endif
#undef LINESURF_NO_CONTRACT

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(SegmentLoad);
HWY_EXPORT(SegmentToCamera);
bool segmentLoad(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, const Segment* segments, int n,
                 const PreparedSegment* out) {
  return HWY_DYNAMIC_DISPATCH(SegmentLoad)(frame, batch, segments, n, out);
}
void segmentToCamera(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n) {
  HWY_DYNAMIC_DISPATCH(SegmentToCamera)(frame, batch, n);
}
}  // namespace linesurf::detail
#endif  // HWY_ONCE
