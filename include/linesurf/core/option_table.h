#pragma once
/// How an option struct describes its fields once for every front end. Each struct has a
/// describeOptions(struct&, visitor) (pipeline/option_tables.h) that calls the visitor once per
/// field with a reference to it and an OptionSpec: the field's name (camelCase, as validate()
/// names it: the CLI shows flagName(name), Python keywordName(name)), its help, its documented
/// range and which front ends offer it. The CLI binds its flags with it (apps/linesurf/
/// options_bind.h), the Python module its keywords and their defaults (python/src/options.cpp),
/// the viewer page its defaults (src/view/viewer_page.cpp): a field added to a table reaches all
/// three, with the default read from the struct's default instance, never restated.
///
/// The range is what validate() accepts; the front ends print it and tests/options check every
/// numeric field's validate() against it with hostile values (NaN, infinities, 0, 1e-300, ...).
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <utility>

#include "linesurf/core/math.h"

namespace linesurf {

/// The values a numeric option accepts: [lo, hi] with either end open, plus at most one value
/// outside it with a meaning of its own (alphaOverride's -1: keep the model's alpha). NaN and
/// infinities are never accepted.
struct OptionRange {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool loOpen = false, hiOpen = false;
  bool hasSpecial = false;
  double special = 0;

  bool accepts(double v) const {
    if (hasSpecial && v == special) return true;
    if (!(v == v) || v == std::numeric_limits<double>::infinity() || v == -std::numeric_limits<double>::infinity())
      return false;
    return (loOpen ? v > lo : v >= lo) && (hiOpen ? v < hi : v <= hi);
  }
  bool bounded() const { return lo > -std::numeric_limits<double>::infinity() || hi < std::numeric_limits<double>::infinity(); }
  /// "[0, 100]", "(0, 4]", ">= 0", "> 0"; empty for an unbounded range.
  std::string text() const;
};

/// [lo, hi].
constexpr OptionRange closedRange(double lo, double hi) { return {lo, hi}; }
/// (lo, hi].
constexpr OptionRange aboveRange(double lo, double hi) { return {lo, hi, true, false}; }
/// [lo, hi).
constexpr OptionRange belowRange(double lo, double hi) { return {lo, hi, false, true}; }
/// >= lo.
constexpr OptionRange atLeast(double lo) { return {lo}; }
/// > lo.
constexpr OptionRange greaterThan(double lo) { return {lo, std::numeric_limits<double>::infinity(), true, false}; }
/// Any finite value.
constexpr OptionRange anyFinite() { return {}; }

/// Which front ends offer a field.
enum OptionUse : unsigned {
  kUseCli = 1,     ///< a flag of the commands that bind the struct
  kUsePython = 2,  ///< a keyword of the Python functions that take the struct
  kUseViewer = 4,  ///< a default of the viewer page (linesurf view)
  kUseCliPython = kUseCli | kUsePython,
  kUseAll = kUseCli | kUsePython | kUseViewer,
};

/// One field as the front ends show it.
struct OptionSpec {
  const char* name;     ///< the C++ field name (camelCase); flag and keyword derive from it
  const char* help;     ///< one line, without the range or default (the front ends add them)
  OptionRange range{};  ///< numbers only
  unsigned use = kUseCliPython;
  /// Older CLI spellings, comma-separated ("--prefilter"); for a flag that is on by default, the
  /// extra spellings that turn it off ("--no-cull").
  const char* aliases = "";
  /// The default is resolved later from other fields (zThreshold: by its mode); Python shows
  /// None, the CLI `defaultText`.
  const char* defaultText = nullptr;
};

/// Names of an enum's values as the front ends spell them ("primitive", "fixed"): specialise
/// enumNames(E{}) next to a table.
template <typename E>
struct EnumName {
  const char* name;
  E value;
};

/// A WIDTHxHEIGHT pair shown as one option ("size").
struct SizeRef {
  int& width;
  int& height;
};
/// A coordinate axis written x, y, z, -x, -y, -z (ViewOptions::upAxis).
struct AxisRef {
  Vec3f& axis;
};
/// A colour chosen by name or R,G,B[,A] (RenderOptions::background).
struct BackgroundRef {
  Color& color;
};
/// An opaque colour given as three numbers R G B (RenderOptions::defaultColor).
struct RgbRef {
  Color& color;
};

/// A number typed for a single-precision field (narrowToFloat, core/options.h), and refused with
/// a message saying so when the rounding alone moves it out of the field's range (89.9999999 is
/// 90 as a float, outside [0, 90)).
float narrowOption(const OptionSpec& spec, double value);

/// "x", "-z", ...; "" for a vector that is not a coordinate axis.
std::string axisName(const Vec3f& axis);
/// "white", "black", "transparent", else "R,G,B,A" (shortest float spelling).
std::string backgroundName(const Color& c);

}  // namespace linesurf
