#pragma once
/// Reading and writing models. Formats are chosen by extension: .ply (points, segments,
/// meshes; see docs/file-format.md), .obj (+ .mtl and texture image) meshes, .xyz text clouds.
/// Every reader throws linesurf::Error ("PATH: WHERE: WHAT") on malformed input; every writer
/// writes to a temporary file in the destination folder and renames it into place.
#include <filesystem>

#include "linesurf/core/model.h"

namespace linesurf {

enum class PlyEncoding { BinaryLittleEndian, Ascii };

struct WriteOptions {
  PlyEncoding encoding = PlyEncoding::BinaryLittleEndian;
};

/// Reads a point cloud or hybrid model (.ply with vertex and optional segment elements, .xyz).
HybridModel readModel(const std::filesystem::path& path);
/// Reads a triangle mesh (.ply with vertex + face, .obj with optional .mtl texture).
TriangleMesh readMesh(const std::filesystem::path& path);
/// True when the file holds faces (a mesh) rather than points/segments; reads only the header.
bool fileHoldsMesh(const std::filesystem::path& path);

void writeModel(const std::filesystem::path& path, const HybridModel& model, const WriteOptions& options = {});
void writeMesh(const std::filesystem::path& path, const TriangleMesh& mesh, const WriteOptions& options = {});

}  // namespace linesurf
