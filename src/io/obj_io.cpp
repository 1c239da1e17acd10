// Wavefront OBJ meshes (+ MTL diffuse texture) through tinyobjloader; per-corner UVs from `vt`.
#include <tiny_obj_loader.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <vector>

#include "io/detail/readers.h"
#include "linesurf/core/error.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/io/image_io.h"

namespace linesurf::detail {

namespace {
std::string firstLine(std::string s) {
  size_t e = s.find('\n');
  if (e != std::string::npos) s.resize(e);
  while (!s.empty() && (s.back() == '\r' || s.back() == ' ')) s.pop_back();
  return s;
}
}  // namespace

namespace {

bool isSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

std::vector<std::string_view> tokens(std::string_view s) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && isSpace(s[i])) ++i;
    size_t b = i;
    while (i < s.size() && !isSpace(s[i])) ++i;
    if (i > b) out.push_back(s.substr(b, i - b));
  }
  return out;
}

std::string quoted(std::string_view t) { return "'" + std::string(t.substr(0, 40)) + (t.size() > 40 ? "...'" : "'"); }

/// A number as tinyobjloader would read it, but strictly: the whole token, finite, within float.
void number(std::string_view tok, const std::string& name, const std::string& where, const char* what) {
  std::string_view s = tok;
  if (s.size() > 1 && s[0] == '+') s.remove_prefix(1);
  double v = 0;
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec == std::errc::invalid_argument || ptr != s.data() + s.size())
    throwBadInput(name, where, quoted(tok) + " is not a number (" + what + ")");
  if (ec == std::errc::result_out_of_range || !std::isfinite(v) || std::fabs(v) > 3.4028234663852886e38)
    throwBadInput(name, where, quoted(tok) + " is not a finite 32-bit float (" + what + ")");
}

void integer(std::string_view tok, std::string_view corner, const std::string& name, const std::string& where) {
  long long v = 0;
  auto [ptr, ec] = std::from_chars(tok.data(), tok.data() + tok.size(), v);
  if (ec != std::errc() || ptr != tok.data() + tok.size() || v == 0 || v > INT32_MAX || v < -INT32_MAX)
    throwBadInput(name, where, "face corner " + quoted(corner) + " is not a valid index (non-zero integers v, v/t, v//n or v/t/n)");
}

/// The checks tinyobjloader does not make (it reads `v 5 abc 7` as 5 0 7, `v 0.5` as 0.5 0 0,
/// `f 1 2` as nothing): coordinates count and syntax, finite values, face corners. Returns the
/// first `mtllib` file name (or empty).
struct MtlLib {
  std::string file;
  int line = 0;
};
MtlLib prescanObj(std::string_view text, const std::string& name) {
  MtlLib lib;
  std::string& mtllib = lib.file;
  size_t pos = 0;
  int line = 0;
  while (pos < text.size()) {
    size_t e = text.find('\n', pos);
    if (e == std::string_view::npos) e = text.size();
    std::string_view l = text.substr(pos, e - pos);
    pos = e + 1;
    ++line;
    if (size_t h = l.find('#'); h != std::string_view::npos) l = l.substr(0, h);
    auto t = tokens(l);
    if (t.empty()) continue;
    const std::string where = "line " + std::to_string(line);
    const std::string_view key = t[0];
    const size_t n = t.size() - 1;
    if (key == "v") {
      if (n != 3 && n != 4 && n != 6 && n != 7)
        throwBadInput(name, where, "'v' needs x y z [w] or x y z r g b, found " + std::to_string(n) + " values");
      for (size_t i = 1; i <= n; ++i) number(t[i], name, where, "vertex coordinate");
    } else if (key == "vn") {
      if (n != 3) throwBadInput(name, where, "'vn' needs 3 values, found " + std::to_string(n));
      for (size_t i = 1; i <= n; ++i) number(t[i], name, where, "normal");
    } else if (key == "vt") {
      if (n < 1 || n > 3) throwBadInput(name, where, "'vt' needs 1 to 3 values, found " + std::to_string(n));
      for (size_t i = 1; i <= n; ++i) number(t[i], name, where, "texture coordinate");
    } else if (key == "f") {
      if (n < 3) throwBadInput(name, where, "a face needs at least 3 corners, found " + std::to_string(n));
      for (size_t i = 1; i <= n; ++i) {
        std::string_view c = t[i];
        size_t s1 = c.find('/');
        integer(c.substr(0, s1), c, name, where);
        if (s1 == std::string_view::npos) continue;
        std::string_view rest = c.substr(s1 + 1);
        size_t s2 = rest.find('/');
        std::string_view vt = rest.substr(0, s2);
        if (!vt.empty()) integer(vt, c, name, where);
        if (s2 != std::string_view::npos) integer(rest.substr(s2 + 1), c, name, where);
        else if (vt.empty()) integer(vt, c, name, where);  // "1/" is incomplete
      }
    } else if (key == "mtllib" && mtllib.empty() && n >= 1) {
      mtllib = std::string(l.substr(l.find("mtllib") + 6));
      while (!mtllib.empty() && isSpace(mtllib.front())) mtllib.erase(mtllib.begin());
      while (!mtllib.empty() && isSpace(mtllib.back())) mtllib.pop_back();
      lib.line = line;
    }
  }
  return lib;
}

/// The material library an OBJ names: a regular file beside the OBJ (or below its folder), as
/// for a PLY's texture. A missing file, one outside the folder (absolute, or through '..') and
/// anything but a regular file (a device, a pipe, a folder) are refused, not skipped: a mesh
/// that silently lost its material would render differently from what its file says.
std::string readMtlLib(const MtlLib& lib, const std::string& name, const std::filesystem::path& dir) {
  const std::string where = "line " + std::to_string(lib.line);
  const std::filesystem::path rel(lib.file);
  if (rel.is_absolute()) throwBadInput(name, where, "mtllib '" + lib.file + "' is outside the OBJ's folder (an absolute path)");
  for (const auto& part : rel)
    if (part == "..") throwBadInput(name, where, "mtllib '" + lib.file + "' is outside the OBJ's folder ('..')");
  const std::filesystem::path mtl = dir / rel;
  std::error_code ec;
  const auto st = std::filesystem::status(mtl, ec);
  if (ec || !std::filesystem::exists(st)) throwBadInput(name, where, "mtllib '" + lib.file + "' not found beside the OBJ");
  if (!std::filesystem::is_regular_file(st))
    throwBadInput(name, where, "mtllib '" + lib.file + "' is not a regular file");
  return readFileBytes(mtl);
}

}  // namespace

bool objHasFaces(std::string_view text) {
  size_t pos = 0;
  while (pos < text.size()) {
    size_t e = text.find('\n', pos);
    if (e == std::string_view::npos) e = text.size();
    size_t i = pos;
    while (i < e && (text[i] == ' ' || text[i] == '\t')) ++i;
    if (i + 1 < e && text[i] == 'f' && (text[i + 1] == ' ' || text[i + 1] == '\t')) return true;
    pos = e + 1;
  }
  return false;
}

TriangleMesh readObj(const std::filesystem::path& path) {
  std::filesystem::path dir = path.parent_path();
  return objToMesh(readFileBytes(path), path.string(), &dir);
}

TriangleMesh objToMesh(std::string_view bytes, const std::string& name, const std::filesystem::path* dir) {
  const std::string text(bytes);
  const MtlLib mtllib = prescanObj(text, name);
  std::string mtlText;
  if (dir && !mtllib.file.empty()) mtlText = readMtlLib(mtllib, name, *dir);
  tinyobj::ObjReaderConfig cfg;
  cfg.triangulate = true;
  cfg.vertex_color = false;  // colours only when every vertex has them
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(text, mtlText, cfg))
    throwBadInput(name, "", "cannot parse OBJ: " + firstLine(reader.Error().empty() ? "unknown error" : reader.Error()));
  const tinyobj::attrib_t& a = reader.GetAttrib();
  const size_t nv = a.vertices.size() / 3, nn = a.normals.size() / 3, nt = a.texcoords.size() / 2;
  if (nv == 0) throwBadInput(name, "", "no vertices ('v' lines) in the OBJ file");
  TriangleMesh mesh;
  mesh.positions.resize(nv);
  for (size_t i = 0; i < nv; ++i) {
    mesh.positions[i] = Vec3f(float(a.vertices[3 * i]), float(a.vertices[3 * i + 1]), float(a.vertices[3 * i + 2]));
    if (!mesh.positions[i].allFinite())
      throwBadInput(name, "vertex " + std::to_string(i + 1), "non-finite coordinate");
  }
  if (a.colors.size() == 3 * nv) {
    mesh.colors.resize(nv);
    for (size_t i = 0; i < nv; ++i)
      mesh.colors[i] = Color(float(a.colors[3 * i]), float(a.colors[3 * i + 1]), float(a.colors[3 * i + 2]), 1.0f);
  }
  bool allNormals = true, anyUV = false;
  std::vector<Vec3f> normalSum(nv, Vec3f::Zero());
  size_t faceNo = 0;
  for (const tinyobj::shape_t& s : reader.GetShapes()) {
    size_t off = 0;
    for (size_t f = 0; f < s.mesh.num_face_vertices.size(); ++f, ++faceNo) {
      const size_t n = s.mesh.num_face_vertices[f];
      if (n != 3) {  // triangulation leaves only triangles; anything else is skipped
        off += n;
        continue;
      }
      std::array<uint32_t, 3> tri;
      std::array<Vec2f, 3> uv;
      for (size_t k = 0; k < 3; ++k) {
        const tinyobj::index_t& ix = s.mesh.indices[off + k];
        if (ix.vertex_index < 0 || size_t(ix.vertex_index) >= nv)
          throwBadInput(name, "face " + std::to_string(faceNo + 1),
                        "vertex index out of range (the file has " + std::to_string(nv) + " vertices)");
        tri[k] = uint32_t(ix.vertex_index);
        if (ix.texcoord_index >= 0) {
          if (size_t(ix.texcoord_index) >= nt)
            throwBadInput(name, "face " + std::to_string(faceNo + 1), "texture coordinate index out of range");
          uv[k] = Vec2f(float(a.texcoords[2 * ix.texcoord_index]), float(a.texcoords[2 * ix.texcoord_index + 1]));
          anyUV = true;
        } else {
          uv[k] = Vec2f::Zero();
        }
        if (ix.normal_index >= 0 && size_t(ix.normal_index) < nn) {
          normalSum[tri[k]] += Vec3f(float(a.normals[3 * ix.normal_index]), float(a.normals[3 * ix.normal_index + 1]),
                                     float(a.normals[3 * ix.normal_index + 2]));
        } else {
          allNormals = false;
        }
      }
      mesh.faces.push_back(tri);
      mesh.cornerUVs.push_back(uv);
      off += 3;
    }
  }
  if (!anyUV) mesh.cornerUVs.clear();
  if (allNormals && nn > 0 && !mesh.faces.empty()) {
    mesh.normals.resize(nv);
    for (size_t i = 0; i < nv; ++i) {
      float len = normalSum[i].norm();
      mesh.normals[i] = len > 0 && std::isfinite(len) ? Vec3f(normalSum[i] / len) : Vec3f::Zero();
    }
  }
  for (const tinyobj::material_t& m : reader.GetMaterials()) {
    if (m.diffuse_texname.empty() || !dir) continue;
    const std::filesystem::path rel(m.diffuse_texname);
    bool outside = rel.is_absolute();
    for (const auto& part : rel) outside = outside || part == "..";
    if (outside)
      throwBadInput(name, "material " + m.name, "texture file '" + m.diffuse_texname + "' is outside the OBJ's folder");
    std::filesystem::path file = *dir / rel;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
      throwBadInput(name, "material " + m.name, "texture file '" + m.diffuse_texname + "' not found");
    mesh.texture = std::make_shared<Image>(readImage(file));
    break;
  }
  // Header comments are not kept for OBJ (tinyobjloader drops them).
  return mesh;
}

namespace {
void num(std::string& out, float v) {
  char buf[32];
  auto r = std::to_chars(buf, buf + sizeof buf, v);
  out += ' ';
  out.append(buf, r.ptr);
}
}  // namespace

void writeObj(const std::filesystem::path& path, const TriangleMesh& mesh) {
  const size_t nv = mesh.positions.size();
  const bool normals = mesh.normals.size() == nv && nv > 0, colors = mesh.colors.size() == nv && nv > 0;
  const bool uvs = !mesh.cornerUVs.empty();
  if (uvs && mesh.cornerUVs.size() != mesh.faces.size())
    throwBadParameter("mesh.cornerUVs", "has " + std::to_string(mesh.cornerUVs.size()) + " entries for " +
                                            std::to_string(mesh.faces.size()) + " faces");
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (uint32_t v : mesh.faces[f])
      if (v >= nv) throwBadParameter("mesh.faces", "face " + std::to_string(f) + " refers to vertex " + std::to_string(v) + " of " + std::to_string(nv));
  std::string out = "# written by linesurf\n";
  for (const std::string& c : mesh.comments) out += "# " + c + "\n";
  const std::string stem = path.stem().string();
  const bool textured = mesh.texture && !mesh.texture->empty();
  if (textured) {
    std::string tex = writeTextureBeside(path, *mesh.texture);
    writeFileAtomically(path.parent_path() / (stem + ".mtl"),
                        "newmtl textured\nKa 0 0 0\nKd 1 1 1\nKs 0 0 0\nmap_Kd " + tex + "\n");
    out += "mtllib " + stem + ".mtl\nusemtl textured\n";
  }
  out.reserve(out.size() + nv * 40 + mesh.faces.size() * (uvs ? 80 : 20));
  for (size_t i = 0; i < nv; ++i) {
    out += 'v';
    for (int c = 0; c < 3; ++c) num(out, mesh.positions[i][c]);
    if (colors)
      for (int c = 0; c < 3; ++c) num(out, mesh.colors[i][c]);
    out += '\n';
  }
  if (normals)
    for (size_t i = 0; i < nv; ++i) {
      out += "vn";
      for (int c = 0; c < 3; ++c) num(out, mesh.normals[i][c]);
      out += '\n';
    }
  if (uvs)
    for (const auto& t : mesh.cornerUVs)
      for (const Vec2f& uv : t) {
        out += "vt";
        num(out, uv.x());
        num(out, uv.y());
        out += '\n';
      }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      const std::string v = std::to_string(mesh.faces[f][k] + 1);
      out += ' ' + v;
      if (uvs) out += '/' + std::to_string(3 * f + k + 1);
      if (normals) out += (uvs ? "/" : "//") + v;
    }
    out += '\n';
  }
  writeFileAtomically(path, out);
}

}  // namespace linesurf::detail
