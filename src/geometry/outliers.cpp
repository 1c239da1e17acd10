// Outliers of a scanned point cloud (see geometry/outliers.h).
#include "linesurf/geometry/outliers.h"

#include <algorithm>
#include <cmath>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"

namespace linesurf {
namespace {

/// The element at v.size() / parts in ascending order (parts 2: the median).
float quantile(std::vector<float>& v, size_t parts) {
  std::nth_element(v.begin(), v.begin() + ptrdiff_t(v.size() / parts), v.end());
  return v[v.size() / parts];
}
float median(std::vector<float>& v) { return quantile(v, 2); }

}  // namespace

void validate(const OutlierOptions& o) {
  requireRange("offSurface", o.offSurface, 0.1, 1e6);
  requireRange("isolated", o.isolated, 1, 1e6);
  requireRange("sparse", o.sparse, 1, 1e6);
  requireRange("floaterVariation", o.floaterVariation, 0, 1.0 / 3.0);
}

OutlierReport findOutliers(const PointGeometry& g, const std::vector<Vec3f>& pos, const OutlierOptions& o) {
  validate(o);
  const size_t n = pos.size(), k = size_t(g.k);
  if (g.neighbours.size() != n * k || g.normals.size() != n || g.spacing.size() != n || g.surfaceVariation.size() != n)
    throwBadParameter("geometry", "does not belong to the cloud (computePointGeometry of the same points)");
  OutlierReport r;
  r.kind.assign(n, kNotOutlier);
  float cloudMedian = 0;
  {
    std::vector<float> s;
    s.reserve(n);
    for (size_t i = 0; i < n; ++i)
      if (g.spacing[i] > 0) s.push_back(g.spacing[i]);
    if (!s.empty()) cloudMedian = median(s);
  }
  parallelForRange(0, n, [&](size_t b, size_t e) {
    std::vector<float> spacing, offset;
    for (size_t i = b; i < e; ++i) {
      spacing.clear(), offset.clear();
      for (size_t t = 0; t < k && g.neighbours[i * k + t] != PointGeometry::kNoNeighbour; ++t) {
        const uint32_t j = g.neighbours[i * k + t];
        spacing.push_back(g.spacing[j]);
        // How far i lies off the tangent plane neighbour j sees the surface in.
        offset.push_back(std::abs(g.normals[j].dot(pos[i] - pos[j])));
      }
      if (spacing.size() < 3) continue;  // too few neighbours to judge (the geometry flags them)
      const float local = median(spacing);
      if (!(local > 0)) continue;
      uint8_t kind = kNotOutlier;
      // The mean distance to the k nearest of points spread over a plane at spacing h is about
      // 0.376 sqrt(k) h: the threshold is in spacings h, whatever k.
      // The lower quartile: at an edge or a crease, the neighbours on the point's own side (about
      // half) see it in their plane, while a cluster of outliers is a few of its k neighbours.
      if (quantile(offset, 4) > o.offSurface * local / (0.376f * std::sqrt(float(k)))) kind |= kOffSurface;
      if (g.spacing[i] > o.isolated * local) kind |= kIsolatedPoint;
      if (cloudMedian > 0 && g.spacing[i] > o.sparse * cloudMedian && g.surfaceVariation[i] > o.floaterVariation) kind |= kFloater;
      r.kind[i] = kind;
    }
  }, 2048);
  for (uint8_t kind : r.kind) {
    r.offSurface += (kind & kOffSurface) != 0;
    r.isolated += (kind & kIsolatedPoint) != 0;
    r.floaters += (kind & kFloater) != 0;
    r.total += kind != kNotOutlier;
  }
  return r;
}

HybridModel withoutOutliers(const HybridModel& cloud, const OutlierReport& report, bool outliers) {
  if (!cloud.segments.empty()) throwBadParameter("cloud", "has segments: remove outliers before an extraction");
  if (report.kind.size() != cloud.points.size()) throwBadParameter("report", "does not belong to the cloud");
  HybridModel out;
  out.attributes = cloud.attributes;
  out.comments = cloud.comments;
  auto kept = [&](size_t i) { return (report.kind[i] != kNotOutlier) == outliers; };
  out.points.reserve(outliers ? report.total : cloud.points.size() - report.total);
  for (size_t i = 0; i < cloud.points.size(); ++i)
    if (kept(i)) out.points.push_back(cloud.points[i]);
  // Every per-point column follows its points.
  auto keep = [&](const auto& column, auto& into) {
    for (size_t i = 0; i < column.size(); ++i)
      if (kept(i)) into.push_back(column[i]);
  };
  if (cloud.pointShadingNormals.size() == cloud.points.size()) keep(cloud.pointShadingNormals, out.pointShadingNormals);
  for (const auto& [name, column] : cloud.pointProperties)
    if (column.size() == cloud.points.size()) keep(column, out.pointProperties[name]);
  return out;
}

}  // namespace linesurf
