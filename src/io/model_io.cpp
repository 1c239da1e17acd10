// Reading and writing models: dispatch on the file extension (see model_io.h).
#include "linesurf/io/model_io.h"

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "io/detail/readers.h"
#include "linesurf/core/error.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/io/las_io.h"
#include "linesurf/io/model_validate.h"

namespace linesurf {

namespace detail {

std::string readFileBytes(const std::filesystem::path& path, size_t maxBytes) {
  const std::string name = path.string();
  std::error_code ec;
  auto st = std::filesystem::status(path, ec);  // follows links: a link to /dev/zero is a device
  if (ec || !std::filesystem::exists(st)) throwBadInput(name, "", "no such file");
  if (std::filesystem::is_directory(st)) throwBadInput(name, "", "is a directory, not a file");
  // FIFOs, devices and sockets would hang or never end: only regular files are read.
  if (!std::filesystem::is_regular_file(st)) throwBadInput(name, "", "is not a regular file (a pipe, device or socket)");
  FILE* f = std::fopen(name.c_str(), "rb");
  if (!f) throwBadInput(name, "", std::string("cannot open: ") + std::strerror(errno));
  noteInput(path);
  std::string bytes;
  char buf[1 << 16];
  uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > 0) bytes.reserve(size_t(std::min<uintmax_t>(size, maxBytes)));
  size_t n;
  while (bytes.size() < maxBytes && (n = std::fread(buf, 1, std::min(sizeof buf, maxBytes - bytes.size()), f)) > 0)
    bytes.append(buf, n);
  const bool failed = std::ferror(f);
  std::fclose(f);
  if (failed) throwBadInput(name, "", "read error");
  return bytes;
}

}  // namespace detail

namespace {

enum class Kind { Ply, Obj, Xyz, Las, Laz };

constexpr const char* kLazRefused = "LAZ is compressed LAS; decompress it first, e.g. with laszip/PDAL, to .las";

Kind kindOf(const std::filesystem::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (ext == ".ply") return Kind::Ply;
  if (ext == ".obj") return Kind::Obj;
  if (ext == ".xyz") return Kind::Xyz;
  if (ext == ".las") return Kind::Las;
  if (ext == ".laz") return Kind::Laz;
  // A .lod file reaches here only when its first bytes are not the hierarchy's magic.
  if (ext == ".lod") throwBadInput(path.string(), "", "not a level-of-detail hierarchy (no .lod magic at its start)");
  throwBadInput(path.string(), "", "unknown file extension '" + path.extension().string() +
                                       "' (supported: .ply, .obj, .xyz, .las)");
}

HybridModel meshVerticesAsPoints(const TriangleMesh& mesh) {
  HybridModel m;
  m.points.resize(mesh.positions.size());
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    m.points[i].position = mesh.positions[i];
    if (!mesh.normals.empty()) m.points[i].normal = mesh.normals[i];
    if (!mesh.colors.empty()) m.points[i].color = mesh.colors[i];
  }
  m.attributes.normals = !mesh.normals.empty();
  m.attributes.colors = !mesh.colors.empty();
  m.comments = mesh.comments;
  return m;
}

}  // namespace

namespace {
HybridModel readModelUnchecked(const std::filesystem::path& path);
TriangleMesh readMeshUnchecked(const std::filesystem::path& path);
}  // namespace

HybridModel readModel(const std::filesystem::path& path) {
  // An OBJ is a mesh: its faces (texture coordinates included) pass the mesh checks first, so
  // that every command refuses the same files.
  if (kindOf(path) == Kind::Obj) {
    HybridModel m = meshVerticesAsPoints(readMesh(path));
    validateModel(m, path.string());
    return m;
  }
  HybridModel m = readModelUnchecked(path);
  validateModel(m, path.string());
  return m;
}

TriangleMesh readMesh(const std::filesystem::path& path) {
  TriangleMesh m = readMeshUnchecked(path);
  validateMesh(m, path.string());
  return m;
}

namespace {
HybridModel readModelUnchecked(const std::filesystem::path& path) {
  switch (kindOf(path)) {
    case Kind::Ply: {
      std::string bytes = detail::readFileBytes(path);
      std::filesystem::path dir = path.parent_path();
      return detail::plyToModel(bytes, path.string(), &dir);
    }
    case Kind::Obj: return meshVerticesAsPoints(detail::readObj(path));
    case Kind::Xyz: return detail::xyzToModel(detail::readFileBytes(path), path.string());
    case Kind::Las: return detail::lasToModel(detail::readFileBytes(path), path.string());
    case Kind::Laz: detail::readFileBytes(path, 0); throwBadInput(path.string(), "", kLazRefused);
  }
  return {};
}

TriangleMesh readMeshUnchecked(const std::filesystem::path& path) {
  switch (kindOf(path)) {
    case Kind::Ply: {
      std::string bytes = detail::readFileBytes(path);
      std::filesystem::path dir = path.parent_path();
      return detail::plyToMesh(bytes, path.string(), &dir);
    }
    case Kind::Obj: return detail::readObj(path);
    case Kind::Xyz:
      detail::readFileBytes(path);  // missing file / directory first
      throwBadInput(path.string(), "", "an .xyz file holds points, not a mesh");
    case Kind::Las:
      detail::readFileBytes(path, 0);
      throwBadInput(path.string(), "", "a .las file holds points, not a mesh");
    case Kind::Laz: detail::readFileBytes(path, 0); throwBadInput(path.string(), "", kLazRefused);
  }
  return {};
}
}  // namespace

bool fileHoldsMesh(const std::filesystem::path& path) {
  switch (kindOf(path)) {
    case Kind::Obj: return detail::objHasFaces(detail::readFileBytes(path));
    case Kind::Xyz: detail::readFileBytes(path); return false;
    case Kind::Las: detail::readFileBytes(path, 0); return false;
    case Kind::Laz: detail::readFileBytes(path, 0); throwBadInput(path.string(), "", kLazRefused);
    case Kind::Ply: break;
  }
  // Only the header is needed: try the first 64 KiB, the whole file when the header is longer.
  std::string head = detail::readFileBytes(path, 1 << 16);
  if (head.size() == (1 << 16) && head.find("end_header") == std::string::npos) head = detail::readFileBytes(path);
  return detail::plyHoldsMesh(head, path.string());
}

void writeModel(const std::filesystem::path& path, const HybridModel& model, const WriteOptions& options) {
  validateModel(model, path.string(), Error::Kind::Io);  // never write what the readers refuse
  switch (kindOf(path)) {
    case Kind::Ply: return detail::writePlyModel(path, model, options);
    case Kind::Xyz:
      if (!model.segments.empty())
        throwBadParameter(path.string(), "an .xyz file cannot hold line segments (write .ply)");
      if (model.points.empty()) throwIo(path.string(), "an .xyz file needs at least one point (write .ply)");
      return detail::writeXyz(path, model);
    case Kind::Las: return writeLasModel(path, model);
    case Kind::Obj: throwBadParameter(path.string(), "points and segments are written as .ply, .xyz or .las, not .obj");
    case Kind::Laz: throwBadParameter(path.string(), "LAZ (compressed LAS) is not written: write .las and compress it with laszip/PDAL");
  }
}

void writeMesh(const std::filesystem::path& path, const TriangleMesh& mesh, const WriteOptions& options) {
  validateMesh(mesh, path.string(), Error::Kind::Io);
  switch (kindOf(path)) {
    case Kind::Ply: return detail::writePlyMesh(path, mesh, options);
    case Kind::Obj: return detail::writeObj(path, mesh);
    case Kind::Xyz: throwBadParameter(path.string(), "a mesh is written as .ply or .obj, not .xyz");
    case Kind::Las:
    case Kind::Laz: throwBadParameter(path.string(), "a mesh is written as .ply or .obj, not " + path.extension().string());
  }
}

HybridModel readPlyModelFromMemory(std::string_view bytes, const std::string& nameForMessages) {
  HybridModel m = detail::plyToModel(bytes, nameForMessages, nullptr);
  validateModel(m, nameForMessages);
  return m;
}

TriangleMesh readPlyMeshFromMemory(std::string_view bytes, const std::string& nameForMessages) {
  TriangleMesh m = detail::plyToMesh(bytes, nameForMessages, nullptr);
  validateMesh(m, nameForMessages);
  return m;
}

HybridModel readXyzModelFromMemory(std::string_view bytes, const std::string& nameForMessages) {
  HybridModel m = detail::xyzToModel(bytes, nameForMessages);
  validateModel(m, nameForMessages);
  return m;
}

TriangleMesh readObjMeshFromMemory(std::string_view bytes, const std::string& nameForMessages) {
  TriangleMesh m = detail::objToMesh(bytes, nameForMessages, nullptr);
  validateMesh(m, nameForMessages);
  return m;
}

}  // namespace linesurf
