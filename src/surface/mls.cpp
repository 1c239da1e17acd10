// The MLS surface of a point model (thesis §9.1; see surface/mls.h).
#include "linesurf/surface/mls.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>

#include "detail/point_tree.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf {
namespace {

using Cloud = detail::PointCloud;
using Tree = detail::PointTree;

/// A polynomial in the segment parameter s, degree < 12 (the integrands reach degree 10).
struct Poly {
  std::array<double, 12> c{};
  int degree = 0;
};
Poly operator*(const Poly& a, const Poly& b) {
  Poly r;
  r.degree = a.degree + b.degree;
  for (int i = 0; i <= a.degree; ++i)
    for (int j = 0; j <= b.degree; ++j) r.c[size_t(i + j)] += a.c[size_t(i)] * b.c[size_t(j)];
  return r;
}
Poly operator*(double k, Poly a) {
  for (int i = 0; i <= a.degree; ++i) a.c[size_t(i)] *= k;
  return a;
}
Poly operator+(Poly a, const Poly& b) {
  a.degree = std::max(a.degree, b.degree);
  for (int i = 0; i <= b.degree; ++i) a.c[size_t(i)] += b.c[size_t(i)];
  return a;
}
Poly linear(double c0, double c1) {
  Poly p;
  p.c[0] = c0, p.c[1] = c1, p.degree = 1;
  return p;
}
/// The integral of p over [a, b].
double integral(const Poly& p, double a, double b) {
  double r = 0, pa = a, pb = b;
  for (int k = 0; k <= p.degree; ++k, pa *= a, pb *= b) r += p.c[size_t(k)] * (pb - pa) / double(k + 1);
  return r;
}

}  // namespace

void validate(const MlsOptions& o) {
  requireRange("supportScale", o.supportScale, 1.5, 10);
  requireRange("maxIterations", o.maxIterations, 1, 1000);
  if (!(o.tolerance > 0 && o.tolerance <= 0.1f)) throwBadOption("tolerance", "must be in (0, 0.1]");
  requireRange("robustIterations", o.robustIterations, 1, 10);
  if (!(o.sigmaNormal > 0 && o.sigmaNormal <= 4)) throwBadOption("sigmaNormal", "must be in (0, 4]");
  if (!(o.sigmaResidual > 0 && o.sigmaResidual <= 10)) throwBadOption("sigmaResidual", "must be in (0, 10]");
}

struct MlsSurface::Impl {
  MlsOptions options;
  Cloud cloud;
  std::vector<Vec3d> normal;
  std::vector<double> area, h2;  ///< a_i, h_i^2
  double reach = 0;              ///< the largest h_i
  double medianSpacing = 0;
  /// Queries search the tree with `narrowReach` (the 90th percentile of h_i) and the few
  /// sources of a larger support in `wide` with `reach`: exact, with a fraction of the
  /// candidates one search with the largest support would visit on an uneven sampling.
  double narrowReach = 0;
  Cloud wideCloud;
  std::vector<uint32_t> wideIndex;
  std::unique_ptr<Tree> wide;
  std::unique_ptr<Tree> tree;
  /// Segment sources: endpoints, endpoint normals (the one normal twice without endpoint
  /// normals), strip weight per unit parameter (2 r L), h^2; a tree over their midpoints, queried
  /// with the support plus the longest half-length.
  struct SegmentSource {
    Vec3d p0, d, n0, n1;
    double weight = 0, h2 = 0;
  };
  std::vector<SegmentSource> segments;
  Cloud midpoints;
  std::unique_ptr<Tree> segmentTree;
  double segmentReach = 0;

  /// The sources whose support holds x, in index order (a sum's order independent of the tree).
  void inReach(const Vec3d& x, std::vector<std::pair<uint32_t, float>>& found) const {
    found.clear();
    if (!tree) return;
    const float q[3] = {float(x.x()), float(x.y()), float(x.z())};
    nanoflann::SearchParams params;
    params.sorted = false;
    tree->radiusSearch(q, float(narrowReach * narrowReach), found, params);
    if (wide) {
      // The wide sources found by the narrow search come again from the wide one.
      found.erase(std::remove_if(found.begin(), found.end(), [&](const auto& f) { return h2[f.first] > narrowReach * narrowReach; }),
                  found.end());
      thread_local std::vector<std::pair<uint32_t, float>> more;
      more.clear();
      wide->radiusSearch(q, float(reach * reach), more, params);
      for (const auto& [j, d2] : more) found.emplace_back(wideIndex[j], d2);
    }
    std::sort(found.begin(), found.end());
  }
};

MlsSurface::MlsSurface(const HybridModel& model, const MlsOptions& options) : impl_(std::make_unique<Impl>()) {
  validate(options);
  Impl& m = *impl_;
  m.options = options;
  const size_t n = model.points.size();
  if (n == 0 && model.segments.empty()) throwBadParameter("model", "has no points and no segments");
  if (n > 0 && !model.attributes.normals) throwBadParameter("model", "has no normals (an MLS surface needs oriented points)");
  for (size_t j = 0; j < model.segments.size(); ++j) {
    const Segment& sg = model.segments[j];
    if (!sg.p0.allFinite() || !sg.p1.allFinite() || !sg.normal.allFinite() || !(sg.radius > 0) || !std::isfinite(sg.radius))
      throwBadParameter("model", "segment " + std::to_string(j) + " has a non-finite endpoint or normal, or no radius");
  }
  for (size_t i = 0; i < n; ++i) {
    const Point& p = model.points[i];
    if (!p.position.allFinite() || !p.normal.allFinite() || std::abs(p.normal.squaredNorm() - 1.0f) > 1e-3f)
      throwBadParameter("model", "point " + std::to_string(i) + " has a non-finite position or a normal that is not unit");
  }
  // The spacing of §6.1 stage 5 (the file's normals kept, nothing else computed); a model of
  // segments alone takes its strips' half-widths for it.
  PointGeometry g;
  double medianSpacing = 0;
  if (n >= 2) {
    GeometryOptions go;
    go.orientNormals = go.delaunayNeighbours = go.curvature = go.coverRadius = false;
    if (model.segments.empty()) {
      g = computePointGeometry(model, go);
    } else {  // the points' spacing among themselves (the segments would widen the duplicate tolerance)
      HybridModel points;
      points.points = model.points;
      points.attributes = model.attributes;
      g = computePointGeometry(points, go);
    }
    std::vector<float> sorted(g.spacing);
    std::nth_element(sorted.begin(), sorted.begin() + ptrdiff_t(n / 2), sorted.end());
    medianSpacing = sorted[n / 2] > 0 ? sorted[n / 2] : g.averageSpacing;
  } else {
    g.spacing.assign(n, 0.0f);
  }
  if (!(medianSpacing > 0) && !model.segments.empty()) {
    std::vector<float> r;
    for (const Segment& sg : model.segments) r.push_back(sg.radius);
    std::nth_element(r.begin(), r.begin() + ptrdiff_t(r.size() / 2), r.end());
    medianSpacing = r[r.size() / 2];
  }
  if (!(medianSpacing > 0)) throwBadParameter("model", "has no spacing (coincident points)");
  m.medianSpacing = medianSpacing;
  m.cloud.pts.resize(n);
  m.normal.resize(n), m.area.resize(n), m.h2.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Point& p = model.points[i];
    m.cloud.pts[i] = p.position;
    m.normal[i] = p.normal.cast<double>();
    // An outlier's spacing is its distance to the surface, and the largest support is every
    // query's radius: 2 x the median bounds both.
    const double s = std::clamp(double(g.spacing[i]), 0.25 * medianSpacing, 2.0 * medianSpacing);
    const double h = double(options.supportScale) * s;
    m.h2[i] = h * h;
    m.reach = std::max(m.reach, h);
    const double r = p.radius > 0 ? double(p.radius) : s;
    m.area[i] = r * r;
  }
  if (n > 0) {
    m.tree = std::make_unique<Tree>(3, m.cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    m.tree->buildIndex();
    std::vector<double> h2(m.h2);
    std::nth_element(h2.begin(), h2.begin() + ptrdiff_t(9 * n / 10), h2.end());
    m.narrowReach = std::sqrt(h2[9 * n / 10]);
    for (size_t i = 0; i < n; ++i)
      if (m.h2[i] > m.narrowReach * m.narrowReach) m.wideCloud.pts.push_back(m.cloud.pts[i]), m.wideIndex.push_back(uint32_t(i));
    if (!m.wideIndex.empty()) {
      m.wide = std::make_unique<Tree>(3, m.wideCloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
      m.wide->buildIndex();
    }
  }
  // A segment is a strip of half-width r: its spacing across is about r, so its support is
  // supportScale x r (clamped as the points'); its weight per unit parameter is the strip's area.
  double longest = 0;
  for (const Segment& sg : model.segments) {
    Impl::SegmentSource src;
    src.p0 = sg.p0.cast<double>();
    src.d = (sg.p1 - sg.p0).cast<double>();
    const bool ends = model.attributes.endpointNormals && sg.normal0 != Vec3f::Zero() && sg.normal1 != Vec3f::Zero();
    src.n0 = (ends ? sg.normal0 : sg.normal).cast<double>().normalized();
    src.n1 = (ends ? sg.normal1 : sg.normal).cast<double>().normalized();
    const double r = std::clamp(double(sg.radius), 0.25 * medianSpacing, 2.0 * medianSpacing);
    const double h = double(options.supportScale) * r;
    src.h2 = h * h;
    src.weight = 2 * double(sg.radius) * src.d.norm();
    m.segmentReach = std::max(m.segmentReach, h);
    longest = std::max(longest, src.d.norm());
    m.segments.push_back(src);
    m.midpoints.pts.push_back((0.5f * (sg.p0 + sg.p1)));
  }
  m.segmentReach += 0.5 * longest;
  if (!m.segments.empty()) {
    m.segmentTree = std::make_unique<Tree>(3, m.midpoints, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    m.segmentTree->buildIndex();
  }
}

MlsSurface::~MlsSurface() = default;
MlsSurface::MlsSurface(MlsSurface&&) noexcept = default;
MlsSurface& MlsSurface::operator=(MlsSurface&&) noexcept = default;

size_t MlsSurface::sources() const { return impl_->cloud.pts.size() + impl_->segments.size(); }
double MlsSurface::medianSpacing() const { return impl_->medianSpacing; }

MlsSample MlsSurface::evaluate(const Vec3d& x, bool second) const {
  if (!impl_->options.robust) return accumulate(x, second, nullptr);
  // RIMLS: each refit weighs the sources by their agreement with the previous fit.
  MlsSample fit = accumulate(x, false, nullptr);
  for (int k = 0; k < impl_->options.robustIterations && fit.valid(); ++k) {
    const bool last = k + 1 == impl_->options.robustIterations;
    MlsSample next = accumulate(x, second && last, &fit);
    if (!next.valid()) break;  // every source disagrees: keep the previous fit
    fit = next;
  }
  return fit;
}

MlsSample MlsSurface::accumulate(const Vec3d& x, bool second, const MlsSample* fit) const {
  const Impl& m = *impl_;
  // The robust weight of a source with signed distance d and normal n against the fit.
  const double fitValue = fit ? fit->value : 0.0;
  const double gnorm = fit ? fit->gradient.norm() : 0.0;
  const Vec3d fitNormal = gnorm > 0 ? Vec3d(fit->gradient / gnorm) : Vec3d::Zero();
  const double invSn2 = 1.0 / (double(m.options.sigmaNormal) * double(m.options.sigmaNormal));
  const double sr = double(m.options.sigmaResidual);
  auto robustWeight = [&](double d, const Vec3d& n, double h2) {
    if (!fit || !(gnorm > 0)) return 1.0;
    const double e = (d - fitValue);
    return std::exp(-(e * e) / (sr * sr * h2)) * std::exp(-(n - fitNormal).squaredNorm() * invSn2);
  };
  thread_local std::vector<std::pair<uint32_t, float>> found;
  m.inReach(x, found);
  // N = sum w_i d_i, D = sum w_i with w_i = a_i phi(t_i), t_i = |x - p_i|^2 / h_i^2, d_i = n_i.(x - p_i).
  double N = 0, D = 0;
  Vec3d gN = Vec3d::Zero(), gD = Vec3d::Zero();
  Mat3d hN = Mat3d::Zero(), hD = Mat3d::Zero();
  MlsSample s;
  for (const auto& [i, d2f] : found) {
    const Vec3d r = x - m.cloud.pts[i].cast<double>();
    const double t = r.squaredNorm() / m.h2[i];
    if (t >= 1) continue;
    const Vec3d& nrm = m.normal[i];
    const double di = nrm.dot(r);
    const double u = 1 - t, a = m.area[i] * robustWeight(di, nrm, m.h2[i]);
    const double phi = a * u * u * u * u, dphi = -4 * a * u * u * u, ddphi = 12 * a * u * u;  // d/dt
    const Vec3d gphi = (2 * dphi / m.h2[i]) * r;
    N += phi * di, D += phi;
    gN += gphi * di + phi * nrm, gD += gphi;
    s.normalField += phi * nrm;
    if (second) {
      const Mat3d hphi = (4 * ddphi / (m.h2[i] * m.h2[i])) * (r * r.transpose()) + (2 * dphi / m.h2[i]) * Mat3d::Identity();
      hN += hphi * di + gphi * nrm.transpose() + nrm * gphi.transpose(), hD += hphi;
      s.normalJacobian += nrm * gphi.transpose();
    }
    ++s.sources;
  }
  if (m.segmentTree) {
    thread_local std::vector<std::pair<uint32_t, float>> near;
    near.clear();
    const float q[3] = {float(x.x()), float(x.y()), float(x.z())};
    nanoflann::SearchParams params;
    params.sorted = false;
    m.segmentTree->radiusSearch(q, float(m.segmentReach * m.segmentReach), near, params);
    std::sort(near.begin(), near.end());
    for (const auto& [j, unused] : near) {
      const Impl::SegmentSource& sg = m.segments[j];
      // Along the segment p(s) = p0 + s d, t(s) = |x - p(s)|^2 / h^2 = A - 2 B s + C s^2 and
      // u = 1 - t is a quadratic; the kernel u^4 and every term below are polynomials in s,
      // integrated exactly over the part of [0, 1] inside the support. The support's ends move
      // with x, but u^4 and its first derivatives vanish there, so the derivatives pass under
      // the integral.
      const Vec3d r0 = x - sg.p0;
      const double A = r0.squaredNorm() / sg.h2, B = sg.d.dot(r0) / sg.h2, C = sg.d.squaredNorm() / sg.h2;
      double lo = 0, hi = 1;
      if (C > 0) {
        const double disc = B * B - C * (A - 1);
        if (disc <= 0) continue;
        const double root = std::sqrt(disc);
        lo = std::max(0.0, (B - root) / C), hi = std::min(1.0, (B + root) / C);
      } else if (A >= 1) {
        continue;
      }
      if (!(hi > lo)) continue;
      Poly u;
      u.c[0] = 1 - A, u.c[1] = 2 * B, u.c[2] = -C, u.degree = 2;
      const Poly u2 = u * u, u3 = u2 * u, u4 = u2 * u2;
      // grad u = -(2 / h^2)(r0 - s d), componentwise linear in s; n(s) = n0 + s (n1 - n0).
      std::array<Poly, 3> gu, nn;
      for (int i = 0; i < 3; ++i) {
        gu[size_t(i)] = linear(-2 * r0[i] / sg.h2, 2 * sg.d[i] / sg.h2);
        nn[size_t(i)] = linear(sg.n0[i], sg.n1[i] - sg.n0[i]);
      }
      // d(s) = n(s) . (x - p(s)) = n(s) . (r0 - s d).
      Poly dist;
      for (int i = 0; i < 3; ++i) dist = dist + nn[size_t(i)] * linear(r0[i], -sg.d[i]);
      double w = sg.weight;
      if (fit) {
        // One robust weight for the segment, at its point nearest x within the support (the
        // exponentials have no closed-form integral against the kernel).
        const double sc = std::clamp(C > 0 ? B / C : 0.0, lo, hi);
        const Vec3d ns = (sg.n0 + sc * (sg.n1 - sg.n0)).normalized();
        w *= robustWeight(ns.dot(r0 - sc * sg.d), ns, sg.h2);
      }
      auto I = [&](const Poly& p) { return w * integral(p, lo, hi); };
      const Poly phiD = u4 * dist;
      N += I(phiD), D += I(u4);
      std::array<Poly, 3> gphi;
      for (int i = 0; i < 3; ++i) gphi[size_t(i)] = 4.0 * (u3 * gu[size_t(i)]);
      for (int i = 0; i < 3; ++i) {
        gD[i] += I(gphi[size_t(i)]);
        gN[i] += I(gphi[size_t(i)] * dist + u4 * nn[size_t(i)]);
        s.normalField[i] += I(u4 * nn[size_t(i)]);
        for (int k = 0; k < 3 && second; ++k) {
          // H phi = 12 u^2 grad u grad u^T + 4 u^3 H u, H u = -(2 / h^2) I.
          Poly hphi = 12.0 * (u2 * gu[size_t(i)] * gu[size_t(k)]);
          if (i == k) hphi = hphi + (-8.0 / sg.h2) * u3;
          hD(i, k) += I(hphi);
          hN(i, k) += I(hphi * dist + gphi[size_t(i)] * nn[size_t(k)] + nn[size_t(i)] * gphi[size_t(k)]);
          s.normalJacobian(i, k) += I(nn[size_t(i)] * gphi[size_t(k)]);
        }
      }
      ++s.sources;
    }
  }
  s.weight = D;
  if (!(D > 0)) return s;
  // f = N / D; grad f = (grad N - f grad D) / D; H f = (H N - f H D - grad f grad D^T - grad D grad f^T) / D.
  s.value = N / D;
  s.gradient = (gN - s.value * gD) / D;
  if (second) s.hessian = (hN - s.value * hD - s.gradient * gD.transpose() - gD * s.gradient.transpose()) / D;
  return s;
}

MlsCurvature MlsSurface::curvature(const Vec3d& x) const {
  MlsCurvature c;
  const MlsSample s = evaluate(x);
  const double len = s.normalField.norm();
  if (!s.valid() || !(len > 0)) return c;
  // The shape operator of the normal field n = m / |m| (m: the sources' normals averaged by their
  // weights): dn/dx = (I - n n^T) dm/dx / |m|, restricted to the tangent plane. Not the Hessian
  // of f: f's second derivatives carry the sources' plane offsets, which irregular sampling makes
  // bumpy (a sphere's curvature 24% off at the median against 1% from the normal field).
  const Vec3d n = s.normalField / len;
  const Mat3d P = Mat3d::Identity() - n * n.transpose();
  const Mat3d S = P * (P * s.normalJacobian / len) * P;
  Eigen::SelfAdjointEigenSolver<Mat3d> es(0.5 * (S + S.transpose()));
  // The eigenvector along n has eigenvalue 0; the other two span the tangent plane.
  int along = 0;
  for (int e = 1; e < 3; ++e)
    if (std::abs(es.eigenvectors().col(e).dot(n)) > std::abs(es.eigenvectors().col(along).dot(n))) along = e;
  const int a = along == 0 ? 1 : 0, b = along == 2 ? 1 : 2;  // eigenvalues ascend: a's <= b's
  c.kMin = es.eigenvalues()[a], c.kMax = es.eigenvalues()[b];
  c.dirMin = es.eigenvectors().col(a).normalized();
  c.dirMax = es.eigenvectors().col(b).normalized();
  if (c.dirMin.cross(c.dirMax).dot(n) < 0) c.dirMax = -c.dirMax;
  c.normal = n;
  c.valid = true;
  return c;
}

double MlsSurface::localSupport(const Vec3d& x) const {
  const Impl& m = *impl_;
  const float q[3] = {float(x.x()), float(x.y()), float(x.z())};
  uint32_t idx = 0;
  float d2 = 0;
  if (m.tree) {
    m.tree->knnSearch(q, 1, &idx, &d2);
    return std::sqrt(m.h2[idx]);
  }
  m.segmentTree->knnSearch(q, 1, &idx, &d2);
  return std::sqrt(m.segments[idx].h2);
}

MlsProjection MlsSurface::project(const Vec3d& x0) const {
  MlsProjection p;
  p.point = x0;
  const double tol = double(impl_->options.tolerance) * localSupport(x0);
  for (p.iterations = 0; p.iterations < impl_->options.maxIterations; ++p.iterations) {
    const MlsSample s = evaluate(p.point, false);
    const double g2 = s.gradient.squaredNorm();
    if (!s.valid() || !(g2 > 0)) return p;
    const Vec3d step = s.value * s.gradient / g2;
    p.point -= step;
    p.normal = s.gradient / std::sqrt(g2);
    if (std::abs(s.value) < tol && step.norm() < tol) {
      p.converged = true;
      ++p.iterations;
      return p;
    }
  }
  return p;
}

}  // namespace linesurf
