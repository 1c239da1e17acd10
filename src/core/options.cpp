#include "linesurf/core/options.h"

#include <cctype>
#include <cfloat>
#include <cmath>

#include <fmt/format.h>

#include <limits>

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

std::string numberText(double value) {
  // A value a float field held prints as that float (1e-30, not 1.0000000031710769e-30).
  const float f = float(value);
  return double(f) == value ? fmt::format("{}", f) : fmt::format("{}", value);
}

void requireFinite(std::string_view field, double value) {
  if (!std::isfinite(value)) throwBadOption(field, "must be a finite number, got " + numberText(value));
}

void requireRange(std::string_view field, double value, double lo, double hi, const std::string& unit) {
  if (!(value >= lo && value <= hi))  // false for NaN
    throwBadOption(field, fmt::format("must be in [{:g}, {:g}]{}, got {}", lo, hi, unit.empty() ? "" : " " + unit,
                                      numberText(value)));
}

void requirePositive(std::string_view field, double value) {
  if (!(value > 0) || !std::isfinite(value)) throwBadOption(field, "must be a finite number > 0, got " + numberText(value));
}

float narrowToFloat(std::string_view field, double value) {
  if (std::isfinite(value) && std::abs(value) > double(FLT_MAX))
    throwBadOption(field, fmt::format("{} is beyond the largest single-precision number ({:g})", numberText(value), FLT_MAX));
  const float f = float(value);
  if (value != 0 && f == 0)
    throwBadOption(field, fmt::format("{} is below the smallest single-precision number ({:g}) and would read as 0",
                                      numberText(value), double(std::numeric_limits<float>::denorm_min())));
  return f;
}

}  // namespace linesurf
