#include "linesurf/core/error.h"

#include <cstdio>
#include <cstdlib>

namespace linesurf {

namespace {

std::string compose(const std::string& path, const std::string& where, const std::string& what) {
  std::string s = path;
  if (!where.empty()) s += ": " + where;
  s += ": " + what;
  return oneLine(s);
}

bool isDigit(char c) { return c >= '0' && c <= '9'; }

// Length of a valid UTF-8 sequence starting at s[i] (0 when invalid).
size_t utf8Length(std::string_view s, size_t i) {
  const auto b = static_cast<unsigned char>(s[i]);
  size_t n = b >= 0xF0 && b <= 0xF4 ? 4 : b >= 0xE0 ? 3 : b >= 0xC2 && b < 0xE0 ? 2 : 0;
  if (n == 0 || i + n > s.size()) return 0;
  for (size_t k = 1; k < n; ++k)
    if ((static_cast<unsigned char>(s[i + k]) & 0xC0) != 0x80) return 0;
  const auto b1 = static_cast<unsigned char>(s[i + 1]);
  if ((b == 0xE0 && b1 < 0xA0) || (b == 0xF0 && b1 < 0x90) || (b == 0xF4 && b1 >= 0x90) || (b == 0xED && b1 >= 0xA0))
    return 0;  // overlong, beyond U+10FFFF or a surrogate
  return n;
}

}  // namespace

std::string oneLine(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  size_t i = 0;
  while (i < text.size()) {
    const char c = text[i];
    // A long number (digits with an optional fraction): shorten when it has more than 17 digits.
    if (isDigit(c) && (i == 0 || (!isDigit(text[i - 1]) && text[i - 1] != '.'))) {
      size_t j = i, digits = 0;
      while (j < text.size() && (isDigit(text[j]) || text[j] == '.')) digits += isDigit(text[j++]);
      if (digits > 17) {
        std::string num(text.substr(i, j - i));
        char buf[40];
        std::snprintf(buf, sizeof buf, "%.6g", std::strtod(num.c_str(), nullptr));
        out += buf;
        i = j;
        continue;
      }
    }
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x80) {
      size_t n = utf8Length(text, i);
      if (n) {
        out.append(text.substr(i, n));
        i += n;
        continue;
      }
    }
    if (c == '\n') out += "\\n";
    else if (c == '\r') out += "\\r";
    else if (c == '\t') out += "\\t";
    else if (c == '\0') out += "\\0";
    else if (u < 0x20 || u == 0x7F || u >= 0x80) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", u);
      out += buf;
    } else {
      out += c;
    }
    ++i;
  }
  return out;
}

Error::Error(Kind kind, std::string path, std::string where, std::string what)
    : std::runtime_error(compose(path, where, what)), kind_(kind), path_(std::move(path)),
      where_(std::move(where)), reason_(std::move(what)) {}

void throwBadInput(const std::string& path, const std::string& where, const std::string& what) {
  throw Error(Error::Kind::BadInput, path, where, what);
}

void throwBadParameter(const std::string& name, const std::string& what) {
  throw Error(Error::Kind::BadParameter, name, "", what);
}

void throwIo(const std::string& path, const std::string& what) { throw Error(Error::Kind::Io, path, "", what); }

}  // namespace linesurf
