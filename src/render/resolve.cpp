// The resolve of a Z^3 tile's one-layer pixels in SIMD rows (thesis §6.2.3 step 2; resolve.h).
// Compiled once per x86 target (Google Highway); the best one the CPU runs is picked at run time.
#include "resolve.h"

#include <cmath>
#include <limits>

#include "silhouette_coverage.h"

#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "render/resolve.cpp"
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

// One row of the resolve, pixels with one layer (resolve.h): the formula of
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


}  // namespace HWY_NAMESPACE
}  // namespace linesurf::detail
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace linesurf::detail {
HWY_EXPORT(ResolveSingleLayerRow);

int resolveSingleLayerRow(Z3Tile& tile, int y, int x0, int n, const float* bg, float* out, bool& others, float* frontZ,
                          std::vector<SilhouettePixel>* cands) {
  return HWY_DYNAMIC_DISPATCH(ResolveSingleLayerRow)(tile, y, x0, n, bg, out, others, frontZ, cands);
}
}  // namespace linesurf::detail
#endif
