#pragma once
/// Reading and writing models. Formats are chosen by extension: .ply (points, segments,
/// meshes; see docs/file-format.md), .obj (+ .mtl and texture image) meshes, .xyz text clouds.
/// Every reader throws linesurf::Error ("PATH: WHERE: WHAT") on malformed input; every writer
/// writes to a temporary file in the destination folder and renames it into place.
#include <filesystem>
#include <string>
#include <string_view>

#include "linesurf/core/model.h"
#include "linesurf/io/write_options.h"

namespace linesurf {


/// Reads a point cloud or hybrid model (.ply with vertex and optional segment elements, .xyz).
/// A mesh file (.ply with faces, .obj) gives its vertices as points (with their normals and
/// colours); the faces are not read.
HybridModel readModel(const std::filesystem::path& path);
/// Reads a triangle mesh (.ply with vertex + face, .obj with optional .mtl texture).
TriangleMesh readMesh(const std::filesystem::path& path);
/// True when the file holds faces (a mesh) rather than points/segments: a .ply that declares a
/// face element (only its header is read), an .obj with a face line ('f'); an .obj without faces
/// is a point cloud of its vertices.
bool fileHoldsMesh(const std::filesystem::path& path);

/// Writes points + segments as .ply (binary little-endian unless options say ascii) or .xyz
/// (points only). Normals, colours, radii and segment uv are written only when
/// model.attributes says so; a texture (with texcoords) goes beside as <stem>_texture.png.
void writeModel(const std::filesystem::path& path, const HybridModel& model, const WriteOptions& options = {});
/// Writes a mesh as .ply or .obj (+ .mtl and <stem>_texture.png when textured).
void writeMesh(const std::filesystem::path& path, const TriangleMesh& mesh, const WriteOptions& options = {});

/// PLY readers over bytes in memory (fuzzing, tests); `nameForMessages` stands for the path in
/// error messages. A `comment TextureFile` is kept out of comments but not loaded.
HybridModel readPlyModelFromMemory(std::string_view bytes, const std::string& nameForMessages);
TriangleMesh readPlyMeshFromMemory(std::string_view bytes, const std::string& nameForMessages);
/// The XYZ and OBJ readers over bytes in memory (an OBJ's mtllib is not loaded).
HybridModel readXyzModelFromMemory(std::string_view bytes, const std::string& nameForMessages);
TriangleMesh readObjMeshFromMemory(std::string_view bytes, const std::string& nameForMessages);

}  // namespace linesurf
