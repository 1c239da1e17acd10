#include "linesurf/core/option_table.h"

#include <fmt/format.h>

#include "linesurf/core/options.h"

namespace linesurf {

std::string OptionRange::text() const {
  const bool hasLo = lo > -std::numeric_limits<double>::infinity(), hasHi = hi < std::numeric_limits<double>::infinity();
  if (hasLo && hasHi) return fmt::format("{}{:g}, {:g}{}", loOpen ? '(' : '[', lo, hi, hiOpen ? ')' : ']');
  if (hasLo) return fmt::format("{} {:g}", loOpen ? ">" : ">=", lo);
  if (hasHi) return fmt::format("{} {:g}", hiOpen ? "<" : "<=", hi);
  return "";
}

float narrowOption(const OptionSpec& spec, double value) {
  const float f = narrowToFloat(spec.name, value);
  if (spec.range.accepts(value) && !spec.range.accepts(f))
    throwBadOption(spec.name, fmt::format("{} rounds to {} in single precision, outside {}", numberText(value),
                                          numberText(f), spec.range.text()));
  return f;
}

std::string axisName(const Vec3f& a) {
  for (int i = 0; i < 3; ++i) {
    Vec3f e = Vec3f::Zero();
    e[i] = 1;
    const char* names[] = {"x", "y", "z"};
    if (a == e) return names[i];
    if (a == -e) return std::string("-") + names[i];
  }
  return "";
}

std::string backgroundName(const Color& c) {
  if (c == Color(1, 1, 1, 1)) return "white";
  if (c == Color(0, 0, 0, 1)) return "black";
  if (c == Color(0, 0, 0, 0)) return "transparent";
  return fmt::format("{},{},{},{}", c.x(), c.y(), c.z(), c.w());
}

}  // namespace linesurf
