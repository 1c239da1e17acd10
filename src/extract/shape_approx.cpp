// Shape-approximation based line-segment extraction, thesis §3.2.4 (per-cluster segment bunches).
#include "linesurf/extract/shape_approx.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "detail/endpoint_normals.h"
#include "detail/segment_attributes.h"
#include "detail/segment_width.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf {
void validate(const ShapeApproxOptions& o) {
  validate(o.clustering);
  if (o.minClusterSize < 2)
    throwBadOption("minClusterSize", "must be >= 2 (got " + std::to_string(o.minClusterSize) + ")");
  if (o.minRunPoints < 2)
    throwBadOption("minRunPoints", "must be >= 2 (got " + std::to_string(o.minRunPoints) + ")");
  requireRange("curvatureSwitchDegrees", o.curvatureSwitchDegrees, 0, 90, "degrees");
  requireRange("curvatureCoherence", o.curvatureCoherence, 0, 1);
  if (!(o.radiusScale > 0 && o.radiusScale <= 1e3))
    throwBadOption("radiusScale", "must be in (0, 1000] (got " + numberText(o.radiusScale) + ")");
}

namespace {

/// What one cluster contributes; clusters are processed independently and concatenated in order.
struct ClusterOutput {
  std::vector<Segment> segments;
  std::vector<std::vector<uint32_t>> provenance;  ///< always filled: the widths need the members
  bool small = false, degenerate = false, curvatureUsed = false;
  size_t degenerateRuns = 0;
};

struct Context {
  const HybridModel& cloud;
  const PointGeometry& geometry;
  const Clustering& clustering;
  const ShapeApproxOptions& options;
  std::vector<uint8_t>& replaced;  ///< per point; each cluster writes only its own members
};

/// §3.2.4.1: the two tangent columns of the Householder matrix that maps e1 to +-n.
void householderFrame(const Vec3d& n, Vec3d& x, Vec3d& y) {
  // v = n -+ e1, choosing the sign that keeps |v| away from 0 (H n = +-e1, H e1 = +-n).
  Vec3d v = n;
  v.x() += n.x() > 0 ? 1.0 : -1.0;
  Mat3d h = Mat3d::Identity() - 2.0 * v * v.transpose() / v.squaredNorm();
  x = h.col(1);
  y = h.col(2);
}

ClusterOutput extractCluster(size_t c, const Context& ctx) {
  ClusterOutput out;
  const auto& g = ctx.geometry;
  const auto& opt = ctx.options;
  const auto members = ctx.clustering.membersOf(c);
  const size_t m = members.size();
  if (m < size_t(opt.minClusterSize)) {
    out.small = true;
    return out;
  }
  const Vec3d n = ctx.clustering.seedingNormals[c].cast<double>();
  if (!(n.squaredNorm() > 0.25)) {
    out.degenerate = true;
    return out;
  }
  auto position = [&](uint32_t p) { return ctx.cloud.points[p].position.cast<double>(); };

  // §3.2.4.1 centroid, frame, projection onto the xy plane.
  Vec3d centroid = Vec3d::Zero();
  for (uint32_t p : members) centroid += position(p);
  centroid /= double(m);
  Vec3d x0, y0;
  householderFrame(n.normalized(), x0, y0);
  std::vector<Vec2d> proj(m);
  for (size_t i = 0; i < m; ++i) {
    Vec3d d = position(members[i]) - centroid;
    proj[i] = Vec2d(d.dot(x0), d.dot(y0));
  }

  // §3.2.4.2 shape direction d_s: longer edges of the minimum-area rectangle.
  const Rectangle2 rect = minAreaRectangle(proj);
  if (!(rect.longLength > 0)) {
    out.degenerate = true;
    return out;
  }
  Vec2d df = rect.longAxis;
  // Average minimum-curvature direction as an axial (sign-free) mean: doubled angles.
  if (g.minCurvatureDir.size() == g.size() && opt.curvatureCoherence < 1.0f) {
    double sx = 0, sy = 0;
    size_t cnt = 0;
    for (uint32_t p : members) {
      const Vec3d k = g.minCurvatureDir[p].cast<double>();
      double a = k.dot(x0), b = k.dot(y0), len2 = a * a + b * b;
      if (!(len2 > 1e-12) || !std::isfinite(len2)) continue;
      sx += (a * a - b * b) / len2, sy += 2 * a * b / len2, ++cnt;
    }
    if (cnt > 0 && std::hypot(sx, sy) / double(cnt) >= opt.curvatureCoherence) {
      double ang = 0.5 * std::atan2(sy, sx);
      Vec2d kmin(std::cos(ang), std::sin(ang));
      double between = std::acos(std::min(1.0, std::abs(kmin.dot(df)))) * 180.0 / std::numbers::pi;
      if (between > opt.curvatureSwitchDegrees) {
        df = kmin;
        out.curvatureUsed = true;
      }
    }
  }

  // §3.2.4.3 rotate the frame so y follows d_f; project again.
  const Vec3d Y = (df.x() * x0 + df.y() * y0).normalized();
  const Vec3d X = Y.cross(n).normalized();
  for (size_t i = 0; i < m; ++i) {
    Vec3d d = position(members[i]) - centroid;
    proj[i] = Vec2d(d.dot(X), d.dot(Y));
  }
  // Average projected spacing along x and y. Per point, the x spacing averages |dx| over the
  // Delaunay neighbours that lie closer to the x axis than to the y axis (and vice versa), so a
  // regular grid of spacing h gives h (docs/decisions.md).
  std::vector<double> avgX(m, -1), avgY(m, -1);
  const bool haveDelaunay = g.delaunayOffsets.size() == g.size() + 1;
  double sumX = 0, sumY = 0;
  size_t cntX = 0, cntY = 0;
  const auto& labels = ctx.clustering.labels;
  for (size_t i = 0; i < m; ++i) {
    const uint32_t p = members[i];
    double ax = 0, ay = 0, allX = 0, allY = 0;
    int nx = 0, ny = 0, all = 0;
    auto visit = [&](uint32_t q, bool sameClusterOnly) {
      if (q >= g.size() || q == p || (sameClusterOnly && labels[q] != c)) return;
      Vec3d d = position(p) - position(q);
      double dx = std::abs(d.dot(X)), dy = std::abs(d.dot(Y));
      allX += dx, allY += dy, ++all;
      if (dx >= dy) ax += dx, ++nx;
      if (dy >= dx) ay += dy, ++ny;
    };
    for (bool sameOnly : {true, false}) {
      if (haveDelaunay) {
        for (uint32_t q : g.delaunayOf(p)) visit(q, sameOnly);
      } else {
        for (int a = 0; a < g.k; ++a) visit(g.neighbours[size_t(p) * g.k + a], sameOnly);
      }
      if (all > 0) break;
    }
    if (all == 0) continue;
    avgX[i] = nx ? ax / nx : allX / all;
    avgY[i] = ny ? ay / ny : allY / all;
    if (avgX[i] > 0) sumX += avgX[i], ++cntX;
    if (avgY[i] > 0) sumY += avgY[i], ++cntY;
  }
  if (cntX == 0 || cntY == 0) {
    out.degenerate = true;
    return out;
  }
  const double dAvgX = sumX / double(cntX), dAvgY = sumY / double(cntY);
  for (size_t i = 0; i < m; ++i) {
    if (!(avgX[i] > 0)) avgX[i] = dAvgX;
    if (!(avgY[i] > 0)) avgY[i] = dAvgY;
  }

  // §3.2.4.4 grid over the x/y-aligned bounding rectangle R_s.
  double minX = proj[0].x(), maxX = minX, minY = proj[0].y(), maxY = minY;
  for (const Vec2d& q : proj) {
    minX = std::min(minX, q.x()), maxX = std::max(maxX, q.x());
    minY = std::min(minY, q.y()), maxY = std::max(maxY, q.y());
  }
  // Counts: the number of sample rows a width holds (fence posts: extent/spacing + 1).
  const size_t cy = std::clamp<size_t>(size_t(std::llround((maxX - minX) / dAvgX)) + 1, 1, m);  // y-slices
  const size_t cx = std::clamp<size_t>(size_t(std::llround((maxY - minY) / dAvgY)) + 1, 1, 4 * m + 1);  // x-slices
  const double square = (maxY - minY) / double(cx);  // uniform x-slice height along y
  auto squareOf = [&](double yv) -> int64_t {
    if (!(square > 0)) return 0;
    return std::clamp<int64_t>(int64_t(std::floor((yv - minY) / square)), 0, int64_t(cx) - 1);
  };

  // Equal-count y-slices: rank along x decides a point's slice; the geometric boundaries
  // (midway between the ranks that separate slices) decide which slices a zone influences.
  std::vector<uint32_t> order(m);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    return proj[a].x() < proj[b].x() || (proj[a].x() == proj[b].x() && members[a] < members[b]);
  });
  std::vector<size_t> sliceStart(cy + 1);
  for (size_t k = 0; k <= cy; ++k) sliceStart[k] = k * m / cy;
  std::vector<double> boundary(cy + 1);
  boundary[0] = -std::numeric_limits<double>::infinity();
  boundary[cy] = std::numeric_limits<double>::infinity();
  for (size_t k = 1; k < cy; ++k)
    boundary[k] = 0.5 * (proj[order[sliceStart[k] - 1]].x() + proj[order[sliceStart[k]]].x());
  double maxZoneX = 0;
  for (size_t i = 0; i < m; ++i) maxZoneX = std::max(maxZoneX, avgX[i]);
  std::vector<double> sortedX(m);
  for (size_t r = 0; r < m; ++r) sortedX[r] = proj[order[r]].x();

  const bool colors = ctx.cloud.attributes.colors;
  std::vector<std::pair<int64_t, int64_t>> intervals;
  std::vector<std::pair<int64_t, uint32_t>> own;  // (square, local index) of the slice's points
  for (size_t k = 0; k < cy; ++k) {
    const double lo = boundary[k], hi = boundary[k + 1];
    // Influence zones Z(p'_j): 2 d_avg,x(p'_j) by 2 d_avg,y(p'_j) rectangles about p'_j.
    intervals.clear();
    size_t r0 = std::lower_bound(sortedX.begin(), sortedX.end(), lo - maxZoneX) - sortedX.begin();
    size_t r1 = std::upper_bound(sortedX.begin(), sortedX.end(), hi + maxZoneX) - sortedX.begin();
    for (size_t r = r0; r < r1; ++r) {
      const uint32_t i = order[r];
      const double px = proj[i].x(), py = proj[i].y();
      bool inSlice = r >= sliceStart[k] && r < sliceStart[k + 1];
      if (!inSlice && (px + avgX[i] < lo || px - avgX[i] > hi)) continue;
      intervals.emplace_back(squareOf(py - avgY[i]), squareOf(py + avgY[i]));
    }
    std::sort(intervals.begin(), intervals.end());
    own.clear();
    for (size_t r = sliceStart[k]; r < sliceStart[k + 1]; ++r) own.emplace_back(squareOf(proj[order[r]].y()), order[r]);
    std::sort(own.begin(), own.end(), [&](auto& a, auto& b) {
      return a.first < b.first || (a.first == b.first && proj[a.second].y() < proj[b.second].y()) ||
             (a.first == b.first && proj[a.second].y() == proj[b.second].y() && members[a.second] < members[b.second]);
    });
    const double sliceWidth = (k > 0 && k + 1 < cy) ? hi - lo : dAvgX;

    // §3.2.4.5 runs of consecutive influenced squares along +y.
    size_t ownPos = 0, iv = 0;
    while (iv < intervals.size()) {
      int64_t runLo = intervals[iv].first, runHi = intervals[iv].second;
      for (++iv; iv < intervals.size() && intervals[iv].first <= runHi + 1; ++iv) runHi = std::max(runHi, intervals[iv].second);
      while (ownPos < own.size() && own[ownPos].first < runLo) ++ownPos;  // cannot happen: own squares are influenced
      size_t begin = ownPos;
      while (ownPos < own.size() && own[ownPos].first <= runHi) ++ownPos;
      const size_t count = ownPos - begin;
      if (count == 0 || count < size_t(opt.minRunPoints)) continue;
      // Endpoints: the run's points with the smallest and largest y (own is sorted by y within squares,
      // squares increasing, so these are its first and last entries).
      const uint32_t ls = own[begin].second, le = own[ownPos - 1].second;
      const Vec3d ps = position(members[ls]), pe = position(members[le]);
      Vec3d dir = pe - ps;
      const double len = dir.norm();
      if (!(len > 1e-9 * std::max(1.0, ps.norm())) || !(len > 1e-3 * dAvgY)) {
        ++out.degenerateRuns;
        continue;
      }
      dir /= len;
      Vec3d navg = Vec3d::Zero();
      Eigen::Vector4d col = Eigen::Vector4d::Zero();
      for (size_t e = begin; e < ownPos; ++e) {
        const uint32_t p = members[own[e].second];
        navg += g.normals[p].cast<double>();
        col += ctx.cloud.points[p].color.cast<double>();
      }
      // n(L) = (n_avg - (n_avg . d) d) / |...|: perpendicular to the segment.
      Vec3d nseg = navg - navg.dot(dir) * dir;
      if (!(nseg.norm() > 1e-6 * double(count))) {
        ++out.degenerateRuns;
        continue;
      }
      // Beyond the thesis (docs/decisions.md "Hybrid segment widths"): the line through
      // p_s and p_e moved sideways (in the segment's plane) to the middle of the run's spread
      // across it, so that the farthest member is as close as it can be for this direction.
      const Vec3d across = nseg.normalized().cross(dir);
      double lo = 0, hi = 0;
      for (size_t e = begin; e < ownPos; ++e) {
        const double o = (position(members[own[e].second]) - ps).dot(across);
        lo = std::min(lo, o), hi = std::max(hi, o);
      }
      const Vec3d shift = 0.5 * (lo + hi) * across;
      Segment s;
      s.p0 = (ps + shift).cast<float>();
      s.p1 = (pe + shift).cast<float>();
      s.normal = nseg.normalized().cast<float>();
      if (opt.endpointNormals) detail::setEndpointNormals(s, g.normals[members[ls]], g.normals[members[le]]);
      s.color = colors ? Color((col / double(count)).cast<float>()) : Color(1, 1, 1, 1);
      s.radius = float(opt.radiusScale * std::clamp(sliceWidth, dAvgX, 2.0 * dAvgX));
      // With point radii the width is set once all segments exist (extractShapeApprox below).
      out.segments.push_back(s);
      std::vector<uint32_t> prov;
      prov.reserve(count);
      for (size_t e = begin; e < ownPos; ++e) {
        const uint32_t p = members[own[e].second];
        ctx.replaced[p] = 1;
        prov.push_back(p);
      }
      std::sort(prov.begin(), prov.end());
      out.provenance.push_back(std::move(prov));
    }
  }
  return out;
}

}  // namespace

Clustering clusterShapeApprox(const PointGeometry& geometry, const ShapeApproxOptions& options) {
  return options.method == ClusteringMethod::Hierarchical ? clusterHierarchical(geometry, options.clustering)
                                                         : clusterGreedy(geometry, options.clustering);
}

HybridModel extractShapeApprox(const HybridModel& cloud, const PointGeometry& geometry, const ShapeApproxOptions& options,
                               ShapeApproxStats* stats) {
  validate(options);
  if (geometry.size() != cloud.points.size())
    throwBadParameter("geometry", "holds " + std::to_string(geometry.size()) + " points but the cloud has " +
                                      std::to_string(cloud.points.size()));
  Timer timer;
  ShapeApproxOptions clusteringOptions = options;
  if (!clusteringOptions.clustering.progress) clusteringOptions.clustering.progress = options.progress;
  Clustering clustering = clusterShapeApprox(geometry, clusteringOptions);
  const double clusteringSeconds = timer.seconds();
  HybridModel out = extractShapeApprox(cloud, geometry, clustering, options, stats);
  if (stats) stats->clusteringSeconds = clusteringSeconds;
  return out;
}

HybridModel extractShapeApprox(const HybridModel& cloud, const PointGeometry& geometry, const Clustering& clustering,
                               const ShapeApproxOptions& options, ShapeApproxStats* stats) {
  validate(options);
  const size_t n = cloud.points.size();
  if (geometry.size() != n)
    throwBadParameter("geometry", "holds " + std::to_string(geometry.size()) + " points but the cloud has " +
                                      std::to_string(n));
  if (clustering.labels.size() != n)
    throwBadParameter("clustering", "labels " + std::to_string(clustering.labels.size()) + " points but the cloud has " +
                                        std::to_string(n));
  Timer timer;
  std::vector<uint8_t> replaced(n, 0);
  const size_t nc = clustering.size();
  std::vector<ClusterOutput> outputs(nc);
  Context ctx{cloud, geometry, clustering, options, replaced};
  // Blocks so that progress is reported from the calling thread.
  const size_t block = std::max<size_t>(1024, nc / 50 + 1);
  for (size_t b = 0; b < nc; b += block) {
    const size_t e = std::min(nc, b + block);
    parallelFor(b, e, [&](size_t c) { outputs[c] = extractCluster(c, ctx); }, 8);
    reportProgress(options.progress, "shape-approx segments", double(e) / double(nc));
  }

  HybridModel out;
  out.attributes.normals = true;
  out.attributes.colors = cloud.attributes.colors;
  out.attributes.radii = true;
  out.attributes.endpointNormals = options.endpointNormals;
  out.comments = cloud.comments;
  out.comments.push_back(std::string("linesurf: shape-approximation extraction (§3.2), ") +
                         (options.method == ClusteringMethod::Hierarchical ? "hierarchical" : "greedy") +
                         " clustering, delta_n " + std::to_string(options.clustering.deltaN));
  std::vector<uint32_t> kept;
  for (size_t i = 0; i < n; ++i)
    if (!replaced[i]) kept.push_back(uint32_t(i));
  out.points.reserve(kept.size());
  const bool haveSpacing = geometry.spacing.size() == n;
  for (uint32_t i : kept) {
    Point p = cloud.points[i];
    p.normal = geometry.normals[i];
    // Same rule as applyGeometry: the per-point spacing, else the cloud's average spacing.
    if (!(p.radius > 0) && haveSpacing) p.radius = geometry.spacing[i] > 0 ? geometry.spacing[i] : geometry.averageSpacing;
    out.points.push_back(p);
  }
  for (const auto& [name, values] : cloud.pointProperties) {
    if (values.size() != n) continue;
    auto& dst = out.pointProperties[name];
    dst.reserve(kept.size());
    for (uint32_t i : kept) dst.push_back(values[i]);
  }
  ShapeApproxStats st;
  std::vector<uint32_t> owner(n, detail::kKeptPoint);  // the segment that replaced each point
  for (size_t c = 0; c < nc; ++c) {
    auto& o = outputs[c];
    st.segments += o.segments.size();
    for (auto& p : o.provenance) {
      for (uint32_t j : p) owner[j] = uint32_t(out.segments.size());
      out.segments.push_back(o.segments[&p - o.provenance.data()]);
      if (options.provenance) out.provenance.push_back(std::move(p));
    }
    st.smallClusters += o.small;
    st.degenerateClusters += o.degenerate;
    st.curvatureDirectionUsed += o.curvatureUsed;
    st.clustersWithSegments += !o.segments.empty();
    st.degenerateRuns += o.degenerateRuns;
    const size_t size = clustering.clusterSize(c);
    int bin = size <= 1 ? 0 : size <= 3 ? 1 : size <= 9 ? 2 : size <= 99 ? 3 : size <= 999 ? 4 : 5;
    ++st.sizeHistogram[bin];
    if (size > 100) ++st.largeClusters, st.largeClusterPoints += size;
  }
  // Hybrids close where their point models close: with point radii, the strips and
  // the kept discs cover every replaced point's Voronoi cell (the rule of the hole-free point
  // radius), no wider than each member's disc plus its distance (the rule of §3.1.5);
  // docs/decisions.md "Hybrid segment widths". Without radii the slice-width rule stays.
  if (cloud.attributes.radii) {
    std::vector<double> radii(n);
    for (size_t j = 0; j < n; ++j) radii[j] = cloud.points[j].radius;
    detail::setSegmentWidths(out.segments, owner, radii, cloud, geometry);
  }
  detail::setSegmentProperties(out, cloud, owner);
  st.inputPoints = n;
  st.clusters = nc;
  st.pointsKept = kept.size();
  st.pointsReplaced = n - kept.size();
  st.splits = clustering.splits;
  st.iterations = clustering.iterations;
  st.extractionSeconds = timer.seconds();
  if (stats) *stats = st;
  return out;
}

}  // namespace linesurf
