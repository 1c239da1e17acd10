#include "drawable_model.h"

#include <fmt/format.h>

#include <algorithm>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/io/model_validate.h"
#include "linesurf/pipeline/render_job.h"

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
  PrepareReport r;
  estimateMissingPointGeometry(model, k, r, progressBar());  // the library's rule, shared with Python
  endProgress();
  if (r.computedRadii)
    say(fmt::format("geometry (§6.1): {} for {} points (k = {}) in {:.2f} s", r.computedNormals ? "normals + radii" : "radii",
                    model.points.size(), k, r.geometrySeconds));
}

}  // namespace linesurf::cli
