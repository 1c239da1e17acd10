#include "drawable_model.h"

#include <fmt/format.h>

#include <algorithm>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/io/model_validate.h"

namespace linesurf::cli {

HybridModel meshVerticesAsPoints(const TriangleMesh& mesh) {
  HybridModel model;
  model.points.resize(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    model.points[i].position = mesh.positions[i];
    if (!mesh.normals.empty()) {
      Vec3f n = mesh.normals[i];
      model.points[i].normal = n.norm() > 0 ? Vec3f(n.normalized()) : Vec3f::Zero();
    }
    if (!mesh.colors.empty()) model.points[i].color = mesh.colors[i];
  }
  model.attributes.normals = !mesh.normals.empty();
  model.attributes.colors = !mesh.colors.empty();
  return model;
}

HybridModel readDrawableModel(const std::string& path) {
  HybridModel model;
  if (fileHoldsMesh(path)) {
    model = meshVerticesAsPoints(readMesh(path));
    say(fmt::format("{}: mesh, drawing its {} vertices as points", path, model.points.size()));
  } else {
    model = readModel(path);
  }
  if (model.empty()) throw Error(Error::Kind::BadInput, path, "", "the model holds no points and no segments");
  if (size_t n = estimateSegmentRadii(model))
    say(fmt::format("{} segments without a radius: estimated from the spacing of their neighbours", n));
  return model;
}

void completePointGeometry(HybridModel& model, int k) {
  const bool pointWithoutRadius =
      std::any_of(model.points.begin(), model.points.end(), [](const Point& p) { return p.radius == 0.0f; });
  if (model.points.empty() || (model.attributes.normals && model.attributes.radii && !pointWithoutRadius)) return;
  Timer t;
  const std::string what = !model.attributes.normals ? "normals + radii" : "radii";
  GeometryOptions go;
  go.k = k;
  go.delaunayNeighbours = false;
  go.curvature = false;
  go.progress = progressBar();
  PointGeometry geo = computePointGeometry(model, go);
  applyGeometry(model, geo);
  for (size_t i = 0; i < model.points.size() && i < geo.spacing.size(); ++i)  // hybrid: radii on segments only
    if (model.points[i].radius == 0.0f) model.points[i].radius = geo.spacing[i] > 0 ? geo.spacing[i] : geo.averageSpacing;
  endProgress();
  say(fmt::format("geometry (§6.1): {} for {} points (k = {}) in {:.2f} s", what, model.points.size(), k, t.seconds()));
}

}  // namespace linesurf::cli
