// Geometry processing of point clouds, thesis §6.1 (five stages; see point_geometry.h).
// Every stage is parallel over points and each task writes only its own slots, so the result is
// identical for any thread count (the MST orientation's forest is unique under a strict edge order).
#include "linesurf/geometry/point_geometry.h"

#include <nanoflann.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <tuple>

#include "geometry/detail/geometry_stages.h"
#include "geometry/detail/local_delaunay.h"
#include "geometry/detail/point_geometry_tile.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"

namespace linesurf {
namespace {

using detail::forBlocks;
using detail::householderTangents;
constexpr uint32_t kNone = PointGeometry::kNoNeighbour;
/// A point whose spacing exceeds this many times the median spacing of its neighbours stands off
/// the surface (no point of the shared clean models does: their largest ratio is 3.2, on al)...
constexpr float kOffSurfaceRatio = 4.0f;
/// ...and its disc is at most this many times that median, the cap its own spacing would give.
constexpr float kNeighbourBound = 3.0f;
constexpr float kInf = std::numeric_limits<float>::infinity();

struct CloudAdaptor {
  const std::vector<Vec3f>* pts;
  size_t kdtree_get_point_count() const { return pts->size(); }
  float kdtree_get_pt(size_t i, size_t d) const { return (*pts)[i][int(d)]; }
  template <class B> bool kdtree_get_bbox(B&) const { return false; }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, CloudAdaptor>, CloudAdaptor, 3, uint32_t>;

// ---------------------------------------------------------------------------------------------
// Stage 1: exact k nearest neighbours (nanoflann kd-tree).
void computeNeighbours(const std::vector<Vec3f>& pos, const KdTree& tree, int k, PointGeometry& g,
                       std::vector<uint32_t>& orderOut, const ProgressFn& progress) {
  const size_t n = pos.size();
  orderOut.resize(n);
  std::iota(orderOut.begin(), orderOut.end(), 0u);
  g.neighbours.assign(n * size_t(k), kNone);
  g.neighbourDistances.assign(n * size_t(k), kInf);
  if (n < 2) return;
  if (tree.vAcc.size() == n) orderOut.assign(tree.vAcc.begin(), tree.vAcc.end());
  // One result more than needed (self + k + 1) tells whether the k-th place is tied; only then
  // a radius search collects every tied point, so ties are always broken by index.
  const size_t want = std::min(n, size_t(k) + 2);
  // Query in the tree's leaf order: consecutive queries touch the same nodes (cache locality).
  // Each query writes only its own row, so the order does not change the result.
  const std::vector<uint32_t>& order = orderOut;
  forBlocks(n, progress, "neighbours", 512, [&](size_t b, size_t e) {
    std::vector<uint32_t> idx(want);
    std::vector<float> d2(want);
    std::vector<std::pair<float, uint32_t>> row;
    std::vector<std::pair<uint32_t, float>> tied;
    for (size_t o = b; o < e; ++o) {
      const size_t i = order[o];
      nanoflann::KNNResultSet<float, uint32_t> rs(want);
      rs.init(idx.data(), d2.data());
      const float* query = pos[i].data();
      tree.findNeighbors(rs, query, nanoflann::SearchParams());
      row.clear();
      for (size_t t = 0; t < rs.size(); ++t) row.emplace_back(d2[t], idx[t]);
      // Sorted by distance already: order equal distances by index (insertion sort, ~free).
      for (size_t a = 1; a < row.size(); ++a)
        for (size_t c = a; c > 0 && row[c] < row[c - 1]; --c) std::swap(row[c], row[c - 1]);
      if (row.size() == size_t(k) + 2 && row[size_t(k) + 1].first == row[size_t(k)].first) {
        tied.clear();
        tree.radiusSearch(query, std::nextafter(row[size_t(k)].first, kInf), tied, nanoflann::SearchParams(32, 0, false));
        row.clear();
        for (auto& [j, d] : tied) row.emplace_back(d, j);
        std::sort(row.begin(), row.end());
      }
      // Drop the point itself (first among its duplicates by index, not necessarily first).
      for (size_t t = 0; t < row.size(); ++t)
        if (row[t].second == i) {
          row.erase(row.begin() + std::ptrdiff_t(t));
          break;
        }
      const size_t m = std::min(row.size(), size_t(k));
      for (size_t t = 0; t < m; ++t) {
        g.neighbours[i * k + t] = row[t].second;
        g.neighbourDistances[i * k + t] = std::sqrt(row[t].first);
      }
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Stage 2a: PCA normals (Hoppe 1992): covariance of p and its neighbours about their centroid.
void computeNormals(const HybridModel& cloud, const std::vector<Vec3f>& pos, const std::vector<uint32_t>& order, int k, float dupTol, bool keepFileNormals, PointGeometry& g,
                    std::vector<uint8_t>& fixedNormal, const ProgressFn& progress) {
  const size_t n = cloud.points.size();
  g.normals.assign(n, Vec3f(0, 0, 1));
  g.eigenvalues.assign(n, Vec3f::Zero());
  g.surfaceVariation.assign(n, 0.0f);
  fixedNormal.assign(n, 0);
  forBlocks(n, progress, "normals", 256, [&](size_t b, size_t e) {
    for (size_t o = b; o < e; ++o) {
      const size_t i = order[o];
      const Vec3d p = pos[i].cast<double>();
      Vec3d sum = Vec3d::Zero();
      int cnt = 1, distinct = 0;
      for (int t = 0; t < k; ++t) {
        const uint32_t j = g.neighbours[i * k + t];
        if (j == kNone) break;
        sum += pos[j].cast<double>() - p;
        ++cnt;
        if (g.neighbourDistances[i * k + t] > dupTol) ++distinct;
        else g.flags[i] |= kPointDuplicate;
      }
      const Vec3d mean = sum / cnt;  // relative to p
      Mat3d cov = Mat3d::Zero();
      for (int t = 0; t < k; ++t) {
        const uint32_t j = g.neighbours[i * k + t];
        if (j == kNone) break;
        const Vec3d d = pos[j].cast<double>() - p - mean;
        cov += d * d.transpose();
      }
      cov += mean * mean.transpose();  // p itself (at 0 relative to p)
      cov /= cnt;
      Eigen::SelfAdjointEigenSolver<Mat3d> es;
      es.computeDirect(cov);
      Vec3d lambda = es.eigenvalues().cwiseMax(0.0);
      const double total = lambda.sum();
      g.eigenvalues[i] = lambda.cast<float>();
      g.surfaceVariation[i] = total > 0 ? float(lambda[0] / total) : 0.0f;
      if (distinct < 3) g.flags[i] |= kPointFewNeighbours;
      Vec3d nrm(0, 0, 1);
      if (!(lambda[2] > 0) || !std::isfinite(lambda[2])) {
        g.flags[i] |= kPointFlatNeighbourhood;  // all neighbours coincide: nothing to fit
      } else if (lambda[1] <= 1e-6 * lambda[2]) {
        // Collinear neighbourhood: any normal of the line fits; take a deterministic one.
        g.flags[i] |= kPointFlatNeighbourhood;
        const Vec3d dir = es.eigenvectors().col(2).normalized();
        Vec3d axis = Vec3d::Zero();
        int a = 0;
        dir.cwiseAbs().minCoeff(&a);
        axis[a] = 1;
        nrm = dir.cross(axis).normalized();
      } else {
        nrm = es.eigenvectors().col(0).normalized();
      }
      if (!nrm.allFinite()) nrm = Vec3d(0, 0, 1);
      g.normals[i] = nrm.cast<float>();
      if (keepFileNormals) {
        const Vec3f fn = cloud.points[i].normal;
        const float len = fn.norm();
        if (len > 0 && std::isfinite(len)) {
          g.normals[i] = fn / len;
          fixedNormal[i] = 1;
        }
      }
    }
  });
}

// ---------------------------------------------------------------------------------------------
// Stages 3 and 4.
// Hole-free radius (beyond the thesis) = this x the farthest vertex of the point's
// Voronoi cell among its nearest neighbours in its tangent plane, i.e. the largest circumradius
// of its closed Delaunay star: the splat's cut-off reaches the cell's vertices at 1.0; 10% covers
// the surface's deviation from the plane, normal error and pixel sampling.
constexpr double kCoverMargin = 1.1;
// The cell of a closed star of the k nearest neighbours contains the true cell (fewer points, a
// larger cell), so its radius is safe. An open (boundary) star leaves its open side out and can
// be 5x too small: 12 directions within a half-plane, 0.6% of the points of a uniformly random
// sampling. So an open star's radius comes from the star of 2k, then 4k nearest neighbours, the
// first that closes; one still open at 4k is a border of the surface and keeps the k-star's
// radius (docs/decisions.md, "Spacing and the cover radius").
constexpr int kCoverGrowth = 4;

/// Largest circumradius of the star triangles (0, q_a, q_b), consecutive counter-clockwise
/// neighbours turning by less than pi: R = |a| |b| |a - b| / (2 |a x b|); a boundary star's open
/// side is left out.
double starCircumradius(std::span<const Vec2d> q, const detail::LocalStar& star) {
  double rmax = 0;
  const size_t s = star.ids.size();
  for (size_t t = 0; t < s && s >= 2; ++t) {
    if (star.boundary && t + 1 == s) break;  // the open side of a boundary star
    const Vec2d a = q[size_t(star.ids[t])], b = q[size_t(star.ids[(t + 1) % s])];
    const double cr = a.x() * b.y() - a.y() * b.x();
    if (!(cr > 0)) continue;
    rmax = std::max(rmax, a.norm() * b.norm() * (a - b).norm() / (2 * cr));
  }
  return rmax;
}

void computeDelaunay(const std::vector<Vec3f>& pos, const KdTree* tree, const std::vector<uint32_t>& order, int k, float dupTol,
                     bool useCgal, PointGeometry& g, const ProgressFn& progress, std::vector<float>* reach) {
  const size_t n = pos.size();
  std::vector<uint32_t> tmpIdx(n * size_t(k), kNone);
  std::vector<float> tmpW(n * size_t(k), 0.0f);
  std::vector<uint32_t> count(n, 0);
  const double minDist2 = double(dupTol) * dupTol;
  const size_t kMax = size_t(k) * kCoverGrowth;
  forBlocks(n, progress, "local Delaunay", 256, [&](size_t b, size_t e) {
    detail::LocalStar star, grown;
    detail::StarScratch scratch;
    std::vector<Vec2d> q(static_cast<size_t>(k)), qg(kMax);
    std::vector<uint32_t> idx(kMax + 1);
    std::vector<float> d2(kMax + 1);
    for (size_t o = b; o < e; ++o) {
      const size_t i = order[o];
      const Vec3d p = pos[i].cast<double>();
      Vec3d x, y;
      householderTangents(g.normals[i].cast<double>(), x, y);
      int m = 0;
      for (; m < k; ++m) {
        const uint32_t j = g.neighbours[i * k + m];
        if (j == kNone) break;
        const Vec3d d = pos[j].cast<double>() - p;
        q[size_t(m)] = Vec2d(d.dot(x), d.dot(y));
      }
      std::span<const Vec2d> qs(q.data(), size_t(m));
      auto build = [&](std::span<const Vec2d> pts, detail::LocalStar& out) {
        if (useCgal) detail::localDelaunayStarCgal(pts, minDist2, out);
        else detail::localDelaunayStar(pts, minDist2, out, scratch);
      };
      build(qs, star);
      double total = 0;
      for (double a : star.areas) total += a;
      const size_t s = star.ids.size();
      for (size_t t = 0; t < s; ++t) {
        tmpIdx[i * k + t] = g.neighbours[i * k + size_t(star.ids[t])];
        tmpW[i * k + t] = total > 0 ? float(star.areas[t] / total) : 0.0f;
      }
      count[i] = uint32_t(s);
      if (star.triangles == 0) g.flags[i] |= kPointNoStar;
      if (g.coverRadius.empty()) continue;
      double rmax = starCircumradius(qs, star);
      // An open star from a full row (m == k; a shorter row lists the cloud): grow it.
      if (tree && m == k && star.boundary) {
        for (size_t want = 2 * size_t(k); want <= kMax && want < n; want *= 2) {
          nanoflann::KNNResultSet<float, uint32_t> rs(want + 1);  // + the point itself
          rs.init(idx.data(), d2.data());
          tree->findNeighbors(rs, pos[i].data(), nanoflann::SearchParams());
          if (reach && rs.size() > 0) (*reach)[i] = std::max((*reach)[i], std::sqrt(d2[rs.size() - 1]));
          size_t mg = 0;
          for (size_t t = 0; t < rs.size() && mg < want; ++t) {
            if (idx[t] == i) continue;
            const Vec3d d = pos[idx[t]].cast<double>() - p;
            qg[mg++] = Vec2d(d.dot(x), d.dot(y));
          }
          const std::span<const Vec2d> qgs(qg.data(), mg);
          build(qgs, grown);
          if (!grown.boundary) {
            rmax = starCircumradius(qgs, grown);
            break;
          }
        }
        // still open with 4k neighbours: a border of the surface, its open side has none; the
        // k-star's radius stays (a wider star only adds long triangles along the border)
      }
      g.coverRadius[i] = float(kCoverMargin * rmax);
    }
  });
  g.delaunayOffsets.assign(n + 1, 0);
  for (size_t i = 0; i < n; ++i) g.delaunayOffsets[i + 1] = g.delaunayOffsets[i] + count[i];
  g.delaunayIndices.resize(g.delaunayOffsets[n]);
  g.delaunayWeights.resize(g.delaunayOffsets[n]);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      std::copy_n(tmpIdx.begin() + i * k, count[i], g.delaunayIndices.begin() + g.delaunayOffsets[i]);
      std::copy_n(tmpW.begin() + i * k, count[i], g.delaunayWeights.begin() + g.delaunayOffsets[i]);
    }
  }, 4096);
}


/// The cover radius of a point off the surface bounded by its neighbours' spacing (beyond the
/// thesis; docs/decisions.md "Spacing and the cover radius"): an outlier's own spacing is its
/// distance to the surface, so 3 x its own spacing drew it as a disc of that size; the median of
/// its neighbours' spacing is the surface's. The median, not the largest: a cluster of up to k/2
/// outliers does not vouch for itself. A tile's point reads its neighbours' spacing, so its reach
/// grows by their k-balls (the halo must hold those too for the tile to reproduce the radius).
void boundByNeighbours(PointGeometry& g, std::vector<float>* reach) {
  const size_t n = g.spacing.size(), k = size_t(g.k);
  auto kth = [&](size_t j) {
    for (size_t t = k; t-- > 0;)
      if (g.neighbours[j * k + t] != kNone) return g.neighbourDistances[j * k + t];
    return 0.0f;
  };
  std::vector<float> grown(reach ? n : 0);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    std::vector<float> s;
    for (size_t i = b; i < e; ++i) {
      s.clear();
      float far = 0;
      for (size_t t = 0; t < k && g.neighbours[i * k + t] != kNone; ++t) {
        const uint32_t j = g.neighbours[i * k + t];
        s.push_back(g.spacing[j]);
        if (reach) far = std::max(far, g.neighbourDistances[i * k + t] + kth(j));
      }
      if (reach) grown[i] = far;
      if (s.empty()) continue;
      std::nth_element(s.begin(), s.begin() + ptrdiff_t(s.size() / 2), s.end());
      const float median = s[s.size() / 2];
      if (median > 0 && g.spacing[i] > kOffSurfaceRatio * median)
        g.coverRadius[i] = std::min(g.coverRadius[i], kNeighbourBound * median);
    }
  }, 4096);
  if (reach)
    for (size_t i = 0; i < n; ++i) (*reach)[i] = std::max((*reach)[i], grown[i]);
}

}  // namespace

size_t PointGeometry::countFlag(PointFlag f) const {
  size_t c = 0;
  for (uint8_t v : flags)
    if (f == kPointOk ? v == 0 : (v & f) != 0) ++c;
  return c;
}

void validate(const GeometryOptions& options) {
  if (options.k < 3) throwBadOption("k", "must be at least 3 (got " + std::to_string(options.k) + ")");
  if (options.k > 256) throwBadOption("k", "must be at most 256 (got " + std::to_string(options.k) + ")");
  requireRange("orientationPenalty", options.orientationPenalty, 0, 1e6);
  if (!options.viewpoint.allFinite()) throwBadOption("viewpoint", "must be finite");
}

PointGeometry computePointGeometry(const HybridModel& cloud, const GeometryOptions& options) {
  return detail::computePointGeometryTile(cloud, options, -1.0f, nullptr);
}

PointGeometry detail::computePointGeometryTile(const HybridModel& cloud, const GeometryOptions& options, float dupTolOverride,
                                               TileGeometryExtras* extras) {
  validate(options);
  for (size_t i = 0; i < cloud.points.size(); ++i)
    if (!cloud.points[i].position.allFinite())
      throwBadParameter("points", "point " + std::to_string(i) + " has a non-finite position");
  PointGeometry g;
  const int k = options.k;
  g.k = k;
  const size_t n = cloud.points.size();
  g.flags.assign(n, kPointOk);
  const Bounds3f bb = cloud.bounds();
  const float diag = n > 0 ? bb.diagonal().norm() : 0.0f;
  const float dupTol = dupTolOverride >= 0 ? dupTolOverride : 1e-6f * diag;
  const ProgressFn& progress = options.progress;

  Timer timer;
  std::vector<Vec3f> pos(n);
  for (size_t i = 0; i < n; ++i) pos[i] = cloud.points[i].position;
  std::vector<uint32_t> order;
  CloudAdaptor adaptor{&pos};
  KdTree tree(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  if (n >= 2) tree.buildIndex();
  computeNeighbours(pos, tree, k, g, order, progress);
  g.times.neighbours = timer.seconds();
  if (extras) {
    // The farthest point any query of point i looked at: its k-th neighbour, widened below by the
    // cover-radius growth (stage 3). A tile reproduces the in-memory result for i when this ball
    // lies inside the tile's halo.
    extras->reach.assign(n, 0.0f);
    for (size_t i = 0; i < n; ++i)
      for (int t = k - 1; t >= 0; --t)
        if (g.neighbours[i * k + t] != kNone) {
          extras->reach[i] = g.neighbourDistances[i * k + t];
          break;
        }
    extras->component.clear();
  }

  timer.reset();
  const bool keepFile = cloud.attributes.normals && !options.recomputeNormals;
  std::vector<uint8_t> fixedNormal;
  computeNormals(cloud, pos, order, k, dupTol, keepFile, g, fixedNormal, progress);
  g.times.normals = timer.seconds();

  timer.reset();
  const bool needOrient = options.orientNormals &&
                          std::any_of(fixedNormal.begin(), fixedNormal.end(), [](uint8_t f) { return f == 0; });
  if (needOrient) {
    reportProgress(progress, "orientation", 0.0);
    // A tile of an out-of-core run leaves the side to the join, which sees the whole component.
    const detail::SideChoice side{options.orient, options.viewpoint, !extras};
    detail::orientNormals(pos, k, options.orientationPenalty, side, g, fixedNormal, extras ? &extras->component : nullptr);
    reportProgress(progress, "orientation", 1.0);
  }
  g.times.orientation = timer.seconds();

  if (options.delaunayNeighbours || options.curvature || options.coverRadius) {
    timer.reset();
    if (options.coverRadius) g.coverRadius.assign(n, 0.0f);
    computeDelaunay(pos, n >= 2 ? &tree : nullptr, order, k, dupTol, options.cgalDelaunay, g, progress,
                    extras ? &extras->reach : nullptr);
    if (!options.delaunayNeighbours && !options.curvature) {  // stage 3 ran only for the radii
      g.delaunayOffsets.clear();
      g.delaunayIndices.clear();
      g.delaunayWeights.clear();
    }
    g.times.delaunay = timer.seconds();
  }
  if (options.curvature) {
    timer.reset();
    detail::computeCurvature(pos, order, options.curvatureFit, g, progress);
    g.times.curvature = timer.seconds();
  }

  // Stage 5: spacing = mean distance to the k nearest neighbours; global = mean over points.
  timer.reset();
  g.spacing.assign(n, 0.0f);
  parallelForRange(0, n, [&](size_t b, size_t e) {
    for (size_t i = b; i < e; ++i) {
      double s = 0;
      int c = 0;
      for (int t = 0; t < k && g.neighbours[i * k + t] != kNone; ++t) s += g.neighbourDistances[i * k + t], ++c;
      g.spacing[i] = c > 0 ? float(s / c) : 0.0f;
    }
  }, 4096);
  double total = 0;
  size_t counted = 0;
  for (size_t i = 0; i < n; ++i)
    if (g.neighbours.empty() || g.neighbours[i * k] != kNone) total += g.spacing[i], ++counted;
  g.averageSpacing = counted > 0 ? float(total / double(counted)) : 0.0f;
  for (size_t i = 0; i < g.coverRadius.size(); ++i)  // a degenerate star must not blow a disc up
    g.coverRadius[i] = std::min(g.coverRadius[i], 3.0f * (g.spacing[i] > 0 ? g.spacing[i] : g.averageSpacing));
  if (!g.coverRadius.empty()) boundByNeighbours(g, extras ? &extras->reach : nullptr);
  g.times.spacing = timer.seconds();
  return g;
}

void applyGeometry(HybridModel& cloud, const PointGeometry& geometry) {
  const size_t n = std::min(cloud.points.size(), geometry.size());
  for (size_t i = 0; i < n; ++i) cloud.points[i].normal = geometry.normals[i];
  cloud.attributes.normals = true;
  if (!cloud.attributes.radii && geometry.spacing.size() >= n) {
    // Radius rule (docs/decisions.md): the hole-free cover radius, else the per-point spacing,
    // else the cloud's average.
    const bool cover = geometry.coverRadius.size() >= n;
    for (size_t i = 0; i < n; ++i)
      cloud.points[i].radius = cover && geometry.coverRadius[i] > 0 ? geometry.coverRadius[i]
                               : geometry.spacing[i] > 0            ? geometry.spacing[i]
                                                                    : geometry.averageSpacing;
    cloud.attributes.radii = true;
  }
}

void addCurvatureProperties(HybridModel& cloud, const PointGeometry& geometry) {
  const size_t n = cloud.points.size();
  if (geometry.kMin.size() != n) throwBadParameter("curvature", "geometry has no curvature for this cloud");
  auto& props = cloud.pointProperties;
  props["k_min"] = geometry.kMin;
  props["k_max"] = geometry.kMax;
  std::vector<float> dx(n), dy(n), dz(n);
  for (size_t i = 0; i < n; ++i) {
    dx[i] = geometry.minCurvatureDir[i].x();
    dy[i] = geometry.minCurvatureDir[i].y();
    dz[i] = geometry.minCurvatureDir[i].z();
  }
  props["dmin_x"] = std::move(dx);
  props["dmin_y"] = std::move(dy);
  props["dmin_z"] = std::move(dz);
}

}  // namespace linesurf

