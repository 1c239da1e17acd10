// The segment splat approximation of thesis §5.2.3 (segment_approx.h): the weight textures T1 and
// T2 (§5.2.3.2), the bounding quadrilaterals of a segment (§5.2.3.1) and their weights with the
// interpolated scaling factor (§5.2.3.3). See docs/segment-splatting.md.
#include "segment_approx.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>

namespace linesurf {

namespace segment {

namespace {

// --- weight textures (§5.2.3.2) --------------------------------------------------------------

// Closed forms, in this project's weight units (no 1/(2 pi)): the cut-off unit Gaussian
// integrated over t in [0, inf) at (x - t, y), and over all t.
double t1Exact(double R, double x, double y) {
  if (std::abs(y) >= R) return 0;
  const double w = std::sqrt(R * R - y * y);
  const double xc = std::clamp(x, -w, w);
  return std::sqrt(std::numbers::pi / 2) * std::exp(-0.5 * y * y) * (std::erf(w / std::sqrt(2.0)) + std::erf(xc / std::sqrt(2.0)));
}
double t2Exact(double R, double y) {
  if (std::abs(y) >= R) return 0;
  const double w = std::sqrt(R * R - y * y);
  return std::sqrt(2 * std::numbers::pi) * std::exp(-0.5 * y * y) * std::erf(w / std::sqrt(2.0));
}

}  // namespace

/// §5.2.3.2 tables for one cutoff radius: T1 on a (N+1) x (N/2+1) grid over [-R, R] x [0, R],
/// T2 on N/2+1 samples over [0, R]; bilinear lookups, symmetric in y.
struct WeightTextures {
  float R = 0;
  static constexpr int nx = kWeightTextureSize, ny = kWeightTextureSize / 2;
  std::vector<float> t1, t2;
  explicit WeightTextures(float cutoff) : R(cutoff), t1(size_t(nx + 1) * (ny + 1)), t2(ny + 1) {
    for (int j = 0; j <= ny; ++j) {
      const double y = double(R) * j / ny;
      t2[j] = float(t2Exact(R, y));
      for (int i = 0; i <= nx; ++i) t1[size_t(j) * (nx + 1) + i] = float(t1Exact(R, -double(R) + 2.0 * R * i / nx, y));
    }
  }
  float lookupT1(float x, float y) const {
    y = std::abs(y);
    if (y >= R || x <= -R) return 0;
    if (x >= R) return lookupT2(y);
    const float fx = (x + R) / (2 * R) * nx, fy = y / R * ny;
    const int i = std::min(int(fx), nx - 1), j = std::min(int(fy), ny - 1);
    const float u = fx - i, v = fy - j;
    const float* r0 = t1.data() + size_t(j) * (nx + 1) + i;
    const float* r1 = r0 + (nx + 1);
    return (1 - v) * ((1 - u) * r0[0] + u * r0[1]) + v * ((1 - u) * r1[0] + u * r1[1]);
  }
  float lookupT2(float y) const {
    y = std::abs(y);
    if (y >= R) return 0;
    const float fy = y / R * ny;
    const int j = std::min(int(fy), ny - 1);
    const float v = fy - j;
    return (1 - v) * t2[j] + v * t2[j + 1];
  }
};

namespace {

// One table per cutoff radius for the life of the program (a handful at most).
const WeightTextures* weightTextures(float R) {
  thread_local const WeightTextures* last = nullptr;
  if (last && last->R == R) return last;
  static std::mutex mutex;
  static std::map<float, std::unique_ptr<WeightTextures>> cache;
  std::lock_guard<std::mutex> lock(mutex);
  auto& slot = cache[R];
  if (!slot) slot = std::make_unique<WeightTextures>(R);
  last = slot.get();
  return last;
}

// --- the Approx construction (§5.2.3.1) ------------------------------------------------------

double cross2(const Vec2dd& a, const Vec2dd& b) { return a.x() * b.y() - a.y() * b.x(); }

// Intersection of the lines n1.u = k1 and n2.u = k2; false when (nearly) parallel.
bool intersectLines(const Vec2dd& n1, double k1, const Vec2dd& n2, double k2, Vec2dd& out) {
  const double det = cross2(n1, n2);
  if (!(std::abs(det) > 1e-9 * n1.norm() * n2.norm())) return false;
  out = Vec2dd((k1 * n2.y() - k2 * n1.y()) / det, (n1.x() * k2 - n2.x() * k1) / det);
  return out.allFinite();
}

struct ApproxInput {
  Mat2d A0, A1;  // cutoff ellipses R^2 M_k, (a, b) coordinates, centres (0,0) and (L,0)
  Mat2d M0, M1;
  double L = 0, R = 0, h = 0;
};

// Root of f on [lo, hi] with f(lo), f(hi) of opposite signs (Illinois false position).
template <class F>
double bracketRoot(F&& f, double lo, double hi, double flo, double fhi) {
  int side = 0;
  double x = lo;
  for (int it = 0; it < 80; ++it) {
    x = fhi != flo ? (lo * fhi - hi * flo) / (fhi - flo) : 0.5 * (lo + hi);
    if (!(x > std::min(lo, hi) && x < std::max(lo, hi))) x = 0.5 * (lo + hi);
    const double fx = f(x);
    if (fx == 0 || std::abs(hi - lo) < 1e-13) break;
    if ((fx > 0) == (fhi > 0)) {
      hi = x;
      fhi = fx;
      if (side == -1) flo *= 0.5;
      side = -1;
    } else {
      lo = x;
      flo = fx;
      if (side == 1) fhi *= 0.5;
      side = 1;
    }
  }
  return x;
}

// Builds the 10 (long) or 8 (short) quadrilaterals; false when the construction is unsound
// (the caller then falls back to the ScreenSpace evaluation and counts it).
bool buildQuads(const ApproxInput& in, std::vector<SegmentQuad>& quads, bool& longCase) {
  const double L = in.L, R = in.R;
  const Vec2dd c0(0, 0), c1(L, 0);
  auto support = [&](const Mat2d& A, const Vec2dd& n) { return std::sqrt(std::max(0.0, n.dot(A * n))); };
  // Outer common tangents (points 1-4): lines n.u = k supporting both ellipses, both on the
  // side n.u <= k: f(phi) = h1(n) - h0(n) = L cos(phi) + s1(n) - s0(n) = 0 (n = (cos, sin)).
  auto f = [&](double phi) {
    const Vec2dd n(std::cos(phi), std::sin(phi));
    return L * n.x() + support(in.A1, n) - support(in.A0, n);
  };
  const double f0 = f(0), fpi = f(std::numbers::pi);
  // One ellipse reaches past the other at both ends of the axis (nested along the axis).
  if (!(f0 > 1e-9 * L && fpi < -1e-9 * L)) return false;
  const double phiT = bracketRoot(f, 0.0, std::numbers::pi, f0, fpi);
  const double phiB = bracketRoot(f, std::numbers::pi, 2 * std::numbers::pi, fpi, f0);
  const Vec2dd nT(std::cos(phiT), std::sin(phiT)), nB(std::cos(phiB), std::sin(phiB));
  const double kT = support(in.A0, nT), kB = support(in.A0, nB);
  auto touch = [&](const Mat2d& A, const Vec2dd& c, const Vec2dd& n) -> Vec2dd { return c + A * n / support(A, n); };
  const Vec2dd p1 = touch(in.A0, c0, nT), p2 = touch(in.A1, c1, nT), p3 = touch(in.A1, c1, nB), p4 = touch(in.A0, c0, nB);
  if (!(p1.y() > 0 && p2.y() > 0 && p3.y() < 0 && p4.y() < 0)) return false;
  // Points 9, 10: the crossing lines 1-4 and 2-3 meet the axis b = 0.
  const double a9 = p1.x() + (p4.x() - p1.x()) * p1.y() / (p1.y() - p4.y());
  const double a10 = p2.x() + (p3.x() - p2.x()) * p2.y() / (p2.y() - p3.y());
  // Points 5-8: the axis meets the ellipses at c_k +- rho_k, rho_k = 1 / sqrt((A_k^-1)_aa).
  const Mat2d A0i = inverse2(in.A0), A1i = inverse2(in.A1);
  const double rho0 = 1 / std::sqrt(A0i(0, 0)), rho1 = 1 / std::sqrt(A1i(0, 0));
  const double a5 = -rho0, a6 = rho0, a7 = L - rho1, a8 = L + rho1;
  if (!(a5 < a9 && a9 < a6 && a7 < a10 && a10 < a8 && a9 < a10)) return false;
  // Tangent lines at the axis points (11-18): normal A^-1 (P - c) = +-(A^-1)_{.,0}.
  const Vec2dd t0(A0i(0, 0), A0i(1, 0)), t1(A1i(0, 0), A1i(1, 0));
  Vec2dd q11, q12, q13, q14, q15, q16, q17, q18;
  auto meet = [&](const Vec2dd& tn, double a, Vec2dd& top, Vec2dd& bottom) {
    const double k = tn.x() * a;  // the tangent line passes through (a, 0)
    return intersectLines(tn, k, nT, kT, top) && intersectLines(tn, k, nB, kB, bottom);
  };
  if (!meet(t0, a5, q11, q18) || !meet(t0, a6, q12, q17) || !meet(t1, a7, q13, q16) || !meet(t1, a8, q14, q15))
    return false;
  // Order along the top line (direction (sin, -cos) of nT) and the bottom one.
  const Vec2dd dT(nT.y(), -nT.x()), dB(-nB.y(), nB.x());
  auto ordered = [](std::initializer_list<double> v) {
    double prev = -std::numeric_limits<double>::infinity();
    for (double x : v) {
      if (!(x >= prev)) return false;
      prev = x;
    }
    return true;
  };
  if (!ordered({dT.dot(q11), dT.dot(p1), dT.dot(q12)}) || !ordered({dT.dot(q13), dT.dot(p2), dT.dot(q14)}) ||
      !ordered({dB.dot(q18), dB.dot(p4), dB.dot(q17)}) || !ordered({dB.dot(q16), dB.dot(p3), dB.dot(q15)}))
    return false;
  longCase = a6 < a7 && dT.dot(q12) <= dT.dot(q13) && dB.dot(q17) <= dB.dot(q16);
  double am = 0;  // short case: where the separating line meets the axis
  if (!longCase) {
    // The line through the ellipses' intersection points: walk E0's boundary from point 6
    // (inside E1 in the short case) up to 5 and down to 5, finding where it leaves E1.
    const Mat2d M0h = [&] {  // A0^(1/2): the boundary is c0 + A0^(1/2) (cos, sin)
      Eigen::SelfAdjointEigenSolver<Mat2d> es(in.A0);
      return Mat2d(es.eigenvectors() * es.eigenvalues().cwiseMax(0).cwiseSqrt().asDiagonal() *
                   es.eigenvectors().transpose());
    }();
    const Mat2d M0hi = inverse2(M0h);
    auto g = [&](double th) {
      const Vec2dd u = M0h * Vec2dd(std::cos(th), std::sin(th)) - c1;
      return u.dot(A1i * u) - 1;
    };
    const Vec2dd y6 = M0hi * Vec2dd(a6, 0);
    const double th6 = std::atan2(y6.y(), y6.x());
    const double g6 = g(th6), g5 = g(th6 + std::numbers::pi);
    if (!(g6 < 0 && g5 > 0)) return false;
    const double thT = bracketRoot(g, th6, th6 + std::numbers::pi, g6, g5);
    const double thB = bracketRoot(g, th6, th6 - std::numbers::pi, g6, g5);
    const Vec2dd xT = M0h * Vec2dd(std::cos(thT), std::sin(thT)), xB = M0h * Vec2dd(std::cos(thB), std::sin(thB));
    if (!(xT.y() > 0 && xB.y() < 0)) return false;
    const Vec2dd dir = xT - xB;
    const Vec2dd sn(dir.y(), -dir.x());  // separating line sn.u = sn.xT
    const double ks = sn.dot(xT);
    Vec2dd m;
    if (!intersectLines(sn, ks, Vec2dd(0, 1), 0, m) || !intersectLines(sn, ks, nT, kT, q12) ||
        !intersectLines(sn, ks, nB, kB, q17))
      return false;
    am = m.x();
    q13 = q12;
    q16 = q17;
    if (!(a9 < am && am < a10)) return false;
    if (!ordered({dT.dot(q11), dT.dot(p1), dT.dot(q12), dT.dot(p2), dT.dot(q14)}) ||
        !ordered({dB.dot(q18), dB.dot(p4), dB.dot(q17), dB.dot(p3), dB.dot(q15)}))
      return false;
  }
  const double a6m = longCase ? a6 : am, a7m = longCase ? a7 : am;
  // Weight scaling (§5.2.3.3, Figure 19): 1 / (h r0 r1 lambda) at points 9 and 10, lambda the
  // texture units per object length along the axis (the thesis omits it: docs/decisions.md),
  // linear along the axis and constant across it.
  const double lam0 = R / (a6 - a9), lam1 = R / (a10 - a7);
  const double s9 = 1 / (in.h * std::sqrt(in.M0.determinant()) * lam0);
  const double s10 = 1 / (in.h * std::sqrt(in.M1.determinant()) * lam1);
  const double sMin = 0.25 * std::min(s9, s10);
  auto scaleAt = [&](double a) { return float(std::max(sMin, s9 + (s10 - s9) * (a - a9) / (a10 - a9))); };
  // Texture coordinates: x inward from the endpoint (9 -> 0, 6 -> R; 10 -> 0, 7 -> R), y across.
  const float Rf = float(R);
  const float xs0 = float(R * (a6m - a9) / (a6 - a9)), xs1 = float(R * (a10 - a7m) / (a10 - a7));
  const float tail0 = float(R * (a10 - a9) / (a6 - a9)), tail1 = float(R * (a10 - a9) / (a10 - a7));
  const Vec2dd p5(a5, 0), p6(a6m, 0), p7(a7m, 0), p8(a8, 0), p9(a9, 0), p10(a10, 0);
  const float s5 = scaleAt(a5), s6 = scaleAt(a6m), s7 = scaleAt(a7m), s8 = scaleAt(a8), sc9 = scaleAt(a9),
              sc10 = scaleAt(a10);
  quads.clear();
  auto add = [&](std::array<Vec2dd, 4> c, std::array<Vec2f, 4> t, std::array<float, 4> s, bool middle, float tail) {
    SegmentQuad q;
    for (int i = 0; i < 4; ++i) {
      q.corner[i] = c[i].cast<float>();
      q.tex[i] = t[i];
      q.scale[i] = s[i];
    }
    q.middle = middle;
    q.tail = tail;
    q.lo = q.corner[0].cwiseMin(q.corner[1]).cwiseMin(q.corner[2]).cwiseMin(q.corner[3]);
    q.hi = q.corner[0].cwiseMax(q.corner[1]).cwiseMax(q.corner[2]).cwiseMax(q.corner[3]);
    quads.push_back(q);
  };
  // endpoint 0 (quads 11-1-9-5, 1-12-6-9, 5-9-4-18, 9-6-17-4)
  add({p5, p9, p1, q11}, {Vec2f(-Rf, 0), Vec2f(0, 0), Vec2f(0, Rf), Vec2f(-Rf, Rf)}, {s5, sc9, sc9, s5}, false, tail0);
  add({p9, p6, q12, p1}, {Vec2f(0, 0), Vec2f(xs0, 0), Vec2f(xs0, Rf), Vec2f(0, Rf)}, {sc9, s6, s6, sc9}, false, tail0);
  add({q18, p4, p9, p5}, {Vec2f(-Rf, -Rf), Vec2f(0, -Rf), Vec2f(0, 0), Vec2f(-Rf, 0)}, {s5, sc9, sc9, s5}, false, tail0);
  add({p4, q17, p6, p9}, {Vec2f(0, -Rf), Vec2f(xs0, -Rf), Vec2f(xs0, 0), Vec2f(0, 0)}, {sc9, s6, s6, sc9}, false, tail0);
  // endpoint 1 (mirrored: x grows towards endpoint 0)
  add({p7, p10, p2, q13}, {Vec2f(xs1, 0), Vec2f(0, 0), Vec2f(0, Rf), Vec2f(xs1, Rf)}, {s7, sc10, sc10, s7}, false, tail1);
  add({p10, p8, q14, p2}, {Vec2f(0, 0), Vec2f(-Rf, 0), Vec2f(-Rf, Rf), Vec2f(0, Rf)}, {sc10, s8, s8, sc10}, false, tail1);
  add({q16, p3, p10, p7}, {Vec2f(xs1, -Rf), Vec2f(0, -Rf), Vec2f(0, 0), Vec2f(xs1, 0)}, {s7, sc10, sc10, s7}, false, tail1);
  add({p3, q15, p8, p10}, {Vec2f(0, -Rf), Vec2f(-Rf, -Rf), Vec2f(-Rf, 0), Vec2f(0, 0)}, {sc10, s8, s8, sc10}, false, tail1);
  if (longCase) {  // middle portion 12-13-16-17, split by the axis
    add({p6, p7, q13, q12}, {Vec2f(0, 0), Vec2f(0, 0), Vec2f(0, Rf), Vec2f(0, Rf)}, {s6, s7, s7, s6}, true, 1e30f);
    add({q17, q16, p7, p6}, {Vec2f(0, -Rf), Vec2f(0, -Rf), Vec2f(0, 0), Vec2f(0, 0)}, {s6, s7, s7, s6}, true, 1e30f);
  }
  // Sanity: finite, inside a generous box, each quad convex and consistently oriented (or flat).
  const double box = L + 4 * (rho0 + rho1) + 4 * (kT + kB);
  for (const SegmentQuad& q : quads) {
    double signs = 0;
    for (int i = 0; i < 4; ++i) {
      const Vec2f& c = q.corner[i];
      if (!c.allFinite() || std::abs(c.x()) > box + L || std::abs(c.y()) > box) return false;
      const Vec2f e1 = q.corner[(i + 1) % 4] - c, e2 = q.corner[(i + 2) % 4] - q.corner[(i + 1) % 4];
      const double cr = double(e1.x()) * e2.y() - double(e1.y()) * e2.x();
      if (cr * signs < -1e-9 * box * box) return false;
      if (std::abs(cr) > 1e-12 * box * box) signs = cr;
    }
  }
  return true;
}

// Inverse of the bilinear map of a quad (corners 00, 10, 11, 01): (alpha, beta) in [0, 1]^2
// with P = bilinear(alpha, beta); false when p is outside.
bool inverseBilinear(const SegmentQuad& q, const Vec2f& p, float& alpha, float& beta) {
  const Vec2f& a = q.corner[0];
  const Vec2f e = q.corner[1] - a, f = q.corner[3] - a, g = a - q.corner[1] + q.corner[2] - q.corner[3], h = p - a;
  auto cr = [](const Vec2f& u, const Vec2f& v) { return u.x() * v.y() - u.y() * v.x(); };
  const float k2 = cr(g, f), k1 = cr(e, f) + cr(h, g), k0 = cr(h, e);
  const float tol = 1e-4f;
  auto tryV = [&](float v) {
    if (!(v >= -tol && v <= 1 + tol)) return false;
    const Vec2f den = e + g * v;
    const float dd = den.squaredNorm();
    if (!(dd > 0)) return false;
    const float u = (h - f * v).dot(den) / dd;
    if (!(u >= -tol && u <= 1 + tol)) return false;
    alpha = std::clamp(u, 0.0f, 1.0f);
    beta = std::clamp(v, 0.0f, 1.0f);
    return true;
  };
  const float scale = std::abs(k1) + std::abs(k0) + 1e-30f;
  if (std::abs(k2) < 1e-6f * scale) {  // parallelogram-like: linear in v
    if (k1 == 0) return false;
    return tryV(-k0 / k1);
  }
  float w = k1 * k1 - 4 * k0 * k2;
  if (w < 0) return false;
  w = std::sqrt(w);
  const float ik2 = 0.5f / k2;
  return tryV((-k1 - w) * ik2) || tryV((-k1 + w) * ik2);
}

}  // namespace

bool buildApprox(const Mat2d& M0, const Mat2d& M1, double L, double R, double h, SegmentExtra& x, double& aMin,
                 double& aMax, double& bMax) {
  ApproxInput in;
  in.M0 = M0;
  in.M1 = M1;
  in.A0 = R * R * M0;
  in.A1 = R * R * M1;
  in.L = L;
  in.R = R;
  in.h = h;
  if (!buildQuads(in, x.quads, x.longCase)) {
    x.quads.clear();
    return false;
  }
  x.textures = weightTextures(float(R));
  double qa0 = 0, qa1 = L, qb = 0;
  for (const SegmentQuad& q : x.quads)
    for (const Vec2f& c : q.corner) {
      qa0 = std::min(qa0, double(c.x()));
      qa1 = std::max(qa1, double(c.x()));
      qb = std::max(qb, double(std::abs(c.y())));
    }
  aMin = qa0;
  aMax = qa1;
  bMax = qb;
  return true;
}

float approxWeight(const SegmentExtra& x, float a, float b) {
  const Vec2f p(a, b);
  for (const SegmentQuad& q : x.quads) {
    if (a < q.lo.x() || a > q.hi.x() || b < q.lo.y() || b > q.hi.y()) continue;
    float al, be;
    if (!inverseBilinear(q, p, al, be)) continue;
    auto bil = [&](auto v0, auto v1, auto v2, auto v3) {
      return (1 - be) * ((1 - al) * v0 + al * v1) + be * ((1 - al) * v3 + al * v2);
    };
    const Vec2f t = bil(q.tex[0], q.tex[1], q.tex[2], q.tex[3]);
    const float scale = bil(q.scale[0], q.scale[1], q.scale[2], q.scale[3]);
    const WeightTextures& T = *x.textures;
    const float tw = q.middle ? T.lookupT2(t.y()) : T.lookupT1(t.x(), t.y()) - T.lookupT1(t.x() - q.tail, t.y());
    return std::max(0.0f, tw) * scale;
  }
  return 0;
}

}  // namespace segment

float weightTextureT1(float cutoffRadius, float x, float y) { return segment::weightTextures(cutoffRadius)->lookupT1(x, y); }
float weightTextureT2(float cutoffRadius, float y) { return segment::weightTextures(cutoffRadius)->lookupT2(y); }


}  // namespace linesurf
