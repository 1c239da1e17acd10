// Stage 4 of the §6.1 geometry (see detail/geometry_stages.h): parallel over points, each task writing
// its own slots.
#include "geometry/detail/geometry_stages.h"

#include <Eigen/Eigenvalues>

#include <cmath>

#include "linesurf/geometry/point_geometry.h"

namespace linesurf::detail {
namespace {
constexpr uint32_t kNone = PointGeometry::kNoNeighbour;
}  // namespace

void computeCurvature(const std::vector<Vec3f>& pos, const std::vector<uint32_t>& order, CurvatureFit fit, PointGeometry& g, const ProgressFn& progress) {
  const size_t n = pos.size();
  g.kMin.assign(n, 0.0f);
  g.kMax.assign(n, 0.0f);
  g.minCurvatureDir.assign(n, Vec3f::Zero());
  g.maxCurvatureDir.assign(n, Vec3f::Zero());
  forBlocks(n, progress, "curvature", 256, [&](size_t b, size_t e) {
    for (size_t o = b; o < e; ++o) {
      const size_t i = order[o];
      const Vec3d p = pos[i].cast<double>();
      const Vec3d nrm = g.normals[i].cast<double>();
      Vec3d x, y;
      householderTangents(nrm, x, y);
      const auto ids = g.delaunayOf(i);
      const auto ws = g.delaunayWeightsOf(i);
      double m11 = 0, m12 = 0, m22 = 0;  // Taubin's M in the (x, y) basis
      for (size_t t = 0; t < ids.size(); ++t) {
        const Vec3d d = p - pos[ids[t]].cast<double>();  // q_j -> p
        const double d2 = d.squaredNorm();
        double tx = d.dot(x), ty = d.dot(y);
        const double tl = std::sqrt(tx * tx + ty * ty);
        if (!(d2 > 0) || !(tl > 0)) continue;
        tx /= tl, ty /= tl;
        const double kappa = 2.0 * nrm.dot(d) / d2;  // §6.1.2 directional curvature, convex > 0
        const double w = double(ws[t]);
        m11 += w * kappa * tx * tx;
        m12 += w * kappa * tx * ty;
        m22 += w * kappa * ty * ty;
      }
      // Symmetric 2x2 block [s11 s12; s12 s22] whose eigen decomposition gives the directions.
      double s11 = m11, s12 = m12, s22 = m22;
      bool taubin = true;
      if (fit == CurvatureFit::Quadric) {
        // h(u, v) = n.(q - p) = (a u^2 + 2 b u v + c v^2) / 2 + e u + f v, least squares over the
        // kNN row with coordinates scaled by the spacing; convex-positive curvature is -Hessian.
        using Vec5d = Eigen::Matrix<double, 5, 1>;
        Eigen::Matrix<double, 5, 5> ata = Eigen::Matrix<double, 5, 5>::Zero();
        Vec5d atb = Vec5d::Zero();
        double scale = g.spacing.empty() ? 0.0 : double(g.spacing[i]);
        int rows = 0;
        for (int t = 0; t < g.k; ++t) {
          const uint32_t j = g.neighbours[i * size_t(g.k) + t];
          if (j == kNone) break;
          if (scale <= 0) scale = double(g.neighbourDistances[i * size_t(g.k) + t]);
          if (!(scale > 0)) continue;
          const Vec3d d = (pos[j].cast<double>() - p) / scale;
          const double u = d.dot(x), v = d.dot(y), h = d.dot(nrm);
          Vec5d phi;
          phi << 0.5 * u * u, u * v, 0.5 * v * v, u, v;
          ata += phi * phi.transpose();
          atb += h * phi;
          ++rows;
        }
        if (rows >= 5 && scale > 0) {
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 5, 5>> es(ata);
          const auto ev = es.eigenvalues();
          if (ev[0] > 1e-8 * ev[4]) {
            const Vec5d sol = es.eigenvectors() * ((es.eigenvectors().transpose() * atb).cwiseQuotient(ev));
            if (sol.allFinite())
              s11 = -sol[0] / scale, s12 = -sol[1] / scale, s22 = -sol[2] / scale, taubin = false;
          }
        }
      }
      const double half = 0.5 * (s11 - s22), r = std::hypot(half, s12), mid = 0.5 * (s11 + s22);
      const double e1 = mid + r, e2 = mid - r;  // e1 >= e2
      double ux = 1, uy = 0;                    // eigenvector of e1
      if (r > 0) {
        const double theta = 0.5 * std::atan2(s12, half);
        ux = std::cos(theta), uy = std::sin(theta);
      }
      const Vec3d dMax = ux * x + uy * y, dMin = -uy * x + ux * y;
      g.kMax[i] = float(taubin ? 3 * e1 - e2 : e1);  // §6.1.2: kappa_1 = 3 m11 - m22 (diagonalised)
      g.kMin[i] = float(taubin ? 3 * e2 - e1 : e2);
      g.maxCurvatureDir[i] = canonicalDirection(dMax.cast<float>().normalized());
      g.minCurvatureDir[i] = canonicalDirection(dMin.cast<float>().normalized());
    }
  });
}

}  // namespace linesurf::detail
