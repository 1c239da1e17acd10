// The cross field of the curvature-line extraction (thesis §9.2; see detail/cross_field.h).
#include "detail/cross_field.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <span>

#include "linesurf/core/parallel.h"
#include "linesurf/surface/mls.h"

namespace linesurf::detail {
namespace {

/// A tangent frame at n, fixed by n alone (so every pass sees the same angles).
void tangentFrame(const Vec3f& n, Vec3f& e1, Vec3f& e2) {
  const Vec3f a = n.cwiseAbs();
  Vec3f helper = a.x() <= a.y() && a.x() <= a.z() ? Vec3f::UnitX() : (a.y() <= a.z() ? Vec3f::UnitY() : Vec3f::UnitZ());
  e1 = (helper - helper.dot(n) * n).normalized();
  e2 = n.cross(e1);
}

/// exp(4 i theta) of direction d in the frame (e1, e2), d first projected onto the plane.
std::complex<double> fourfold(const Vec3f& d, const Vec3f& e1, const Vec3f& e2) {
  const double theta = std::atan2(double(d.dot(e2)), double(d.dot(e1)));
  return std::polar(1.0, 4.0 * theta);
}

}  // namespace

CrossField computeCrossField(const HybridModel& cloud, const PointGeometry& g, const MlsSurface& surface,
                             int iterations, double dataWeight) {
  const size_t n = cloud.points.size();
  CrossField f;
  f.axis.assign(n, Vec3f::Zero());
  f.normal = g.normals;
  f.coherence.assign(n, 0.0f);
  f.kMin.assign(n, 0.0f), f.kMax.assign(n, 0.0f);
  f.minDir.assign(n, Vec3f::Zero());
  std::vector<Vec3f> e1(n), e2(n);
  std::vector<std::complex<double>> data(n), z(n), next(n);
  const double k0 = 0.002 / std::max(double(g.averageSpacing), 1e-30);
  parallelFor(0, n, [&](size_t i) {
    tangentFrame(g.normals[i], e1[i], e2[i]);
    const MlsCurvature c = surface.curvature(cloud.points[i].position.cast<double>());
    if (!c.valid || !std::isfinite(c.kMin) || !std::isfinite(c.kMax)) {
      data[i] = 0;  // no direction here: the neighbours' carry over
      return;
    }
    f.kMin[i] = float(c.kMin), f.kMax[i] = float(c.kMax);
    f.minDir[i] = c.dirMin.cast<float>();
    const double aniso = std::abs(c.kMax - c.kMin) / (std::abs(c.kMax) + std::abs(c.kMin) + k0);
    data[i] = dataWeight * aniso * fourfold(f.minDir[i], e1[i], e2[i]);
  });
  z = data;
  // Points with no direction at all (a plane) start from the frame's own axis: the smoothing
  // then makes the field as parallel as the frames allow.
  for (size_t i = 0; i < n; ++i)
    if (std::abs(z[i]) < 1e-12) z[i] = 1e-6;
  // The neighbour graph: the local Delaunay star where the geometry has it (the out-of-core
  // tiles keep only that, so in memory and out of core smooth over the same graph), else the k
  // nearest.
  const bool knn = g.delaunayOffsets.size() != n + 1;
  const int k = g.k;
  auto neighbours = [&](size_t i) -> std::span<const uint32_t> {
    if (!knn) return g.delaunayOf(i);
    std::span<const uint32_t> row(g.neighbours.data() + i * size_t(k), size_t(k));
    size_t m = 0;
    while (m < row.size() && row[m] != PointGeometry::kNoNeighbour) ++m;
    return row.first(m);
  };
  // The connection: j's frame turned into i's by the angle phi_ij of e1_j projected onto i's
  // plane (the frames are right-handed about consistently oriented normals), so a direction at
  // theta in j's frame lies at theta + phi_ij in i's, and z_j seen from i is z_j exp(4 i phi_ij).
  // Computed once; each iteration is then complex products only.
  std::vector<uint32_t> offsets(n + 1, 0), adjacent;
  for (size_t i = 0; i < n; ++i) offsets[i + 1] = offsets[i] + uint32_t(neighbours(i).size());
  adjacent.resize(offsets[n]);
  std::vector<std::complex<double>> connection(offsets[n]);
  parallelFor(0, n, [&](size_t i) {
    uint32_t e = offsets[i];
    for (const uint32_t j : neighbours(i)) {
      adjacent[e] = j;
      connection[e++] = fourfold(e1[j], e1[i], e2[i]);
    }
  });
  for (int it = 0; it < iterations; ++it) {
    parallelFor(0, n, [&](size_t i) {
      std::complex<double> sum = 0;
      for (uint32_t e = offsets[i]; e < offsets[i + 1]; ++e) sum += z[adjacent[e]] * connection[e];
      const uint32_t count = offsets[i + 1] - offsets[i];
      const std::complex<double> v = data[i] + (count ? sum / double(count) : 0.0);
      next[i] = std::abs(v) > 1e-12 ? v / std::abs(v) : z[i];
    });
    std::swap(z, next);
  }
  parallelFor(0, n, [&](size_t i) {
    const double theta = std::arg(z[i]) / 4.0;
    f.axis[i] = float(std::cos(theta)) * e1[i] + float(std::sin(theta)) * e2[i];
    std::complex<double> sum = 0;
    for (uint32_t e = offsets[i]; e < offsets[i + 1]; ++e) sum += z[adjacent[e]] * connection[e];
    const uint32_t count = offsets[i + 1] - offsets[i];
    f.coherence[i] = count ? float(std::abs(sum * std::conj(z[i])) / count) : 0.0f;
  });
  return f;
}

}  // namespace linesurf::detail
