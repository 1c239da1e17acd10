// The MLS surface of a point model (thesis §9.1; see surface/mls.h).
#include "linesurf/surface/mls.h"

#include <nanoflann.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf {
namespace {

struct Cloud {
  std::vector<Vec3f> pts;
  size_t kdtree_get_point_count() const { return pts.size(); }
  float kdtree_get_pt(size_t i, size_t d) const { return pts[i][int(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>, Cloud, 3, uint32_t>;

}  // namespace

void validate(const MlsOptions& o) {
  requireRange("supportScale", o.supportScale, 1.5, 10);
  requireRange("maxIterations", o.maxIterations, 1, 1000);
  if (!(o.tolerance > 0 && o.tolerance <= 0.1f)) throwBadOption("tolerance", "must be in (0, 0.1]");
}

struct MlsSurface::Impl {
  MlsOptions options;
  Cloud cloud;
  std::vector<Vec3d> normal;
  std::vector<double> area, h2;  ///< a_i, h_i^2
  double reach = 0;              ///< the largest h_i: every query's radius
  std::unique_ptr<Tree> tree;

  /// The sources whose support holds x, in index order (a sum's order independent of the tree).
  void inReach(const Vec3d& x, std::vector<std::pair<uint32_t, float>>& found) const {
    found.clear();
    if (!tree) return;
    const float q[3] = {float(x.x()), float(x.y()), float(x.z())};
    nanoflann::SearchParams params;
    params.sorted = false;
    tree->radiusSearch(q, float(reach * reach), found, params);
    std::sort(found.begin(), found.end());
  }
};

MlsSurface::MlsSurface(const HybridModel& model, const MlsOptions& options) : impl_(std::make_unique<Impl>()) {
  validate(options);
  Impl& m = *impl_;
  m.options = options;
  const size_t n = model.points.size();
  if (n == 0) throwBadParameter("model", "has no points");
  if (!model.attributes.normals) throwBadParameter("model", "has no normals (an MLS surface needs oriented points)");
  for (size_t i = 0; i < n; ++i) {
    const Point& p = model.points[i];
    if (!p.position.allFinite() || !p.normal.allFinite() || std::abs(p.normal.squaredNorm() - 1.0f) > 1e-3f)
      throwBadParameter("model", "point " + std::to_string(i) + " has a non-finite position or a normal that is not unit");
  }
  // The spacing of §6.1 stage 5 (the file's normals kept, nothing else computed).
  GeometryOptions go;
  go.orientNormals = go.delaunayNeighbours = go.curvature = go.coverRadius = false;
  const PointGeometry g = computePointGeometry(model, go);
  std::vector<float> sorted(g.spacing);
  std::nth_element(sorted.begin(), sorted.begin() + ptrdiff_t(n / 2), sorted.end());
  const double medianSpacing = sorted[n / 2] > 0 ? sorted[n / 2] : std::max(g.averageSpacing, 1e-30f);
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
  m.tree = std::make_unique<Tree>(3, m.cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  m.tree->buildIndex();
}

MlsSurface::~MlsSurface() = default;
MlsSurface::MlsSurface(MlsSurface&&) noexcept = default;
MlsSurface& MlsSurface::operator=(MlsSurface&&) noexcept = default;

size_t MlsSurface::sources() const { return impl_->cloud.pts.size(); }

MlsSample MlsSurface::evaluate(const Vec3d& x) const {
  const Impl& m = *impl_;
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
    const double u = 1 - t, a = m.area[i];
    const double phi = a * u * u * u * u, dphi = -4 * a * u * u * u, ddphi = 12 * a * u * u;  // d/dt
    const Vec3d gphi = (2 * dphi / m.h2[i]) * r;
    const Mat3d hphi = (4 * ddphi / (m.h2[i] * m.h2[i])) * (r * r.transpose()) + (2 * dphi / m.h2[i]) * Mat3d::Identity();
    const Vec3d& nrm = m.normal[i];
    const double di = nrm.dot(r);
    N += phi * di, D += phi;
    gN += gphi * di + phi * nrm, gD += gphi;
    hN += hphi * di + gphi * nrm.transpose() + nrm * gphi.transpose(), hD += hphi;
    s.normalField += phi * nrm, s.normalJacobian += nrm * gphi.transpose();
    ++s.sources;
  }
  s.weight = D;
  if (!(D > 0)) return s;
  // f = N / D; grad f = (grad N - f grad D) / D; H f = (H N - f H D - grad f grad D^T - grad D grad f^T) / D.
  s.value = N / D;
  s.gradient = (gN - s.value * gD) / D;
  s.hessian = (hN - s.value * hD - s.gradient * gD.transpose() - gD * s.gradient.transpose()) / D;
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
  m.tree->knnSearch(q, 1, &idx, &d2);
  return std::sqrt(m.h2[idx]);
}

MlsProjection MlsSurface::project(const Vec3d& x0) const {
  MlsProjection p;
  p.point = x0;
  const double tol = double(impl_->options.tolerance) * localSupport(x0);
  for (p.iterations = 0; p.iterations < impl_->options.maxIterations; ++p.iterations) {
    const MlsSample s = evaluate(p.point);
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
