#include "linesurf/core/error.h"

namespace linesurf {

namespace {
std::string compose(const std::string& path, const std::string& where, const std::string& what) {
  std::string s = path;
  if (!where.empty()) s += ": " + where;
  s += ": " + what;
  return s;
}
}  // namespace

Error::Error(Kind kind, std::string path, std::string where, std::string what)
    : std::runtime_error(compose(path, where, what)), kind_(kind), path_(std::move(path)),
      where_(std::move(where)), reason_(std::move(what)) {}

void throwBadInput(const std::string& path, const std::string& where, const std::string& what) {
  throw Error(Error::Kind::BadInput, path, where, what);
}

void throwBadParameter(const std::string& name, const std::string& what) {
  throw Error(Error::Kind::BadParameter, name, "", what);
}

}  // namespace linesurf
