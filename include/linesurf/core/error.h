#pragma once
/// The library's one error type. Library code never prints and never exits: bad input throws
/// linesurf::Error carrying the path, the location inside it and what is wrong; the CLI prints
/// `what()` (formatted "PATH: WHERE: WHAT") on one line and exits with the kind's code:
/// 1 BadParameter (usage, absurd option value), 2 BadInput (malformed or unreadable input file),
/// 3 Io (cannot write an output) and any other failure.
#include <stdexcept>
#include <string>
#include <string_view>

namespace linesurf {

class Error : public std::runtime_error {
 public:
  enum class Kind { BadInput, BadParameter, Io };
  /// what() is "PATH: WHERE: WHAT" (WHERE omitted when empty) made printable by oneLine().
  Error(Kind kind, std::string path, std::string where, std::string what);
  Kind kind() const { return kind_; }
  const std::string& path() const { return path_; }
  const std::string& where() const { return where_; }
  const std::string& reason() const { return reason_; }

 private:
  Kind kind_;
  std::string path_, where_, reason_;
};

/// A malformed or unreadable input file: "PATH: WHERE: WHAT".
[[noreturn]] void throwBadInput(const std::string& path, const std::string& where, const std::string& what);
/// An absurd parameter value (e.g. negative epsilon): "NAME: WHAT".
[[noreturn]] void throwBadParameter(const std::string& name, const std::string& what);
/// An output that cannot be written: "PATH: WHAT".
[[noreturn]] void throwIo(const std::string& path, const std::string& what);

/// `text` as one printable line: control bytes (newline, NUL, ...), DEL and bytes that are not
/// valid UTF-8 become \n, \0, \xNN escapes (nothing is cut off); a number written with more than
/// 17 digits (e.g. 1.8e308 printed in full) is shortened to 6 significant digits.
std::string oneLine(std::string_view text);

}  // namespace linesurf
