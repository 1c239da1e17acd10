// The option tables (pipeline/option_tables.h) against what each front end does with them:
//  - every numeric option of every command, with NaN, +-inf, a negative value, 0, 1e-300, 1e300,
//    the type's limits and the range's ends, gets the documented outcome (the table's range):
//    validate() accepts or refuses it naming the field, and the CLI refuses it with exit 1 and a
//    one-line "FLAG: WHAT" before any work, or accepts it (and stops only at a bad --output);
//  - `--help`, the viewer page and the page's script agree with the tables and the structs'
//    defaults. Python's signatures are checked against the CLI in tests/python/test_options.py.
// Everything is derived from the tables: a field added to a table is covered without a new test.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <limits>
#include <optional>
#include <regex>
#include <set>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "linesurf/core/option_table.h"
#include "linesurf/core/options.h"
#include "linesurf/pipeline/option_tables.h"
#include "linesurf/view/viewer_page.h"
#include "test_util.h"

namespace linesurf {
namespace {

using json = nlohmann::json;

/// One numeric field of a struct: how to set it in a copy of the defaults and validate that copy.
struct NumericField {
  std::string name;
  OptionSpec spec;
  enum Kind { Float, Double, Int, Unsigned } kind;
  std::function<void(double)> setAndValidate;  // throws OptionError when validate() refuses
};

template <typename S>
struct NumericCollector {
  const S& defaults;
  std::vector<NumericField>& out;
  void group(const char*, const char*) {}
  template <typename T>
  void operator()(T&& field, const OptionSpec& s) {
    using U = std::remove_cvref_t<T>;
    if constexpr (std::is_same_v<U, std::optional<float>>) {  // a default resolved later: given as a float
      const size_t offset = size_t(reinterpret_cast<const char*>(&field) - reinterpret_cast<const char*>(&defaults));
      const S copyFrom = defaults;
      out.push_back({s.name, s, NumericField::Float, [copyFrom, offset](double v) {
                       S c = copyFrom;
                       *reinterpret_cast<U*>(reinterpret_cast<char*>(&c) + offset) = float(v);
                       validate(c);
                     }});
    } else if constexpr (std::is_arithmetic_v<U> && !std::is_same_v<U, bool>) {
      const size_t offset = size_t(reinterpret_cast<const char*>(&field) - reinterpret_cast<const char*>(&defaults));
      NumericField f{s.name, s,
                     std::is_same_v<U, float>    ? NumericField::Float
                     : std::is_floating_point_v<U> ? NumericField::Double
                     : std::is_unsigned_v<U>       ? NumericField::Unsigned
                                                   : NumericField::Int,
                     {}};
      const S copyFrom = defaults;
      f.setAndValidate = [copyFrom, offset](double v) {
        S c = copyFrom;
        *reinterpret_cast<U*>(reinterpret_cast<char*>(&c) + offset) = U(v);
        validate(c);
      };
      out.push_back(f);
    }
  }
};

// validate() is a free function for every struct but ShapeApproxOptions' clustering fields, which
// ShapeApproxOptions' validate() checks too.
template <typename S>
std::vector<NumericField> numericFields() {
  static S defaults{};
  std::vector<NumericField> out;
  NumericCollector<S> c{defaults, out};
  describeOptions(defaults, c);
  return out;
}

/// The values every numeric field is tried with, as typed on a command line, and the value the
/// field then holds (NaN when the text is not a number of its type at all).
struct Probe {
  std::string text;
  double value;
};

std::vector<Probe> probes(const NumericField& f) {
  const double inf = std::numeric_limits<double>::infinity(), nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Probe> p = {{"nan", nan}, {"inf", inf}, {"-inf", -inf}, {"-1", -1}, {"0", 0},
                          {"1e-300", 1e-300}, {"1e300", 1e300}};
  auto add = [&](double v) { p.push_back({fmt::format("{}", v), v}); };
  switch (f.kind) {
    case NumericField::Float:
      add(FLT_MAX), add(-FLT_MAX), add(std::numeric_limits<float>::denorm_min());
      break;
    case NumericField::Double:
      add(DBL_MAX), add(-DBL_MAX), add(std::numeric_limits<double>::denorm_min());
      break;
    case NumericField::Int:
      p.push_back({"2147483647", 2147483647.0});
      p.push_back({"-2147483648", -2147483648.0});
      p.push_back({"2147483648", 2147483648.0});
      break;
    case NumericField::Unsigned:
      p.push_back({"18446744073709551615", 18446744073709551615.0});
      p.push_back({"18446744073709551616", 18446744073709551616.0});
      break;
  }
  // each finite end of the range and the nearest value of the field's type beyond it
  for (const double end : {f.spec.range.lo, f.spec.range.hi}) {
    if (!std::isfinite(end)) continue;
    const double out = end == f.spec.range.lo ? -std::numeric_limits<double>::infinity()
                                              : std::numeric_limits<double>::infinity();
    switch (f.kind) {
      case NumericField::Float: add(end), add(std::nextafter(float(end), float(out))); break;
      case NumericField::Double: add(end), add(std::nextafter(end, out)); break;
      case NumericField::Int:
      case NumericField::Unsigned:
        if (end == std::floor(end)) add(end), add(end + (out > 0 ? 1 : -1));
        break;
    }
  }
  return p;
}

/// The documented outcome of typing `p` for `f`: whether the value is a number of the field's type
/// (an integer field takes integers only; a float field refuses what float cannot hold) inside the
/// table's range.
bool documentedAccept(const NumericField& f, const Probe& p) {
  const double v = p.value;
  switch (f.kind) {
    case NumericField::Float:
      if (std::isfinite(v) && (std::abs(v) > FLT_MAX || (v != 0 && float(v) == 0))) return false;
      return f.spec.range.accepts(v) && f.spec.range.accepts(float(v));
    case NumericField::Double: return f.spec.range.accepts(v);
    case NumericField::Int:
      return std::isfinite(v) && v == std::floor(v) && v >= -2147483648.0 && v <= 2147483647.0 &&
             p.text.find_first_of(".eE") == std::string::npos && f.spec.range.accepts(v);
    case NumericField::Unsigned:
      return std::isfinite(v) && v >= 0 && p.text.find_first_of("-.eEn") == std::string::npos &&
             p.text != "18446744073709551616" && f.spec.range.accepts(v);
  }
  return false;
}

template <typename S>
void checkValidateAgainstTable(const char* structName) {
  const std::vector<NumericField> fields = numericFields<S>();
  ASSERT_FALSE(fields.empty()) << structName;
  for (const NumericField& f : fields)
    for (const Probe& p : probes(f)) {
      // the library sees what the front end stores: the value in the field's own type
      const bool storable = documentedAccept(f, p) || (f.kind == NumericField::Float
                                                          ? !(std::isfinite(p.value) && (std::abs(p.value) > FLT_MAX ||
                                                                                         (p.value != 0 && float(p.value) == 0)))
                                                          : f.kind == NumericField::Double ||
                                                                (std::isfinite(p.value) && p.value == std::floor(p.value) &&
                                                                 (f.kind == NumericField::Int
                                                                      ? p.value >= -2147483648.0 && p.value <= 2147483647.0
                                                                      : p.value >= 0 && p.value < 1.8446744073709552e19)));
      if (!storable) continue;
      const double stored = f.kind == NumericField::Float ? double(float(p.value)) : p.value;
      std::string refusedBy;
      try {
        f.setAndValidate(stored);
      } catch (const OptionError& e) {
        refusedBy = e.field();
      }
      const bool expect = f.spec.range.accepts(stored);
      EXPECT_EQ(refusedBy.empty(), expect)
          << structName << "." << f.name << " = " << p.text << ": the table says " << f.spec.range.text()
          << (refusedBy.empty() ? "; validate() accepts it" : "; validate() refuses it as " + refusedBy);
      if (!refusedBy.empty()) EXPECT_EQ(refusedBy, f.name) << structName << "." << f.name << " = " << p.text;
    }
}

TEST(OptionTables, ValidateAcceptsExactlyTheDocumentedRange) {
  checkValidateAgainstTable<ViewOptions>("ViewOptions");
  checkValidateAgainstTable<PrepareOptions>("PrepareOptions");
  checkValidateAgainstTable<RenderOptions>("RenderOptions");
  checkValidateAgainstTable<DrawingOptions>("DrawingOptions");
  checkValidateAgainstTable<GeometryOptions>("GeometryOptions");
  checkValidateAgainstTable<EpsDeltaOptions>("EpsDeltaOptions");
  checkValidateAgainstTable<ShapeApproxOptions>("ShapeApproxOptions");
  checkValidateAgainstTable<ContourOptions>("ContourOptions");
}

struct DefaultsInRange {
  std::string structName;
  void group(const char*, const char*) {}
  template <typename T>
  void operator()(T&& v, const OptionSpec& s) {
    if constexpr (std::is_arithmetic_v<std::remove_cvref_t<T>> && !std::is_same_v<std::remove_cvref_t<T>, bool>)
      if (!s.defaultText)
        EXPECT_TRUE(s.range.accepts(double(v))) << structName << "." << s.name << " default " << v << " outside "
                                                << s.range.text();
  }
};

TEST(OptionTables, DefaultsLieInTheirRanges) {
  auto check = [](auto defaults, const char* name) {
    DefaultsInRange c{name};
    describeOptions(defaults, c);
  };
  check(ViewOptions{}, "ViewOptions");
  check(PrepareOptions{}, "PrepareOptions");
  check(RenderOptions{}, "RenderOptions");
  check(MeshRenderOptions{}, "MeshRenderOptions");
  check(DrawingOptions{}, "DrawingOptions");
  check(GeometryOptions{}, "GeometryOptions");
  check(EpsDeltaOptions{}, "EpsDeltaOptions");
  check(ShapeApproxOptions{}, "ShapeApproxOptions");
  check(ContourOptions{}, "ContourOptions");
}

// ---------------------------------------------------------------------------------------------
// The CLI.

/// A command, its input and the option structs it binds (their flags are read from its --help).
struct Command {
  std::string name, input, extension;
  std::vector<std::function<std::vector<NumericField>()>> structs;
};

std::vector<Command> commands() {
  const std::string points = (test::bundledData() / "igea_points.ply").string();
  const std::string mesh = (test::bundledData() / "al_mesh.ply").string();
  return {
      {"render", points, ".png",
       {numericFields<ViewOptions>, numericFields<PrepareOptions>, numericFields<RenderOptions>,
        numericFields<MeshRenderOptions>, numericFields<DrawingOptions>}},
      {"view", points, ".html", {numericFields<ViewOptions>, numericFields<RenderOptions>, numericFields<PrepareOptions>}},
      {"extract eps-delta", points, ".ply", {numericFields<EpsDeltaOptions>, numericFields<GeometryOptions>}},
      {"extract shape-approx", points, ".ply", {numericFields<ShapeApproxOptions>, numericFields<GeometryOptions>}},
      {"extract contour", mesh, ".ply", {numericFields<ContourOptions>}},
      {"normals", points, ".ply", {numericFields<GeometryOptions>}},
  };
}

std::string escaped(const std::string& flag) { return std::regex_replace(flag, std::regex("-"), "\\-"); }

/// Whether --help lists `flag` as an option (among the spellings that start a line), not only
/// mentions it in a help text.
bool helpHasFlag(const std::string& help, const std::string& flag) {
  return std::regex_search(help, std::regex("(^|\n) *(-[^ \n]*,)*" + escaped(flag) + "[ ,=\n]"));
}

TEST(CliOptions, EveryNumericOptionGetsItsDocumentedOutcomeBeforeAnyWork) {
  const std::filesystem::path dir = test::scratchDir("cli_option_table");
  size_t tried = 0;
  for (const Command& c : commands()) {
    const std::string help = test::runCli(c.name + " --help").out;
    std::set<std::string> seen;
    for (const auto& fieldsOf : c.structs)
      for (const NumericField& f : fieldsOf()) {
        const std::string flag = flagName(f.name);
        if (!helpHasFlag(help, flag) || !seen.insert(flag).second) continue;
        for (const Probe& p : probes(f)) {
          // A refused value must fail before the output is even checked; an accepted one passes
          // parsing and validation and stops at the output's bad extension (no work either way).
          const bool accept = documentedAccept(f, p);
          const std::filesystem::path out = dir / (accept ? "out.bad_extension" : "out" + c.extension);
          const test::CliResult r = test::runCli(fmt::format("-q {} {} -o {} {}={}", c.name, c.input, out.string(), flag, p.text));
          const std::string where = c.name + " " + flag + "=" + p.text + " (" + f.spec.range.text() + "):\n" + r.out;
          ++tried;
          EXPECT_EQ(r.exitCode, 1) << where;
          EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << where;
          EXPECT_EQ(r.out.rfind((accept ? "--output" : flag) + ": ", 0), 0u) << where;
          EXPECT_FALSE(std::filesystem::exists(out)) << where;
        }
      }
    EXPECT_FALSE(seen.empty()) << c.name;
  }
  // the global options are read the same way
  for (const char* bad : {"--max-mb=nan", "--max-mb=0", "--max-mb=1e300", "--threads=-1", "--threads=nan", "--threads=1e300"}) {
    const test::CliResult r = test::runCli(std::string(bad) + " normals x.ply -o y.ply");
    EXPECT_EQ(r.exitCode, 1) << bad << "\n" << r.out;
    EXPECT_EQ(r.out.rfind(std::string(bad).substr(0, std::string(bad).find('=')) + ": ", 0), 0u) << bad << "\n" << r.out;
  }
  EXPECT_GT(tried, 500u);
}

// ---------------------------------------------------------------------------------------------
// --help, the viewer page and its script against the tables.

/// Each table field as the CLI shows it: flag, default text, use.
struct Shown {
  std::string flag, def;
  unsigned use;
  bool onFlag;  // a boolean on by default: --x and --no-x
};

struct ShownCollector {
  std::vector<Shown>& out;
  void group(const char*, const char*) {}
  template <typename T>
  void operator()(T&& v, const OptionSpec& s) {
    using U = std::remove_cvref_t<T>;
    Shown x{flagName(s.name), "", s.use, false};
    if (s.defaultText) x.def = s.defaultText;
    else if constexpr (std::is_same_v<U, bool>) x.onFlag = v;
    else if constexpr (std::is_arithmetic_v<U>) x.def = fmt::format("{}", v);
    else if constexpr (std::is_enum_v<U>) {
      for (const auto& [n, e] : enumNames(U{}))
        if (e == v) x.def = n;
    } else if constexpr (std::is_same_v<U, Vec3f>) x.def = fmt::format("{} {} {}", v.x(), v.y(), v.z());
    else if constexpr (std::is_same_v<U, RgbRef>) x.def = fmt::format("{} {} {}", v.color.x(), v.color.y(), v.color.z());
    else if constexpr (std::is_same_v<U, SizeRef>) x.def = fmt::format("{}x{}", v.width, v.height);
    else if constexpr (std::is_same_v<U, AxisRef>) x.def = axisName(v.axis);
    else if constexpr (std::is_same_v<U, BackgroundRef>) x.def = backgroundName(v.color);
    out.push_back(x);
  }
};

template <typename S>
std::vector<Shown> shown(S defaults = {}) {
  std::vector<Shown> out;
  ShownCollector c{out};
  describeOptions(defaults, c);
  return out;
}

void checkHelp(const std::string& command, const std::vector<Shown>& fields, unsigned use) {
  const std::string help = test::runCli(command + " --help").out;
  EXPECT_EQ(help.find("{false}"), std::string::npos) << command << ": a flag pair shows a default of its own\n" << help;
  EXPECT_EQ(help.find("{true}"), std::string::npos) << command << "\n" << help;
  for (const Shown& s : fields) {
    const bool offered = s.use & use;
    EXPECT_EQ(helpHasFlag(help, s.flag), offered) << command << " " << s.flag;
    if (!offered) continue;
    if (s.onFlag) {
      EXPECT_TRUE(helpHasFlag(help, "--no-" + s.flag.substr(2))) << command << " " << s.flag;
      EXPECT_NE(help.find("(default on)"), std::string::npos) << command << " " << s.flag;
    } else if (!s.def.empty()) {
      // "--flag[,aliases] TYPE=DEFAULT"
      const std::regex shownDefault("(^|\n) *(-[^ \n]*,)*" + escaped(s.flag) + "(,[^ \n]+)* [^=\n]*=([^\n]*)");
      std::smatch m;
      ASSERT_TRUE(std::regex_search(help, m, shownDefault)) << command << " " << s.flag << "\n" << help;
      EXPECT_EQ(m[4].str().substr(0, s.def.size()), s.def) << command << " " << s.flag;
    }
  }
}

TEST(CliOptions, HelpShowsEveryTableOptionWithTheStructsDefault) {
  std::vector<Shown> render = shown<ViewOptions>();
  auto append = [](std::vector<Shown>& a, const std::vector<Shown>& b) { a.insert(a.end(), b.begin(), b.end()); };
  append(render, shown<PrepareOptions>());
  append(render, shown<RenderOptions>());
  append(render, shown<MeshRenderOptions>());
  append(render, shown<DrawingOptions>());
  checkHelp("render", render, kUseCli);
  std::vector<Shown> view = shown<ViewOptions>();
  append(view, shown<RenderOptions>());
  checkHelp("view", view, kUseViewer);
  checkHelp("extract contour", shown<ContourOptions>(), kUseCli);
  checkHelp("extract eps-delta", shown<EpsDeltaOptions>(), kUseCli);
  checkHelp("extract shape-approx", shown<ShapeApproxOptions>(), kUseCli);
}

std::string scriptText(const std::string& page, const std::string& id) {
  const size_t tag = page.find("<script id=\"" + id + "\"");
  if (tag == std::string::npos) return "";
  const size_t start = page.find('>', tag) + 1;
  return page.substr(start, page.find("</script>", start) - start);
}

/// Checks each viewer field of a table against the page's defaults, collecting their names.
struct ViewerDefaultCheck {
  const json& d;
  std::set<std::string>& want;
  void group(const char*, const char*) {}
  template <typename T>
  void operator()(T&& v, const OptionSpec& s) {
    using U = std::remove_cvref_t<T>;
    if (!(s.use & kUseViewer)) return;
    want.insert(s.name);
    ASSERT_TRUE(d.contains(s.name)) << s.name;
    const json& x = d[s.name];
    if constexpr (std::is_arithmetic_v<U>) EXPECT_FLOAT_EQ(x.get<float>(), float(v)) << s.name;
    else if constexpr (std::is_same_v<U, std::optional<float>>)
      EXPECT_FLOAT_EQ(x.get<float>(), v.value_or(defaultZThreshold(ZThresholdMode::PerPrimitive))) << s.name;
    else if constexpr (std::is_same_v<U, Vec3f>) {
      for (int i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(x[i].get<float>(), v[i]) << s.name;
    } else if constexpr (std::is_same_v<U, RgbRef> || std::is_same_v<U, BackgroundRef>) {
      for (int i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(x[i].get<float>(), v.color[i]) << s.name;
    } else if constexpr (std::is_same_v<U, AxisRef>) {
      for (int i = 0; i < 3; ++i) EXPECT_FLOAT_EQ(x[i].get<float>(), v.axis[i]) << s.name;
    } else {
      ADD_FAILURE() << s.name << ": a viewer field of a type the page cannot take";
    }
  }
};

TEST(ViewerOptions, ThePageTakesTheTablesViewerFieldsWithTheStructsDefaults) {
  HybridModel m;
  for (int i = 0; i < 8; ++i) {
    Point p;
    p.position = Vec3f(float(i % 2), float(i / 2 % 2), float(i / 4));
    p.normal = Vec3f(0, 0, 1);
    p.radius = 0.3f;
    m.points.push_back(p);
  }
  m.attributes.normals = m.attributes.radii = true;
  const std::string page = viewerPage(m);
  const json meta = json::parse(scriptText(page, "linesurf-meta"));
  ASSERT_TRUE(meta.contains("defaults"));
  const json& d = meta["defaults"];
  std::set<std::string> want;
  ViewOptions view;
  RenderOptions render;
  ViewerDefaultCheck c{d, want};
  describeOptions(view, c);
  describeOptions(render, c);
  std::set<std::string> got;
  for (auto it = d.begin(); it != d.end(); ++it) got.insert(it.key());
  EXPECT_EQ(got, want) << "the page's defaults are exactly the tables' viewer fields";

  // The script (its modules, web/modules/*.js) reads each of them (meta.defaults as D) and no
  // other; its shader constants come from the page too (no copy of the renderer's limits).
  std::stringstream ss;
  const std::filesystem::path modules = std::filesystem::path(LINESURF_SOURCE_DIR) / "web" / "modules";
  for (const auto& entry : std::filesystem::directory_iterator(modules))
    if (entry.path().extension() == ".js") ss << std::ifstream(entry.path()).rdbuf() << '\n';
  const std::string script = ss.str();
  ASSERT_NE(script.find("meta.defaults"), std::string::npos) << "web/modules/ holds the viewer's script";
  std::set<std::string> used;
  const std::regex ref("\\bD\\.([A-Za-z]+)");
  for (auto it = std::sregex_iterator(script.begin(), script.end(), ref); it != std::sregex_iterator(); ++it)
    used.insert((*it)[1].str());
  EXPECT_EQ(used, want) << "web/modules/*.js read the page's defaults by the tables' names";
  EXPECT_EQ(script.find("24.0"), std::string::npos) << "kMaxStretch is passed in, not copied";
  ASSERT_TRUE(meta.contains("constants"));
  EXPECT_GT(meta["constants"]["maxStretch"].get<float>(), 1.0f);
}

}  // namespace
}  // namespace linesurf
