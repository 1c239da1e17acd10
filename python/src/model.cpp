// linesurf.Model and linesurf.Mesh: the library's models as numpy arrays (thesis §3).
#include "model.h"

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include <array>

#include "arrays.h"

namespace linesurf::python {

namespace {

// ---------------------------------------------------------------------------------------------
// Models.

/// Reserves n elements and, for large blocks, asks Linux for transparent huge pages before the
/// memory is first touched (as numpy does): 1 M points are 48 MB, whose 12 k page faults of 4 KB
/// otherwise cost more than the conversion itself.
template <typename T>
void reserveHugePages(std::vector<T>& v, size_t n) {
  v.reserve(n);
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  const size_t bytes = n * sizeof(T);
  if (bytes >= (size_t(4) << 20)) {
    const uintptr_t page = 4096;
    const uintptr_t b = (reinterpret_cast<uintptr_t>(v.data()) + page - 1) & ~(page - 1);
    const uintptr_t e = (reinterpret_cast<uintptr_t>(v.data()) + bytes) & ~(page - 1);
    if (e > b) madvise(reinterpret_cast<void*>(b), e - b, MADV_HUGEPAGE);
  }
#endif
}

void setPoints(HybridModel& m, py::handle obj) {
  FloatArray a = floatArray(obj, "points", {3}, false);
  std::vector<Point> points;  // the model changes only once the array is known good
  reserveHugePages(points, size_t(a.n));
  points.resize(size_t(a.n));
  if (a.n) copyVec3(a.array, "points", points[0].position.data(), sizeof(Point), size_t(a.n));
  if (points.size() != m.points.size()) {
    m.points = std::move(points);
    m.attributes.normals = m.attributes.colors = m.attributes.radii = m.attributes.shadingNormals = false;
    m.pointProperties.clear();
    m.pointShadingNormals.clear();
  } else {
    for (size_t i = 0; i < points.size(); ++i) m.points[i].position = points[i].position;
  }
}

void setSegments(HybridModel& m, py::handle obj) {
  FloatArray a = floatArray(obj, "segments", {2, 3});
  if (size_t(a.n) != m.segments.size()) {
    m.segments.assign(size_t(a.n), Segment{});
    m.attributes.texcoords = m.attributes.endpointNormals = false;
    m.provenance.clear();
    m.segmentProperties.clear();
  }
  for (py::ssize_t i = 0; i < a.n; ++i) m.segments[i].p0 = vec3At(a, i, 0), m.segments[i].p1 = vec3At(a, i, 1);
}

/// One per-primitive attribute of a Model as a numpy column: its name, which list and attribute
/// flag it belongs to, the trailing shape of its array, and how one primitive's values are read
/// and written (flattened). Every optional attribute is None when the model lacks it, set by
/// assignment (rows checked against the primitive count) and dropped by assigning None.
struct Column {
  const char* name;
  bool points;  ///< of the points (else of the segments)
  bool Attributes::*flag;
  std::array<py::ssize_t, 2> shape;  ///< trailing dimensions, 0 = none ({0, 0}: one value per primitive)
  bool color;   ///< (N, 3) or (N, 4) in, (N, 4) out
  void (*get)(const void* primitive, float* out);
  void (*set)(void* primitive, const FloatArray& a, py::ssize_t i);
  const char* doc;
};

void put3(const Vec3f& v, float* out) { out[0] = v.x(), out[1] = v.y(), out[2] = v.z(); }
const Point& P(const void* p) { return *static_cast<const Point*>(p); }
Point& P(void* p) { return *static_cast<Point*>(p); }
const Segment& S(const void* s) { return *static_cast<const Segment*>(s); }
Segment& S(void* s) { return *static_cast<Segment*>(s); }

const Column kColumns[] = {
    {"normals", true, &Attributes::normals, {3, 0}, false, [](const void* p, float* o) { put3(P(p).normal, o); },
     [](void* p, const FloatArray& a, py::ssize_t i) { P(p).normal = vec3At(a, i); },
     "Unit point normals, (N, 3) float32, or None."},
    {"colors", true, &Attributes::colors, {4, 0}, true,
     [](const void* p, float* o) { for (int k = 0; k < 4; ++k) o[k] = P(p).color[k]; },
     [](void* p, const FloatArray& a, py::ssize_t i) { P(p).color = colorAt(a, i); },
     "Point colours, (N, 4) float32 RGBA in [0, 1] (set with (N, 3) or (N, 4)), or None."},
    {"radii", true, &Attributes::radii, {0, 0}, false, [](const void* p, float* o) { o[0] = P(p).radius; },
     [](void* p, const FloatArray& a, py::ssize_t i) { P(p).radius = float(a.at(i)); },
     "Point radii (object space), (N,) float32, or None."},
    {"segment_normals", false, &Attributes::normals, {3, 0}, false, [](const void* s, float* o) { put3(S(s).normal, o); },
     [](void* s, const FloatArray& a, py::ssize_t i) { S(s).normal = vec3At(a, i); },
     "Segment normals (unit, perpendicular to the segment), (M, 3) float32, or None."},
    {"segment_colors", false, &Attributes::colors, {4, 0}, true,
     [](const void* s, float* o) { for (int k = 0; k < 4; ++k) o[k] = S(s).color[k]; },
     [](void* s, const FloatArray& a, py::ssize_t i) { S(s).color = colorAt(a, i); },
     "Segment colours, (M, 4) float32 RGBA, or None."},
    {"segment_radii", false, &Attributes::radii, {0, 0}, false, [](const void* s, float* o) { o[0] = S(s).radius; },
     [](void* s, const FloatArray& a, py::ssize_t i) { S(s).radius = float(a.at(i)); },
     "Segment half-widths, (M,) float32, or None."},
    {"segment_uv", false, &Attributes::texcoords, {2, 2}, false,
     [](const void* s, float* o) { o[0] = S(s).uv0.x(), o[1] = S(s).uv0.y(), o[2] = S(s).uv1.x(), o[3] = S(s).uv1.y(); },
     [](void* s, const FloatArray& a, py::ssize_t i) {
       S(s).uv0 = Vec2f(float(a.at(i, 0, 0)), float(a.at(i, 0, 1)));
       S(s).uv1 = Vec2f(float(a.at(i, 1, 0)), float(a.at(i, 1, 1)));
     },
     "Texture coordinates at the segment endpoints, (M, 2, 2) float32, or None."},
    {"segment_endpoint_normals", false, &Attributes::endpointNormals, {2, 3}, false,
     [](const void* s, float* o) { put3(S(s).normal0, o), put3(S(s).normal1, o + 3); },
     [](void* s, const FloatArray& a, py::ssize_t i) { S(s).normal0 = vec3At(a, i, 0), S(s).normal1 = vec3At(a, i, 1); },
     "Normals at the two endpoints (normal0, normal1) of smooth line models, (M, 2, 3) float32, or None."},
};

py::object getColumn(const HybridModel& h, const Column& c) {
  if (!(h.attributes.*c.flag)) return py::none();
  const size_t n = c.points ? h.points.size() : h.segments.size();
  std::vector<py::ssize_t> shape{py::ssize_t(n)};
  size_t per = 1;
  for (py::ssize_t d : c.shape)
    if (d) shape.push_back(d), per *= size_t(d);
  auto out = newArray<float>(shape);
  float* p = out.mutable_data();
  for (size_t i = 0; i < n; ++i) c.get(c.points ? static_cast<const void*>(&h.points[i]) : &h.segments[i], p + i * per);
  return out;
}

void setColumn(HybridModel& h, const Column& c, py::handle value) {
  if (value.is_none()) return void(h.attributes.*c.flag = false);
  const FloatArray a = c.color           ? colorArray(value, c.name)
                       : c.shape[0] == 0 ? floatArray(value, c.name, {})
                       : c.shape[1] == 0 ? floatArray(value, c.name, {c.shape[0]})
                                         : floatArray(value, c.name, {c.shape[0], c.shape[1]});
  const size_t n = c.points ? h.points.size() : h.segments.size();
  requireRows(c.name, a.n, n, c.points ? "points" : "segments");
  for (size_t i = 0; i < n; ++i) c.set(c.points ? static_cast<void*>(&h.points[i]) : &h.segments[i], a, py::ssize_t(i));
  h.attributes.*c.flag = true;
}

/// A model from the constructor's keywords: positions first, then every column given.
HybridModel makeModel(py::object points, py::object segments, const py::kwargs& columns) {
  HybridModel m;
  if (!points.is_none()) setPoints(m, points);
  if (!segments.is_none()) setSegments(m, segments);
  // A column not given (None) is left alone: point and segment normals share one attribute flag,
  // so a None segment_normals would clear the normals just given to the points.
  for (const Column& c : kColumns)
    if (columns.contains(c.name) && !columns[c.name].is_none()) setColumn(m, c, columns[c.name]);
  return m;
}

}  // namespace

ModelArg modelArg(py::handle obj, const char* name) {
  ModelArg r;
  if (py::isinstance<HybridModel>(obj)) {
    r.model = &obj.cast<const HybridModel&>();
  } else {
    try {
      setPoints(r.owned, obj);
    } catch (const py::type_error&) {
      throw py::type_error(std::string(name) + ": expected a linesurf.Model or an (N, 3) float array of points");
    }
    r.model = &r.owned;
  }
  return r;
}

namespace {

std::string modelRepr(const HybridModel& m) {
  std::string attrs;
  auto add = [&](bool b, const char* s) {
    if (b) attrs += attrs.empty() ? s : std::string(", ") + s;
  };
  add(m.attributes.normals, "normals");
  add(m.attributes.colors, "colors");
  add(m.attributes.radii, "radii");
  add(m.attributes.texcoords, "uv");
  add(m.attributes.endpointNormals, "endpoint normals");
  add(m.attributes.shadingNormals, "shading normals");
  add(!m.provenance.empty(), "provenance");
  return "<linesurf.Model: " + std::to_string(m.points.size()) + " points, " + std::to_string(m.segments.size()) +
         " segments" + (attrs.empty() ? "" : "; " + attrs) + ">";
}

}  // namespace

void bindModel(py::module_& m) {
  // --- Model ----------------------------------------------------------------------------------
  py::class_<HybridModel> model(m, "Model", R"doc(A hybrid point + line-segment model (thesis §3); a point cloud has no segments.

Arrays are returned as new numpy arrays (copies) and set by assignment; optional attributes are
None when the model does not carry them. Points: points (N, 3), normals (N, 3), colors (N, 4)
RGBA in [0, 1], radii (N,). Segments: segments (M, 2, 3) endpoints, segment_normals (M, 3),
segment_colors (M, 4), segment_radii (M,), segment_uv (M, 2, 2), segment_endpoint_normals
(M, 2, 3) (normal0/normal1 of smooth line models). Assigning points or segments of another count
drops the per-primitive attributes of that kind.)doc");
  model.def(py::init([](py::object points, py::object normals, py::object colors, py::object radii, py::object segments,
                       py::object segment_normals, py::object segment_colors, py::object segment_radii,
                       py::object segment_uv, py::object segment_endpoint_normals) {
             py::kwargs columns;
             columns["normals"] = normals, columns["colors"] = colors, columns["radii"] = radii;
             columns["segment_normals"] = segment_normals, columns["segment_colors"] = segment_colors;
             columns["segment_radii"] = segment_radii, columns["segment_uv"] = segment_uv;
             columns["segment_endpoint_normals"] = segment_endpoint_normals;
             return makeModel(points, segments, columns);
           }),
           py::kw_only(), py::arg("points") = py::none(), py::arg("normals") = py::none(),
           py::arg("colors") = py::none(), py::arg("radii") = py::none(), py::arg("segments") = py::none(),
           py::arg("segment_normals") = py::none(), py::arg("segment_colors") = py::none(),
           py::arg("segment_radii") = py::none(), py::arg("segment_uv") = py::none(),
           py::arg("segment_endpoint_normals") = py::none(),
           "A model from arrays (float32 or float64, any memory order); every argument is optional.")
      .def("__repr__", &modelRepr)
      .def("__len__", [](const HybridModel& h) { return h.points.size() + h.segments.size(); },
           "Number of primitives (points + segments).")
      .def("copy", [](const HybridModel& h) { return HybridModel(h); }, "A deep copy.")
      .def_property(
          "points", [](const HybridModel& h) { return vec3Array(h.points.size(), [&](size_t i) { return h.points[i].position; }); },
          [](HybridModel& h, py::object a) { setPoints(h, a); }, "Point positions, (N, 3) float32.")
      .def_property(
          "segments",
          [](const HybridModel& h) {
            auto out = newArray<float>({py::ssize_t(h.segments.size()), 2, 3});
            float* p = out.mutable_data();
            for (size_t i = 0; i < h.segments.size(); ++i)
              for (int k = 0; k < 3; ++k) p[6 * i + k] = h.segments[i].p0[k], p[6 * i + 3 + k] = h.segments[i].p1[k];
            return out;
          },
          [](HybridModel& h, py::object a) { setSegments(h, a); }, "Segment endpoints, (M, 2, 3) float32.")
      .def_property_readonly(
          "provenance",
          [](const HybridModel& h) {
            py::list l;
            for (const auto& p : h.provenance) {
              auto a = newArray<int64_t>({py::ssize_t(p.size())});
              for (size_t i = 0; i < p.size(); ++i) a.mutable_data()[i] = p[i];
              l.append(a);
            }
            return l;
          },
          "Per segment, the input point indices it replaced (extraction with provenance=True); else [].")
      .def_property(
          "point_masses",
          [](const HybridModel& h) -> py::object {
            const std::vector<float>* m = pointMasses(h);
            return m ? py::object(floatVector(*m)) : py::none();
          },
          [](HybridModel& h, py::object a) {
            if (a.is_none()) {
              h.pointProperties.erase(kPointMassProperty);
              return;
            }
            FloatArray v = floatArray(a, "point_masses", {});
            requireRows("point_masses", v.n, h.points.size(), "points");
            std::vector<float> m(h.points.size());
            for (size_t i = 0; i < m.size(); ++i) {
              m[i] = float(v.at(i));
              if (!validPointMass(m[i]))
                throw py::value_error("point_masses: point " + std::to_string(i) + " has mass " + std::to_string(v.at(i)) +
                                      "; masses must be in (0, 1e6]");
            }
            h.pointProperties[kPointMassProperty] = std::move(m);
          },
          "Point masses (beyond the thesis): (N,) float32, each point weighing as that many unit splats "
          "(the PLY property 'mass'), or None (every point weighs 1).")
      .def_property_readonly(
          "point_properties",
          [](const HybridModel& h) {
            py::dict d;
            for (const auto& [name, v] : h.pointProperties) d[py::str(name)] = floatVector(v);
            return d;
          },
          "Extra per-point scalar properties read from or written to PLY (e.g. 'k_min'), name -> (N,) float32.")
      .def_property_readonly(
          "segment_properties",
          [](const HybridModel& h) {
            py::dict d;
            for (const auto& [name, v] : h.segmentProperties) d[py::str(name)] = floatVector(v);
            return d;
          },
          "Extra per-segment scalar properties (an extraction's segments take their points' 'intensity' as the "
          "mean, a 'classification' as the mode), name -> (M,) float32.")
      .def_readwrite("comments", &HybridModel::comments, "PLY header comments kept through read/write.");
  for (const Column& c : kColumns)
    model.def_property(
        c.name, [&c](const HybridModel& h) { return getColumn(h, c); },
        [&c](HybridModel& h, py::object v) { setColumn(h, c, v); }, c.doc);

  // --- Mesh -----------------------------------------------------------------------------------
  py::class_<TriangleMesh>(m, "Mesh", R"doc(A triangle mesh (input of the §3.3 contour extraction).

vertices (V, 3), faces (F, 3) int64, normals (V, 3) or None, colors (V, 4) or None, uv (F, 3, 2)
per-corner texture coordinates or None. A texture image read with the mesh is kept inside.)doc")
      .def(py::init([](py::object vertices, py::object faces, py::object normals, py::object colors) {
             TriangleMesh mesh;
             FloatArray v = floatArray(vertices, "vertices", {3});
             for (py::ssize_t i = 0; i < v.n; ++i) mesh.positions.push_back(vec3At(v, i));
             py::array f = py::array::ensure(faces);
             if (!f || f.ndim() != 2 || f.shape(1) != 3 || (f.dtype().kind() != 'i' && f.dtype().kind() != 'u'))
               throw py::value_error("faces: expected an (F, 3) integer array");
             auto fi = f.attr("astype")("int64").cast<py::array_t<int64_t, py::array::c_style | py::array::forcecast>>();
             for (py::ssize_t i = 0; i < fi.shape(0); ++i) {
               std::array<uint32_t, 3> tri;
               for (int k = 0; k < 3; ++k) {
                 const int64_t x = fi.at(i, k);
                 if (x < 0 || size_t(x) >= mesh.positions.size())
                   throw py::value_error("faces: face " + std::to_string(i) + " refers to vertex " + std::to_string(x) +
                                         " of " + std::to_string(mesh.positions.size()));
                 tri[k] = uint32_t(x);
               }
               mesh.faces.push_back(tri);
             }
             if (!normals.is_none()) {
               FloatArray a = floatArray(normals, "normals", {3});
               requireRows("normals", a.n, mesh.positions.size(), "vertices");
               for (py::ssize_t i = 0; i < a.n; ++i) mesh.normals.push_back(vec3At(a, i));
             }
             if (!colors.is_none()) {
               FloatArray a = colorArray(colors, "colors");
               requireRows("colors", a.n, mesh.positions.size(), "vertices");
               for (py::ssize_t i = 0; i < a.n; ++i) mesh.colors.push_back(colorAt(a, i));
             }
             return mesh;
           }),
           py::arg("vertices"), py::arg("faces"), py::kw_only(), py::arg("normals") = py::none(),
           py::arg("colors") = py::none(), "A mesh from vertex positions (V, 3) and triangles (F, 3).")
      .def("__repr__", [](const TriangleMesh& t) {
        return "<linesurf.Mesh: " + std::to_string(t.positions.size()) + " vertices, " + std::to_string(t.faces.size()) +
               " faces" + (t.cornerUVs.empty() ? "" : ", uv") + (t.texture ? ", texture" : "") + ">";
      })
      .def_property_readonly("vertices", [](const TriangleMesh& t) { return vec3Array(t.positions.size(), [&](size_t i) { return t.positions[i]; }); },
                             "Vertex positions, (V, 3) float32.")
      .def_property_readonly("faces",
                             [](const TriangleMesh& t) {
                               auto out = newArray<int64_t>({py::ssize_t(t.faces.size()), 3});
                               for (size_t i = 0; i < t.faces.size(); ++i)
                                 for (int k = 0; k < 3; ++k) out.mutable_data()[3 * i + k] = t.faces[i][k];
                               return out;
                             },
                             "Triangles as vertex indices, (F, 3) int64.")
      .def_property_readonly("normals",
                             [](const TriangleMesh& t) -> py::object {
                               if (t.normals.empty()) return py::none();
                               return vec3Array(t.normals.size(), [&](size_t i) { return t.normals[i]; });
                             },
                             "Vertex normals, (V, 3) float32, or None.")
      .def_property_readonly("colors",
                             [](const TriangleMesh& t) -> py::object {
                               if (t.colors.empty()) return py::none();
                               auto out = newArray<float>({py::ssize_t(t.colors.size()), 4});
                               for (size_t i = 0; i < t.colors.size(); ++i)
                                 for (int k = 0; k < 4; ++k) out.mutable_data()[4 * i + k] = t.colors[i][k];
                               return out;
                             },
                             "Vertex colours, (V, 4) float32 RGBA, or None.")
      .def_property_readonly("uv",
                             [](const TriangleMesh& t) -> py::object {
                               if (t.cornerUVs.empty()) return py::none();
                               auto out = newArray<float>({py::ssize_t(t.cornerUVs.size()), 3, 2});
                               for (size_t i = 0; i < t.cornerUVs.size(); ++i)
                                 for (int c = 0; c < 3; ++c)
                                   for (int k = 0; k < 2; ++k) out.mutable_data()[6 * i + 2 * c + k] = t.cornerUVs[i][c][k];
                               return out;
                             },
                             "Per-corner texture coordinates, (F, 3, 2) float32, or None.");
}

}  // namespace linesurf::python
