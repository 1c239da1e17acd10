#pragma once
/// Vertex normals of a triangle mesh, shared by contour extraction (§3.3, smooth line models) and
/// the mesh renderer (the ground truth of a mesh).
#include <vector>

#include "linesurf/core/model.h"

namespace linesurf {

/// Unit vertex normals of `mesh`: its own normals (normalised) when it has them, else the
/// area-weighted average of the incident faces' normals (sum of the faces' cross products).
/// A vertex with no non-degenerate incident face gets a zero normal. positions.size() entries.
/// Face indices must be in range (throws linesurf::Error BadInput otherwise).
std::vector<Vec3f> meshVertexNormals(const TriangleMesh& mesh);

}  // namespace linesurf
