#pragma once
// numpy arrays in and out of the library's types: read in place (any float32/float64 array of
// the right shape, C- or F-ordered or strided; the only copy is into the library's layout), new
// arrays owned by Python out.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "linesurf/core/image.h"
#include "linesurf/core/math.h"
#include "linesurf/core/options.h"
#include "linesurf/io/image_io.h"

namespace linesurf::python {

namespace py = pybind11;

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

inline std::string shapeText(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

inline void requireRows(const char* name, py::ssize_t rows, size_t expected, const char* of) {
  if (size_t(rows) != expected)
    throw py::value_error(std::string(name) + ": has " + std::to_string(rows) + " rows for " + std::to_string(expected) + " " + of);
}

/// `shape` lists the trailing dimensions (empty: 1-D); -1 in it accepts any of `alternatives`.
inline FloatArray floatArray(py::handle obj, const char* name, std::initializer_list<py::ssize_t> shape,
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
inline void copyRows3(const py::array& a, py::ssize_t n, float* dst, size_t stride, const char* name) {
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
inline void copyVec3(py::handle obj, const char* name, float* first, size_t strideBytes, size_t expected) {
  FloatArray v = floatArray(obj, name, {3}, false);
  if (expected != size_t(-1)) requireRows(name, v.n, expected, "points");
  const size_t stride = strideBytes / sizeof(float);
  if (v.f64) copyRows3<double>(v.array, v.n, first, stride, name);
  else copyRows3<float>(v.array, v.n, first, stride, name);
}

inline Vec3f vec3At(const FloatArray& a, py::ssize_t i, py::ssize_t j = -1) {
  if (j < 0) return Vec3f(float(a.at(i, 0)), float(a.at(i, 1)), float(a.at(i, 2)));
  return Vec3f(float(a.at(i, j, 0)), float(a.at(i, j, 1)), float(a.at(i, j, 2)));
}

inline std::optional<Vec3f> optionalVec3(const std::optional<std::vector<double>>& v, const char* field) {
  if (!v) return std::nullopt;
  if (v->size() != 3) throwBadOption(field, "needs three numbers x y z");
  return Vec3f(float((*v)[0]), float((*v)[1]), float((*v)[2]));
}

inline Color colorAt(const FloatArray& a, py::ssize_t i) {
  return Color(float(a.at(i, 0)), float(a.at(i, 1)), float(a.at(i, 2)), a.d1 == 4 ? float(a.at(i, 3)) : 1.0f);
}

inline FloatArray colorArray(py::handle obj, const char* name) {
  py::array a = py::array::ensure(obj);
  const bool four = a && a.ndim() == 2 && a.shape(1) == 4;
  return four ? floatArray(obj, name, {4}) : floatArray(obj, name, {3});
}

// ---------------------------------------------------------------------------------------------
// numpy out: new arrays owned by Python.

template <typename T>
inline py::array_t<T> newArray(std::vector<py::ssize_t> shape) {
  return py::array_t<T>(shape);
}

inline py::array_t<float> vec3Array(size_t n, const std::function<Vec3f(size_t)>& f) {
  auto out = newArray<float>({py::ssize_t(n), 3});
  float* p = out.mutable_data();
  for (size_t i = 0; i < n; ++i) {
    Vec3f v = f(i);
    p[3 * i] = v.x(), p[3 * i + 1] = v.y(), p[3 * i + 2] = v.z();
  }
  return out;
}

inline py::array_t<float> floatVector(const std::vector<float>& v) {
  auto out = newArray<float>({py::ssize_t(v.size())});
  if (!v.empty()) std::memcpy(out.mutable_data(), v.data(), v.size() * sizeof(float));
  return out;
}

// ---------------------------------------------------------------------------------------------
// Images.

/// (H, W, 3|4) uint8 or float array in [0, 1] -> Image; alpha 1 when absent.
inline Image imageFrom(py::handle obj, const char* name) {
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

inline py::array_t<uint8_t> rgba8(const Image& img) {
  auto out = newArray<uint8_t>({img.height, img.width, 4});
  quantize8(img, 4, out.mutable_data());
  return out;
}

/// Channel `c` of an image as an (H, W) float32 array, or channels 0..2 as (H, W, 3).
inline py::array_t<float> channels(const Image& img, int first, int count) {
  std::vector<py::ssize_t> shape{img.height, img.width};
  if (count > 1) shape.push_back(count);
  auto out = newArray<float>(shape);
  float* p = out.mutable_data();
  for (size_t i = 0; i < img.pixels.size(); ++i)
    for (int k = 0; k < count; ++k) p[i * count + k] = img.pixels[i][first + k];
  return out;
}


}  // namespace linesurf::python
