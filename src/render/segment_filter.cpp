// The segment filter of thesis §5.1 and its exact evaluations (segment_filter.h): the resampling
// covariance along a segment (§5.1.2), the ScreenSpace closed form per sub-segment, the Reference
// quadrature. See docs/segment-splatting.md.
#include "segment_filter.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace linesurf {

namespace segment {

// Reference quadrature: node spacing sigma_r / kNodesPerSigma, at most kMaxNodes nodes.
constexpr double kNodesPerSigma = 32.0;
constexpr int kMaxNodes = 1 << 16;

// Behind the eye the prefilter is dropped, as for point splats.
Mat2d resamplingCovariance(const Vec3d& p, const Vec3d& e, const Vec3d& s, double sigmaR, double Vh, double f) {
  const Sym2 M = covariance(p.data(), e.data(), s.data(), sigmaR, Vh, f);
  Mat2d out;
  out << M.a, M.b, M.b, M.c;
  return out;
}

namespace {

// erf from a table (4096 intervals over [0, 4], linear: error < 1e-6; erf(4) = 1 - 1.5e-8).
struct ErfTable {
  static constexpr int n = 4096;
  static constexpr float scale = n / 4.0f;
  float v[n + 2];
  ErfTable() {
    for (int i = 0; i <= n + 1; ++i) v[i] = float(std::erf(double(i) / scale));
  }
};
// Built at static initialisation (no guard check per lookup); only read while rendering.
const ErfTable kErfTable;
inline float fastErf(float x) {
  const ErfTable& T = kErfTable;
  const float ax = std::min(std::abs(x), 4.0f) * ErfTable::scale;
  const int i = int(ax);
  const float r = T.v[i] + (ax - float(i)) * (T.v[i + 1] - T.v[i]);
  return x < 0 ? -r : r;
}

}  // namespace

SegmentPiece makePiece(double a0, double a1, const Mat2d& M, const Mat2d& M0, const Mat2d& M1, double h, double R) {
  const Mat2d Mi = inverse2(M);
  SegmentPiece p;
  p.a0 = float(a0);
  p.a1 = float(a1);
  p.m00 = float(Mi(0, 0));
  p.m01 = float(Mi(0, 1));
  p.m11 = float(Mi(1, 1));
  p.scale0 = float(1 / (h * std::sqrt(M0.determinant())));
  p.scale1 = float(1 / (h * std::sqrt(M1.determinant())));
  p.reach = float(R * std::sqrt(M(0, 0)));
  p.skew = float(Mi(0, 1) / Mi(0, 0));
  p.across = float(Mi(1, 1) - Mi(0, 1) * Mi(0, 1) / Mi(0, 0));
  p.invM00 = float(1 / Mi(0, 0));
  p.k = float(std::sqrt(0.5 * Mi(0, 0)));
  p.erfScale = float(std::sqrt(std::numbers::pi) / 2 / std::sqrt(0.5 * Mi(0, 0)));
  const double slope = (double(p.scale1) - p.scale0) / (a1 - a0);
  p.slope = std::abs(slope) * (a1 - a0) > 1e-4 * p.scale0 ? float(slope) : 0.0f;
  return p;
}

// ScreenSpace: the cut-off Gaussian integrated along each sub-segment in closed form. With
// x = a - a0 - tau along and b across, q(tau) = m00 (x - tau)^2 + 2 m01 (x - tau) b + m11 b^2
// = m00 (tau - tau*)^2 + qmin; each kernel counts where q <= R^2, i.e. |tau - tau*| <= delta.
float screenSpaceWeight(const SegmentPiece* pieces, int K, float pieceInvLength, float pieceMaxReach, float a,
                        float b, float R2) {
  using detail::gaussHalf;
  float w = 0;
  // Only the pieces whose reach can contain a (with a piece of margin each side against
  // rounding): the others are skipped by the test below anyway, so the sum is unchanged.
  int k0 = 0, k1 = K;
  if (K > 1) {
    const float lo = std::floor((a - pieceMaxReach) * pieceInvLength);
    const float hi = std::floor((a + pieceMaxReach) * pieceInvLength);
    k0 = int(std::clamp(lo - 1.0f, 0.0f, float(K)));
    k1 = int(std::clamp(hi + 2.0f, 0.0f, float(K)));
  }
  for (int k = k0; k < k1; ++k) {
    const SegmentPiece& p = pieces[k];
    if (a < p.a0 - p.reach || a > p.a1 + p.reach) continue;
    const float len = p.a1 - p.a0;
    const float x = a - p.a0;
    const float tauStar = x + p.skew * b;
    const float qmin = b * b * p.across;
    if (!(qmin < R2)) continue;
    const float delta = std::sqrt((R2 - qmin) * p.invM00);
    const float t0 = std::max(0.0f, tauStar - delta), t1 = std::min(len, tauStar + delta);
    if (!(t1 > t0)) continue;
    const float u0 = p.k * (t0 - tauStar), u1 = p.k * (t1 - tauStar);
    // integral of exp(-m00 (tau - tau*)^2 / 2) (= sqrt(pi)/2 / k (erf(u1) - erf(u0))) and of
    // (tau - tau*) times it
    // exp(-qmin/2) exp(-u^2) = exp(-q/2) with q = qmin + 2 u^2 in [0, R^2]: table lookups
    const float i0 = p.erfScale * (fastErf(u1) - fastErf(u0));
    const detail::PieceScale sc = detail::pieceScale(p.scale0, p.slope, len);  // as the SIMD kernel
    float sum = (sc.scale0 + sc.slope * tauStar) * i0 * gaussHalf(qmin);
    if (sc.slope != 0) sum += sc.slope * p.invM00 * (gaussHalf(qmin + 2 * u0 * u0) - gaussHalf(qmin + 2 * u1 * u1));
    w += sum;
  }
  return w;
}

void referenceNodes(double L, double sigmaR, double h, double R, const Vec3d& c0, const Vec3d& e, const Vec3d& s,
                    double Vh, double f, SegmentExtra& x, double& aMin, double& aMax, double& bMax) {
  const double step0 = sigmaR / kNodesPerSigma;
  const int N = int(std::clamp(std::ceil(L / step0), 1.0, double(kMaxNodes)));
  const double step = L / N;
  x.nodes.resize(N);
  double maxEig = 0;
  for (int k = 0; k < N; ++k) {
    const Mat2d M = resamplingCovariance(c0 + (k + 0.5) * step * e, e, s, sigmaR, Vh, f);
    const Mat2d Mi = inverse2(M);
    SegmentNode& nd = x.nodes[k];
    nd.m00 = float(Mi(0, 0));
    nd.m01 = float(Mi(0, 1));
    nd.m11 = float(Mi(1, 1));
    nd.scale = float(step / (h * std::sqrt(M.determinant())));
    maxEig = std::max(maxEig, 0.5 * (M.trace() + std::sqrt(std::pow(M(0, 0) - M(1, 1), 2) + 4 * M(0, 1) * M(0, 1))));
    aMin = std::min(aMin, (k + 0.5) * step - R * std::sqrt(M(0, 0)));
    aMax = std::max(aMax, (k + 0.5) * step + R * std::sqrt(M(0, 0)));
    bMax = std::max(bMax, R * std::sqrt(M(1, 1)));
  }
  x.nodeStep = float(step);
  x.nodeReach = float(R * std::sqrt(maxEig));
}

float referenceWeight(const SegmentExtra& x, float a, float b, float R2) {
  const int N = int(x.nodes.size());
  const float step = x.nodeStep;
  const int k0 = std::max(0, int(std::floor((a - x.nodeReach) / step - 0.5f)));
  const int k1 = std::min(N - 1, int(std::ceil((a + x.nodeReach) / step - 0.5f)));
  double w = 0;
  for (int k = k0; k <= k1; ++k) {
    const SegmentNode& nd = x.nodes[k];
    const float dx = a - (float(k) + 0.5f) * step;
    const float q = nd.m00 * dx * dx + 2 * nd.m01 * dx * b + nd.m11 * b * b;
    if (q <= R2) w += double(std::exp(-0.5f * q) * nd.scale);
  }
  return float(w);
}

}  // namespace segment

}  // namespace linesurf
