// linesurf._linesurf: the Python binding (pybind11 + numpy). Arrays in and out, keyword options
// named keywordName(field) of the library's option structs (core/options.h), library errors as
// ValueError (bad parameters) or linesurf.FileFormatError / OSError (bad files), the GIL released
// during every long call. The pure-Python package linesurf/__init__.py re-exports everything.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "linesurf/core/error.h"
#include "linesurf/core/model.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/eval/image_metrics.h"
#include "linesurf/extract/contour.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/extract/shape_approx.h"
#include "linesurf/extract/verify.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/io/model_io.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/pipeline/verify_job.h"
#include "linesurf/render/renderer.h"

namespace py = pybind11;
using namespace linesurf;

namespace {

// ---------------------------------------------------------------------------------------------
// numpy in: any float32/float64 array of the right shape, C- or F-ordered or strided, read in
// place (the only copy is into the library's own layout).

/// A validated read-only view of a float array of shape (n, d1[, d2]).
struct FloatArray {
  py::array array;
  py::ssize_t n = 0, d1 = 1, d2 = 1;
  bool f64 = false;
  double at(py::ssize_t i, py::ssize_t j = 0, py::ssize_t k = 0) const {
    const char* p = static_cast<const char*>(array.data()) + i * array.strides(0);
    if (array.ndim() > 1) p += j * array.strides(1);
    if (array.ndim() > 2) p += k * array.strides(2);
    if (f64) {
      double v;
      std::memcpy(&v, p, sizeof v);
      return v;
    }
    float v;
    std::memcpy(&v, p, sizeof v);
    return v;
  }
};

std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

void requireRows(const char* name, py::ssize_t rows, size_t expected, const char* of) {
  if (size_t(rows) != expected)
    throw py::value_error(std::string(name) + ": has " + std::to_string(rows) + " rows for " + std::to_string(expected) + " " + of);
}

/// `shape` lists the trailing dimensions (empty: 1-D); -1 in it accepts any of `alternatives`.
FloatArray floatArray(py::handle obj, const char* name, std::initializer_list<py::ssize_t> shape,
                      bool finite = true) {
  py::array a = py::array::ensure(obj);
  if (!a) throw py::type_error(std::string(name) + ": expected a numpy array (or nested sequence) of numbers");
  const char kind = a.dtype().kind();
  if (kind == 'i' || kind == 'u' || kind == 'b') a = a.attr("astype")("float64");  // small ints are exact
  else if (kind != 'f' || (a.itemsize() != 4 && a.itemsize() != 8))
    throw py::type_error(std::string(name) + ": expected a float32 or float64 array, got dtype " +
                         std::string(py::str(a.dtype())));
  const std::string want = [&] {
    std::string s = "(N";
    for (py::ssize_t d : shape) s += ", " + std::to_string(d);
    return s + (shape.size() == 0 ? ",)" : ")");
  }();
  if (a.ndim() != py::ssize_t(1 + shape.size()))
    throw py::value_error(std::string(name) + ": expected shape " + want + ", got " + shapeText(a));
  py::ssize_t i = 1;
  for (py::ssize_t d : shape)
    if (a.shape(i++) != d) throw py::value_error(std::string(name) + ": expected shape " + want + ", got " + shapeText(a));
  FloatArray v{a, a.shape(0), a.ndim() > 1 ? a.shape(1) : 1, a.ndim() > 2 ? a.shape(2) : 1, a.itemsize() == 8};
  if (finite)
    for (py::ssize_t r = 0; r < v.n; ++r)
      for (py::ssize_t j = 0; j < v.d1; ++j)
        for (py::ssize_t k = 0; k < v.d2; ++k)
          if (!std::isfinite(v.at(r, j, k)))
            throw py::value_error(std::string(name) + ": row " + std::to_string(r) + " holds a non-finite value");
  return v;
}

/// Row i of an (N, 3) array into dst[i * stride] (floats), in one typed pass; non-finite values
/// are reported by row (the hot path of passing large clouds in).
template <typename T>
void copyRows3(const py::array& a, py::ssize_t n, float* dst, size_t stride, const char* name) {
  const char* base = static_cast<const char*>(a.data());
  const py::ssize_t s0 = a.strides(0), s1 = a.strides(1);
  bool finite = true;
  for (py::ssize_t i = 0; i < n; ++i) {
    const char* row = base + i * s0;
    T x, y, z;
    std::memcpy(&x, row, sizeof(T));
    std::memcpy(&y, row + s1, sizeof(T));
    std::memcpy(&z, row + 2 * s1, sizeof(T));
    float* d = dst + size_t(i) * stride;
    d[0] = float(x), d[1] = float(y), d[2] = float(z);
    finite &= std::isfinite(x) & std::isfinite(y) & std::isfinite(z);
  }
  if (!finite)
    for (py::ssize_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k)
        if (!std::isfinite(dst[size_t(i) * stride + k]))
          throw py::value_error(std::string(name) + ": row " + std::to_string(i) + " holds a non-finite value");
}

/// An (N, 3) float array into the Vec3f member at `first` of n structs `stride` bytes apart.
void copyVec3(py::handle obj, const char* name, float* first, size_t strideBytes, size_t expected) {
  FloatArray v = floatArray(obj, name, {3}, false);
  if (expected != size_t(-1)) requireRows(name, v.n, expected, "points");
  const size_t stride = strideBytes / sizeof(float);
  if (v.f64) copyRows3<double>(v.array, v.n, first, stride, name);
  else copyRows3<float>(v.array, v.n, first, stride, name);
}

Vec3f vec3At(const FloatArray& a, py::ssize_t i, py::ssize_t j = -1) {
  if (j < 0) return Vec3f(float(a.at(i, 0)), float(a.at(i, 1)), float(a.at(i, 2)));
  return Vec3f(float(a.at(i, j, 0)), float(a.at(i, j, 1)), float(a.at(i, j, 2)));
}

std::optional<Vec3f> optionalVec3(const std::optional<std::vector<double>>& v, const char* field) {
  if (!v) return std::nullopt;
  if (v->size() != 3) throwBadOption(field, "needs three numbers x y z");
  return Vec3f(float((*v)[0]), float((*v)[1]), float((*v)[2]));
}

Color colorAt(const FloatArray& a, py::ssize_t i) {
  return Color(float(a.at(i, 0)), float(a.at(i, 1)), float(a.at(i, 2)), a.d1 == 4 ? float(a.at(i, 3)) : 1.0f);
}

FloatArray colorArray(py::handle obj, const char* name) {
  py::array a = py::array::ensure(obj);
  const bool four = a && a.ndim() == 2 && a.shape(1) == 4;
  return four ? floatArray(obj, name, {4}) : floatArray(obj, name, {3});
}

// ---------------------------------------------------------------------------------------------
// numpy out: new arrays owned by Python.

template <typename T>
py::array_t<T> newArray(std::vector<py::ssize_t> shape) {
  return py::array_t<T>(shape);
}

py::array_t<float> vec3Array(size_t n, const std::function<Vec3f(size_t)>& f) {
  auto out = newArray<float>({py::ssize_t(n), 3});
  float* p = out.mutable_data();
  for (size_t i = 0; i < n; ++i) {
    Vec3f v = f(i);
    p[3 * i] = v.x(), p[3 * i + 1] = v.y(), p[3 * i + 2] = v.z();
  }
  return out;
}

py::array_t<float> floatVector(const std::vector<float>& v) {
  auto out = newArray<float>({py::ssize_t(v.size())});
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(float));
  return out;
}

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
  }
  for (py::ssize_t i = 0; i < a.n; ++i) m.segments[i].p0 = vec3At(a, i, 0), m.segments[i].p1 = vec3At(a, i, 1);
}

struct ModelFields {
  py::object points, normals, colors, radii, segments, segment_normals, segment_colors, segment_radii, segment_uv,
      segment_endpoint_normals;
};

HybridModel makeModel(const ModelFields& f) {
  HybridModel m;
  if (!f.points.is_none()) setPoints(m, f.points);
  if (!f.segments.is_none()) setSegments(m, f.segments);
  const size_t np = m.points.size(), ns = m.segments.size();
  if (!f.normals.is_none()) {
    FloatArray a = floatArray(f.normals, "normals", {3});
    requireRows("normals", a.n, np, "points");
    for (size_t i = 0; i < np; ++i) m.points[i].normal = vec3At(a, i);
    m.attributes.normals = true;
  }
  if (!f.colors.is_none()) {
    FloatArray a = colorArray(f.colors, "colors");
    requireRows("colors", a.n, np, "points");
    for (size_t i = 0; i < np; ++i) m.points[i].color = colorAt(a, i);
    m.attributes.colors = true;
  }
  if (!f.radii.is_none()) {
    FloatArray a = floatArray(f.radii, "radii", {});
    requireRows("radii", a.n, np, "points");
    for (size_t i = 0; i < np; ++i) m.points[i].radius = float(a.at(i));
    m.attributes.radii = true;
  }
  if (!f.segment_normals.is_none()) {
    FloatArray a = floatArray(f.segment_normals, "segment_normals", {3});
    requireRows("segment_normals", a.n, ns, "segments");
    for (size_t i = 0; i < ns; ++i) m.segments[i].normal = vec3At(a, i);
    m.attributes.normals = true;
  }
  if (!f.segment_colors.is_none()) {
    FloatArray a = colorArray(f.segment_colors, "segment_colors");
    requireRows("segment_colors", a.n, ns, "segments");
    for (size_t i = 0; i < ns; ++i) m.segments[i].color = colorAt(a, i);
    m.attributes.colors = true;
  }
  if (!f.segment_radii.is_none()) {
    FloatArray a = floatArray(f.segment_radii, "segment_radii", {});
    requireRows("segment_radii", a.n, ns, "segments");
    for (size_t i = 0; i < ns; ++i) m.segments[i].radius = float(a.at(i));
    m.attributes.radii = true;
  }
  if (!f.segment_uv.is_none()) {
    FloatArray a = floatArray(f.segment_uv, "segment_uv", {2, 2});
    requireRows("segment_uv", a.n, ns, "segments");
    for (size_t i = 0; i < ns; ++i) {
      m.segments[i].uv0 = Vec2f(float(a.at(i, 0, 0)), float(a.at(i, 0, 1)));
      m.segments[i].uv1 = Vec2f(float(a.at(i, 1, 0)), float(a.at(i, 1, 1)));
    }
    m.attributes.texcoords = true;
  }
  if (!f.segment_endpoint_normals.is_none()) {
    FloatArray a = floatArray(f.segment_endpoint_normals, "segment_endpoint_normals", {2, 3});
    requireRows("segment_endpoint_normals", a.n, ns, "segments");
    for (size_t i = 0; i < ns; ++i) m.segments[i].normal0 = vec3At(a, i, 0), m.segments[i].normal1 = vec3At(a, i, 1);
    m.attributes.endpointNormals = true;
  }
  return m;
}

/// A model argument: a Model, or an (N, 3) array of points.
struct ModelArg {
  HybridModel owned;
  const HybridModel* model = nullptr;
  HybridModel& mutableCopy() {
    if (model != &owned) owned = *model, model = &owned;
    return owned;
  }
};

ModelArg modelArg(py::handle obj, const char* name = "model") {
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

// ---------------------------------------------------------------------------------------------
// Images.

/// (H, W, 3|4) uint8 or float array in [0, 1] -> Image; alpha 1 when absent.
Image imageFrom(py::handle obj, const char* name) {
  if (py::isinstance<py::str>(obj)) {
    const std::string path = obj.cast<std::string>();
    py::gil_scoped_release release;
    return readImage(path);
  }
  py::array a = py::array::ensure(obj);
  if (!a || a.ndim() != 3 || (a.shape(2) != 3 && a.shape(2) != 4))
    throw py::value_error(std::string(name) + ": expected an (H, W, 3) or (H, W, 4) image array" +
                          (a ? ", got shape " + shapeText(a) : std::string()));
  if (a.shape(0) < 1 || a.shape(1) < 1 || a.shape(0) > 65536 || a.shape(1) > 65536)
    throw py::value_error(std::string(name) + ": image size must be 1..65536 pixels per side, got " + shapeText(a));
  const int h = int(a.shape(0)), w = int(a.shape(1)), c = int(a.shape(2));
  Image img(w, h, Color(0, 0, 0, 1));
  if (a.dtype().kind() == 'u' && a.itemsize() == 1) {
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x)
        for (int k = 0; k < c; ++k)
          img.at(x, y)[k] = *static_cast<const uint8_t*>(a.data(y, x, k)) / 255.0f;
    return img;
  }
  FloatArray f = floatArray(a.reshape({py::ssize_t(h) * w, py::ssize_t(c)}), name, {c});
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int k = 0; k < c; ++k) img.at(x, y)[k] = float(f.at(py::ssize_t(y) * w + x, k));
  return img;
}

py::array_t<uint8_t> rgba8(const Image& img) {
  auto out = newArray<uint8_t>({img.height, img.width, 4});
  quantize8(img, 4, out.mutable_data());
  return out;
}

/// Channel `c` of an image as an (H, W) float32 array, or channels 0..2 as (H, W, 3).
py::array_t<float> channels(const Image& img, int first, int count) {
  std::vector<py::ssize_t> shape{img.height, img.width};
  if (count > 1) shape.push_back(count);
  auto out = newArray<float>(shape);
  float* p = out.mutable_data();
  for (size_t i = 0; i < img.pixels.size(); ++i)
    for (int k = 0; k < count; ++k) p[i * count + k] = img.pixels[i][first + k];
  return out;
}

// ---------------------------------------------------------------------------------------------
// Options from keywords (names: keywordName of the fields).

template <typename E>
E enumFrom(const std::string& value, const char* field, std::initializer_list<std::pair<const char*, E>> names) {
  std::string choices;
  for (auto& [n, e] : names) {
    if (value == n) return e;
    if (!choices.empty()) choices += ", ";
    choices += n;
  }
  throwBadOption(field, "expected one of " + choices + ", got '" + value + "'");
}

GeometryOptions geometryOptions(int k, bool recompute, bool orient, float penalty) {
  GeometryOptions o;
  o.k = k;
  o.recomputeNormals = recompute;
  o.orientNormals = orient;
  o.orientationPenalty = penalty;
  validate(o);
  return o;
}

py::object namespaceOf(py::dict d) { return py::module_::import("types").attr("SimpleNamespace")(**d); }

py::dict geometryDict(const PointGeometry& g) {
  py::dict d;
  const size_t n = g.size();
  const int k = g.k;
  auto nb = newArray<int64_t>({py::ssize_t(n), k});
  auto nd = newArray<float>({py::ssize_t(n), k});
  for (size_t i = 0; i < n * size_t(k); ++i) {
    const uint32_t j = g.neighbours[i];
    nb.mutable_data()[i] = j == PointGeometry::kNoNeighbour ? -1 : int64_t(j);
    nd.mutable_data()[i] = g.neighbourDistances[i];
  }
  d["k"] = k;
  d["neighbours"] = nb;
  d["neighbour_distances"] = nd;
  d["normals"] = vec3Array(n, [&](size_t i) { return g.normals[i]; });
  d["eigenvalues"] = vec3Array(n, [&](size_t i) { return g.eigenvalues[i]; });
  d["surface_variation"] = floatVector(g.surfaceVariation);
  d["spacing"] = floatVector(g.spacing);
  d["average_spacing"] = g.averageSpacing;
  auto flags = newArray<uint8_t>({py::ssize_t(n)});
  if (n) std::memcpy(flags.mutable_data(), g.flags.data(), n);
  d["flags"] = flags;
  d["orientation_flips"] = g.orientationFlips;
  if (!g.delaunayOffsets.empty()) {
    auto off = newArray<int64_t>({py::ssize_t(g.delaunayOffsets.size())});
    for (size_t i = 0; i < g.delaunayOffsets.size(); ++i) off.mutable_data()[i] = g.delaunayOffsets[i];
    auto idx = newArray<int64_t>({py::ssize_t(g.delaunayIndices.size())});
    for (size_t i = 0; i < g.delaunayIndices.size(); ++i) idx.mutable_data()[i] = g.delaunayIndices[i];
    d["delaunay_offsets"] = off;
    d["delaunay_indices"] = idx;
  }
  if (g.kMin.size() == n && n) {
    d["k_min"] = floatVector(g.kMin);
    d["k_max"] = floatVector(g.kMax);
    d["min_curvature_dir"] = vec3Array(n, [&](size_t i) { return g.minCurvatureDir[i]; });
    d["max_curvature_dir"] = vec3Array(n, [&](size_t i) { return g.maxCurvatureDir[i]; });
  }
  return d;
}

/// Whether prepareForRendering would change the model (it is copied only then).
bool needsPreparation(const HybridModel& m, float radiusScale) {
  if (radiusScale != 1.0f) return true;
  if (!m.points.empty() && (!m.attributes.normals || !m.attributes.radii)) return true;
  for (const Point& p : m.points)
    if (p.radius == 0.0f) return true;
  for (const Segment& s : m.segments)
    if (s.radius == 0.0f) return true;
  return false;
}

std::unique_ptr<ThreadLimit>& threadLimit() {
  static std::unique_ptr<ThreadLimit> limit;
  return limit;
}

}  // namespace

PYBIND11_MODULE(_linesurf, m) {
  m.doc() = "linesurf: surface modelling and rendering with line segments (numpy in and out).";

  // --- errors ---------------------------------------------------------------------------------
  static py::exception<Error> fileFormatError(m, "FileFormatError", PyExc_OSError);
  fileFormatError.doc() = "A malformed or unreadable input file (an OSError); the message is the CLI's one line "
                          "'PATH: WHERE: WHAT'.";
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const OptionError& e) {
      PyErr_SetString(PyExc_ValueError, pythonMessage(e).c_str());
    } catch (const Error& e) {
      if (e.kind() == Error::Kind::BadParameter) PyErr_SetString(PyExc_ValueError, e.what());
      else if (e.kind() == Error::Kind::BadInput) PyErr_SetString(fileFormatError.ptr(), e.what());
      else PyErr_SetString(PyExc_OSError, e.what());
    }
  });

  // --- Model ----------------------------------------------------------------------------------
  py::class_<HybridModel>(m, "Model", R"doc(A hybrid point + line-segment model (thesis §3); a point cloud has no segments.

Arrays are returned as new numpy arrays (copies) and set by assignment; optional attributes are
None when the model does not carry them. Points: points (N, 3), normals (N, 3), colors (N, 4)
RGBA in [0, 1], radii (N,). Segments: segments (M, 2, 3) endpoints, segment_normals (M, 3),
segment_colors (M, 4), segment_radii (M,), segment_uv (M, 2, 2), segment_endpoint_normals
(M, 2, 3) (normal0/normal1 of smooth line models). Assigning points or segments of another count
drops the per-primitive attributes of that kind.)doc")
      .def(py::init([](py::object points, py::object normals, py::object colors, py::object radii, py::object segments,
                       py::object segment_normals, py::object segment_colors, py::object segment_radii,
                       py::object segment_uv, py::object segment_endpoint_normals) {
             return makeModel({points, normals, colors, radii, segments, segment_normals, segment_colors, segment_radii,
                               segment_uv, segment_endpoint_normals});
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
          "normals",
          [](const HybridModel& h) -> py::object {
            if (!h.attributes.normals) return py::none();
            return vec3Array(h.points.size(), [&](size_t i) { return h.points[i].normal; });
          },
          [](HybridModel& h, py::object a) {
            if (a.is_none()) return void(h.attributes.normals = false);
            FloatArray v = floatArray(a, "normals", {3});
            requireRows("normals", v.n, h.points.size(), "points");
            for (size_t i = 0; i < h.points.size(); ++i) h.points[i].normal = vec3At(v, i);
            h.attributes.normals = true;
          },
          "Unit point normals, (N, 3) float32, or None.")
      .def_property(
          "colors",
          [](const HybridModel& h) -> py::object {
            if (!h.attributes.colors) return py::none();
            auto out = newArray<float>({py::ssize_t(h.points.size()), 4});
            for (size_t i = 0; i < h.points.size(); ++i)
              for (int k = 0; k < 4; ++k) out.mutable_data()[4 * i + k] = h.points[i].color[k];
            return out;
          },
          [](HybridModel& h, py::object a) {
            if (a.is_none()) return void(h.attributes.colors = false);
            FloatArray v = colorArray(a, "colors");
            requireRows("colors", v.n, h.points.size(), "points");
            for (size_t i = 0; i < h.points.size(); ++i) h.points[i].color = colorAt(v, i);
            h.attributes.colors = true;
          },
          "Point colours, (N, 4) float32 RGBA in [0, 1] (set with (N, 3) or (N, 4)), or None.")
      .def_property(
          "radii",
          [](const HybridModel& h) -> py::object {
            if (!h.attributes.radii) return py::none();
            auto out = newArray<float>({py::ssize_t(h.points.size())});
            for (size_t i = 0; i < h.points.size(); ++i) out.mutable_data()[i] = h.points[i].radius;
            return out;
          },
          [](HybridModel& h, py::object a) {
            if (a.is_none()) return void(h.attributes.radii = false);
            FloatArray v = floatArray(a, "radii", {});
            requireRows("radii", v.n, h.points.size(), "points");
            for (size_t i = 0; i < h.points.size(); ++i) h.points[i].radius = float(v.at(i));
            h.attributes.radii = true;
          },
          "Point radii (object space), (N,) float32, or None.")
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
      .def_property(
          "segment_normals",
          [](const HybridModel& h) -> py::object {
            if (!h.attributes.normals) return py::none();
            return vec3Array(h.segments.size(), [&](size_t i) { return h.segments[i].normal; });
          },
          [](HybridModel& h, py::object a) {
            FloatArray v = floatArray(a, "segment_normals", {3});
            requireRows("segment_normals", v.n, h.segments.size(), "segments");
            for (size_t i = 0; i < h.segments.size(); ++i) h.segments[i].normal = vec3At(v, i);
            h.attributes.normals = true;
          },
          "Segment normals (unit, perpendicular to the segment), (M, 3) float32, or None.")
      .def_property(
          "segment_colors",
          [](const HybridModel& h) -> py::object {
            if (!h.attributes.colors) return py::none();
            auto out = newArray<float>({py::ssize_t(h.segments.size()), 4});
            for (size_t i = 0; i < h.segments.size(); ++i)
              for (int k = 0; k < 4; ++k) out.mutable_data()[4 * i + k] = h.segments[i].color[k];
            return out;
          },
          [](HybridModel& h, py::object a) {
            FloatArray v = colorArray(a, "segment_colors");
            requireRows("segment_colors", v.n, h.segments.size(), "segments");
            for (size_t i = 0; i < h.segments.size(); ++i) h.segments[i].color = colorAt(v, i);
            h.attributes.colors = true;
          },
          "Segment colours, (M, 4) float32 RGBA, or None.")
      .def_property(
          "segment_radii",
          [](const HybridModel& h) -> py::object {
            if (!h.attributes.radii) return py::none();
            auto out = newArray<float>({py::ssize_t(h.segments.size())});
            for (size_t i = 0; i < h.segments.size(); ++i) out.mutable_data()[i] = h.segments[i].radius;
            return out;
          },
          [](HybridModel& h, py::object a) {
            FloatArray v = floatArray(a, "segment_radii", {});
            requireRows("segment_radii", v.n, h.segments.size(), "segments");
            for (size_t i = 0; i < h.segments.size(); ++i) h.segments[i].radius = float(v.at(i));
            h.attributes.radii = true;
          },
          "Segment half-widths, (M,) float32, or None.")
      .def_property(
          "segment_uv",
          [](const HybridModel& h) -> py::object {
            if (!h.attributes.texcoords) return py::none();
            auto out = newArray<float>({py::ssize_t(h.segments.size()), 2, 2});
            float* p = out.mutable_data();
            for (size_t i = 0; i < h.segments.size(); ++i)
              p[4 * i] = h.segments[i].uv0.x(), p[4 * i + 1] = h.segments[i].uv0.y(), p[4 * i + 2] = h.segments[i].uv1.x(),
              p[4 * i + 3] = h.segments[i].uv1.y();
            return out;
          },
          [](HybridModel& h, py::object a) {
            FloatArray v = floatArray(a, "segment_uv", {2, 2});
            requireRows("segment_uv", v.n, h.segments.size(), "segments");
            for (size_t i = 0; i < h.segments.size(); ++i) {
              h.segments[i].uv0 = Vec2f(float(v.at(i, 0, 0)), float(v.at(i, 0, 1)));
              h.segments[i].uv1 = Vec2f(float(v.at(i, 1, 0)), float(v.at(i, 1, 1)));
            }
            h.attributes.texcoords = true;
          },
          "Texture coordinates at the segment endpoints, (M, 2, 2) float32, or None.")
      .def_property(
          "segment_endpoint_normals",
          [](const HybridModel& h) -> py::object {
            if (!h.attributes.endpointNormals) return py::none();
            auto out = newArray<float>({py::ssize_t(h.segments.size()), 2, 3});
            float* p = out.mutable_data();
            for (size_t i = 0; i < h.segments.size(); ++i)
              for (int k = 0; k < 3; ++k) p[6 * i + k] = h.segments[i].normal0[k], p[6 * i + 3 + k] = h.segments[i].normal1[k];
            return out;
          },
          [](HybridModel& h, py::object a) {
            FloatArray v = floatArray(a, "segment_endpoint_normals", {2, 3});
            requireRows("segment_endpoint_normals", v.n, h.segments.size(), "segments");
            for (size_t i = 0; i < h.segments.size(); ++i) h.segments[i].normal0 = vec3At(v, i, 0), h.segments[i].normal1 = vec3At(v, i, 1);
            h.attributes.endpointNormals = true;
          },
          "Normals at the two endpoints (normal0, normal1) of smooth line models, (M, 2, 3) float32, or None.")
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
      .def_readwrite("comments", &HybridModel::comments, "PLY header comments kept through read/write.");

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

  // --- files ----------------------------------------------------------------------------------
  m.def(
      "read",
      [](const std::string& path) {
        py::gil_scoped_release release;
        return readModel(path);
      },
      py::arg("path"),
      "Reads a point cloud or hybrid model (.ply, .xyz; a mesh file gives its vertices) as a Model.\n"
      "Raises FileFormatError (an OSError) with the CLI's one-line message on a bad file.");
  m.def(
      "read_mesh",
      [](const std::string& path) {
        py::gil_scoped_release release;
        return readMesh(path);
      },
      py::arg("path"), "Reads a triangle mesh (.ply with faces, .obj with optional .mtl texture) as a Mesh.");
  m.def(
      "write",
      [](const std::string& path, py::object obj, bool ascii) {
        WriteOptions wo;
        if (ascii) wo.encoding = PlyEncoding::Ascii;
        if (py::isinstance<TriangleMesh>(obj)) {
          const TriangleMesh& mesh = obj.cast<const TriangleMesh&>();
          py::gil_scoped_release release;
          writeMesh(path, mesh, wo);
          return;
        }
        ModelArg a = modelArg(obj);
        py::gil_scoped_release release;
        writeModel(path, *a.model, wo);
      },
      py::arg("path"), py::arg("model"), py::kw_only(), py::arg("ascii") = false,
      "Writes a Model (or an (N, 3) points array) as .ply / .xyz, or a Mesh as .ply / .obj. The file is\n"
      "written to a temporary file and renamed into place.");

  // --- geometry (§6.1) ------------------------------------------------------------------------
  m.def(
      "geometry",
      [](py::object model, int k, bool recompute_normals, bool orient_normals, float orientation_penalty,
         bool delaunay_neighbours, bool curvature, const std::string& curvature_fit) {
        ModelArg a = modelArg(model);
        GeometryOptions o = geometryOptions(k, recompute_normals, orient_normals, orientation_penalty);
        o.delaunayNeighbours = delaunay_neighbours || curvature;
        o.curvature = curvature;
        o.curvatureFit = enumFrom<CurvatureFit>(curvature_fit, "curvatureFit",
                                                {{"taubin", CurvatureFit::Taubin}, {"quadric", CurvatureFit::Quadric}});
        PointGeometry g;
        {
          py::gil_scoped_release release;
          g = computePointGeometry(*a.model, o);
        }
        return namespaceOf(geometryDict(g));
      },
      py::arg("model"), py::kw_only(), py::arg("k") = 12, py::arg("recompute_normals") = false,
      py::arg("orient_normals") = true, py::arg("orientation_penalty") = 0.5f, py::arg("delaunay_neighbours") = false,
      py::arg("curvature") = false, py::arg("curvature_fit") = "taubin",
      R"doc(The §6.1 geometry of a point cloud (a Model or an (N, 3) array), computed once:

neighbours (N, k) int64 (exact kNN, nearest first, -1 padded), neighbour_distances (N, k),
normals (N, 3) unit, MST-oriented (kept from the model unless recompute_normals), eigenvalues
(N, 3), surface_variation (N,), spacing (N,) and average_spacing, flags (N,) uint8; with
delaunay_neighbours: delaunay_offsets / delaunay_indices (CSR); with curvature: k_min, k_max
(N,), min_curvature_dir, max_curvature_dir (N, 3). Returned as a SimpleNamespace.)doc");
  m.def(
      "normals",
      [](py::object model, int k, bool recompute_normals, bool orient_normals, float orientation_penalty) {
        ModelArg a = modelArg(model);
        GeometryOptions o = geometryOptions(k, recompute_normals, orient_normals, orientation_penalty);
        o.delaunayNeighbours = false;
        o.curvature = false;
        PointGeometry g;
        {
          py::gil_scoped_release release;
          g = computePointGeometry(*a.model, o);
        }
        return vec3Array(g.size(), [&](size_t i) { return g.normals[i]; });
      },
      py::arg("points"), py::kw_only(), py::arg("k") = 12, py::arg("recompute_normals") = false,
      py::arg("orient_normals") = true, py::arg("orientation_penalty") = 0.5f,
      "Unit normals (N, 3) float32 of a point cloud (Model or (N, 3) array) by PCA over the k nearest\n"
      "neighbours (Hoppe 1992), consistently oriented by a minimum spanning tree (thesis §6.1).");
  m.def(
      "prepare",
      [](py::object model, int k, float radius_scale) {
        ModelArg a = modelArg(model);
        HybridModel out = *a.model;
        PrepareOptions o;
        o.k = k;
        o.radiusScale = radius_scale;
        py::gil_scoped_release release;
        prepareForRendering(out, o);
        return out;
      },
      py::arg("model"), py::kw_only(), py::arg("k") = 12, py::arg("radius_scale") = 1.0f,
      "A copy of the model ready to render: normals and radii of raw scans from the §6.1 geometry\n"
      "(kept when present), radii times radius_scale; what render() does on every call otherwise.");

  // --- extraction (§3) ------------------------------------------------------------------------
  m.def(
      "extract_eps_delta",
      [](py::object model, double epsilon, double epsilon_relative, double delta, int min_replaced, int max_replaced,
         bool provenance, int k, bool recompute_normals, float orientation_penalty) {
        ModelArg a = modelArg(model);
        EpsDeltaOptions o;
        o.epsilon = epsilon, o.epsilonRelative = epsilon_relative, o.delta = delta;
        o.minReplaced = min_replaced, o.maxReplaced = max_replaced, o.provenance = provenance;
        validate(o);
        GeometryOptions go = geometryOptions(k, recompute_normals, true, orientation_penalty);
        go.curvature = false;
        if (!a.model->segments.empty()) throwBadOption("model", "already holds segments; extraction needs a point cloud");
        EpsDeltaStats st;
        HybridModel out;
        {
          py::gil_scoped_release release;
          PointGeometry geo = computePointGeometry(*a.model, go);
          out = extractEpsDelta(*a.model, geo, o, &st);
        }
        out.comments.push_back(std::string("eps-delta: normals=") +
                               (a.model->attributes.normals && !recompute_normals ? "file" : "computed"));
        py::dict stats;
        stats["input_points"] = st.inputPoints, stats["kept_points"] = st.keptPoints, stats["segments"] = st.segments;
        stats["replaced_points"] = st.replacedPoints, stats["epsilon"] = st.epsilon, stats["delta"] = st.delta;
        stats["data_reduction"] = st.dataReduction(), stats["seed_directions"] = st.seedDirections;
        stats["candidate_directions"] = st.candidateDirections;
        py::dict r;
        r["model"] = out;
        r["stats"] = stats;
        return namespaceOf(r);
      },
      py::arg("cloud"), py::kw_only(), py::arg("epsilon") = 0.0, py::arg("epsilon_relative") = 0.05,
      py::arg("delta") = 0.004, py::arg("min_replaced") = 4, py::arg("max_replaced") = 0, py::arg("provenance") = false,
      py::arg("k") = 12, py::arg("recompute_normals") = false, py::arg("orientation_penalty") = 0.5f,
      R"doc((epsilon, delta) error-bounded line segment extraction, thesis §3.1 (= `linesurf extract eps-delta`).

epsilon: distance tolerance (0: epsilon_relative x average spacing); delta: bound on 1 - n_i.n_j.
Returns a namespace with model (the hybrid Model) and stats (dict: input_points, kept_points,
segments, replaced_points, epsilon, delta, data_reduction, ...). provenance=True records the
replaced points (needed by verify()).)doc");
  m.def(
      "extract_shape_approx",
      [](py::object model, const std::string& method, float delta_n, uint64_t seed, int max_iterations,
         float radius_scale, int min_cluster_size, int min_run_points, bool provenance, bool curvature, int k,
         bool recompute_normals, float orientation_penalty) {
        ModelArg a = modelArg(model);
        ShapeApproxOptions o;
        o.method = enumFrom<ClusteringMethod>(method, "method",
                                              {{"greedy", ClusteringMethod::Greedy}, {"hierarchical", ClusteringMethod::Hierarchical}});
        o.clustering.deltaN = delta_n, o.clustering.seed = seed, o.clustering.maxIterations = max_iterations;
        o.radiusScale = radius_scale, o.minClusterSize = min_cluster_size, o.minRunPoints = min_run_points;
        o.provenance = provenance;
        validate(o);
        GeometryOptions go = geometryOptions(k, recompute_normals, true, orientation_penalty);
        go.curvature = curvature;
        if (!a.model->segments.empty()) throwBadOption("model", "already holds segments; extraction needs a point cloud");
        if (a.model->points.empty()) throwBadOption("model", "holds no points");
        ShapeApproxStats st;
        HybridModel out;
        Clustering c;
        {
          py::gil_scoped_release release;
          PointGeometry geo = computePointGeometry(*a.model, go);
          c = clusterShapeApprox(geo, o);
          out = extractShapeApprox(*a.model, geo, c, o, &st);
        }
        py::dict stats;
        stats["input_points"] = st.inputPoints, stats["clusters"] = st.clusters, stats["segments"] = st.segments;
        stats["points_kept"] = st.pointsKept, stats["points_replaced"] = st.pointsReplaced;
        stats["clusters_with_segments"] = st.clustersWithSegments, stats["data_reduction"] = st.dataReduction();
        auto labels = newArray<int64_t>({py::ssize_t(c.labels.size())});
        for (size_t i = 0; i < c.labels.size(); ++i) labels.mutable_data()[i] = c.labels[i];
        py::dict r;
        r["model"] = out;
        r["stats"] = stats;
        r["labels"] = labels;
        return namespaceOf(r);
      },
      py::arg("cloud"), py::kw_only(), py::arg("method") = "greedy", py::arg("delta_n") = 0.008f, py::arg("seed") = 1,
      py::arg("max_iterations") = 16, py::arg("radius_scale") = 1.0f, py::arg("min_cluster_size") = 4,
      py::arg("min_run_points") = 4, py::arg("provenance") = false, py::arg("curvature") = true, py::arg("k") = 12,
      py::arg("recompute_normals") = false, py::arg("orientation_penalty") = 0.5f,
      R"doc(Shape-approximation extraction, thesis §3.2 (= `linesurf extract shape-approx`).

method: "greedy" (§3.2.3.1) or "hierarchical" (§3.2.3.2) normal-variation clustering with
tolerance delta_n on ||n(C) - n_j||^2. Returns a namespace with model, stats (dict: clusters,
segments, points_kept, points_replaced, ...) and labels (N,) int64 cluster ids.)doc");
  m.def(
      "extract_contour",
      [](const TriangleMesh& mesh, float spacing, float spacing_scale, uint64_t seed, float radius_scale,
         float points_below, bool all_points, bool vertex_normals, float family_switch_sine, bool endpoint_normals,
         float merge_normal_deviation, float merge_tangent_deviation, float merge_angle, int merge_max_pieces,
         float diagonal_divisions, float merge_strip_angle, bool point_masses) {
        ContourOptions o;
        o.spacing = spacing, o.spacingScale = spacing_scale, o.seed = seed, o.radiusScale = radius_scale;
        o.pointsBelow = points_below, o.allPoints = all_points, o.vertexNormals = vertex_normals;
        o.familySwitchSine = family_switch_sine;
        o.endpointNormals = endpoint_normals;
        o.mergeNormalDeviation = merge_normal_deviation, o.mergeTangentDeviation = merge_tangent_deviation;
        o.mergeAngle = merge_angle, o.mergeMaxPieces = merge_max_pieces;
        o.diagonalDivisions = diagonal_divisions;
        o.mergeStripAngle = merge_strip_angle;
        o.pointMasses = point_masses;
        validate(o);
        if (mesh.faces.empty()) throwBadOption("mesh", "holds no faces: contour extraction needs a triangle mesh");
        ContourStats st;
        HybridModel out;
        {
          py::gil_scoped_release release;
          out = extractContour(mesh, o, &st);
        }
        py::dict stats;
        stats["triangles"] = st.triangles, stats["segments"] = st.segments, stats["points"] = st.points;
        stats["spacing"] = st.spacing, stats["radius"] = st.radius, stats["degenerate_triangles"] = st.degenerateTriangles;
        stats["mean_edge_length"] = st.meanEdgeLength, stats["spacing_from_diagonal"] = st.spacingFromDiagonal;
        stats["converted_segments"] = st.convertedSegments;
        stats["segments_before_merge"] = st.segmentsBeforeMerge, stats["polylines"] = st.polylines;
        py::dict r;
        r["model"] = out;
        r["stats"] = stats;
        return namespaceOf(r);
      },
      py::arg("mesh"), py::kw_only(), py::arg("spacing") = 0.0f, py::arg("spacing_scale") = 1.0f, py::arg("seed") = 1,
      py::arg("radius_scale") = ContourOptions{}.radiusScale, py::arg("points_below") = 0.0f, py::arg("all_points") = false,
      py::arg("vertex_normals") = false, py::arg("family_switch_sine") = 1.0f, py::arg("endpoint_normals") = true,
      py::arg("merge_normal_deviation") = ContourOptions{}.mergeNormalDeviation,
      py::arg("merge_tangent_deviation") = ContourOptions{}.mergeTangentDeviation,
      py::arg("merge_angle") = ContourOptions{}.mergeAngle, py::arg("merge_max_pieces") = ContourOptions{}.mergeMaxPieces,
      py::arg("diagonal_divisions") = ContourOptions{}.diagonalDivisions,
      py::arg("merge_strip_angle") = ContourOptions{}.mergeStripAngle, py::arg("point_masses") = true,
      R"doc(Contour-plane extraction from a triangle Mesh, thesis §3.3 (= `linesurf extract contour`).

spacing: largest distance d between neighbouring segments (0: spacing_scale x min(mean edge length,
bounding-box diagonal / diagonal_divisions); diagonal_divisions=0: the mean edge alone);
endpoint_normals=False gives the thesis's one normal per segment (the CLI's --flat);
merge_normal_deviation=0 keeps one segment per face and plane (no polyline merging);
point_masses=False leaves the points (all_points, points_below) the thesis's unit splats instead of
weighing the contour length they stand for (Model.point_masses; the CLI's --no-point-masses).
Returns a namespace with model and stats (dict: triangles, segments, points, spacing, radius, ...).)doc");
  m.def(
      "verify",
      [](py::object cloud, const HybridModel& hybrid, std::optional<double> epsilon, std::optional<double> delta,
         std::optional<int> k) {
        ModelArg a = modelArg(cloud, "cloud");
        RecordedVerifyOptions o;
        o.epsilon = epsilon, o.delta = delta, o.k = k;
        RecordedVerifyResult r;
        {
          py::gil_scoped_release release;
          r = verifyAsRecorded(*a.model, hybrid, "hybrid", o);
        }
        const VerifyReport& v = r.report;
        py::dict d;
        d["ok"] = v.ok(), d["segments"] = v.segments, d["replaced_points"] = v.replacedPoints;
        d["kept_points"] = v.keptPoints, d["distance_violations"] = v.distanceViolations;
        d["normal_violations"] = v.normalViolations, d["bad_segments"] = v.badSegments, d["bad_indices"] = v.badIndices;
        d["replaced_twice"] = v.replacedTwice, d["missing"] = v.missing, d["unmatched_points"] = v.unmatchedPoints;
        d["max_distance"] = v.maxDistance, d["max_normal_deviation"] = v.maxNormalDeviation;
        d["epsilon"] = r.epsilon, d["delta"] = r.delta, d["k"] = r.k, d["messages"] = v.messages;
        return d;
      },
      py::arg("cloud"), py::arg("hybrid"), py::kw_only(), py::arg("epsilon") = py::none(), py::arg("delta") = py::none(),
      py::arg("k") = py::none(),
      "The certificate check of an (epsilon, delta) extraction (= `linesurf verify-extraction`): every\n"
      "replaced point within epsilon of its segment and delta of its anchor normal, every input point\n"
      "kept or replaced once. Tolerances default to those the hybrid records. Returns a dict with 'ok'.");

  // --- rendering (§4-§6.2) --------------------------------------------------------------------
  m.def(
      "render",
      [](py::object model, std::pair<int, int> size, float azimuth, float elevation, float distance, float zoom,
         float fov, const std::string& up_axis, std::optional<std::vector<double>> eye,
         std::optional<std::vector<double>> target, std::optional<std::vector<double>> up, float prefilter_variance,
         float cutoff_radius, float reconstruction_scale, float radius_scale, int layers,
         const std::string& z_threshold_mode, std::optional<float> z_threshold, float alpha_override,
         bool backface_culling, float ambient, float diffuse, float specular, float shininess,
         std::optional<std::vector<double>> light, bool world_light, std::optional<std::vector<double>> default_color,
         bool per_pixel_lighting, py::object background, const std::string& segment_method, float segment_lod, float coverage_gain, int coverage_reach, float tail_coverage, int k,
         int tile_size, bool depth, bool alpha, bool normal) -> py::object {
        RenderOptions o;
        o.prefilterVariance = prefilter_variance, o.cutoffRadius = cutoff_radius;
        o.reconstructionScale = reconstruction_scale, o.layers = layers;
        o.zThresholdMode = enumFrom<ZThresholdMode>(z_threshold_mode, "zThresholdMode",
                                                    {{"primitive", ZThresholdMode::PerPrimitive}, {"fixed", ZThresholdMode::Fixed}});
        o.zThreshold = z_threshold;
        o.alphaOverride = alpha_override, o.backfaceCulling = backface_culling;
        o.material = {ambient, diffuse, specular, shininess};
        if (auto l = optionalVec3(light, "light")) o.light.direction = *l;
        o.light.headlight = !world_light;
        if (auto c = optionalVec3(default_color, "defaultColor")) o.defaultColor = Color(c->x(), c->y(), c->z(), 1);
        o.perPixelLighting = per_pixel_lighting;
        if (py::isinstance<py::str>(background)) {
          o.background = parseBackground(background.cast<std::string>());
        } else {
          auto v = background.cast<std::vector<double>>();
          if (v.size() == 3) v.push_back(1);
          if (v.size() != 4) throwBadOption("background", "expected a name or 3 or 4 numbers in [0, 1]");
          o.background = Color(float(v[0]), float(v[1]), float(v[2]), float(v[3]));
        }
        o.segmentMethod = enumFrom<SegmentMethod>(segment_method, "segmentMethod",
                                                  {{"approx", SegmentMethod::Approx}, {"screen", SegmentMethod::ScreenSpace},
                                                   {"reference", SegmentMethod::Reference}});
        o.segmentLod = segment_lod, o.coverageGain = coverage_gain, o.coverageReach = coverage_reach;
        o.tailCoverage = tail_coverage;
        o.tileSize = tile_size, o.depthBuffer = depth, o.alphaBuffer = alpha, o.normalBuffer = normal;
        validate(o);
        ViewOptions v;
        v.width = size.first, v.height = size.second;
        v.azimuth = azimuth, v.elevation = elevation, v.distance = distance, v.zoom = zoom, v.fov = fov;
        v.upAxis = parseUpAxis(up_axis);
        v.eye = optionalVec3(eye, "eye"), v.target = optionalVec3(target, "target"), v.up = optionalVec3(up, "up");
        validate(v);
        PrepareOptions p;
        p.k = k, p.radiusScale = radius_scale;
        validate(p);

        ModelArg a = modelArg(model);
        if (a.model->empty()) throwBadOption("model", "holds no points and no segments");
        RenderResult r;
        {
          py::gil_scoped_release release;
          // What `linesurf render` does to a model before drawing it; a copy only when it changes it.
          const ModelFrame frame = normalizingFrame(a.model->bounds());
          if (!frame.identity()) toFrame(a.mutableCopy(), frame);
          if (needsPreparation(*a.model, radius_scale)) prepareForRendering(a.mutableCopy(), p);
          Renderer renderer(*a.model, o);
          r = renderer.render(viewCameras(renderer.sphere(), v, frame).front());
        }
        py::array_t<uint8_t> color = rgba8(r.color);
        if (!depth && !alpha && !normal) return color;
        py::dict d;
        d["color"] = color;
        if (r.depth) {
          auto dz = channels(*r.depth, 0, 1);
          for (size_t i = 0; i < r.depth->pixels.size(); ++i)
            if (!(r.depth->pixels[i].w() > 0)) dz.mutable_data()[i] = 0;
          d["depth"] = dz;
        }
        if (r.alpha) d["alpha"] = channels(*r.alpha, 0, 1);
        if (r.normal) d["normal"] = channels(*r.normal, 0, 3);
        return d;
      },
      py::arg("model"), py::kw_only(), py::arg("size") = std::pair<int, int>(512, 512), py::arg("azimuth") = 30.0f,
      py::arg("elevation") = 20.0f, py::arg("distance") = 0.0f, py::arg("zoom") = 1.0f, py::arg("fov") = 30.0f,
      py::arg("up_axis") = "y", py::arg("eye") = py::none(), py::arg("target") = py::none(), py::arg("up") = py::none(),
      py::arg("prefilter_variance") = RenderOptions{}.prefilterVariance, py::arg("cutoff_radius") = 2.0f, py::arg("reconstruction_scale") = 0.5f,
      py::arg("radius_scale") = 1.0f, py::arg("layers") = 4, py::arg("z_threshold_mode") = "primitive",
      py::arg("z_threshold") = py::none(), py::arg("alpha_override") = -1.0f, py::arg("backface_culling") = true,
      py::arg("ambient") = 0.25f, py::arg("diffuse") = 0.75f, py::arg("specular") = 0.2f, py::arg("shininess") = 24.0f,
      py::arg("light") = py::none(), py::arg("world_light") = false, py::arg("default_color") = py::none(),
      py::arg("per_pixel_lighting") = false, py::arg("background") = "white", py::arg("segment_method") = "screen",
      py::arg("segment_lod") = RenderOptions{}.segmentLod,
      py::arg("coverage_gain") = RenderOptions{}.coverageGain,
      py::arg("coverage_reach") = RenderOptions{}.coverageReach, py::arg("tail_coverage") = RenderOptions{}.tailCoverage,
      py::arg("k") = 12, py::arg("tile_size") = 64, py::arg("depth") = false, py::arg("alpha") = false,
      py::arg("normal") = false,
      R"doc(Renders a point or hybrid model by EWA splatting (thesis §4-§6.2) = `linesurf render`.

Returns an (H, W, 4) uint8 RGBA array, or, when depth/alpha/normal is requested, a dict with
'color' and the requested (H, W) float32 'depth' (linear depth, 0 where empty), (H, W) 'alpha',
(H, W, 3) 'normal' ((n+1)/2). size = (width, height). Camera: an orbit view (azimuth, elevation,
distance, zoom, fov, up_axis) auto-framed on the bounding sphere, or look-at (eye, target, up).
Raw scans get normals and radii from the §6.1 geometry (k) on every call; prepare() once for
repeated renders. The other keywords are the fields of RenderOptions. The GIL is released.)doc");

  // --- images (§7) ----------------------------------------------------------------------------
  m.def(
      "compare",
      [](py::object a, py::object b) {
        Image ia = imageFrom(a, "a"), ib = imageFrom(b, "b");
        if (ia.width != ib.width || ia.height != ib.height)
          throwBadOption("b", "size " + std::to_string(ib.width) + "x" + std::to_string(ib.height) + " differs from a (" +
                                  std::to_string(ia.width) + "x" + std::to_string(ia.height) + ")");
        ImageMetrics mt;
        {
          py::gil_scoped_release release;
          mt = compareImages(ia, ib);
        }
        py::dict d;
        d["mse"] = mt.mse, d["psnr"] = mt.psnr, d["nccm"] = mt.nccm, d["ssim"] = mt.ssim;
        d["mean_abs_diff"] = mt.meanAbsDiff, d["std_abs_diff"] = mt.stdAbsDiff, d["max_abs_diff"] = mt.maxAbsDiff;
        d["differing_pixels"] = mt.differingPixels;
        return d;
      },
      py::arg("a"), py::arg("b"),
      "Image metrics of thesis §7 (= `linesurf compare`): mse, psnr (inf when identical), nccm, ssim,\n"
      "mean/std/max absolute difference in grey levels, fraction of differing pixels. a and b are\n"
      "(H, W, 3|4) uint8 or float [0, 1] arrays, or image paths; alpha is ignored.");
  m.def(
      "difference_heatmap",
      [](py::object a, py::object b, double saturate) {
        Image ia = imageFrom(a, "a"), ib = imageFrom(b, "b");
        if (ia.width != ib.width || ia.height != ib.height) throwBadOption("b", "size differs from a");
        if (!(saturate > 0) || !std::isfinite(saturate)) throwBadOption("saturate", "must be a finite number > 0");
        return rgba8(differenceHeatmap(ia, ib, saturate));
      },
      py::arg("a"), py::arg("b"), py::kw_only(), py::arg("saturate") = 32.0,
      "Heat-map (H, W, 4) uint8 of the per-pixel maximum channel difference (= compare --diff).");
  m.def(
      "read_image",
      [](const std::string& path) {
        Image img;
        {
          py::gil_scoped_release release;
          img = readImage(path);
        }
        return rgba8(img);
      },
      py::arg("path"), "Reads a PNG/JPEG/BMP/TGA image as an (H, W, 4) uint8 array.");
  m.def(
      "write_png",
      [](const std::string& path, py::object image) {
        Image img = imageFrom(image, "image");
        py::array a = py::array::ensure(image);
        const bool withAlpha = a && a.ndim() == 3 && a.shape(2) == 4;
        py::gil_scoped_release release;
        writePng(path, img, withAlpha);
      },
      py::arg("path"), py::arg("image"), "Writes an (H, W, 3|4) uint8 or float [0, 1] array as an 8-bit PNG.");

  // --- threads --------------------------------------------------------------------------------
  m.def(
      "set_threads",
      [](int threads) {
        if (threads < 0 || threads > 1024) throwBadOption("threads", "must be in [0, 1024] (0 = all cores)");
        threadLimit().reset();
        if (threads > 0) threadLimit() = std::make_unique<ThreadLimit>(threads);
      },
      py::arg("threads"),
      "Limits the worker threads of every later call (0 = all cores). Results do not depend on it.");
  m.def("thread_count", &currentThreadCount, "Number of worker threads calls use now.");
}
