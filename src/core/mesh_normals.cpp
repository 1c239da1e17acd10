// Area-weighted vertex normals of a triangle mesh (see mesh_normals.h).
#include "linesurf/core/mesh_normals.h"

#include <string>

#include "linesurf/core/error.h"

namespace linesurf {

std::vector<Vec3f> meshVertexNormals(const TriangleMesh& mesh) {
  const size_t n = mesh.positions.size();
  std::vector<Vec3f> out(n, Vec3f::Zero());
  if (mesh.normals.size() == n && n > 0) {
    for (size_t i = 0; i < n; ++i) {
      const Vec3f& v = mesh.normals[i];
      const float len = v.norm();
      out[i] = std::isfinite(len) && len > 0 ? Vec3f(v / len) : Vec3f::Zero();
    }
    return out;
  }
  // Sum in double so the result does not depend on rounding order beyond the face order.
  std::vector<Vec3d> acc(n, Vec3d::Zero());
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& t = mesh.faces[f];
    if (t[0] >= n || t[1] >= n || t[2] >= n)
      throwBadInput("mesh", "face " + std::to_string(f), "vertex index out of range");
    const Vec3d a = mesh.positions[t[0]].cast<double>(), b = mesh.positions[t[1]].cast<double>(),
                c = mesh.positions[t[2]].cast<double>();
    const Vec3d cr = (b - a).cross(c - a);  // |cr| = 2 area: area weighting
    if (!cr.allFinite()) continue;
    for (uint32_t v : t) acc[v] += cr;
  }
  for (size_t i = 0; i < n; ++i) {
    const double len = acc[i].norm();
    if (len > 0 && std::isfinite(len)) out[i] = (acc[i] / len).cast<float>();
  }
  return out;
}

}  // namespace linesurf
