#include "extract_common.h"

#include <fmt/format.h>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "options_bind.h"

namespace linesurf::cli {

void bindGeometryOptions(CLI::App* sub, GeometryOptions& o) {
  bindOptions(sub, o, {"k", "recomputeNormals", "orientationPenalty", "orient", "viewpoint"});
}

CloudWithGeometry readCloudWithGeometry(const std::string& path, GeometryOptions options) {
  validate(options);  // before reading a (large) file
  CloudWithGeometry r;
  Timer t;
  r.cloud = readModel(path);
  r.readSeconds = t.seconds();
  if (!r.cloud.segments.empty())
    throwBadInput(path, "segments", fmt::format("already holds {} segments; extraction needs a point cloud",
                                                r.cloud.segments.size()));
  if (r.cloud.points.empty()) throwBadInput(path, "vertex", "holds no points");
  checkGeometry(path, r.cloud.points.size(), options.k);
  r.normalsFromFile = r.cloud.attributes.normals && !options.recomputeNormals;
  say(fmt::format("input        {} points ({}), normals {}", r.cloud.points.size(), path,
                  r.normalsFromFile ? "from file" : "computed (PCA, MST-oriented)"));
  t.reset();
  options.progress = progressBar();
  r.geometry = computePointGeometry(r.cloud, options);
  r.geometrySeconds = t.seconds();
  for (auto [flag, name] : {std::pair{kPointDuplicate, "duplicate"}, {kPointFewNeighbours, "with few neighbours"},
                            {kPointFlatNeighbourhood, "with collinear neighbourhoods"}, {kPointIsolated, "isolated"}})
    if (size_t c = r.geometry.countFlag(flag)) say(fmt::format("warning      {} points {}", c, name));
  return r;
}

void writeExtracted(const std::string& path, const HybridModel& model, bool ascii) {
  WriteOptions wo;
  if (ascii) wo.encoding = PlyEncoding::Ascii;
  writeModel(path, model, wo);
}

}  // namespace linesurf::cli
