#pragma once
/// One rule for naming options in messages. Every option struct (RenderOptions, GeometryOptions,
/// EpsDeltaOptions, ...) holds its defaults and has a validate() that throws OptionError naming
/// the offending *field* as spelled in C++ (camelCase, e.g. "zThreshold"). Front ends translate
/// the field to what their user typed:
///   CLI:    "zThreshold" -> "--z-threshold"   (flagName)
///   Python: "zThreshold" -> "z_threshold"     (keywordName)
/// so that a message reads "--z-threshold: must be finite and >= 0" in a shell and
/// "z_threshold: must be finite and >= 0" in Python. Nested fields use the leaf name; a reason
/// that names another field writes it `backquoted` (cliMessage / pythonMessage rename it).
#include <string>
#include <string_view>

#include "linesurf/core/error.h"

namespace linesurf {

/// A bad option value (Error::Kind::BadParameter); path() and field() are the field name.
class OptionError : public Error {
 public:
  OptionError(std::string field, std::string what);
  const std::string& field() const { return path(); }
};

/// Throws OptionError("FIELD: WHAT").
[[noreturn]] void throwBadOption(std::string_view field, const std::string& what);

/// "zThreshold" -> "--z-threshold"; "k" -> "--k".
std::string flagName(std::string_view field);
/// "zThreshold" -> "z_threshold".
std::string keywordName(std::string_view field);

/// The one-line message of an OptionError as a front end shows it: "FLAG: REASON" for the CLI,
/// "keyword: REASON" for Python. Other fields named in the reason as `field` (backquoted) are
/// renamed the same way.
std::string cliMessage(const OptionError& error);
std::string pythonMessage(const OptionError& error);

/// The checks every validate() uses; all reject NaN and infinities.
void requireFinite(std::string_view field, double value);
/// lo <= value <= hi.
void requireRange(std::string_view field, double value, double lo, double hi, const std::string& unit = "");
/// value > 0 (and finite).
void requirePositive(std::string_view field, double value);

/// A number typed for a single-precision field, checked before it is narrowed: a value that
/// float cannot hold (|v| > FLT_MAX, or a non-zero value that rounds to 0, such as 1e-300, which
/// would otherwise read as the field's "automatic" 0) throws OptionError instead of silently
/// becoming infinity or 0. NaN and infinities pass (validate() names them).
float narrowToFloat(std::string_view field, double value);

/// A number for messages: the shortest text that reads back as the same value (89.9999999 as a
/// double prints so, not "90").
std::string numberText(double value);

}  // namespace linesurf
