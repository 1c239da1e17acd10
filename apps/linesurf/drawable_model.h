#pragma once
// Reading a model to draw, shared by `linesurf render` and `linesurf view`: a mesh gives its
// vertices as points, raw scans get normals and radii from the geometry stage (§6.1).
#include <string>

#include "linesurf/core/model.h"

namespace linesurf::cli {

/// The mesh's vertices as points (normals and colours kept when present).
HybridModel meshVerticesAsPoints(const TriangleMesh& mesh);

/// Reads a point / hybrid model, or a mesh's vertices as points (says so); segments without a
/// radius get an estimated one. Throws linesurf::Error (BadInput) for a model without points and
/// segments.
HybridModel readDrawableModel(const std::string& path);

/// Estimates normals and / or radii (k neighbours, §6.1) of points that lack them; prints one
/// summary line. Does nothing for models whose points carry both.
void completePointGeometry(HybridModel& model, int k);

}  // namespace linesurf::cli
