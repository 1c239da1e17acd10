#pragma once
// How the CLI binds its options: from the option tables (pipeline/option_tables.h), straight onto
// the library's option structs, whose defaults are the only defaults. Each flag is spelled
// flagName(field) (core/options.h), so that a validation message names the flag the user typed;
// older spellings stay as aliases. Numbers are read here, not by CLI11: a value that is not a
// number of the field's type (1e300 for an int, -1 for an unsigned, 1e-300 for a float, where it
// would read as 0) is refused with exit 1 and "FLAG: WHAT" before any work, like every value
// validate() refuses.
#include <CLI/CLI.hpp>

#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include <fmt/format.h>

#include "linesurf/core/math.h"
#include "linesurf/core/option_table.h"
#include "linesurf/core/options.h"
#include "linesurf/pipeline/option_tables.h"

namespace linesurf::cli {

/// "--prefilter-variance" for field "prefilterVariance", plus aliases ("--prefilter").
inline std::string flags(const std::string& field, const std::string& aliases = "") {
  return flagName(field) + (aliases.empty() ? "" : "," + aliases);
}

/// A number of type T from the text typed for `spec`; throws OptionError naming the field.
template <typename T>
T parseNumber(const OptionSpec& spec, const std::string& text) {
  const char* s = text.c_str();
  char* end = nullptr;
  errno = 0;
  if constexpr (std::is_floating_point_v<T>) {
    const double d = std::strtod(s, &end);
    if (text.empty() || *end != 0) throwBadOption(spec.name, "expected a number, got '" + text + "'");
    if constexpr (std::is_same_v<T, float>) return narrowOption(spec, d);
    else return d;
  } else {
    const std::string range = spec.range.text();
    const std::string what = fmt::format("expected an integer{}{}, got '{}'",
                                         range.empty() ? "" : range[0] == '[' || range[0] == '(' ? " in " : " ", range, text);
    if constexpr (std::is_unsigned_v<T>) {
      if (text.find('-') != std::string::npos) throwBadOption(spec.name, what);
      const unsigned long long v = std::strtoull(s, &end, 10);
      if (text.empty() || *end != 0 || errno == ERANGE || v > std::numeric_limits<T>::max()) throwBadOption(spec.name, what);
      return T(v);
    } else {
      const long long v = std::strtoll(s, &end, 10);
      if (text.empty() || *end != 0 || errno == ERANGE || v < std::numeric_limits<T>::min() ||
          v > std::numeric_limits<T>::max())
        throwBadOption(spec.name, what);
      return T(v);
    }
  }
}

/// Binds the fields of an option table that the CLI offers (OptionSpec::use & kUseCli, or the
/// front end given as `use`) onto one subcommand, each group as a help section. `only`, when
/// given, limits it to those fields.
class TableBinder {
 public:
  explicit TableBinder(CLI::App* app, std::set<std::string> only = {}, unsigned use = kUseCli)
      : app_(app), only_(std::move(only)), use_(use) {}

  void group(const char* name, const char* title) { groupName_ = name, groupTitle_ = title, group_ = nullptr; }

  /// The option bound for `field` (nullptr when not bound).
  CLI::Option* option(const std::string& field) const {
    auto it = bound_.find(field);
    return it == bound_.end() ? nullptr : it->second;
  }
  /// Whether the user typed the field's flag (or one of its aliases).
  bool given(const std::string& field) const {
    CLI::Option* o = option(field);
    return o && o->count() > 0;
  }

  void operator()(bool& value, const OptionSpec& s) {
    if (!wanted(s)) return;
    CLI::App* g = target();
    const std::string name = flagName(s.name);
    if (value) {  // on by default: --x and --no-x (+ aliases that turn it off)
      const std::string off = "--no-" + name.substr(2) + (*s.aliases ? std::string(",") + s.aliases : "");
      bound_[s.name] = g->add_flag_callback(name, [&value] { value = true; }, std::string(s.help) + " (default on)");
      g->add_flag_callback(off, [&value] { value = false; }, "Turn " + name + " off");
      offFlags_[s.name] = off;
    } else {
      bound_[s.name] = g->add_flag_callback(flags(s.name, s.aliases), [&value] { value = true; }, std::string(s.help) + " (default off)");
    }
  }

  template <typename T>
    requires(std::is_arithmetic_v<T> && !std::is_same_v<T, bool>)
  void operator()(T& value, const OptionSpec& s) {
    if (!wanted(s)) return;
    add(s, [&value, s](const std::string& t) { value = parseNumber<T>(s, t); },
        std::is_floating_point_v<T> ? "FLOAT" : std::is_unsigned_v<T> ? "UINT" : "INT",
        s.defaultText ? std::string(s.defaultText) : fmt::format("{}", value));
  }

  template <typename E>
    requires std::is_enum_v<E>
  void operator()(E& value, const OptionSpec& s) {
    if (!wanted(s)) return;
    std::string def, choices;
    for (const auto& [n, e] : enumNames(E{})) {
      if (e == value) def = n;
      choices += (choices.empty() ? "" : "|") + std::string(n);
    }
    add(s, [&value, s, choices](const std::string& t) {
          for (const auto& [n, e] : enumNames(E{}))
            if (CLI::detail::to_lower(t) == n) return void(value = e);
          throwBadOption(s.name, "expected one of " + choices + ", got '" + t + "'");
        }, "{" + choices + "}", def);
  }

  /// A number whose default is resolved later (std::nullopt until given; defaultText says how).
  template <typename T>
    requires std::is_arithmetic_v<T>
  void operator()(std::optional<T>& value, const OptionSpec& s) {
    if (!wanted(s)) return;
    add(s, [&value, s](const std::string& t) { value = parseNumber<T>(s, t); },
        std::is_floating_point_v<T> ? "FLOAT" : "INT", s.defaultText ? std::string(s.defaultText) : "");
  }

  void operator()(Vec3f& value, const OptionSpec& s) {
    if (!wanted(s)) return;
    add3(s, [&value](const Vec3f& v) { value = v; }, fmt::format("{} {} {}", value.x(), value.y(), value.z()));
  }
  void operator()(std::optional<Vec3f>& value, const OptionSpec& s) {
    if (!wanted(s)) return;
    add3(s, [&value](const Vec3f& v) { value = v; }, "");
  }
  void operator()(RgbRef r, const OptionSpec& s) {
    if (!wanted(s)) return;
    Color& c = r.color;
    add3(s, [&c](const Vec3f& v) { c = Color(v.x(), v.y(), v.z(), 1); }, fmt::format("{} {} {}", c.x(), c.y(), c.z()));
  }
  void operator()(SizeRef r, const OptionSpec& s) {
    if (!wanted(s)) return;
    int& w = r.width;
    int& h = r.height;
    add(s, [&w, &h, s](const std::string& t) {
          const size_t x = t.find_first_of("xX");
          if (x == std::string::npos) throwBadOption(s.name, "expected WIDTHxHEIGHT, got '" + t + "'");
          OptionSpec side = s;
          side.range = {};
          w = parseNumber<int>(side, t.substr(0, x)), h = parseNumber<int>(side, t.substr(x + 1));
        }, "WxH", fmt::format("{}x{}", w, h));
  }
  void operator()(AxisRef r, const OptionSpec& s) {
    if (!wanted(s)) return;
    Vec3f& a = r.axis;
    add(s, [&a](const std::string& t) { a = parseUpAxis(t); }, "AXIS", axisName(a));
  }
  void operator()(BackgroundRef r, const OptionSpec& s) {
    if (!wanted(s)) return;
    Color& c = r.color;
    add(s, [&c, s](const std::string& t) { c = parseColor(s.name, t); }, "COLOR", backgroundName(c));
  }

 private:
  bool wanted(const OptionSpec& s) const { return (s.use & use_) && (only_.empty() || only_.count(s.name)); }
  CLI::App* target() {
    if (!group_) group_ = groupName_.empty() ? app_ : app_->add_option_group(groupName_, groupTitle_);
    return group_;
  }
  static std::string helpOf(const OptionSpec& s) {
    const std::string range = s.range.text();
    return std::string(s.help) + (range.empty() ? "" : ", " + range);
  }
  void add(const OptionSpec& s, std::function<void(const std::string&)> f, const std::string& type, const std::string& def) {
    bound_[s.name] = target()->add_option_function<std::string>(flags(s.name, s.aliases), std::move(f), helpOf(s))
                         ->type_name(type)
                         ->default_str(def);
  }
  void add3(const OptionSpec& s, std::function<void(const Vec3f&)> f, const std::string& def) {
    bound_[s.name] = target()
                         ->add_option_function<std::vector<std::string>>(
                             flags(s.name, s.aliases),
                             [f, s](const std::vector<std::string>& t) {
                               OptionSpec one = s;
                               one.range = {};
                               f(Vec3f(parseNumber<float>(one, t[0]), parseNumber<float>(one, t[1]),
                                       parseNumber<float>(one, t[2])));
                             },
                             helpOf(s))
                         ->expected(3)
                         ->type_name("X Y Z")
                         ->default_str(def);
  }

  CLI::App* app_;
  std::set<std::string> only_;
  unsigned use_;
  std::string groupName_, groupTitle_;
  CLI::App* group_ = nullptr;
  std::map<std::string, CLI::Option*> bound_;
  std::map<std::string, std::string> offFlags_;
};

/// Binds every CLI field of `options`' table (or those in `only`; or those of front end `use`)
/// onto `app`.
template <typename S>
TableBinder bindOptions(CLI::App* app, S& options, std::set<std::string> only = {}, unsigned use = kUseCli) {
  TableBinder b(app, std::move(only), use);
  describeOptions(options, b);
  return b;
}

/// A number (or any CLI11-parsable value) bound to a field outside the tables; no CLI-side range
/// check: the struct's validate() reports bad values (NaN included) by their flag.
template <typename T>
CLI::Option* bind(CLI::App* app, const std::string& field, T& value, const std::string& help,
                  const std::string& aliases = "") {
  return app->add_option(flags(field, aliases), value, help)->capture_default_str();
}

}  // namespace linesurf::cli
