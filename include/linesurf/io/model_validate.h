#pragma once
/// One validation of a model after reading, applied by every reader (PLY, OBJ, XYZ) whichever
/// command calls it, and by every writer before it writes (a writer never writes what the
/// readers refuse). See docs/file-format.md for the list of checks and their messages.
#include <string>

#include "linesurf/core/error.h"
#include "linesurf/core/model.h"

namespace linesurf {

/// Checks positions, normals, colours, radii, uv, extra properties and provenance of `model`:
/// every value finite (and within float range), colour channels and alpha in [0, 1], radii > 0
/// where the model carries radii (attributes.radii; a segment or point without a radius keeps
/// 0 = unknown). Throws Error of `kind` ("NAME: element vertex 12: ...") on the first violation.
void validateModel(const HybridModel& model, const std::string& name, Error::Kind kind = Error::Kind::BadInput);

/// The same for a mesh, plus faces (indices < positions.size()), normals/colours/cornerUVs sizes.
void validateMesh(const TriangleMesh& mesh, const std::string& name, Error::Kind kind = Error::Kind::BadInput);

/// Gives every segment whose radius is 0 (unknown: the file had no `radius`) an estimated one,
/// as the geometry stage does for points (§6.1): 0.75 x the distance from its midpoint to the
/// nearest other primitive centre, bounded by [0.05, 1] x its own length when it has one.
/// Returns how many segments got a radius.
size_t estimateSegmentRadii(HybridModel& model);

}  // namespace linesurf
