#pragma once
/// Summary figures of a model file for `linesurf info`: kind, counts, bounds, attributes and the
/// average point spacing (mean distance to the nearest neighbour, over a kd-tree).
#include <filesystem>
#include <string>
#include <vector>

#include "linesurf/core/model.h"

namespace linesurf {

/// Mean distance from each position to its nearest other position (nanoflann kd-tree), object
/// units. Coincident duplicates contribute 0. Returns 0 for fewer than 2 positions.
/// Deterministic for any thread count.
double averageSpacing(const std::vector<Vec3f>& positions);

struct ModelSummary {
  std::string kind;  ///< "points", "hybrid" (has segments) or "mesh"
  size_t points = 0, segments = 0, vertices = 0, faces = 0;
  Bounds3f bounds;
  std::vector<std::string> properties;  ///< present attributes: normals, colors, radii, texcoords, extra names
  double averageSpacing = 0;            ///< over points (or mesh vertices)
  /// The points' splat radii when the file carries them (else all 0): their spread, and how many
  /// exceed 10 x the median (an outlier drawn as a disc larger than the scan's detail).
  float radiusMin = 0, radiusMedian = 0, radiusMax = 0;
  size_t radiiAbove10xMedian = 0;
  int textureWidth = 0, textureHeight = 0;  ///< 0 when untextured
  std::vector<std::string> comments;
};

/// Reads `path` (a mesh when fileHoldsMesh, else points/segments) and summarises it; the point
/// positions (or mesh vertices) into `positions` when given, for figures a higher module computes.
/// Throws like readModel/readMesh on bad input.
ModelSummary summarizeFile(const std::filesystem::path& path, std::vector<Vec3f>* positions = nullptr);

}  // namespace linesurf
