// Summary of a model file (linesurf info): counts, bounds, attributes, average spacing.
#include "linesurf/io/model_stats.h"

#include <nanoflann.hpp>

#include <algorithm>
#include <cmath>

#include "linesurf/core/parallel.h"
#include "linesurf/io/model_io.h"
#include "linesurf/io/model_validate.h"

namespace linesurf {

namespace {
struct Cloud {
  const std::vector<Vec3f>& p;
  size_t kdtree_get_point_count() const { return p.size(); }
  float kdtree_get_pt(size_t i, size_t d) const { return p[i][int(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const { return false; }
};
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>, Cloud, 3, uint32_t>;
}  // namespace

double averageSpacing(const std::vector<Vec3f>& positions) {
  const size_t n = positions.size();
  if (n < 2) return 0;
  Cloud cloud{positions};
  Tree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  std::vector<double> nearest(n, 0.0);
  parallelFor(0, n, [&](size_t i) {
    uint32_t idx[2];
    float d2[2];
    size_t found = tree.knnSearch(positions[i].data(), 2, idx, d2);
    // The query point itself comes back at distance 0; with duplicates it may be second.
    float best = std::numeric_limits<float>::infinity();
    for (size_t k = 0; k < found; ++k)
      if (idx[k] != i) best = std::min(best, d2[k]);
    nearest[i] = std::isfinite(best) ? std::sqrt(double(best)) : 0.0;
  }, 1024);
  double sum = 0;  // serial sum: same result for any thread count
  for (double d : nearest) sum += d;
  return sum / double(n);
}

size_t estimateSegmentRadii(HybridModel& m) {
  size_t missing = 0;
  for (const Segment& s : m.segments) missing += s.radius == 0.0f;
  if (missing == 0) return 0;
  // Centres of every primitive: points and segment midpoints (computed in a frame centred on
  // the model, so distances do not lose precision far from the origin).
  std::vector<Vec3f> centres;
  centres.reserve(m.points.size() + m.segments.size());
  for (const Point& p : m.points) centres.push_back(p.position);
  for (const Segment& s : m.segments) centres.push_back(0.5f * (s.p0 + s.p1));
  if (centres.size() < 2) {
    for (Segment& s : m.segments)
      if (s.radius == 0.0f) s.radius = s.length() > 0 ? 0.25f * s.length() : 1.0f;
    return missing;
  }
  Cloud cloud{centres};
  Tree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  tree.buildIndex();
  for (size_t i = 0; i < m.segments.size(); ++i) {
    Segment& s = m.segments[i];
    if (s.radius != 0.0f) continue;
    const size_t self = m.points.size() + i;
    uint32_t idx[4];
    float d2[4];
    const size_t found = tree.knnSearch(centres[self].data(), 4, idx, d2);
    float best = std::numeric_limits<float>::infinity();
    for (size_t k = 0; k < found; ++k)
      if (idx[k] != self && d2[k] > 0) best = std::min(best, d2[k]);
    const float len = s.length();
    float r = std::isfinite(best) ? 0.75f * std::sqrt(best) : 0.25f * len;
    if (len > 0) r = std::clamp(r, 0.05f * len, len);
    if (!(r > 0) || !std::isfinite(r)) r = len > 0 ? 0.25f * len : 1.0f;
    s.radius = r;
  }
  return missing;
}

ModelSummary summarizeFile(const std::filesystem::path& path, std::vector<Vec3f>* positions) {
  ModelSummary s;
  if (fileHoldsMesh(path)) {
    TriangleMesh m = readMesh(path);
    s.kind = "mesh";
    s.vertices = m.positions.size();
    s.faces = m.faces.size();
    s.bounds = m.bounds();
    if (!m.normals.empty()) s.properties.push_back("normals");
    if (!m.colors.empty()) s.properties.push_back("colors");
    if (!m.cornerUVs.empty()) s.properties.push_back("texcoords");
    s.averageSpacing = averageSpacing(m.positions);
    if (m.texture) s.textureWidth = m.texture->width, s.textureHeight = m.texture->height;
    s.comments = m.comments;
    if (positions) *positions = std::move(m.positions);
    return s;
  }
  HybridModel m = readModel(path);
  s.kind = m.segments.empty() ? "points" : "hybrid";
  s.points = m.points.size();
  s.segments = m.segments.size();
  s.bounds = m.bounds();
  if (m.attributes.normals) s.properties.push_back("normals");
  if (m.attributes.colors) s.properties.push_back("colors");
  if (m.attributes.radii) s.properties.push_back("radii");
  if (m.attributes.texcoords) s.properties.push_back("texcoords");
  if (m.attributes.shadingNormals) s.properties.push_back("shading normals");
  if (!m.provenance.empty()) s.properties.push_back("provenance");
  for (const auto& kv : m.pointProperties) s.properties.push_back(kv.first);
  for (const auto& kv : m.segmentProperties)
    if (!m.pointProperties.count(kv.first)) s.properties.push_back("segment " + kv.first);
  std::vector<Vec3f> pos(m.points.size());
  for (size_t i = 0; i < pos.size(); ++i) pos[i] = m.points[i].position;
  s.averageSpacing = averageSpacing(pos);
  if (m.attributes.radii && !m.points.empty()) {
    std::vector<float> r(m.points.size());
    for (size_t i = 0; i < r.size(); ++i) r[i] = m.points[i].radius;
    const auto [lo, hi] = std::minmax_element(r.begin(), r.end());
    s.radiusMin = *lo, s.radiusMax = *hi;
    std::vector<float> sorted = r;
    std::nth_element(sorted.begin(), sorted.begin() + ptrdiff_t(sorted.size() / 2), sorted.end());
    s.radiusMedian = sorted[sorted.size() / 2];
    for (float x : r) s.radiiAbove10xMedian += x > 10 * s.radiusMedian;
  }
  if (m.texture) s.textureWidth = m.texture->width, s.textureHeight = m.texture->height;
  s.comments = m.comments;
  if (positions) *positions = std::move(pos);
  return s;
}

}  // namespace linesurf
