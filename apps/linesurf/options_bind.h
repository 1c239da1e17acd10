#pragma once
// How the CLI binds its options: straight onto the library's option structs (their defaults are
// the only defaults), with each flag spelled flagName(field) (core/options.h) so that a
// validation message names the flag the user typed. Older spellings stay as aliases.
#include <CLI/CLI.hpp>

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "linesurf/core/math.h"
#include "linesurf/core/options.h"

namespace linesurf::cli {

/// "--prefilter-variance" for field "prefilterVariance", plus aliases ("--prefilter").
inline std::string flags(const std::string& field, const std::string& aliases = "") {
  return flagName(field) + (aliases.empty() ? "" : "," + aliases);
}

/// A number (or any CLI11-parsable value) bound to a struct field; no CLI-side range check: the
/// struct's validate() reports bad values (NaN included) by their flag.
template <typename T>
CLI::Option* bind(CLI::App* app, const std::string& field, T& value, const std::string& help,
                  const std::string& aliases = "") {
  return app->add_option(flags(field, aliases), value, help)->capture_default_str();
}

/// Three numbers into a Vec3f field (or an optional one).
inline CLI::Option* bindVec3(CLI::App* app, const std::string& field, Vec3f& value, const std::string& help,
                             const std::string& aliases = "") {
  return app->add_option_function<std::vector<float>>(
                flags(field, aliases), [&value](const std::vector<float>& v) { value = Vec3f(v[0], v[1], v[2]); }, help)
      ->expected(3);
}
inline CLI::Option* bindVec3(CLI::App* app, const std::string& field, std::optional<Vec3f>& value,
                             const std::string& help, const std::string& aliases = "") {
  return app->add_option_function<std::vector<float>>(
                flags(field, aliases), [&value](const std::vector<float>& v) { value = Vec3f(v[0], v[1], v[2]); }, help)
      ->expected(3);
}

/// An enum field chosen by name.
template <typename E>
CLI::Option* bindEnum(CLI::App* app, const std::string& field, E& value, const std::map<std::string, E>& names,
                      const std::string& help, const std::string& aliases = "") {
  std::string def, choices;
  for (const auto& [name, e] : names) {
    if (e == value) def = name;
    choices += (choices.empty() ? "" : "|") + name;
  }
  return app->add_option(flags(field, aliases), value, help)
      ->transform(CLI::CheckedTransformer(names, CLI::ignore_case).description(""))
      ->type_name("{" + choices + "}")
      ->default_str(def);
}

}  // namespace linesurf::cli
