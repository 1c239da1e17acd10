#pragma once
// What the point-cloud extract commands share: reading the cloud, the §6.1 geometry preamble and
// its warnings, the geometry flags, and writing the result.
#include <CLI/CLI.hpp>

#include <string>

#include "linesurf/core/model.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"

namespace linesurf::cli {

struct CloudWithGeometry {
  HybridModel cloud;
  PointGeometry geometry;
  double readSeconds = 0, geometrySeconds = 0;
  bool normalsFromFile = false;
};

/// Binds GeometryOptions' user-facing fields: -k/--k/--neighbours, --recompute-normals,
/// --orientation-penalty.
void bindGeometryOptions(CLI::App* sub, GeometryOptions& options);

/// Reads a point cloud (rejecting models with segments or without points), says so, and runs
/// the geometry stage with `options` (progress bar attached), warning about degenerate points.
CloudWithGeometry readCloudWithGeometry(const std::string& path, GeometryOptions options);

/// Writes a model as binary PLY (ASCII with `ascii`).
void writeExtracted(const std::string& path, const HybridModel& model, bool ascii);

}  // namespace linesurf::cli
