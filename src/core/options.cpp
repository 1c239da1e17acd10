#include "linesurf/core/options.h"

#include <cctype>
#include <cmath>

#include <fmt/format.h>

namespace linesurf {

OptionError::OptionError(std::string field, std::string what)
    : Error(Kind::BadParameter, std::move(field), "", std::move(what)) {}

void throwBadOption(std::string_view field, const std::string& what) { throw OptionError(std::string(field), what); }

namespace {
std::string splitCamel(std::string_view field, char sep) {
  std::string out;
  for (char c : field) {
    if (std::isupper(static_cast<unsigned char>(c))) {
      if (!out.empty()) out += sep;
      out += char(std::tolower(static_cast<unsigned char>(c)));
    } else {
      out += c;
    }
  }
  return out;
}
}  // namespace

std::string flagName(std::string_view field) { return "--" + splitCamel(field, '-'); }
std::string keywordName(std::string_view field) { return splitCamel(field, '_'); }

namespace {
std::string renamed(const OptionError& e, std::string (*name)(std::string_view)) {
  std::string out = name(e.field()) + ": ";
  const std::string& r = e.reason();
  for (size_t i = 0; i < r.size(); ++i) {
    const size_t end = r[i] == '`' ? r.find('`', i + 1) : std::string::npos;
    if (end == std::string::npos) {
      out += r[i];
      continue;
    }
    out += name(std::string_view(r).substr(i + 1, end - i - 1));
    i = end;
  }
  return out;
}
}  // namespace

std::string cliMessage(const OptionError& e) { return renamed(e, flagName); }
std::string pythonMessage(const OptionError& e) { return renamed(e, keywordName); }

void requireFinite(std::string_view field, double value) {
  if (!std::isfinite(value)) throwBadOption(field, fmt::format("must be a finite number, got {}", value));
}

void requireRange(std::string_view field, double value, double lo, double hi, const std::string& unit) {
  if (!(value >= lo && value <= hi))  // false for NaN
    throwBadOption(field, fmt::format("must be in [{:g}, {:g}]{}, got {:g}", lo, hi, unit.empty() ? "" : " " + unit, value));
}

void requirePositive(std::string_view field, double value) {
  if (!(value > 0) || !std::isfinite(value)) throwBadOption(field, fmt::format("must be a finite number > 0, got {:g}", value));
}

}  // namespace linesurf
