#pragma once
// Python keywords from the option tables (pipeline/option_tables.h): a field's keyword is
// keywordName(field), its default the value in the function's default instance of the struct
// (never a literal here), its help the table's. optionSpecs() lists them for the signatures that
// linesurf/__init__.py builds; applyOptions() sets a struct from the keywords given.
#include <pybind11/pybind11.h>

#include <cmath>
#include <optional>
#include <set>
#include <string>
#include <type_traits>

#include <fmt/format.h>

#include "linesurf/core/option_table.h"
#include "linesurf/core/options.h"
#include "linesurf/pipeline/option_tables.h"

namespace linesurf::python {

namespace py = pybind11;

/// A float as Python shows it: the shortest decimal that reads back as the same float (0.2, not
/// 0.20000000298023224).
inline py::float_ pyFloat(float v) { return py::float_(std::stod(fmt::format("{}", v))); }

/// Collects {keyword, default, help} of the fields a function offers.
class SpecCollector {
 public:
  SpecCollector(py::list& out, std::set<std::string> only) : out_(out), only_(std::move(only)) {}
  void group(const char*, const char*) {}
  template <typename T>
  void operator()(T&& value, const OptionSpec& s) {
    if (!(s.use & kUsePython) || (!only_.empty() && !only_.count(s.name))) return;
    py::dict d;
    d["keyword"] = keywordName(s.name);
    d["field"] = s.name;
    d["default"] = s.defaultText ? py::none() : toPython(value);
    const std::string range = s.range.text();
    d["help"] = std::string(s.help) + (range.empty() ? "" : ", " + range) +
                (s.defaultText ? std::string("; default ") + s.defaultText : "");
    out_.append(d);
  }

 private:
  template <typename T>
  static py::object toPython(const T& v) {
    using U = std::remove_cvref_t<T>;
    if constexpr (std::is_same_v<U, bool>) return py::bool_(v);
    else if constexpr (std::is_same_v<U, float>) return pyFloat(v);
    else if constexpr (std::is_floating_point_v<U>) return py::float_(v);
    else if constexpr (std::is_integral_v<U>) return py::int_(v);
    else if constexpr (std::is_enum_v<U>) {
      for (const auto& [n, e] : enumNames(U{}))
        if (e == v) return py::str(n);
      return py::none();
    } else if constexpr (std::is_same_v<U, Vec3f>) return py::make_tuple(pyFloat(v.x()), pyFloat(v.y()), pyFloat(v.z()));
    else if constexpr (std::is_same_v<U, std::optional<Vec3f>> || std::is_same_v<U, std::optional<float>>)
      return v ? toPython(*v) : py::none();
    else if constexpr (std::is_same_v<U, SizeRef>) return py::make_tuple(v.width, v.height);
    else if constexpr (std::is_same_v<U, AxisRef>) return py::str(axisName(v.axis));
    else if constexpr (std::is_same_v<U, BackgroundRef>) return py::str(backgroundName(v.color));
    else if constexpr (std::is_same_v<U, RgbRef>)
      return py::make_tuple(pyFloat(v.color.x()), pyFloat(v.color.y()), pyFloat(v.color.z()));
    else static_assert(sizeof(U) == 0, "an option type Python does not know");
  }

  py::list& out_;
  std::set<std::string> only_;
};

/// Sets the fields whose keywords `kwargs` holds (and removes those keywords from it).
class OptionApplier {
 public:
  OptionApplier(py::dict& kwargs, std::set<std::string> only) : kwargs_(kwargs), only_(std::move(only)) {}
  void group(const char*, const char*) {}
  /// Fields set from a keyword (a None for a field with a resolved default counts as not set).
  std::set<std::string> given;

  template <typename T>
  void operator()(T&& field, const OptionSpec& s) {
    if (!(s.use & kUsePython) || (!only_.empty() && !only_.count(s.name))) return;
    const std::string key = keywordName(s.name);
    if (!kwargs_.contains(key)) return;
    py::object v = kwargs_[py::str(key)];
    PyDict_DelItemString(kwargs_.ptr(), key.c_str());
    if (v.is_none() && s.defaultText) return;
    set(field, v, s);
    given.insert(s.name);
  }

 private:
  static double number(const py::handle& v, const OptionSpec& s) {
    if (py::isinstance<py::str>(v) || !PyNumber_Check(v.ptr()))
      throwBadOption(s.name, "expected a number, got " + std::string(py::repr(v)));
    return v.cast<double>();
  }
  template <typename I>
  static I integer(const py::handle& v, const OptionSpec& s) {
    const std::string range = s.range.text();
    const std::string what = "expected an integer" + (range.empty() ? std::string() : (range[0] == '[' || range[0] == '(' ? " in " : " ") + range) + ", got " +
                             std::string(py::repr(v));
    if (py::isinstance<py::str>(v) || PyFloat_Check(v.ptr()) || !PyIndex_Check(v.ptr())) throwBadOption(s.name, what);
    py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(v.ptr()));
    int overflow = 0;
    const long long x = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
    if constexpr (std::is_unsigned_v<I>) {
      if (overflow < 0 || (!overflow && x < 0)) throwBadOption(s.name, what);
      const unsigned long long u = PyLong_AsUnsignedLongLong(i.ptr());
      if (PyErr_Occurred() || u > std::numeric_limits<I>::max()) {
        PyErr_Clear();
        throwBadOption(s.name, what);
      }
      return I(u);
    } else {
      if (overflow || x < std::numeric_limits<I>::min() || x > std::numeric_limits<I>::max()) throwBadOption(s.name, what);
      return I(x);
    }
  }
  static Vec3f vec3(const py::handle& v, const OptionSpec& s) {
    if (py::isinstance<py::str>(v) || !PySequence_Check(v.ptr()) || py::len(v) != 3)
      throwBadOption(s.name, "expected three numbers x y z");
    OptionSpec one = s;
    one.range = {};
    py::sequence q = py::reinterpret_borrow<py::sequence>(v);
    return Vec3f(narrowOption(one, number(q[0], s)), narrowOption(one, number(q[1], s)), narrowOption(one, number(q[2], s)));
  }

  static void set(bool& f, const py::object& v, const OptionSpec& s) {
    if (!py::isinstance<py::bool_>(v) && std::string(py::str(py::type::of(v).attr("__name__"))) != "bool_")
      throwBadOption(s.name, "expected True or False, got " + std::string(py::repr(v)));
    f = v.cast<bool>();
  }
  template <typename T>
    requires(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>)
  static void set(T& f, const py::object& v, const OptionSpec& s) {
    if constexpr (std::is_same_v<T, float>) f = narrowOption(s, number(v, s));
    else if constexpr (std::is_floating_point_v<T>) f = number(v, s);
    else f = integer<T>(v, s);
  }
  template <typename E>
    requires std::is_enum_v<E>
  static void set(E& f, const py::object& v, const OptionSpec& s) {
    std::string choices;
    if (py::isinstance<py::str>(v)) {
      const std::string t = v.cast<std::string>();
      for (const auto& [n, e] : enumNames(E{}))
        if (t == n) return void(f = e);
    }
    for (const auto& [n, e] : enumNames(E{})) choices += (choices.empty() ? "" : ", ") + std::string(n);
    throwBadOption(s.name, "expected one of " + choices + ", got " + std::string(py::repr(v)));
  }
  static void set(Vec3f& f, const py::object& v, const OptionSpec& s) { f = vec3(v, s); }
  static void set(std::optional<float>& f, const py::object& v, const OptionSpec& s) {
    if (v.is_none()) return f.reset();
    float x = 0;
    set(x, v, s);
    f = x;
  }
  static void set(std::optional<Vec3f>& f, const py::object& v, const OptionSpec& s) {
    if (v.is_none()) f.reset();
    else f = vec3(v, s);
  }
  static void set(RgbRef r, const py::object& v, const OptionSpec& s) {
    const Vec3f c = vec3(v, s);
    r.color = Color(c.x(), c.y(), c.z(), 1);
  }
  static void set(SizeRef r, const py::object& v, const OptionSpec& s) {
    if (py::isinstance<py::str>(v) || !PySequence_Check(v.ptr()) || py::len(v) != 2)
      throwBadOption(s.name, "expected (width, height)");
    py::sequence q = py::reinterpret_borrow<py::sequence>(v);
    OptionSpec side = s;
    side.range = {};
    r.width = integer<int>(q[0], side), r.height = integer<int>(q[1], side);
  }
  static void set(AxisRef r, const py::object& v, const OptionSpec& s) {
    if (!py::isinstance<py::str>(v)) throwBadOption(s.name, "expected x, y, z, -x, -y or -z");
    r.axis = parseUpAxis(v.cast<std::string>());
  }
  static void set(BackgroundRef r, const py::object& v, const OptionSpec& s) {
    if (py::isinstance<py::str>(v)) return void(r.color = parseColor(s.name, v.cast<std::string>()));
    if (!PySequence_Check(v.ptr()) || (py::len(v) != 3 && py::len(v) != 4))
      throwBadOption(s.name, "expected a name or 3 or 4 numbers in [0, 1]");
    py::sequence q = py::reinterpret_borrow<py::sequence>(v);
    OptionSpec one = s;
    one.range = {};
    Color c(0, 0, 0, 1);
    for (size_t i = 0; i < py::len(q); ++i) c[int(i)] = narrowOption(one, number(q[i], s));
    r.color = c;
  }

  py::dict& kwargs_;
  std::set<std::string> only_;
};

/// Appends the keyword specs of `defaults`' table (those in `only`, or all Python fields).
template <typename S>
void optionSpecs(py::list& out, S defaults, std::set<std::string> only = {}) {
  SpecCollector c(out, std::move(only));
  describeOptions(defaults, c);
}

/// Sets `options` from the keywords `kwargs` holds for it; returns the fields given.
template <typename S>
std::set<std::string> applyOptions(py::dict& kwargs, S& options, std::set<std::string> only = {}) {
  OptionApplier a(kwargs, std::move(only));
  describeOptions(options, a);
  return a.given;
}

/// Raises TypeError for keywords no table took (the Python wrapper's signature refuses them
/// first; this guards direct calls of the native functions).
inline void rejectUnknown(const py::dict& kwargs) {
  if (kwargs.size() == 0) return;
  std::string names;
  for (auto item : kwargs) names += (names.empty() ? "" : ", ") + std::string(py::str(item.first));
  throw py::type_error("unexpected keyword argument(s): " + names);
}

}  // namespace linesurf::python
