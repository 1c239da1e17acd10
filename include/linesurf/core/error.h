#pragma once
/// The library's one error type. Library code never prints and never exits: bad input throws
/// linesurf::Error carrying the path, the location inside it and what is wrong; the CLI prints
/// `what()` (formatted "PATH: WHERE: WHAT") on one line and exits with code 2.
#include <stdexcept>
#include <string>

namespace linesurf {

class Error : public std::runtime_error {
 public:
  enum class Kind { BadInput, BadParameter, Io };
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

}  // namespace linesurf
