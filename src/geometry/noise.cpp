// Noise of a scan along its normals, from the §6.1 neighbourhoods (include/linesurf/geometry/noise.h).
#include "linesurf/geometry/noise.h"

#include <nanoflann.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <vector>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"

namespace linesurf {
namespace {

struct SpanCloud {
  std::span<const Vec3f> pts;
  size_t kdtree_get_point_count() const { return pts.size(); }
  float kdtree_get_pt(size_t i, size_t d) const { return pts[i][int(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, SpanCloud>, SpanCloud, 3, uint32_t>;

constexpr int kSmallestNeighbourhood = 24;

struct LocalFit {
  double variance = 0;  ///< residual variance, divided by the chi-square median of its degrees of freedom
  int neighbours = 0;
  bool fitted = false, resolved = false;
};

// The height-function fit over the first k of `nb` (nearest first, the sample itself first).
// Returns false when the neighbourhood is degenerate (coincident or collinear points).
bool fitHeight(std::span<const Vec3f> pts, const std::vector<uint32_t>& nb, int k, double& variance, double& radius) {
  const Vec3d p = pts[nb[0]].cast<double>();
  Vec3d mean = Vec3d::Zero();
  for (int j = 0; j < k; ++j) mean += pts[nb[size_t(j)]].cast<double>();
  mean /= k;
  Mat3d cov = Mat3d::Zero();
  radius = 0;
  for (int j = 0; j < k; ++j) {
    const Vec3d q = pts[nb[size_t(j)]].cast<double>();
    cov += (q - mean) * (q - mean).transpose();
    radius = std::max(radius, (q - p).norm());
  }
  if (!(radius > 0)) return false;
  Eigen::SelfAdjointEigenSolver<Mat3d> es(cov);
  const Vec3d lambda = es.eigenvalues();  // ascending
  if (!(lambda[1] > 1e-12 * lambda[2])) return false;  // collinear: no tangent plane
  const Vec3d n = es.eigenvectors().col(0), t1 = es.eigenvectors().col(2), t2 = es.eigenvectors().col(1);
  // Coordinates scaled by the radius keep the 6 x 6 normal equations well conditioned.
  Eigen::Matrix<double, 6, 6> ata = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> atb = Eigen::Matrix<double, 6, 1>::Zero();
  std::vector<Eigen::Matrix<double, 6, 1>> rows(static_cast<size_t>(k));
  std::vector<double> ws(static_cast<size_t>(k));
  for (int j = 0; j < k; ++j) {
    const Vec3d d = pts[nb[size_t(j)]].cast<double>() - p;
    const double u = d.dot(t1) / radius, v = d.dot(t2) / radius, w = d.dot(n);
    Eigen::Matrix<double, 6, 1> r;
    r << 0.5 * u * u, u * v, 0.5 * v * v, u, v, 1.0;
    rows[size_t(j)] = r;
    ws[size_t(j)] = w;
    ata += r * r.transpose();
    atb += r * w;
  }
  const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(ata);
  if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().minCoeff() > 1e-12 * ldlt.vectorD().maxCoeff())) return false;
  const Eigen::Matrix<double, 6, 1> coef = ldlt.solve(atb);
  double ss = 0;
  for (int j = 0; j < k; ++j) {
    const double e = ws[size_t(j)] - rows[size_t(j)].dot(coef);
    ss += e * e;
  }
  const double dof = double(k - 6);
  // Median of chi-square(dof)/dof (Wilson–Hilferty), so that the median over samples of the
  // corrected variances estimates sigma² without the small-sample bias of each fit.
  const double chiMedian = std::pow(1.0 - 2.0 / (9.0 * dof), 3.0);
  variance = ss / dof / chiMedian;
  return true;
}

// The `want` nearest points of pts[i] (itself among them), nearest first, ties by index so that
// the neighbourhood does not depend on the tree's traversal; the sample itself first.
std::vector<uint32_t> nearest(const Tree& tree, std::span<const Vec3f> pts, size_t i, size_t want) {
  std::vector<uint32_t> idx(want);
  std::vector<float> d2(want);
  nanoflann::KNNResultSet<float, uint32_t> rs(want);
  rs.init(idx.data(), d2.data());
  tree.findNeighbors(rs, pts[i].data(), nanoflann::SearchParams());
  const size_t found = rs.size();
  std::vector<size_t> order(found);
  for (size_t j = 0; j < found; ++j) order[j] = j;
  std::sort(order.begin(), order.end(), [&](size_t a, size_t b) { return d2[a] != d2[b] ? d2[a] < d2[b] : idx[a] < idx[b]; });
  std::vector<uint32_t> nb(found);
  for (size_t j = 0; j < found; ++j) nb[j] = idx[order[j]];
  if (!nb.empty() && nb[0] != i) {  // a duplicate came first
    const auto it = std::find(nb.begin(), nb.end(), uint32_t(i));
    if (it != nb.end()) std::rotate(nb.begin(), it, it + 1);
  }
  return nb;
}

LocalFit fitSample(const Tree& tree, std::span<const Vec3f> pts, size_t i, int maxK, float footprint) {
  LocalFit out;
  // Most samples settle on the smallest neighbourhood: fetch 4 x k at a time, not maxK at once.
  std::vector<uint32_t> nb;
  for (int k = std::min(kSmallestNeighbourhood, maxK);; k = std::min(2 * k, maxK)) {
    if (size_t(k) > nb.size()) {
      nb = nearest(tree, pts, i, size_t(std::min(maxK, 4 * k)));
      if (nb.size() < 7) return out;
    }
    double variance = 0, radius = 0;
    if (fitHeight(pts, nb, k, variance, radius)) {
      out.fitted = true;
      out.variance = variance;
      out.neighbours = k;
      if (radius >= footprint * std::sqrt(variance)) {
        out.resolved = true;
        return out;
      }
    }
    if (k >= maxK) return out;
  }
}

double lowerQuantile(std::vector<double> v, double q) {
  const size_t at = std::min(v.size() - 1, size_t(q * double(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + ptrdiff_t(at), v.end());
  return v[at];
}

}  // namespace

void validate(const NoiseOptions& o) {
  if (!(o.samples >= 16 && o.samples <= 10000000)) throwBadParameter("samples", fmt::format("{} is outside [16, 10^7]", o.samples));
  if (!(o.maxNeighbours >= kSmallestNeighbourhood && o.maxNeighbours <= 4096))
    throwBadParameter("maxNeighbours", fmt::format("{} is outside [24, 4096]", o.maxNeighbours));
  if (!(o.footprint >= 2 && o.footprint <= 100)) throwBadParameter("footprint", fmt::format("{} is outside [2, 100]", o.footprint));
}

NoiseEstimate estimateNoise(std::span<const Vec3f> positions, const NoiseOptions& options) {
  validate(options);
  NoiseEstimate est;
  const size_t n = positions.size();
  for (size_t i = 0; i < n; ++i)
    if (!positions[i].allFinite()) throwBadParameter("positions", fmt::format("point {} is not finite", i));
  if (n < 7) return est;
  SpanCloud cloud{positions};
  Tree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  const size_t m = std::min(n, size_t(options.samples));
  const int maxK = int(std::min<size_t>(n, size_t(options.maxNeighbours)));
  std::vector<LocalFit> fits(m);
  parallelFor(0, m, [&](size_t j) {
    // Evenly in index order: the (j + 1/2)-th of m equal shares of the file.
    const size_t i = std::min(n - 1, size_t((double(j) + 0.5) * double(n) / double(m)));
    fits[j] = fitSample(tree, positions, i, maxK, options.footprint);
  }, 16);
  std::vector<double> variances, neighbours;
  for (const LocalFit& f : fits) {
    if (!f.fitted) continue;
    variances.push_back(f.variance);
    neighbours.push_back(double(f.neighbours));
    if (!f.resolved) ++est.unresolved;
  }
  est.samples = m;
  est.fitted = variances.size();
  if (variances.empty()) return est;
  est.sigma = std::sqrt(lowerQuantile(variances, 0.5));
  est.lowerQuartile = std::sqrt(lowerQuantile(variances, 0.25));
  est.upperQuartile = std::sqrt(lowerQuantile(variances, 0.75));
  est.medianNeighbours = lowerQuantile(neighbours, 0.5);
  return est;
}

NoiseEstimate estimateNoise(const HybridModel& model, const NoiseOptions& options) {
  std::vector<Vec3f> pos(model.points.size());
  for (size_t i = 0; i < pos.size(); ++i) pos[i] = model.points[i].position;
  return estimateNoise(pos, options);
}

}  // namespace linesurf
