#pragma once
// Per-format readers and writers behind model_io.h (private to src/io).
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "linesurf/core/model.h"
#include "linesurf/io/write_options.h"

namespace linesurf::detail {

/// A decimal number of a text format (ASCII PLY, XYZ) as a double: false when `s` is not one.
/// Underflow gives 0 (or a subnormal), overflow +-inf, so that every text reader agrees on tiny
/// and huge values (callers refuse non-finite ones).
bool parseReal(std::string_view s, double& v);

/// The whole file (or its first maxBytes) as bytes; throws BadInput for a missing file, a
/// directory or a read error.
std::string readFileBytes(const std::filesystem::path& path, size_t maxBytes = size_t(-1));

/// PLY from bytes. `textureDir` is where a `comment TextureFile` is looked up; when null the
/// texture is not loaded (in-memory reads).
HybridModel plyToModel(std::string_view bytes, const std::string& name, const std::filesystem::path* textureDir);
TriangleMesh plyToMesh(std::string_view bytes, const std::string& name, const std::filesystem::path* textureDir);
bool plyHoldsMesh(std::string_view headerBytes, const std::string& name);
void writePlyModel(const std::filesystem::path& path, const HybridModel& model, const WriteOptions& options);
void writePlyMesh(const std::filesystem::path& path, const TriangleMesh& mesh, const WriteOptions& options);
/// Whether the PLY writer takes `name` for an extra vertex property (not a standard one).
bool isPlyExtraPropertyName(std::string_view name);

/// LAS from bytes (las_io.cpp), before validateModel.
HybridModel lasToModel(std::string_view bytes, const std::string& name);

TriangleMesh readObj(const std::filesystem::path& path);
/// Whether an OBJ has a face line ('f'); one without is a point cloud of its vertices.
bool objHasFaces(std::string_view bytes);
/// OBJ from bytes; `mtlDir` is where mtllib and textures are looked up (null: not loaded).
TriangleMesh objToMesh(std::string_view bytes, const std::string& name, const std::filesystem::path* mtlDir);
void writeObj(const std::filesystem::path& path, const TriangleMesh& mesh);

/// One line of an XYZ file, shared by the whole-file and the streaming (ooc) readers so that they
/// accept the same numbers: strips a '#' comment (kept in `comments` when not null), reads up to 6
/// numbers into v and returns how many. Throws BadInput naming `name` and `where`.
int parseXyzLine(std::string_view text, const std::string& name, const std::string& where,
                 std::vector<std::string>* comments, float v[6]);
HybridModel xyzToModel(std::string_view bytes, const std::string& name);
void writeXyz(const std::filesystem::path& path, const HybridModel& model);

/// Writes `image` as PNG beside `modelPath` (named <stem>_texture.png) and returns the file name.
std::string writeTextureBeside(const std::filesystem::path& modelPath, const Image& image);

}  // namespace linesurf::detail
