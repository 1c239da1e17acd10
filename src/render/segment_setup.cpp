// SIMD set-up of segment splats (beyond the thesis: the stages of thesis §5 / §6.2.2 that
// segment_splat.cpp runs per segment, for the common case, over a batch in float), and the batches
// around it (segment_setup.h). The exact path, which takes every lane this code marks for it, is
// prepareSegment (segment_splat.cpp).
#include "segment_setup.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cstddef>
#include <cmath>
#include <numbers>
#include <cstring>
#include <new>

#include "splat_rules.h"
#include "point_setup.h"

#ifndef LINESURF_SEGMENT_SETUP_FLAGS  // once: foreach_target includes this file per target
#define LINESURF_SEGMENT_SETUP_FLAGS
namespace linesurf::detail {
// The word of the record image holding `smooth` and `shade` (the other bytes: the template's).
inline constexpr int kFlagSlot = int((offsetof(PreparedSegment, smooth) - kRecordBegin) / 4);
inline constexpr int kSmoothShift = int(8 * ((offsetof(PreparedSegment, smooth) - kRecordBegin) % 4));
inline constexpr int kShadeShift = int(8 * ((offsetof(PreparedSegment, shade) - kRecordBegin) % 4));
// The word holding `stationCount` (its first byte; the others padding, zero)
inline constexpr int kStationCountSlot = int((offsetof(PreparedSegment, stationCount) - kRecordBegin) / 4);
static_assert((offsetof(PreparedSegment, stationCount) - kRecordBegin) % 4 == 0 && kStationCountSlot != kFlagSlot &&
                  offsetof(PreparedSegment, raster) >= offsetof(PreparedSegment, stationCount) + 4,
              "stationCount: the first byte of a word of its own");
static_assert(int((offsetof(PreparedSegment, shade) - kRecordBegin) / 4) == kFlagSlot && sizeof(SegmentShade) == 1 &&
                  sizeof(bool) == 1 && std::endian::native == std::endian::little,
              "smooth and shade: bytes of one word of the record image");
}  // namespace linesurf::detail
#endif

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/segment_setup.cpp"
#include <hwy/foreach_target.h>  // IWYU pragma: keep
#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>
#include "segment_setup-inl.h"

HWY_BEFORE_NAMESPACE();
namespace linesurf::detail {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// The margins below send a lane to the exact path wherever float rounding could decide a test
// otherwise than the double arithmetic of prepareSegment: relative 1e-4 on the culling and depth
// tests, 2% of an integer on the sub-segment count (its float error is below 1e-3), a facing of 0.02 at the
// ends (below it the float covariance loses more than 1e-4 relative), covariances with an
// eigenvalue within 0.1% of the stretch clamp (beyond it the clamp is applied here).
constexpr float kPieceTolerance2 = float(segment::kPieceTolerance * segment::kPieceTolerance);
constexpr float kShort = float(segment::kShortSegment);
constexpr float kCosStationTurn = 0.99500417f;  // cos(segment::kStationTurn)

// Phong factors (FrameContext::shade with the specular table) at unit shading normal m and
// camera-space point q: colour = (albedo dif + spec) * light colour; for N vectors at once, step
// by step (their dependency chains interleaved).
template <int N, class DF, class VF = hn::Vec<DF>>
HWY_INLINE void PhongN(DF d, const SegmentSetupFrame& F, const VF* mx, const VF* my, const VF* mz, const VF* qx,
                       const VF* qy, const VF* qz, VF* dif, VF* spec) {
  const PointSetupFrame& V = F.view;
  const hn::RebindToSigned<DF> di;
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  auto dot3 = [](VF ax, VF ay, VF az, VF bx, VF by, VF bz) { return hn::MulAdd(ax, bx, hn::MulAdd(ay, by, hn::Mul(az, bz))); };
  const VF lx = hn::Set(d, V.lightDir[0]), ly = hn::Set(d, V.lightDir[1]), lz = hn::Set(d, V.lightDir[2]);
  VF ndl[N], q2[N], iq[N], hx[N], hy[N], hz[N], h2[N], x[N];
  for (int k = 0; k < N; ++k) {
    ndl[k] = hn::Max(zero, dot3(mx[k], my[k], mz[k], lx, ly, lz));
    dif[k] = hn::MulAdd(hn::Set(d, V.diffuse), ndl[k], hn::Set(d, V.ambient));
    spec[k] = zero;
  }
  if (!(V.specular > 0)) return;
  for (int k = 0; k < N; ++k) q2[k] = dot3(qx[k], qy[k], qz[k], qx[k], qy[k], qz[k]);
  for (int k = 0; k < N; ++k) iq[k] = hn::Neg(hn::Div(one, hn::Sqrt(q2[k])));  // view vector -q / |q|
  for (int k = 0; k < N; ++k) {
    hx[k] = hn::MulAdd(qx[k], iq[k], lx), hy[k] = hn::MulAdd(qy[k], iq[k], ly), hz[k] = hn::MulAdd(qz[k], iq[k], lz);
    h2[k] = dot3(hx[k], hy[k], hz[k], hx[k], hy[k], hz[k]);
  }
  const VF table = hn::Set(d, float(FrameContext::kSpecularTable));
  for (int k = 0; k < N; ++k) {
    const VF ndh = hn::Min(one, hn::Max(zero, hn::Div(dot3(mx[k], my[k], mz[k], hx[k], hy[k], hz[k]), hn::Sqrt(h2[k]))));
    // lanes the exact path takes may hold NaN here: the index stays inside the table
    x[k] = hn::Mul(ndh, table);
    x[k] = hn::Min(hn::Max(hn::IfThenElseZero(hn::Eq(x[k], x[k]), x[k]), zero), table);
  }
  for (int k = 0; k < N; ++k) {
    const VF xi = hn::Floor(x[k]);
    const auto i = hn::ConvertTo(di, xi);
    const VF t0 = hn::GatherIndex(d, F.specularTable, i), t1 = hn::GatherIndex(d, F.specularTable + 1, i);
    const VF pw = hn::MulAdd(hn::Sub(x[k], xi), hn::Sub(t1, t0), t0);
    const auto lit = hn::And(hn::And(hn::Gt(ndl[k], zero), hn::Gt(h2[k], zero)), hn::Gt(q2[k], zero));
    spec[k] = hn::IfThenElseZero(lit, hn::Mul(hn::Set(d, V.specular), pw));
  }
}

template <class DF, class VF = hn::Vec<DF>>
HWY_INLINE void Phong(DF d, const SegmentSetupFrame& F, VF mx, VF my, VF mz, VF qx, VF qy, VF qz, VF& dif, VF& spec) {
  PhongN<1>(d, F, &mx, &my, &mz, &qx, &qy, &qz, &dif, &spec);
}

// One channel of the lit colour from Phong's factors: (albedo dif + spec) * light colour.
template <class VF>
HWY_INLINE VF Lit(VF albedo, VF dif, VF spec, VF light) {
  return hn::Mul(hn::MulAdd(albedo, dif, spec), light);
}

// Where each word of the record image comes from: the batch array at that byte offset in
// SegmentSetupBatch (the lane's value), or -1 (the frame's template).
const std::array<int32_t, kRecordSlots>& recordSources() {
  static const std::array<int32_t, kRecordSlots> table = [] {
    std::array<int32_t, kRecordSlots> t;
    t.fill(-1);
    using P = PreparedSegment;
    using B = SegmentSetupBatch;
    auto put = [&](size_t rec, size_t batch) { t[(rec - kRecordBegin) / 4] = int32_t(batch); };
    const size_t b = offsetof(P, bounds), r = offsetof(P, raster), a = offsetof(P, attr);
    put(b + offsetof(PixelRect, x0), offsetof(B, x0)), put(b + offsetof(PixelRect, y0), offsetof(B, y0));
    put(b + offsetof(PixelRect, x1), offsetof(B, x1)), put(b + offsetof(PixelRect, y1), offsetof(B, y1));
    put(offsetof(P, index), offsetof(B, index));
    put(kRecordBegin + 4 * size_t(kFlagSlot), offsetof(B, flags));
    put(kRecordBegin + 4 * size_t(kStationCountSlot), offsetof(B, stationCount));
    auto affine = [&](size_t at, size_t x, size_t y, size_t c) {
      put(at + offsetof(Affine2, dx), x), put(at + offsetof(Affine2, dy), y), put(at + offsetof(Affine2, c), c);
    };
    using R = SegmentRaster;
    affine(r + offsetof(R, N), offsetof(B, Nx), offsetof(B, Ny), offsetof(B, N0));
    affine(r + offsetof(R, A), offsetof(B, Ax), offsetof(B, Ay), offsetof(B, A0));
    affine(r + offsetof(R, B), offsetof(B, Bx), offsetof(B, By), offsetof(B, B0));
    put(r + offsetof(R, depthNum), offsetof(B, depthNum)), put(r + offsetof(R, a0), offsetof(B, a0));
    put(r + offsetof(R, b0), offsetof(B, b0)), put(r + offsetof(R, length), offsetof(B, length));
    put(r + offsetof(R, aMin), offsetof(B, aMin)), put(r + offsetof(R, aMax), offsetof(B, aMax));
    put(r + offsetof(R, bMax), offsetof(B, bMax)), put(r + offsetof(R, skew), offsetof(B, skew));
    put(r + offsetof(R, across), offsetof(B, across)), put(r + offsetof(R, invM00), offsetof(B, invM00));
    put(r + offsetof(R, k), offsetof(B, k)), put(r + offsetof(R, erfScale), offsetof(B, erfScale));
    put(r + offsetof(R, scale0), offsetof(B, scale0)), put(r + offsetof(R, slope), offsetof(B, slope));
    put(r + offsetof(R, zThreshold0), offsetof(B, zt0)), put(r + offsetof(R, zThreshold1), offsetof(B, zt1));
    put(r + offsetof(R, tailB), offsetof(B, tailB));
    put(a + 4 * Z3Tile::kR, offsetof(B, ar)), put(a + 4 * Z3Tile::kG, offsetof(B, ag));
    put(a + 4 * Z3Tile::kB, offsetof(B, ab)), put(a + 4 * Z3Tile::kA, offsetof(B, aa));
    put(a + 4 * Z3Tile::kNx, offsetof(B, n0x)), put(a + 4 * Z3Tile::kNy, offsetof(B, n0y));
    put(a + 4 * Z3Tile::kNz, offsetof(B, n0z));
    const size_t dc[3] = {offsetof(B, dcx), offsetof(B, dcy), offsetof(B, dcz)};
    const size_t n0[3] = {offsetof(B, n0x), offsetof(B, n0y), offsetof(B, n0z)};
    const size_t dn[3] = {offsetof(B, dnx), offsetof(B, dny), offsetof(B, dnz)};
    for (int c = 0; c < 3; ++c) {  // Vec3f: three floats
      put(offsetof(P, dc) + 4 * size_t(c), dc[c]);
      put(offsetof(P, n0) + 4 * size_t(c), n0[c]);
      put(offsetof(P, dn) + 4 * size_t(c), dn[c]);
    }
    for (int k = 0; k < 4; ++k) {
      put(offsetof(P, screenQuad) + sizeof(Vec2f) * size_t(k), offsetof(B, qx) + size_t(k) * sizeof(B::qx[0]));
      put(offsetof(P, screenQuad) + sizeof(Vec2f) * size_t(k) + 4, offsetof(B, qy) + size_t(k) * sizeof(B::qy[0]));
    }
    return t;
  }();
  return table;
}

// Stage 1 of one vector of lanes (camera-space input): the strip's axis and plane, and the
// culling decisions, as SegmentCull and SegmentSetup both take them.
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>>
struct Strip {
  VF len, iL, ex, ey, ez, zmin, nx, ny, nz, D;
  // three kinds of lanes for the exact path, in the order of its tests: unusual input (it may be
  // Degenerate), undecided before the culling tests (early), undecided after them
  MF badInput, outside, early, culled;
};
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>>
HWY_INLINE Strip<DF> StripOf(DF d, const SegmentSetupFrame& F, VF cx, VF cy, VF cz, VF qx1, VF qy1, VF qz1, VF wx,
                             VF wy, VF wz, VF rad) {
  const PointSetupFrame& V = F.view;
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  auto S = [&](float v) { return hn::Set(d, v); };
  auto dot3 = [](VF ax, VF ay, VF az, VF bx, VF by, VF bz) { return hn::MulAdd(ax, bx, hn::MulAdd(ay, by, hn::Mul(az, bz))); };
  const VF inf = S(INFINITY);
  auto finite = [&](VF v) { return hn::Lt(hn::Abs(v), inf); };
  Strip<DF> st;
  const VF dx = hn::Sub(qx1, cx), dy = hn::Sub(qy1, cy), dz = hn::Sub(qz1, cz);
  const VF len = hn::Sqrt(dot3(dx, dy, dz, dx, dy, dz));
  MF badInput = hn::Not(hn::And(hn::Gt(rad, zero), finite(rad)));
  for (VF v : {cx, cy, cz, qx1, qy1, qz1, wx, wy, wz}) badInput = hn::Or(badInput, hn::Not(finite(v)));
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
  st.len = len, st.iL = iL, st.ex = ex, st.ey = ey, st.ez = ez, st.zmin = zmin;
  st.nx = nx, st.ny = ny, st.nz = nz, st.D = D;
  st.badInput = badInput, st.outside = outside, st.early = early, st.culled = culled;
  return st;
}

// Stage 1 over lanes [0, n) (see docs/decisions.md, "Segment prepare"): the lanes it decides (unusual input or
// undecided: the exact path; outside; culled) get their status in B.decidedStatus and
// B.exactLanes, the others are compacted to lanes [0, m) of the batch's input arrays, B.lane[k]
// the original lane of lane k, so that SegmentSetup runs on full vectors of them. Returns m.
int SegmentCull(const SegmentSetupFrame& F, SegmentSetupBatch& B, int n) {
  using DF = hn::ScalableTag<float>;
  const DF d;
  const hn::RebindToSigned<DF> di;
  const int lanes = int(hn::Lanes(d));
  float* const arrays[] = {B.p0x, B.p0y, B.p0z, B.p1x, B.p1y, B.p1z, B.wx, B.wy, B.wz, B.radius, B.smooth,
                           B.cr,  B.cg,  B.cb,  B.ca,  B.m0x, B.m0y, B.m0z, B.m1x, B.m1y, B.m1z};
  const int count = F.smoothFrame ? 21 : 15;
  size_t m = 0;
  B.exactLanes = 0;
  const hn::Rebind<uint8_t, DF> d8;
  for (int i = 0; i < n; i += lanes) {
    auto L = [&](const float* a) { return hn::LoadU(d, a + i); };
    const Strip<DF> st = StripOf(d, F, L(B.p0x), L(B.p0y), L(B.p0z), L(B.p1x), L(B.p1y), L(B.p1z), L(B.wx), L(B.wy),
                                 L(B.wz), L(B.radius));
    const auto exact = hn::Or(st.badInput, hn::AndNot(st.outside, st.early));
    const auto code = hn::IfThenElse(hn::RebindMask(di, st.outside), hn::Set(di, int32_t(PrimitiveStatus::Outside)),
                                     hn::IfThenElseZero(hn::RebindMask(di, st.culled), hn::Set(di, int32_t(PrimitiveStatus::Culled))));
    static_assert(int(PrimitiveStatus::Drawn) == 0, "the placeholder of the lanes decided later");
    hn::StoreU(hn::DemoteTo(d8, code), d8, B.decidedStatus + i);
    uint8_t bits[8] = {};
    hn::StoreMaskBits(d, hn::And(exact, hn::FirstN(d, size_t(n - i))), bits);
    uint64_t word;
    std::memcpy(&word, bits, sizeof(word));
    B.exactLanes |= word << i;
    const auto keep = hn::AndNot(hn::Or(hn::Or(st.badInput, st.outside), hn::Or(st.early, st.culled)),
                                 hn::FirstN(d, size_t(n - i)));
    // in place: lanes [m, m + kept) with m <= i, after their loads
    for (int a = 0; a < count; ++a) hn::CompressBlendedStore(hn::LoadU(d, arrays[a] + i), keep, d, arrays[a] + m);
    hn::CompressBlendedStore(hn::Iota(di, i), hn::RebindMask(di, keep), di, B.lane + m);
    m += hn::CountTrue(d, keep);
  }
  // harmless padding lanes to the last vector's end
  for (size_t j = m; j < size_t(kSegmentBatch) && j < (m + size_t(lanes) - 1) / size_t(lanes) * size_t(lanes); ++j) {
    B.p0x[j] = B.p0y[j] = B.p0z[j] = B.p1y[j] = B.wx[j] = B.wy[j] = 0;
    B.p1x[j] = 1, B.p1z[j] = B.p0z[j] = -2, B.wz[j] = 1, B.radius[j] = 1;
    B.smooth[j] = 0;
    B.m0x[j] = B.m0y[j] = B.m1x[j] = B.m1y[j] = 0;
    B.m0z[j] = B.m1z[j] = 1;
    B.cr[j] = B.cg[j] = B.cb[j] = B.ca[j] = 0;
    B.lane[j] = int32_t(j);
  }
  return int(m);
}

// The lit colours of the interior stations of a batch's turning lanes (segmentSetup queued them as
// jobs: B.stationJobs): the jobs lit a vector at a time, each job's inputs taken from the vectors
// of the lanes it belongs to by a lane permutation (a batch-wide queue needed ~20 gathers per
// vector of jobs); two vectors of jobs interleaved, so that their long dependency chains (three
// square roots, three divisions and a gather in a row) overlap.
HWY_INLINE void SegmentStationColours(const SegmentSetupFrame& F, SegmentSetupBatch& B, int n) {
  using DF = hn::ScalableTag<float>;
  using VF = hn::Vec<DF>;
  using DI = hn::RebindToSigned<DF>;
  using VI = hn::Vec<DI>;
  const DF d;
  const DI di;
  const int lanes = int(hn::Lanes(d));
  const VF one = hn::Set(d, 1.0f);
  auto S = [&](float v) { return hn::Set(d, v); };
  int jobAt[kSegmentBatch * kMaxSegmentPieces], jobGroup[kSegmentBatch * kMaxSegmentPieces], jobVectors = 0;
  for (int i = 0; i < n; i += lanes)
    for (int q = 0; q < B.groupJobs[i / lanes]; q += lanes) jobAt[jobVectors] = q, jobGroup[jobVectors++] = i;
  const VF lr = S(F.lightColor[0]), lg = S(F.lightColor[1]), lb = S(F.lightColor[2]);
  constexpr int W = 2;
  for (int v = 0; v < jobVectors; v += W) {
    VF u[W], mx[W], my[W], mz[W], px[W], py[W], pz[W], ar[W], ag[W], ab[W], dif[W], spec[W];
    for (int w = 0; w < W; ++w) {
      const int jv = std::min(v + w, jobVectors - 1), i = jobGroup[jv], q = jobAt[jv];
      // job j's lane: the last whose first job is <= j
      const VI j = hn::Iota(di, q);
      VI lane = hn::Set(di, lanes - 1);
      for (int t = 1; t < lanes; ++t) lane = hn::Add(lane, hn::VecFromMask(di, hn::Gt(hn::Set(di, B.jobFirst[i + t]), j)));
      const auto idx = hn::IndicesFromVec(d, lane);
      auto T = [&](const float* a) { return hn::TableLookupLanes(hn::LoadU(d, a + i), idx); };
      // u = s / S, s = j - first + 1 (as float(s) / float(S) rounds)
      const VI first = hn::TableLookupLanes(hn::LoadU(di, B.jobFirst + i), hn::IndicesFromVec(di, lane));
      u[w] = hn::Div(hn::ConvertTo(d, hn::Add(hn::Sub(j, first), hn::Set(di, 1))), T(B.jobIntervals));
      mx[w] = hn::MulAdd(u[w], T(B.dnx), T(B.n0x)), my[w] = hn::MulAdd(u[w], T(B.dny), T(B.n0y));
      mz[w] = hn::MulAdd(u[w], T(B.dnz), T(B.n0z));
      const VF cx = T(B.p0x), cy = T(B.p0y), cz = T(B.p0z);
      px[w] = hn::MulAdd(u[w], hn::Sub(T(B.p1cx), cx), cx), py[w] = hn::MulAdd(u[w], hn::Sub(T(B.p1cy), cy), cy);
      pz[w] = hn::MulAdd(u[w], hn::Sub(T(B.p1cz), cz), cz);
      ar[w] = T(B.cr), ag[w] = T(B.cg), ab[w] = T(B.cb);
    }
    for (int w = 0; w < W; ++w) {
      const VF im = hn::Div(one, hn::Sqrt(hn::MulAdd(mx[w], mx[w], hn::MulAdd(my[w], my[w], hn::Mul(mz[w], mz[w])))));
      mx[w] = hn::Mul(mx[w], im), my[w] = hn::Mul(my[w], im), mz[w] = hn::Mul(mz[w], im);
    }
    PhongN<W>(d, F, mx, my, mz, px, py, pz, dif, spec);
    for (int w = 0; w < W && v + w < jobVectors; ++w) {
      const int at = B.groupBase[jobGroup[v + w] / lanes] + jobAt[v + w];
      hn::StoreU(Lit(ar[w], dif[w], spec[w], lr), d, B.stationR + at);
      hn::StoreU(Lit(ag[w], dif[w], spec[w], lg), d, B.stationG + at);
      hn::StoreU(Lit(ab[w], dif[w], spec[w], lb), d, B.stationB + at);
    }
  }
}

// Stage 6's shading normals of a smooth frame (the model's segments carry endpoint normals): the
// endpoint normals n0, n1 on the plane normal n's side where a lane is smooth (sm); a lane turning
// by more than kStationTurn (0.1 rad) is shaded at stations (Gouraud at ceil(turn / kStationTurn)
// + 1 stations, prepareSegment's stage 6; none where lighting is deferred); near the threshold,
// or near an integer ceil(), the exact path decides (exact).
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>>
HWY_INLINE void SegmentSmoothNormals(DF d, const SegmentSetupFrame& F, const SegmentSetupBatch& B, int i, VF nx, VF ny,
                                     VF nz, VF& n0x, VF& n0y, VF& n0z, VF& n1x, VF& n1y, VF& n1z, MF& sm, MF& turning,
                                     VF& stations, MF& exact) {
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  auto S = [&](float v) { return hn::Set(d, v); };
  auto L = [&](const float* a) { return hn::LoadU(d, a + i); };
  auto dot3 = [](VF ax, VF ay, VF az, VF bx, VF by, VF bz) { return hn::MulAdd(ax, bx, hn::MulAdd(ay, by, hn::Mul(az, bz))); };
  const VF inf = S(INFINITY);
  auto finite = [&](VF v) { return hn::Lt(hn::Abs(v), inf); };
  sm = hn::Gt(L(B.smooth), zero);
  VF ax = L(B.m0x), ay = L(B.m0y), az = L(B.m0z), bx = L(B.m1x), by = L(B.m1y), bz = L(B.m1z);
  const VF ia = hn::Div(one, hn::Sqrt(dot3(ax, ay, az, ax, ay, az))), ib = hn::Div(one, hn::Sqrt(dot3(bx, by, bz, bx, by, bz)));
  const MF flip = hn::Lt(dot3(nx, ny, nz, hn::MulAdd(ax, ia, hn::Mul(bx, ib)), hn::MulAdd(ay, ia, hn::Mul(by, ib)),
                              hn::MulAdd(az, ia, hn::Mul(bz, ib))), zero);
  const VF sa = hn::IfThenElse(flip, hn::Neg(ia), ia), sb = hn::IfThenElse(flip, hn::Neg(ib), ib);
  ax = hn::Mul(ax, sa), ay = hn::Mul(ay, sa), az = hn::Mul(az, sa);
  bx = hn::Mul(bx, sb), by = hn::Mul(by, sb), bz = hn::Mul(bz, sb);
  // turning by more than kStationTurn (0.1 rad): shade Stations, Gouraud at ceil(turn /
  // kStationTurn) + 1 stations (prepareSegment's stage 6), or none where lighting is deferred;
  // near the threshold, or near an integer ceil(), the exact path decides
  const VF cosTurn = dot3(ax, ay, az, bx, by, bz);
  exact = hn::Or(exact, hn::And(sm, hn::Not(hn::Gt(hn::Abs(hn::Sub(cosTurn, S(kCosStationTurn))), S(1e-5f)))));
  exact = hn::Or(exact, hn::And(sm, hn::Not(hn::And(finite(ax), finite(bx)))));
  turning = hn::And(sm, hn::Lt(cosTurn, S(kCosStationTurn)));
  if (!hn::AllFalse(d, turning)) {
    if (F.perPixelLighting) {
      stations = hn::IfThenElse(turning, zero, stations);
    } else {
      const VF turn = hn::Acos(d, hn::Min(hn::Max(cosTurn, S(-1.0f)), one));
      const VF x = hn::Div(turn, S(segment::kStationTurn));
      exact = hn::Or(exact, hn::And(turning, hn::Lt(hn::Abs(hn::Sub(x, hn::Round(x))), S(1e-3f))));
      const VF count = hn::Min(hn::Max(hn::Ceil(x), one), S(float(kMaxSegmentPieces)));
      stations = hn::IfThenElse(turning, count, stations);
    }
  }
  n0x = hn::IfThenElse(sm, ax, nx), n0y = hn::IfThenElse(sm, ay, ny), n0z = hn::IfThenElse(sm, az, nz);
  n1x = hn::IfThenElse(sm, bx, nx), n1y = hn::IfThenElse(sm, by, ny), n1z = hn::IfThenElse(sm, bz, nz);
    }

// The record words of a vector of lanes that the batch writes per lane beside the template: the
// index, the word holding `smooth` and `shade`, and stationCount (untexturedStations).
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>>
HWY_INLINE void SegmentFlags(DF d, const SegmentSetupFrame& F, SegmentSetupBatch& B, int i, MF shaded, MF sm,
                             VF stations) {
  const hn::RebindToSigned<DF> di;
  const VF zero = hn::Zero(d);
  auto S = [&](float v) { return hn::Set(d, v); };
  const hn::RebindToUnsigned<DF> du;
  using VU = hn::Vec<decltype(du)>;
  hn::StoreU(hn::Add(hn::Set(du, B.first), hn::BitCast(du, hn::LoadU(di, B.lane + i))), du, B.index + i);
  const VU shade = hn::IfThenElse(hn::RebindMask(du, shaded), hn::Set(du, uint32_t(SegmentShade::Stations)),
                                  hn::IfThenElse(hn::RebindMask(du, sm), hn::Set(du, uint32_t(SegmentShade::Smooth)),
                                                 hn::Set(du, uint32_t(F.perPixelLighting ? SegmentShade::Constant
                                                                                         : SegmentShade::Linear))));
  const VU smooth = hn::IfThenElseZero(hn::RebindMask(du, sm), hn::Set(du, 1u));
  const uint32_t keep = F.record.word[kFlagSlot] & ~((0xFFu << kSmoothShift) | (0xFFu << kShadeShift));
  const VU flags = hn::Or(hn::Set(du, keep), hn::Or(hn::ShiftLeftSame(smooth, kSmoothShift), hn::ShiftLeftSame(shade, kShadeShift)));
  hn::StoreU(flags, du, B.flags + i);
  // stationCount (untexturedStations): 0 where lighting is deferred, kInlineStations for two
  // intervals, else -1 (in SegmentExtra)
  const auto inl = hn::And(shaded, hn::Or(hn::Eq(stations, zero), hn::Eq(stations, S(float(kInlineStations - 1)))));
  const VF count = hn::IfThenElse(inl, hn::IfThenElseZero(hn::Gt(stations, zero), S(float(kInlineStations))), S(-1.0f));
  hn::StoreU(hn::And(hn::BitCast(du, hn::ConvertTo(di, count)), hn::Set(du, 0xFFu)), du, B.stationCount + i);
    }

// Stage 6's attributes at u = 0 (setBaseAttributes) and the colour's change to u = 1: Gouraud
// between the ends (F.light; Phong at the ends n0 at c, n1 at q1); the albedo where lighting is
// deferred, for lanes with stations (shaded: their colours in SegmentExtra) and where
// prepareSegments lights the ends per lane (!F.light).
template <class DF, class VF = hn::Vec<DF>, class MF = hn::Mask<DF>>
HWY_INLINE void SegmentEndColours(DF d, const SegmentSetupFrame& F, SegmentSetupBatch& B, int i, VF n0x, VF n0y,
                                  VF n0z, VF n1x, VF n1y, VF n1z, VF cx, VF cy, VF cz, VF qx1, VF qy1, VF qz1,
                                  MF shaded) {
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f);
  auto S = [&](float v) { return hn::Set(d, v); };
  auto L = [&](const float* a) { return hn::LoadU(d, a + i); };
  auto St = [&](VF v, float* a) { hn::StoreU(v, d, a + i); };
  const VF cr = L(B.cr), cg = L(B.cg), cb = L(B.cb);
  St(hn::Min(hn::Max(L(B.ca), zero), one), B.aa);
  VF ar = cr, ag = cg, ab = cb, dcx = zero, dcy = zero, dcz = zero;
  if (F.light) {
    VF dif0, spec0, dif1, spec1;
    Phong(d, F, n0x, n0y, n0z, cx, cy, cz, dif0, spec0);
    Phong(d, F, n1x, n1y, n1z, qx1, qy1, qz1, dif1, spec1);
    St(dif0, B.diffuse0), St(spec0, B.specular0), St(dif1, B.diffuse1), St(spec1, B.specular1);
    const VF lr = S(F.lightColor[0]), lg = S(F.lightColor[1]), lb = S(F.lightColor[2]);
    const VF r0 = Lit(cr, dif0, spec0, lr), g0 = Lit(cg, dif0, spec0, lg), b0 = Lit(cb, dif0, spec0, lb);
    ar = hn::IfThenElse(shaded, cr, r0), ag = hn::IfThenElse(shaded, cg, g0), ab = hn::IfThenElse(shaded, cb, b0);
    dcx = hn::IfThenElseZero(hn::Not(shaded), hn::Sub(Lit(cr, dif1, spec1, lr), r0));
    dcy = hn::IfThenElseZero(hn::Not(shaded), hn::Sub(Lit(cg, dif1, spec1, lg), g0));
    dcz = hn::IfThenElseZero(hn::Not(shaded), hn::Sub(Lit(cb, dif1, spec1, lb), b0));
  }
  St(ar, B.ar), St(ag, B.ag), St(ab, B.ab), St(dcx, B.dcx), St(dcy, B.dcy), St(dcz, B.dcz);
}

// Stages 1-6 over lanes [0, n) of camera-space input (SegmentCull's compacted lanes).
void SegmentSetup(const SegmentSetupFrame& F, SegmentSetupBatch& B, int n) {
  const PointSetupFrame& V = F.view;
  using DF = hn::ScalableTag<float>;
  using VF = hn::Vec<DF>;
  using MF = hn::Mask<DF>;
  using DI = hn::RebindToSigned<DF>;
  const DF d;
  const DI di;
  const int lanes = int(hn::Lanes(d));
  const VF zero = hn::Zero(d), one = hn::Set(d, 1.0f), half = hn::Set(d, 0.5f);
  auto S = [&](float v) { return hn::Set(d, v); };
  auto dot3 = [](VF ax, VF ay, VF az, VF bx, VF by, VF bz) { return hn::MulAdd(ax, bx, hn::MulAdd(ay, by, hn::Mul(az, bz))); };
  const VF f = S(V.f), R = S(V.cutoff), Vh = S(V.prefilter);
  for (int i = 0; i < n; i += lanes) {
    auto L = [&](const float* a) { return hn::LoadU(d, a + i); };
    auto St = [&](VF v, float* a) { hn::StoreU(v, d, a + i); };
    const VF px0 = L(B.p0x), py0 = L(B.p0y), pz0 = L(B.p0z), px1 = L(B.p1x), py1 = L(B.p1y), pz1 = L(B.p1z);
    const VF wx = L(B.wx), wy = L(B.wy), wz = L(B.wz), rad = L(B.radius);
    // stage 1: the strip (the batch holds camera-space input, rounded as Camera::toCamera rounds
    // for the exact path: a short segment far away gets its direction, not one of other rounding)
    const VF cx = px0, cy = py0, cz = pz0, qx1 = px1, qy1 = py1, qz1 = pz1;
    const Strip<DF> st = StripOf(d, F, cx, cy, cz, qx1, qy1, qz1, wx, wy, wz, rad);
    const VF len = st.len, iL = st.iL, ex = st.ex, ey = st.ey, ez = st.ez, zmin = st.zmin;
    const VF nx = st.nx, ny = st.ny, nz = st.nz, D = st.D;
    const MF badInput = st.badInput, outside = st.outside, culled = st.culled;
    MF early = st.early;
    // near grazing at an end: the float covariance is not accurate enough there
    const VF end2 = hn::Max(dot3(cx, cy, cz, cx, cy, cz), dot3(qx1, qy1, qz1, qx1, qy1, qz1));
    MF exact = hn::Lt(hn::Mul(D, D), hn::Mul(S(4e-4f), end2));
    const VF sx = hn::MulSub(ey, nz, hn::Mul(ez, ny)), sy = hn::MulSub(ez, nx, hn::Mul(ex, nz)),
             sz = hn::MulSub(ex, ny, hn::Mul(ey, nx));
    // stage 2: the resampling covariance (segment::covariance) at both ends and the middle
    const VF sigma = hn::Mul(S(V.reconstructionScale), rad), s2 = hn::Mul(sigma, sigma);
    const VF hiX = hn::Mul(S(kMaxStretch * kMaxStretch), s2);
    using Cov = SegmentCov<VF>;
    const SegmentCovariance<DF> cov{d, V, f, Vh, s2, hiX, ex, ey, ez, sx, sy, sz};
    const Cov M0 = cov(cx, cy, cz, exact);
    const Cov M1 = cov(qx1, qy1, qz1, exact);
    Cov Mm{hn::Mul(half, hn::Add(M0.a, M1.a)), hn::Mul(half, hn::Add(M0.b, M1.b)), hn::Mul(half, hn::Add(M0.c, M1.c)), zero};
    Mm.det = hn::MulSub(Mm.a, Mm.c, hn::Mul(Mm.b, Mm.b));  // the mean's (Mat2d::determinant)
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
      Mm.c = hn::IfThenElse(isShort, Mm.c, Mc.c), Mm.det = hn::IfThenElse(isShort, Mm.det, Mc.det);
    }
    const VF limit = hn::Mul(S(kPieceTolerance2), hn::Min(norm2(M0.a, M0.b, M0.c), norm2(M1.a, M1.b, M1.c)));
    // the sub-segment count K = ceil(change / (kPieceTolerance scale)) (prepareSegment's stage 2);
    // within 2% of an integer ceil() (rounding could decide it), or beyond kBatchPieces, the exact
    // path decides
    const VF ratio = hn::Sqrt(hn::Div(change2, limit));
    const VF near = hn::Round(ratio);
    exact = hn::Or(exact, hn::And(hn::Ge(near, one), hn::Lt(hn::Abs(hn::Sub(ratio, near)), S(0.02f))));
    exact = hn::Or(exact, hn::Not(hn::Lt(ratio, S(float(kBatchPieces)))));
    const VF K = hn::Max(hn::Ceil(hn::Min(ratio, S(float(kBatchPieces)))), one);
    const MF multi = hn::Gt(K, one);
    // the first piece (segment::makePiece) over [0, L] (K = 1) with the middle's covariance
    const VF detm = hn::MulSub(Mm.a, Mm.c, hn::Mul(Mm.b, Mm.b));
    const VF ic = hn::Div(one, Mm.c);
    VF invM00 = hn::Mul(detm, ic);
    VF pieceReach = hn::Mul(R, hn::Sqrt(Mm.a));
    VF scale0 = hn::Div(one, hn::Mul(rad, hn::Sqrt(M0.det)));
    const VF scale1 = hn::Div(one, hn::Mul(rad, hn::Sqrt(M1.det)));
    VF slope = hn::Mul(hn::Sub(scale1, scale0), iL);
    slope = hn::IfThenElseZero(hn::Gt(hn::Mul(hn::Abs(slope), len), hn::Mul(S(1e-4f), scale0)), slope);
    VF skew = hn::Neg(hn::Mul(Mm.b, ic)), across = ic;
    VF aMin = hn::Neg(pieceReach), aMax = hn::Add(len, pieceReach), bMax = hn::Mul(R, hn::Sqrt(Mm.c));
    if (!hn::AllFalse(d, hn::AndNot(exact, hn::And(multi, active))))
      SegmentPieces(d, B, i, cov, R, rad, len, iL, K, multi, active, cx, cy, cz, ex, ey, ez, M0, M1, Mm, exact, skew,
                    across, invM00, scale0, slope, aMin, aMax, bMax);
    St(K, B.pieceCount);
    St(skew, B.skew), St(across, B.across), St(invM00, B.invM00);
    St(hn::Sqrt(hn::Div(half, invM00)), B.k), St(hn::Sqrt(hn::Mul(S(0.5f * float(std::numbers::pi)), invM00)), B.erfScale);
    St(scale0, B.scale0), St(slope, B.slope);
    St(aMin, B.aMin), St(aMax, B.aMax), St(bMax, B.bMax), St(len, B.length);
    // stage 4: the footprint box between the near and far planes, projected (SegmentScreenBox)
    MF cut, empty;
    SegmentScreenBox(d, F, B, i, f, cx, cy, cz, ex, ey, ez, sx, sy, sz, aMin, aMax, bMax, exact, cut, empty);
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
    if (F.z.perPrimitive) St(hn::Mul(S(F.z.scale), extent(M0)), B.zt0), St(hn::Mul(S(F.z.scale), extent(M1)), B.zt1);
    else St(S(F.z.fixed), B.zt0), St(S(F.z.fixed), B.zt1);
    St(hn::Mul(S(kTailDisc), hn::Mul(R, sigma)), B.tailB);
    St(qx1, B.p1cx), St(qy1, B.p1cy), St(qz1, B.p1cz);
    // stage 6: shading normals (smooth: the endpoint normals on the plane normal's side) and Phong
    VF n0x = nx, n0y = ny, n0z = nz, n1x = nx, n1y = ny, n1z = nz;
    MF sm = hn::Lt(one, zero), turning = sm;
    VF stations = S(-1.0f);
    if (F.smoothFrame)
      SegmentSmoothNormals(d, F, B, i, nx, ny, nz, n0x, n0y, n0z, n1x, n1y, n1z, sm, turning, stations, exact);
    // shade Stations: turning, or K > 1 sub-segments with Gouraud colours (at least K intervals:
    // prepareSegment's stage 6)
    MF shaded = turning;
    if (!F.perPixelLighting) {
      shaded = hn::Or(turning, multi);
      stations = hn::IfThenElse(multi, hn::Max(stations, K), stations);
    }
    St(n0x, B.n0x), St(n0y, B.n0y), St(n0z, B.n0z), St(n1x, B.n1x), St(n1y, B.n1y), St(n1z, B.n1z);
    St(hn::Sub(n1x, n0x), B.dnx), St(hn::Sub(n1y, n0y), B.dny), St(hn::Sub(n1z, n0z), B.dnz);
    St(stations, B.stations);
    SegmentEndColours(d, F, B, i, n0x, n0y, n0z, n1x, n1y, n1z, cx, cy, cz, qx1, qy1, qz1, shaded);
    SegmentFlags(d, F, B, i, shaded, sm, stations);
    const VF status = hn::IfThenElse(empty, S(4.0f), hn::IfThenElseZero(cut, S(3.0f)));
    const VF two = S(2.0f);
    St(hn::IfThenElse(badInput, two, hn::IfThenElse(outside, S(4.0f), hn::IfThenElse(early, two,
        hn::IfThenElse(culled, one, hn::IfThenElse(exact, two, status))))), B.status);
    // the interior stations of the drawn lanes with two or more intervals (see docs/decisions.md, "Segment prepare"):
    // lane t's jobs (one per station) at [jobFirst[t], jobFirst[t + 1]) of this vector's, lit below
    const MF drawn = hn::AndNot(hn::Or(hn::Or(hn::Or(badInput, outside), hn::Or(early, culled)), hn::Or(exact, empty)), active);
    const VF jobLanes = hn::IfThenElse(drawn, stations, S(-1.0f));
    B.groupJobs[i / lanes] = 0;
    if (F.light && !hn::AllFalse(d, hn::Ge(jobLanes, two))) {
      alignas(64) int32_t count[kMaxLanes];
      hn::Store(hn::ConvertTo(di, hn::Max(hn::Sub(jobLanes, one), zero)), di, count);
      int32_t* first = B.jobFirst + i;
      for (int t = 0, at = 0; t < lanes; ++t) first[t] = at, at += count[t];
      const int jobs = first[lanes - 1] + count[lanes - 1];
      hn::StoreU(hn::Add(hn::LoadU(di, first), hn::Set(di, B.stationJobs)), di, B.stationJob + i);
      St(jobLanes, B.jobIntervals);
      B.groupJobs[i / lanes] = jobs, B.groupBase[i / lanes] = B.stationJobs;
      B.stationJobs += jobs;
    }
  }
  if (F.light && B.stationJobs > 0) SegmentStationColours(F, B, n);
}

// The records' images (lane-major in 16-byte chunks) from the batch arrays and the template.
void SegmentRecords(const SegmentSetupFrame& F, SegmentSetupBatch& B, int n) {
  using DF = hn::ScalableTag<float>;
  const DF d;
  const hn::RebindToUnsigned<DF> du;
  const std::array<int32_t, kRecordSlots>& src = recordSources();
  const char* base = reinterpret_cast<const char*>(&B);
  const int lanes = int(hn::Lanes(d));
  for (int i = 0; i < n; i += lanes) {
    // no record for a vector of segments not drawn (culled, outside, for the exact path)
    const hn::Vec<DF> status = hn::LoadU(d, B.status + i);
    if (hn::AllFalse(d, hn::Or(hn::Eq(status, hn::Zero(d)), hn::Eq(status, hn::Set(d, 3.0f))))) continue;
    for (int c = 0; c < kRecordChunks; ++c) {
      hn::Vec<DF> v[4];
      for (int k = 0; k < 4; ++k) {
        const int s = 4 * c + k;
        v[k] = src[s] >= 0 ? hn::LoadU(d, reinterpret_cast<const float*>(base + src[s]) + i)
                           : hn::BitCast(d, hn::Set(du, F.record.word[s]));
      }
      hn::StoreInterleaved4(v[0], v[1], v[2], v[3], d, B.rec[c] + 4 * i);
    }
  }
}

}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(SegmentCull);
HWY_EXPORT(SegmentSetup);
HWY_EXPORT(SegmentRecords);
int segmentCull(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n) {
  return HWY_DYNAMIC_DISPATCH(SegmentCull)(frame, batch, n);
}
void segmentSetup(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n) {
  HWY_DYNAMIC_DISPATCH(SegmentSetup)(frame, batch, n);
}
void segmentRecords(const SegmentSetupFrame& frame, SegmentSetupBatch& batch, int n) {
  HWY_DYNAMIC_DISPATCH(SegmentRecords)(frame, batch, n);
}
}  // namespace linesurf::detail

#endif  // HWY_ONCE
