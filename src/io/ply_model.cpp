// PLY schema of linesurf (docs/file-format.md): points in `vertex`, segments in `segment`,
// meshes in `vertex` + `face`; mapping decoded columns onto the model types, and the writers.
#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <set>

#include "io/detail/ply_format.h"
#include "io/detail/readers.h"
#include "linesurf/core/error.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/io/image_io.h"

namespace linesurf::detail {

using namespace linesurf::ply;

namespace {

const std::set<std::string_view> kPointNames = {"x", "y", "z", "nx", "ny", "nz", "red", "green", "blue", "alpha", "radius",
                                                "snx", "sny", "snz"};
const std::set<std::string_view> kSegmentNames = {"x0", "y0", "z0", "x1", "y1", "z1", "nx", "ny", "nz", "red",
                                                  "green", "blue", "alpha", "radius", "u0", "v0", "u1", "v1",
                                                  "nx0", "ny0", "nz0", "nx1", "ny1", "nz1"};
constexpr std::string_view kTextureKey = "TextureFile";

/// The names the writer accepts for extra vertex properties (and so the reader too).
bool validExtraPropertyName(std::string_view name) {
  if (name.empty()) return false;
  for (char c : name)
    if (!(std::isalnum((unsigned char)c) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}

/// A quoted name for a message (bytes outside printable ASCII as '?').
std::string printable(std::string_view s) {
  std::string out = "'";
  for (size_t i = 0; i < s.size() && i < 40; ++i) out += (s[i] >= 32 && s[i] < 127) ? s[i] : '?';
  return out + (s.size() > 40 ? "...'" : "'");
}

std::string lineAt(int line) { return "line " + std::to_string(line); }

/// Requires all or none of `names` in element e; returns whether all are there (scalars).
bool group(const Element& e, std::initializer_list<const char*> names, const std::string& path) {
  int found = 0;
  const char* missing = nullptr;
  for (const char* n : names) {
    int i = e.find(n);
    if (i >= 0) {
      if (e.properties[size_t(i)].isList)
        throwBadInput(path, lineAt(e.properties[size_t(i)].line), "property '" + std::string(n) + "' must not be a list");
      ++found;
    } else if (!missing) {
      missing = n;
    }
  }
  if (found == 0) return false;
  if (missing) {
    std::string all;
    for (const char* n : names) all += std::string(all.empty() ? "" : " ") + n;
    throwBadInput(path, lineAt(e.line), "element " + e.name + " has some but not all of the properties '" + all +
                                            "' (no '" + missing + "')");
  }
  return true;
}

void requireGroup(const Element& e, std::initializer_list<const char*> names, const std::string& path) {
  for (const char* n : names)
    if (e.find(n) < 0) throwBadInput(path, lineAt(e.line), "element " + e.name + " has no property '" + n + "'");
  group(e, names, path);
}

/// Colour channel divisor of property `name` (ply::channelScale).
float channelScale(const Element& e, const char* name) { return ply::channelScale(e.properties[size_t(e.find(name))].type); }

/// The texture named by `comment TextureFile NAME` (MeshLab convention), or null.
std::shared_ptr<const Image> loadTexture(const Header& h, const std::string& path, const std::filesystem::path* dir) {
  for (size_t i = 0; i < h.comments.size(); ++i) {
    std::string_view c = h.comments[i];
    if (c.substr(0, kTextureKey.size()) != kTextureKey || c.size() <= kTextureKey.size() + 1) continue;
    std::string name(c.substr(kTextureKey.size() + 1));
    while (!name.empty() && (name.back() == ' ' || name.back() == '\t')) name.pop_back();
    if (!dir) return nullptr;
    std::filesystem::path file = *dir / name;
    std::error_code ec;
    if (!std::filesystem::is_regular_file(file, ec))
      throwBadInput(path, lineAt(h.commentLines[i]), "texture file '" + name + "' not found beside the PLY");
    return std::make_shared<Image>(readImage(file));
  }
  return nullptr;
}

std::vector<std::string> keptComments(const Header& h) {
  std::vector<std::string> out;
  for (const std::string& c : h.comments)
    if (std::string_view(c).substr(0, kTextureKey.size()) != kTextureKey) out.push_back(c);
  return out;
}

const ElementData* elementData(const Header& h, const std::vector<ElementData>& data, std::string_view name) {
  int i = h.find(name);
  return i < 0 ? nullptr : &data[size_t(i)];
}

/// The face element's index list property: its name ("vertex_indices" or "vertex_index"); it
/// must exist and be a list of integers.
std::string checkFaceHeader(const Element& fe, const std::string& path) {
  std::string indexName = fe.find("vertex_indices") >= 0 ? "vertex_indices" : "vertex_index";
  int ii = fe.find(indexName);
  if (ii < 0) throwBadInput(path, lineAt(fe.line), "element face has no list property 'vertex_indices'");
  const Property& ip = fe.properties[size_t(ii)];
  if (!ip.isList || !isIntegral(ip.type))
    throwBadInput(path, lineAt(ip.line), "property '" + indexName + "' must be a list of integers");
  return indexName;
}

/// Every face has >= 3 corners, indices in [0, nv), and (with texcoords) 2 values per corner.
void checkFaceRows(const ElementData& fd, const std::string& indexName, uint64_t nv, const std::string& path,
                   const ListColumn* tc) {
  const ListColumn& idx = *fd.list(indexName);
  for (size_t f = 0; f < fd.element->count; ++f) {
    const uint64_t b = idx.offsets[f], n = idx.offsets[f + 1] - b;
    if (n < 3)
      throwBadInput(path, fd.where(f), "face " + std::to_string(f) + " has " + std::to_string(n) +
                                           " vertices (at least 3 needed)");
    for (uint64_t k = 0; k < n; ++k) {
      double v = idx.values[b + k];
      if (v < 0 || v >= double(nv))
        throwBadInput(path, fd.where(f), "face " + std::to_string(f) + " vertex index " + std::to_string(int64_t(v)) +
                                             " out of range (the file has " + std::to_string(nv) + " vertices)");
    }
    if (tc) {
      const uint64_t tn = tc->offsets[f + 1] - tc->offsets[f];
      if (tn != 2 * n)
        throwBadInput(path, fd.where(f), "face " + std::to_string(f) + " has " + std::to_string(tn) +
                                             " texcoord values for " + std::to_string(n) + " corners (expected " +
                                             std::to_string(2 * n) + ")");
    }
  }
}

}  // namespace

HybridModel plyToModel(std::string_view bytes, const std::string& path, const std::filesystem::path* textureDir) {
  Header h = parseHeader(bytes, path);
  HybridModel m;
  const int vi = h.find("vertex"), si = h.find("segment");
  if (vi < 0 && si < 0)
    throwBadInput(path, lineAt(h.bodyLine - 1), "no 'vertex' or 'segment' element (nothing to read as points)");
  bool vNormals = false, vColors = false, vAlpha = false, vRadius = false, vShading = false;
  if (vi >= 0) {
    const Element& e = h.elements[size_t(vi)];
    requireGroup(e, {"x", "y", "z"}, path);
    vNormals = group(e, {"nx", "ny", "nz"}, path);
    vColors = group(e, {"red", "green", "blue"}, path);
    vAlpha = group(e, {"alpha"}, path);
    vRadius = group(e, {"radius"}, path);
    vShading = group(e, {"snx", "sny", "snz"}, path);
  }
  bool sNormals = false, sColors = false, sAlpha = false, sRadius = false, sUV = false, sEndNormals = false;
  if (si >= 0) {
    const Element& e = h.elements[size_t(si)];
    requireGroup(e, {"x0", "y0", "z0", "x1", "y1", "z1"}, path);
    sNormals = group(e, {"nx", "ny", "nz"}, path);
    sColors = group(e, {"red", "green", "blue"}, path);
    sAlpha = group(e, {"alpha"}, path);
    sRadius = group(e, {"radius"}, path);
    sUV = group(e, {"u0", "v0", "u1", "v1"}, path);
    sEndNormals = group(e, {"nx0", "ny0", "nz0", "nx1", "ny1", "nz1"}, path);
    int pi = e.find("provenance");
    if (pi >= 0) {
      const Property& p = e.properties[size_t(pi)];
      if (!p.isList || !isIntegral(p.type))
        throwBadInput(path, lineAt(p.line), "property 'provenance' must be a list of integers");
    }
  }
  // Faces are not part of the model, but a file with broken faces is broken for every command.
  const int fi = h.find("face");
  std::string faceIndexName;
  int ti = -1;
  if (fi >= 0) {
    const Element& fe = h.elements[size_t(fi)];
    faceIndexName = checkFaceHeader(fe, path);
    ti = fe.find("texcoord");
    if (ti >= 0 && !fe.properties[size_t(ti)].isList)
      throwBadInput(path, lineAt(fe.properties[size_t(ti)].line), "property 'texcoord' must be a list");
  }
  // An extra vertex or segment property is kept and written back: its name must be one the
  // writer accepts.
  for (int ei : {vi, si}) {
    if (ei < 0) continue;
    const std::set<std::string_view>& standard = ei == vi ? kPointNames : kSegmentNames;
    for (const Property& p : h.elements[size_t(ei)].properties)
      if (!p.isList && !standard.count(p.name) && !validExtraPropertyName(p.name))
        throwBadInput(path, lineAt(p.line), "property name " + printable(p.name) +
                                                " may hold only letters, digits, '_', '-' and '.'");
  }
  auto keep = [&](const Element& e, const Property& p) {
    if (fi >= 0 && &e == &h.elements[size_t(fi)]) return p.isList && (p.name == faceIndexName || p.name == "texcoord");
    if (e.name == "vertex") return !p.isList;  // every scalar: standard or extra property
    if (e.name == "segment") return (p.isList && p.name == "provenance") || !p.isList;  // standard or extra
    return false;
  };
  std::vector<ElementData> data = decodeBody(bytes, h, path, keep);
  if (fi >= 0 && h.elements[size_t(fi)].count > 0)
    checkFaceRows(data[size_t(fi)], faceIndexName, vi >= 0 ? h.elements[size_t(vi)].count : 0, path,
                  ti >= 0 ? data[size_t(fi)].list("texcoord") : nullptr);

  if (const ElementData* d = elementData(h, data, "vertex"); d && d->element->count > 0) {
    const Element& e = *d->element;
    const size_t n = e.count;
    m.points.resize(n);
    auto col = [&](const char* name) { return d->scalar(name)->data(); };
    const double *x = col("x"), *y = col("y"), *z = col("z");
    for (size_t i = 0; i < n; ++i) m.points[i].position = Vec3f(float(x[i]), float(y[i]), float(z[i]));
    if (vNormals) {
      const double *a = col("nx"), *b = col("ny"), *c = col("nz");
      for (size_t i = 0; i < n; ++i) m.points[i].normal = Vec3f(float(a[i]), float(b[i]), float(c[i]));
    }
    if (vColors) {
      const double *r = col("red"), *g = col("green"), *b = col("blue");
      const float sr = channelScale(e, "red"), sg = channelScale(e, "green"), sb = channelScale(e, "blue");
      for (size_t i = 0; i < n; ++i)
        m.points[i].color.head<3>() = Vec3f(float(r[i]) / sr, float(g[i]) / sg, float(b[i]) / sb);
    }
    if (vAlpha) {
      const double* a = col("alpha");
      const float sa = channelScale(e, "alpha");
      for (size_t i = 0; i < n; ++i) m.points[i].color[3] = float(a[i]) / sa;
    }
    if (vRadius) {
      const double* r = col("radius");
      for (size_t i = 0; i < n; ++i) {
        if (r[i] < 0) throwBadInput(path, d->where(i), fmt::format("vertex {}: radius {:g} is negative (0 = unknown)", i, r[i]));
        m.points[i].radius = float(r[i]);
      }
    }
    if (vShading) {  // shading normals; checked by validateModel
      const double *a = col("snx"), *b = col("sny"), *c = col("snz");
      m.pointShadingNormals.resize(n);
      for (size_t i = 0; i < n; ++i) m.pointShadingNormals[i] = Vec3f(float(a[i]), float(b[i]), float(c[i]));
    }
    for (const Property& p : e.properties) {
      if (p.isList || kPointNames.count(p.name)) continue;
      const std::vector<double>& c = *d->scalar(p.name);
      m.pointProperties[p.name].assign(c.begin(), c.end());
    }
  } else if (vi >= 0) {
    for (const Property& p : h.elements[size_t(vi)].properties)
      if (!p.isList && !kPointNames.count(p.name)) m.pointProperties[p.name];
  }
  if (const ElementData* d = elementData(h, data, "segment"); d && d->element->count > 0) {
    const Element& e = *d->element;
    const size_t n = e.count;
    m.segments.resize(n);
    auto col = [&](const char* name) { return d->scalar(name)->data(); };
    const double *x0 = col("x0"), *y0 = col("y0"), *z0 = col("z0"), *x1 = col("x1"), *y1 = col("y1"), *z1 = col("z1");
    for (size_t i = 0; i < n; ++i) {
      m.segments[i].p0 = Vec3f(float(x0[i]), float(y0[i]), float(z0[i]));
      m.segments[i].p1 = Vec3f(float(x1[i]), float(y1[i]), float(z1[i]));
    }
    if (sNormals) {
      const double *a = col("nx"), *b = col("ny"), *c = col("nz");
      for (size_t i = 0; i < n; ++i) m.segments[i].normal = Vec3f(float(a[i]), float(b[i]), float(c[i]));
    }
    if (sColors) {
      const double *r = col("red"), *g = col("green"), *b = col("blue");
      const float sr = channelScale(e, "red"), sg = channelScale(e, "green"), sb = channelScale(e, "blue");
      for (size_t i = 0; i < n; ++i)
        m.segments[i].color.head<3>() = Vec3f(float(r[i]) / sr, float(g[i]) / sg, float(b[i]) / sb);
    }
    if (sAlpha) {
      const double* a = col("alpha");
      const float sa = channelScale(e, "alpha");
      for (size_t i = 0; i < n; ++i) m.segments[i].color[3] = float(a[i]) / sa;
    }
    if (sRadius) {
      const double* r = col("radius");
      for (size_t i = 0; i < n; ++i) {
        if (r[i] < 0) throwBadInput(path, d->where(i), fmt::format("segment {}: radius {:g} is negative (0 = unknown)", i, r[i]));
        m.segments[i].radius = float(r[i]);
      }
    }
    if (sUV) {
      const double *u0 = col("u0"), *v0 = col("v0"), *u1 = col("u1"), *v1 = col("v1");
      for (size_t i = 0; i < n; ++i) {
        m.segments[i].uv0 = Vec2f(float(u0[i]), float(v0[i]));
        m.segments[i].uv1 = Vec2f(float(u1[i]), float(v1[i]));
      }
    }
    if (sEndNormals) {  // smooth line models (endpoint normals)
      const double *a0 = col("nx0"), *b0 = col("ny0"), *c0 = col("nz0"), *a1 = col("nx1"), *b1 = col("ny1"), *c1 = col("nz1");
      for (size_t i = 0; i < n; ++i) {
        m.segments[i].normal0 = Vec3f(float(a0[i]), float(b0[i]), float(c0[i]));
        m.segments[i].normal1 = Vec3f(float(a1[i]), float(b1[i]), float(c1[i]));
      }
    }
    for (const Property& p : e.properties) {
      if (p.isList || kSegmentNames.count(p.name)) continue;
      const std::vector<double>& c = *d->scalar(p.name);
      m.segmentProperties[p.name].assign(c.begin(), c.end());
    }
    if (const ListColumn* pc = d->list("provenance")) {
      m.provenance.resize(n);
      for (size_t i = 0; i < n; ++i) {
        for (uint64_t k = pc->offsets[i]; k < pc->offsets[i + 1]; ++k) {
          double v = pc->values[k];
          if (v < 0 || v > 4294967295.0)
            throwBadInput(path, d->where(i), "provenance index " + std::to_string(int64_t(v)) + " is negative or too large");
          m.provenance[i].push_back(uint32_t(v));
        }
      }
    }
  }
  if (si >= 0 && h.elements[size_t(si)].count == 0)
    for (const Property& p : h.elements[size_t(si)].properties)
      if (!p.isList && !kSegmentNames.count(p.name)) m.segmentProperties[p.name];
  m.attributes.normals = (vi < 0 || vNormals || h.elements[size_t(vi)].count == 0) &&
                         (si < 0 || sNormals || h.elements[size_t(si)].count == 0) && (vNormals || sNormals);
  m.attributes.colors = (vColors || vAlpha || sColors || sAlpha);
  m.attributes.radii = (vRadius || sRadius);
  m.attributes.texcoords = sUV;
  m.attributes.endpointNormals = sEndNormals;
  m.attributes.shadingNormals = vShading;
  m.comments = keptComments(h);
  m.texture = loadTexture(h, path, textureDir);
  return m;
}

TriangleMesh plyToMesh(std::string_view bytes, const std::string& path, const std::filesystem::path* textureDir) {
  Header h = parseHeader(bytes, path);
  const int vi = h.find("vertex"), fi = h.find("face");
  if (fi < 0)
    throwBadInput(path, lineAt(h.bodyLine - 1), "no 'face' element: the file holds points, not a mesh");
  if (vi < 0) throwBadInput(path, lineAt(h.elements[size_t(fi)].line), "faces without a 'vertex' element");
  const Element& ve = h.elements[size_t(vi)];
  const Element& fe = h.elements[size_t(fi)];
  requireGroup(ve, {"x", "y", "z"}, path);
  const bool normals = group(ve, {"nx", "ny", "nz"}, path);
  const bool colors = group(ve, {"red", "green", "blue"}, path);
  const bool alpha = group(ve, {"alpha"}, path);
  const std::string indexName = checkFaceHeader(fe, path);
  int ti = fe.find("texcoord");
  if (ti >= 0 && !fe.properties[size_t(ti)].isList)
    throwBadInput(path, lineAt(fe.properties[size_t(ti)].line), "property 'texcoord' must be a list");

  auto keep = [&](const Element& e, const Property& p) {
    if (&e == &ve) return !p.isList && (kPointNames.count(p.name) > 0);
    if (&e == &fe) return p.isList && (p.name == indexName || p.name == "texcoord");
    return false;
  };
  std::vector<ElementData> data = decodeBody(bytes, h, path, keep);
  const ElementData& vd = data[size_t(vi)];
  const ElementData& fd = data[size_t(fi)];

  TriangleMesh mesh;
  const size_t nv = ve.count;
  mesh.positions.resize(nv);
  if (nv > 0) {
    auto col = [&](const char* name) { return vd.scalar(name)->data(); };
    const double *x = col("x"), *y = col("y"), *z = col("z");
    for (size_t i = 0; i < nv; ++i) mesh.positions[i] = Vec3f(float(x[i]), float(y[i]), float(z[i]));
    if (normals) {
      mesh.normals.resize(nv);
      const double *a = col("nx"), *b = col("ny"), *c = col("nz");
      for (size_t i = 0; i < nv; ++i) mesh.normals[i] = Vec3f(float(a[i]), float(b[i]), float(c[i]));
    }
    if (colors || alpha) {
      mesh.colors.assign(nv, Color(1, 1, 1, 1));
      if (colors) {
        const double *r = col("red"), *g = col("green"), *b = col("blue");
        const float sr = channelScale(ve, "red"), sg = channelScale(ve, "green"), sb = channelScale(ve, "blue");
        for (size_t i = 0; i < nv; ++i)
          mesh.colors[i].head<3>() = Vec3f(float(r[i]) / sr, float(g[i]) / sg, float(b[i]) / sb);
      }
      if (alpha) {
        const double* a = col("alpha");
        const float sa = channelScale(ve, "alpha");
        for (size_t i = 0; i < nv; ++i) mesh.colors[i][3] = float(a[i]) / sa;
      }
    }
  }
  if (fe.count > 0) {
    const ListColumn& idx = *fd.list(indexName);
    const ListColumn* tc = ti >= 0 ? fd.list("texcoord") : nullptr;
    mesh.faces.reserve(idx.values.size() >= 2 * fe.count ? idx.values.size() - 2 * fe.count : fe.count);
    if (tc) mesh.cornerUVs.reserve(mesh.faces.capacity());
    checkFaceRows(fd, indexName, nv, path, tc);
    for (size_t f = 0; f < fe.count; ++f) {
      const uint64_t b = idx.offsets[f], n = idx.offsets[f + 1] - b;
      // Polygons are fan-triangulated around their first corner.
      for (uint64_t k = 1; k + 1 < n; ++k) {
        mesh.faces.push_back({uint32_t(idx.values[b]), uint32_t(idx.values[b + k]), uint32_t(idx.values[b + k + 1])});
        if (tc) {
          const double* t = tc->values.data() + tc->offsets[f];
          auto uv = [&](uint64_t c) { return Vec2f(float(t[2 * c]), float(t[2 * c + 1])); };
          mesh.cornerUVs.push_back({uv(0), uv(k), uv(k + 1)});
        }
      }
    }
  }
  mesh.comments = keptComments(h);
  mesh.texture = loadTexture(h, path, textureDir);
  return mesh;
}

bool isPlyExtraPropertyName(std::string_view name) { return validExtraPropertyName(name) && !kPointNames.count(name); }

bool plyHoldsMesh(std::string_view headerBytes, const std::string& path) {
  Header h = parseHeader(headerBytes, path);
  return h.find("face") >= 0;
}

// ---------------------------------------------------------------------------------------------
// Writing

namespace {

class Body {
 public:
  explicit Body(bool ascii) : ascii_(ascii) {}
  std::string out;

  void f(float v) {
    if (ascii_) {
      sep();
      char buf[32];
      auto r = std::to_chars(buf, buf + sizeof buf, v);
      out.append(buf, r.ptr);
    } else {
      raw(v);
    }
  }
  void u8(uint8_t v) {
    if (ascii_) {
      sep();
      out += std::to_string(v);
    } else {
      raw(v);
    }
  }
  void u32(uint32_t v) {
    if (ascii_) {
      sep();
      out += std::to_string(v);
    } else {
      raw(v);
    }
  }
  void i32(int32_t v) {
    if (ascii_) {
      sep();
      out += std::to_string(v);
    } else {
      raw(v);
    }
  }
  void endRow() {
    if (ascii_) {
      out += '\n';
      first_ = true;
    }
  }

 private:
  bool ascii_;
  bool first_ = true;
  void sep() {
    if (!first_) out += ' ';
    first_ = false;
  }
  template <class T>
  void raw(T v) {
    static_assert(std::endian::native == std::endian::little, "the binary writer assumes a little-endian host");
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    out.append(b, sizeof(T));
  }
};

uint8_t toByte(float c) { return ply::colorByte(c); }

std::string headerStart(const WriteOptions& o, const std::vector<std::string>& comments, const std::string& texture) {
  std::string h = "ply\nformat ";
  h += o.encoding == PlyEncoding::Ascii ? "ascii 1.0\n" : "binary_little_endian 1.0\n";
  for (const std::string& c : comments) {
    std::string line = c;
    std::replace(line.begin(), line.end(), '\n', ' ');
    std::replace(line.begin(), line.end(), '\r', ' ');
    // A free comment that reads as "TextureFile NAME" would make the reader look for a texture
    // (found by the round-trip fuzzer, from an .xyz comment): keep it, but not as a key.
    const size_t start = line.find_first_not_of(" \t\v\f");
    if (start != std::string::npos && std::string_view(line).substr(start, kTextureKey.size()) == kTextureKey)
      line = "(" + line.substr(start) + ")";
    h += "comment " + line + "\n";
  }
  if (!texture.empty()) h += "comment TextureFile " + texture + "\n";
  return h;
}

void checkPropertyName(const std::string& name, bool segment = false) {
  const std::string what = std::string(segment ? "segmentProperties['" : "pointProperties['") + name + "']";
  if (name.empty() || (segment ? kSegmentNames : kPointNames).count(name) || (segment && name == "provenance"))
    throwBadParameter(what, std::string("name is empty or clashes with a standard ") + (segment ? "segment" : "vertex") + " property");
  if (!validExtraPropertyName(name)) throwBadParameter(what, "name may hold only letters, digits, '_', '-' and '.'");
}

}  // namespace

std::string writeTextureBeside(const std::filesystem::path& modelPath, const Image& image) {
  std::string name = modelPath.stem().string() + "_texture.png";
  writePng(modelPath.parent_path() / name, image);
  return name;
}

void writePlyModel(const std::filesystem::path& path, const HybridModel& m, const WriteOptions& o) {
  const Attributes& a = m.attributes;
  for (const auto& [name, values] : m.pointProperties) {
    checkPropertyName(name);
    if (values.size() != m.points.size())
      throwBadParameter("pointProperties['" + name + "']", "has " + std::to_string(values.size()) + " values for " +
                                                               std::to_string(m.points.size()) + " points");
  }
  for (const auto& [name, values] : m.segmentProperties) {
    checkPropertyName(name, true);
    if (values.size() != m.segments.size())
      throwBadParameter("segmentProperties['" + name + "']", "has " + std::to_string(values.size()) + " values for " +
                                                                 std::to_string(m.segments.size()) + " segments");
  }
  if (!m.provenance.empty() && m.provenance.size() != m.segments.size())
    throwBadParameter("provenance", "has " + std::to_string(m.provenance.size()) + " lists for " +
                                        std::to_string(m.segments.size()) + " segments");
  if (a.shadingNormals && m.pointShadingNormals.size() != m.points.size())
    throwBadParameter("pointShadingNormals", "has " + std::to_string(m.pointShadingNormals.size()) + " normals for " +
                                                 std::to_string(m.points.size()) + " points");
  std::string texture;
  if (m.texture && !m.texture->empty() && a.texcoords) texture = writeTextureBeside(path, *m.texture);
  std::string h = headerStart(o, m.comments, texture);
  h += "element vertex " + std::to_string(m.points.size()) + "\n";
  h += "property float x\nproperty float y\nproperty float z\n";
  if (a.normals) h += "property float nx\nproperty float ny\nproperty float nz\n";
  if (a.colors) h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  if (a.radii) h += "property float radius\n";
  if (a.shadingNormals) h += "property float snx\nproperty float sny\nproperty float snz\n";
  for (const auto& kv : m.pointProperties) h += "property float " + kv.first + "\n";
  if (!m.segments.empty()) {
    h += "element segment " + std::to_string(m.segments.size()) + "\n";
    h += "property float x0\nproperty float y0\nproperty float z0\nproperty float x1\nproperty float y1\nproperty float z1\n";
    if (a.normals) h += "property float nx\nproperty float ny\nproperty float nz\n";
    if (a.colors) h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
    if (a.radii) h += "property float radius\n";
    if (a.texcoords) h += "property float u0\nproperty float v0\nproperty float u1\nproperty float v1\n";
    if (a.endpointNormals)
      h += "property float nx0\nproperty float ny0\nproperty float nz0\nproperty float nx1\nproperty float ny1\nproperty float nz1\n";
    for (const auto& kv : m.segmentProperties) h += "property float " + kv.first + "\n";
    if (!m.provenance.empty()) h += "property list uint uint provenance\n";
  }
  h += "end_header\n";

  Body b(o.encoding == PlyEncoding::Ascii);
  b.out = std::move(h);
  std::vector<const std::vector<float>*> extra;
  for (const auto& kv : m.pointProperties) extra.push_back(&kv.second);
  for (size_t i = 0; i < m.points.size(); ++i) {
    const Point& p = m.points[i];
    b.f(p.position.x()), b.f(p.position.y()), b.f(p.position.z());
    if (a.normals) b.f(p.normal.x()), b.f(p.normal.y()), b.f(p.normal.z());
    if (a.colors)
      for (int c = 0; c < 4; ++c) b.u8(toByte(p.color[c]));
    if (a.radii) b.f(p.radius);
    if (a.shadingNormals) {
      const Vec3f& sn = m.pointShadingNormals[i];
      b.f(sn.x()), b.f(sn.y()), b.f(sn.z());
    }
    for (const auto* e : extra) b.f((*e)[i]);
    b.endRow();
  }
  std::vector<const std::vector<float>*> segExtra;
  for (const auto& kv : m.segmentProperties) segExtra.push_back(&kv.second);
  for (size_t i = 0; i < m.segments.size(); ++i) {
    const Segment& s = m.segments[i];
    for (int c = 0; c < 3; ++c) b.f(s.p0[c]);
    for (int c = 0; c < 3; ++c) b.f(s.p1[c]);
    if (a.normals) b.f(s.normal.x()), b.f(s.normal.y()), b.f(s.normal.z());
    if (a.colors)
      for (int c = 0; c < 4; ++c) b.u8(toByte(s.color[c]));
    if (a.radii) b.f(s.radius);
    if (a.texcoords) b.f(s.uv0.x()), b.f(s.uv0.y()), b.f(s.uv1.x()), b.f(s.uv1.y());
    if (a.endpointNormals)
      for (const Vec3f* v : {&s.normal0, &s.normal1}) b.f(v->x()), b.f(v->y()), b.f(v->z());
    for (const auto* e : segExtra) b.f((*e)[i]);
    if (!m.provenance.empty()) {
      b.u32(uint32_t(m.provenance[i].size()));
      for (uint32_t v : m.provenance[i]) b.u32(v);
    }
    b.endRow();
  }
  writeFileAtomically(path, b.out);
}

void writePlyMesh(const std::filesystem::path& path, const TriangleMesh& mesh, const WriteOptions& o) {
  const size_t nv = mesh.positions.size();
  const bool normals = !mesh.normals.empty(), colors = !mesh.colors.empty(), uvs = !mesh.cornerUVs.empty();
  if (normals && mesh.normals.size() != nv)
    throwBadParameter("mesh.normals", "has " + std::to_string(mesh.normals.size()) + " entries for " + std::to_string(nv) + " vertices");
  if (colors && mesh.colors.size() != nv)
    throwBadParameter("mesh.colors", "has " + std::to_string(mesh.colors.size()) + " entries for " + std::to_string(nv) + " vertices");
  if (uvs && mesh.cornerUVs.size() != mesh.faces.size())
    throwBadParameter("mesh.cornerUVs", "has " + std::to_string(mesh.cornerUVs.size()) + " entries for " +
                                            std::to_string(mesh.faces.size()) + " faces");
  for (size_t f = 0; f < mesh.faces.size(); ++f)
    for (uint32_t v : mesh.faces[f])
      if (v >= nv) throwBadParameter("mesh.faces", "face " + std::to_string(f) + " refers to vertex " + std::to_string(v) + " of " + std::to_string(nv));
  std::string texture;
  if (mesh.texture && !mesh.texture->empty()) texture = writeTextureBeside(path, *mesh.texture);
  std::string h = headerStart(o, mesh.comments, texture);
  h += "element vertex " + std::to_string(nv) + "\n";
  h += "property float x\nproperty float y\nproperty float z\n";
  if (normals) h += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colors) h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  h += "element face " + std::to_string(mesh.faces.size()) + "\n";
  h += "property list uchar int vertex_indices\n";
  if (uvs) h += "property list uchar float texcoord\n";
  h += "end_header\n";
  Body b(o.encoding == PlyEncoding::Ascii);
  b.out = std::move(h);
  b.out.reserve(b.out.size() + nv * 12 + mesh.faces.size() * 13);
  for (size_t i = 0; i < nv; ++i) {
    for (int c = 0; c < 3; ++c) b.f(mesh.positions[i][c]);
    if (normals)
      for (int c = 0; c < 3; ++c) b.f(mesh.normals[i][c]);
    if (colors)
      for (int c = 0; c < 4; ++c) b.u8(toByte(mesh.colors[i][c]));
    b.endRow();
  }
  for (size_t f = 0; f < mesh.faces.size(); ++f) {
    b.u8(3);
    for (uint32_t v : mesh.faces[f]) b.i32(int32_t(v));
    if (uvs) {
      b.u8(6);
      for (const Vec2f& t : mesh.cornerUVs[f]) b.f(t.x()), b.f(t.y());
    }
    b.endRow();
  }
  writeFileAtomically(path, b.out);
}

}  // namespace linesurf::detail
