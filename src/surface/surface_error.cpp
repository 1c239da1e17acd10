// The surface error of an extraction (beyond the thesis; see surface/surface_error.h): two MLS
// surfaces (thesis §9.1), or a mesh and one, sampled both ways.
#include "linesurf/surface/surface_error.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <string>

#include "detail/mesh_closest.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/geometry/point_geometry.h"
#include "detail/point_tree.h"

namespace linesurf {
namespace {

using detail::PointCloud;
using detail::PointTree;

/// Points and a kd-tree over them: the nearest source of a surface whose projection failed.
struct Nearest {
  PointCloud cloud;
  std::unique_ptr<PointTree> tree;
  explicit Nearest(std::vector<Vec3f> pts) {
    cloud.pts = std::move(pts);
    tree = std::make_unique<PointTree>(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
    tree->buildIndex();
  }
  Vec3d operator()(const Vec3d& x) const {
    const float q[3] = {float(x.x()), float(x.y()), float(x.z())};
    uint32_t i = 0;
    float d2 = 0;
    tree->knnSearch(q, 1, &i, &d2);
    return cloud.pts[i].cast<double>();
  }
};

/// Every index when n <= s, else s indices by a fixed stride (the middle of each of s runs).
std::vector<size_t> strided(size_t n, size_t s) {
  std::vector<size_t> idx;
  const size_t m = std::min(n, s);
  idx.reserve(m);
  for (size_t i = 0; i < m; ++i) idx.push_back(n <= s ? i : size_t((double(i) + 0.5) * double(n) / double(s)));
  return idx;
}

/// A surface's projection: the point, or nothing when it failed.
using Projector = std::function<std::optional<Vec3d>(const Vec3d&)>;

/// The error of each sample: the distance between its projections onto the reference (a) and
/// the model (b); a failed one replaced by the failed surface's nearest source (header).
struct Errors {
  std::vector<double> d;
  size_t failedReference = 0, failedModel = 0;
};
Errors errorsOf(const std::vector<Vec3d>& samples, const Projector& ref, const Nearest& refNearest, const Projector& mod,
                const Nearest& modNearest) {
  const size_t n = samples.size();
  std::vector<double> d(n);
  std::vector<uint8_t> failed(n);  // bit 0: reference, bit 1: model
  parallelFor(0, n, [&](size_t i) {
    const Vec3d& x = samples[i];
    const std::optional<Vec3d> a = ref(x), b = mod(x);
    const Vec3d pa = a ? *a : refNearest(b ? *b : x);
    const Vec3d pb = b ? *b : modNearest(a ? *a : x);
    d[i] = (pa - pb).norm();
    failed[i] = uint8_t((a ? 0 : 1) | (b ? 0 : 2));
  }, 64);
  Errors e;
  e.d = std::move(d);
  for (uint8_t f : failed) e.failedReference += f & 1, e.failedModel += (f >> 1) & 1;
  return e;
}

SurfaceErrorFigures figuresOf(std::vector<double> d, size_t failedReference, size_t failedModel) {
  SurfaceErrorFigures f;
  f.samples = d.size(), f.failedReference = failedReference, f.failedModel = failedModel;
  if (d.empty()) return f;
  double s2 = 0, s1 = 0;
  for (double x : d) s2 += x * x, s1 += x;  // in sample order: the same sum for any thread count
  f.rms = std::sqrt(s2 / double(d.size()));
  f.mean = s1 / double(d.size());
  std::sort(d.begin(), d.end());
  f.max = d.back();
  // Nearest rank: the smallest value with at least 99% of the samples at or below it.
  const size_t rank = size_t(std::ceil(0.99 * double(d.size())));
  f.p99 = d[std::clamp<size_t>(rank, 1, d.size()) - 1];
  return f;
}

Projector mlsProjector(const MlsSurface& s) {
  return [&s](const Vec3d& x) -> std::optional<Vec3d> {
    const MlsProjection p = s.project(x);
    if (!p.converged || !p.point.allFinite()) return std::nullopt;
    return p.point;
  };
}

/// An MLS surface, its constructor's refusals renamed to `name` ("cloud", "model").
MlsSurface surfaceOf(const HybridModel& m, const MlsOptions& o, const std::string& name) {
  try {
    return MlsSurface(m, o);
  } catch (const OptionError&) {
    throw;
  } catch (const Error& e) {
    if (e.path() == "model" && name != "model") throwBadParameter(name, e.reason());
    throw;
  }
}

}  // namespace

void validate(const SurfaceErrorOptions& o) {
  requireRange("samples", double(o.samples), 100, 1e8);
  validate(o.mls);
}

struct SurfaceErrorReference::Impl {
  SurfaceErrorOptions options;
  double spacing = 0;
  bool mesh = false;
  std::optional<MlsSurface> surface;               // a cloud
  std::unique_ptr<detail::MeshClosestPoint> closest;  // a mesh
  std::unique_ptr<Nearest> nearest;                // its sources: the cloud's points, the mesh's vertices
  std::vector<Vec3d> samples;
};

SurfaceErrorReference::SurfaceErrorReference(const HybridModel& cloud, const SurfaceErrorOptions& o, double averageSpacing)
    : impl_(std::make_unique<Impl>()) {
  validate(o);
  Impl& m = *impl_;
  m.options = o;
  if (cloud.points.empty()) throwBadParameter("cloud", "has no points");
  if (!cloud.attributes.normals) throwBadParameter("cloud", "has no normals (its MLS surface needs oriented points)");
  // The points as the cloud has them (radii included: the points an extraction keeps carry the
  // same, so a model that keeps every point has no error); its segments are not the input's.
  HybridModel points;
  points.points = cloud.points;
  points.attributes = cloud.attributes;
  m.surface.emplace(surfaceOf(points, o.mls, "cloud"));
  if (averageSpacing > 0 && std::isfinite(averageSpacing)) {
    m.spacing = averageSpacing;
  } else {
    GeometryOptions go;
    go.orientNormals = go.delaunayNeighbours = go.curvature = go.coverRadius = false;
    m.spacing = computePointGeometry(points, go).averageSpacing;
  }
  if (!(m.spacing > 0)) throwBadParameter("cloud", "has no spacing (coincident points)");
  std::vector<Vec3f> pts;
  for (const Point& p : points.points) pts.push_back(p.position);
  m.nearest = std::make_unique<Nearest>(pts);
  for (size_t i : strided(pts.size(), o.samples)) m.samples.push_back(pts[i].cast<double>());
}

SurfaceErrorReference::SurfaceErrorReference(const TriangleMesh& mesh, const SurfaceErrorOptions& o)
    : impl_(std::make_unique<Impl>()) {
  validate(o);
  Impl& m = *impl_;
  m.options = o;
  m.mesh = true;
  if (mesh.faces.empty()) throwBadParameter("mesh", "has no faces");
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (!mesh.positions[i].allFinite()) throwBadParameter("mesh", "vertex " + std::to_string(i) + " is not finite");
  double edges = 0;
  std::vector<uint8_t> used(mesh.positions.size());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    for (int k = 0; k < 3; ++k) {
      const uint32_t a = mesh.faces[f][size_t(k)], b = mesh.faces[f][size_t((k + 1) % 3)];
      if (a >= mesh.positions.size() || b >= mesh.positions.size())
        throwBadParameter("mesh", "face " + std::to_string(f) + " indexes a vertex out of range");
      edges += double((mesh.positions[a] - mesh.positions[b]).norm());
      used[a] = 1;
    }
  }
  m.spacing = edges / double(3 * mesh.faces.size());
  m.closest = std::make_unique<detail::MeshClosestPoint>(mesh);
  if (m.closest->triangles() == 0 || !(m.spacing > 0)) throwBadParameter("mesh", "has no face of non-zero area");
  // Its vertices that a face uses are its samples (a stray vertex is no part of the surface).
  std::vector<Vec3f> pts;
  for (size_t i = 0; i < mesh.positions.size(); ++i)
    if (used[i]) pts.push_back(mesh.positions[i]);
  m.nearest = std::make_unique<Nearest>(pts);
  for (size_t i : strided(pts.size(), o.samples)) m.samples.push_back(pts[i].cast<double>());
}

SurfaceErrorReference::~SurfaceErrorReference() = default;
SurfaceErrorReference::SurfaceErrorReference(SurfaceErrorReference&&) noexcept = default;
SurfaceErrorReference& SurfaceErrorReference::operator=(SurfaceErrorReference&&) noexcept = default;

double SurfaceErrorReference::spacing() const { return impl_->spacing; }

SurfaceError SurfaceErrorReference::measure(const HybridModel& model) const {
  const Impl& m = *impl_;
  const MlsSurface surface = surfaceOf(model, m.options.mls, "model");
  // The model's samples: its points, and points along each segment at the middles of
  // ceil(length / spacing) equal pieces (one spacing apart, as the points it replaced).
  // (Segment coordinates are finite: the model's surface above refused any other.)
  // A model of segments far longer than the spacing gets a coarser step, so that the list stays
  // within 16 M samples (about 300 MB with its tree); the stride thins it to `samples` anyway.
  double step = m.spacing, total = 0;
  for (const Segment& s : model.segments) total += std::ceil(double((s.p1 - s.p0).norm()) / step);
  if (total > 16e6) step *= total / 16e6;
  std::vector<Vec3f> all;
  all.reserve(model.points.size() + model.segments.size());
  for (const Point& p : model.points) all.push_back(p.position);
  for (const Segment& s : model.segments) {
    const double len = double((s.p1 - s.p0).norm());
    const size_t pieces = std::max<size_t>(1, size_t(std::ceil(std::min(len / step, 16e6))));
    for (size_t k = 0; k < pieces; ++k) all.push_back(s.p0 + float((double(k) + 0.5) / double(pieces)) * (s.p1 - s.p0));
  }
  const Nearest modelNearest(all);
  std::vector<Vec3d> samples;
  for (size_t i : strided(all.size(), m.options.samples)) samples.push_back(all[i].cast<double>());

  const Projector model_ = mlsProjector(surface);
  const Projector ref = m.mesh ? Projector([&m](const Vec3d& x) -> std::optional<Vec3d> { return m.closest->closest(x); })
                               : mlsProjector(*m.surface);
  const Errors fromRef = errorsOf(m.samples, ref, *m.nearest, model_, modelNearest);
  const Errors fromModel = errorsOf(samples, ref, *m.nearest, model_, modelNearest);

  SurfaceError r;
  r.meshReference = m.mesh;
  r.referenceSpacing = m.spacing;
  r.epsilonRef = kSurfaceErrorEpsilonRelative * m.spacing;
  r.diagonal = double(model.bounds().diagonal().norm());
  r.fromReference = figuresOf(fromRef.d, fromRef.failedReference, fromRef.failedModel);
  r.fromModel = figuresOf(fromModel.d, fromModel.failedReference, fromModel.failedModel);
  std::vector<double> pooled = fromRef.d;
  pooled.insert(pooled.end(), fromModel.d.begin(), fromModel.d.end());
  r.both = figuresOf(std::move(pooled), fromRef.failedReference + fromModel.failedReference,
                     fromRef.failedModel + fromModel.failedModel);
  return r;
}

SurfaceError surfaceError(const HybridModel& cloud, const HybridModel& model, const SurfaceErrorOptions& o) {
  return SurfaceErrorReference(cloud, o).measure(model);
}

SurfaceError surfaceError(const TriangleMesh& mesh, const HybridModel& model, const SurfaceErrorOptions& o) {
  return SurfaceErrorReference(mesh, o).measure(model);
}

}  // namespace linesurf
