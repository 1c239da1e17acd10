// Low-level PLY reader: header parsing and body decoding into columns (see detail/ply_format.h).
#include "io/detail/ply_format.h"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <unordered_set>

#include "io/detail/readers.h"
#include "linesurf/core/error.h"

namespace linesurf::ply {

float channelScale(Type t) {
  switch (t) {
    case Type::UInt8: case Type::Int8: return 255.0f;
    case Type::UInt16: case Type::Int16: return 65535.0f;
    case Type::UInt32: case Type::Int32: return 4294967295.0f;
    default: return 1.0f;
  }
}

uint8_t colorByte(float c) {
  if (!(c >= 0)) c = 0;  // NaN too
  return uint8_t(std::lround(std::min(c, 1.0f) * 255.0f));
}

int typeSize(Type t) {
  switch (t) {
    case Type::Int8: case Type::UInt8: return 1;
    case Type::Int16: case Type::UInt16: return 2;
    case Type::Int32: case Type::UInt32: case Type::Float32: return 4;
    case Type::Float64: return 8;
  }
  return 1;
}

bool isIntegral(Type t) { return t != Type::Float32 && t != Type::Float64; }

const char* typeName(Type t) {
  switch (t) {
    case Type::Int8: return "char";
    case Type::UInt8: return "uchar";
    case Type::Int16: return "short";
    case Type::UInt16: return "ushort";
    case Type::Int32: return "int";
    case Type::UInt32: return "uint";
    case Type::Float32: return "float";
    case Type::Float64: return "double";
  }
  return "?";
}

int Element::find(std::string_view n) const {
  if (byName_.size() != properties.size()) {  // filled by hand (tests): look the slow way
    for (size_t i = 0; i < properties.size(); ++i)
      if (properties[i].name == n) return int(i);
    return -1;
  }
  auto it = byName_.find(std::string(n));
  return it == byName_.end() ? -1 : it->second;
}

bool Element::add(Property p) {
  if (find(p.name) >= 0) return false;
  if (byName_.size() != properties.size()) {
    byName_.clear();
    for (size_t i = 0; i < properties.size(); ++i) byName_.emplace(properties[i].name, int(i));
  }
  byName_.emplace(p.name, int(properties.size()));
  properties.push_back(std::move(p));
  return true;
}

int Header::find(std::string_view n) const {
  for (size_t i = 0; i < elements.size(); ++i)
    if (elements[i].name == n) return int(i);
  return -1;
}

namespace {

std::string lineAt(int line) { return "line " + std::to_string(line); }

bool parseType(std::string_view s, Type& t) {
  static const std::pair<std::string_view, Type> names[] = {
      {"char", Type::Int8},     {"int8", Type::Int8},       {"uchar", Type::UInt8},    {"uint8", Type::UInt8},
      {"short", Type::Int16},   {"int16", Type::Int16},     {"ushort", Type::UInt16},  {"uint16", Type::UInt16},
      {"int", Type::Int32},     {"int32", Type::Int32},     {"uint", Type::UInt32},    {"uint32", Type::UInt32},
      {"float", Type::Float32}, {"float32", Type::Float32}, {"double", Type::Float64}, {"float64", Type::Float64}};
  for (auto& [n, ty] : names)
    if (n == s) {
      t = ty;
      return true;
    }
  return false;
}

std::vector<std::string_view> splitWords(std::string_view s) {
  std::vector<std::string_view> w;
  size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    size_t b = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t') ++i;
    if (i > b) w.push_back(s.substr(b, i - b));
  }
  return w;
}

/// Printable excerpt of a token for messages (binary junk must not garble the one-line error).
std::string quoted(std::string_view s) {
  std::string out = "'";
  for (size_t i = 0; i < s.size() && i < 40; ++i) {
    unsigned char c = (unsigned char)s[i];
    out += (c >= 32 && c < 127) ? char(c) : '?';
  }
  if (s.size() > 40) out += "...";
  return out + "'";
}

}  // namespace

Header parseHeader(std::string_view bytes, const std::string& path) {
  if (bytes.empty()) throwBadInput(path, "line 1", "empty file (a PLY file starts with 'ply')");
  Header h;
  size_t pos = 0;
  int line = 0;
  std::string_view text;
  auto nextLine = [&]() -> bool {
    if (pos >= bytes.size()) return false;
    size_t e = bytes.find('\n', pos);
    if (e == std::string_view::npos) {
      text = bytes.substr(pos);
      pos = bytes.size();
    } else {
      text = bytes.substr(pos, e - pos);
      pos = e + 1;
    }
    if (!text.empty() && text.back() == '\r') text.remove_suffix(1);
    ++line;
    return true;
  };
  nextLine();
  while (!text.empty() && (text.back() == ' ' || text.back() == '\t')) text.remove_suffix(1);
  if (text != "ply") throwBadInput(path, "line 1", "not a PLY file (the first line must be 'ply', found " + quoted(text) + ")");
  bool haveFormat = false;
  std::unordered_set<std::string_view> elementNames;  // views into `bytes`
  for (;;) {
    if (!nextLine()) throwBadInput(path, lineAt(line), "missing end_header (the header never ends)");
    auto w = splitWords(text);
    if (w.empty()) continue;
    const std::string_view key = w[0];
    const std::string where = lineAt(line);
    if (key == "end_header") {
      if (!haveFormat) throwBadInput(path, where, "missing format line before end_header");
      break;
    } else if (key == "comment") {
      std::string_view rest = text.substr(text.find("comment") + 7);
      while (!rest.empty() && (rest.front() == ' ' || rest.front() == '\t')) rest.remove_prefix(1);
      h.comments.emplace_back(rest);
      h.commentLines.push_back(line);
    } else if (key == "obj_info") {
      // informational, dropped
    } else if (key == "format") {
      if (haveFormat) throwBadInput(path, where, "second format line");
      if (w.size() != 3) throwBadInput(path, where, "format line must be 'format <encoding> 1.0'");
      if (w[1] == "ascii") h.format = Format::Ascii;
      else if (w[1] == "binary_little_endian") h.format = Format::BinaryLittleEndian;
      else if (w[1] == "binary_big_endian") h.format = Format::BinaryBigEndian;
      else
        throwBadInput(path, where, "unknown format " + quoted(w[1]) +
                                       " (expected ascii, binary_little_endian or binary_big_endian)");
      if (w[2] != "1.0" && w[2] != "1") throwBadInput(path, where, "unsupported PLY version " + quoted(w[2]));
      haveFormat = true;
    } else if (key == "element") {
      if (!haveFormat) throwBadInput(path, where, "element before the format line");
      if (w.size() != 3) throwBadInput(path, where, "element line must be 'element <name> <count>'");
      if (!elementNames.emplace(w[1]).second) throwBadInput(path, where, "element " + quoted(w[1]) + " declared twice");
      Element e;
      e.name = std::string(w[1]);
      e.line = line;
      std::string_view c = w[2];
      if (!c.empty() && c[0] == '-') throwBadInput(path, where, "negative element count " + quoted(c));
      auto [ptr, ec] = std::from_chars(c.data(), c.data() + c.size(), e.count);
      if (ec == std::errc::result_out_of_range)
        throwBadInput(path, where, "element count " + quoted(c) + " is too large");
      if (ec != std::errc() || ptr != c.data() + c.size())
        throwBadInput(path, where, "element count " + quoted(c) + " is not a non-negative integer");
      h.elements.push_back(std::move(e));
    } else if (key == "property") {
      if (h.elements.empty()) throwBadInput(path, where, "property before any element");
      Element& e = h.elements.back();
      Property p;
      p.line = line;
      if (w.size() >= 2 && w[1] == "list") {
        if (w.size() != 5) throwBadInput(path, where, "list property must be 'property list <count type> <value type> <name>'");
        if (!parseType(w[2], p.countType)) throwBadInput(path, where, "unsupported property type " + quoted(w[2]));
        if (!isIntegral(p.countType))
          throwBadInput(path, where, "list length type must be an integer type, not " + quoted(w[2]));
        if (!parseType(w[3], p.type)) throwBadInput(path, where, "unsupported property type " + quoted(w[3]));
        p.isList = true;
        p.name = std::string(w[4]);
      } else {
        if (w.size() != 3) throwBadInput(path, where, "property line must be 'property <type> <name>'");
        if (!parseType(w[1], p.type)) throwBadInput(path, where, "unsupported property type " + quoted(w[1]));
        p.name = std::string(w[2]);
      }
      const std::string name = p.name;
      if (!e.add(std::move(p)))
        throwBadInput(path, where, "property " + quoted(std::string_view(name)) + " declared twice in element " + quoted(std::string_view(e.name)));
    } else if (std::isdigit((unsigned char)key[0]) || key[0] == '-' || key[0] == '+' || key[0] == '.') {
      throwBadInput(path, where, "missing end_header (body data " + quoted(text) + " found in the header)");
    } else {
      throwBadInput(path, where, "unknown header keyword " + quoted(key));
    }
  }
  h.bodyOffset = pos;
  h.bodyLine = line + 1;
  return h;
}

// ---------------------------------------------------------------------------------------------
// Body

std::string ElementData::where(size_t row) const {
  if (ascii && row < rowLines.size()) return lineAt(int(rowLines[row]));
  return "element " + element->name + " " + std::to_string(row);
}

const std::vector<double>* ElementData::scalar(std::string_view name) const {
  int i = element ? element->find(name) : -1;
  if (i < 0 || element->properties[size_t(i)].isList || scalars.empty()) return nullptr;
  if (scalars[size_t(i)].size() != element->count) return nullptr;
  return &scalars[size_t(i)];
}

const ListColumn* ElementData::list(std::string_view name) const {
  int i = element ? element->find(name) : -1;
  if (i < 0 || !element->properties[size_t(i)].isList || lists.empty()) return nullptr;
  if (lists[size_t(i)].offsets.size() != element->count + 1) return nullptr;
  return &lists[size_t(i)];
}

namespace {

template <class U>
U loadSwapped(const char* p, bool swap) {
  U u;
  std::memcpy(&u, p, sizeof(U));
  if (swap) {
    if constexpr (sizeof(U) == 2) u = __builtin_bswap16(u);
    else if constexpr (sizeof(U) == 4) u = __builtin_bswap32(u);
    else if constexpr (sizeof(U) == 8) u = __builtin_bswap64(u);
  }
  return u;
}

template <class T, class U>
T loadAs(const char* p, bool swap) {
  U u = loadSwapped<U>(p, swap);
  T t;
  std::memcpy(&t, &u, sizeof(T));
  return t;
}

/// Reads one binary value of type t at p (bounds checked by the caller).
inline double loadValue(const char* p, Type t, bool swap) {
  switch (t) {
    case Type::Int8: return double(int8_t(*p));
    case Type::UInt8: return double(uint8_t(*p));
    case Type::Int16: return double(loadAs<int16_t, uint16_t>(p, swap));
    case Type::UInt16: return double(loadSwapped<uint16_t>(p, swap));
    case Type::Int32: return double(loadAs<int32_t, uint32_t>(p, swap));
    case Type::UInt32: return double(loadSwapped<uint32_t>(p, swap));
    case Type::Float32: return double(loadAs<float, uint32_t>(p, swap));
    case Type::Float64: return loadAs<double, uint64_t>(p, swap);
  }
  return 0;
}

void typeRange(Type t, double& lo, double& hi) {
  switch (t) {
    case Type::Int8: lo = -128; hi = 127; return;
    case Type::UInt8: lo = 0; hi = 255; return;
    case Type::Int16: lo = -32768; hi = 32767; return;
    case Type::UInt16: lo = 0; hi = 65535; return;
    case Type::Int32: lo = -2147483648.0; hi = 2147483647.0; return;
    case Type::UInt32: lo = 0; hi = 4294967295.0; return;
    default: lo = -std::numeric_limits<double>::infinity(); hi = -lo; return;
  }
}

class BodyDecoder {
 public:
  BodyDecoder(std::string_view bytes, const Header& h, const std::string& path)
      : bytes_(bytes), h_(h), path_(path), p_(bytes.data() + h.bodyOffset), end_(bytes.data() + bytes.size()),
        swap_(h.format == Format::BinaryBigEndian), line_(h.bodyLine) {}

  std::vector<ElementData> run(const KeepFn& keep) {
    std::vector<ElementData> out(h_.elements.size());
    for (size_t i = 0; i < h_.elements.size(); ++i) {
      const Element& e = h_.elements[i];
      ElementData& d = out[i];
      d.element = &e;
      d.ascii = h_.format == Format::Ascii;
      std::vector<char> kept(e.properties.size(), 0);
      bool any = false;
      for (size_t k = 0; k < e.properties.size(); ++k) {
        kept[k] = keep && keep(e, e.properties[k]);
        any = any || kept[k];
      }
      if (e.properties.empty() || e.count == 0) continue;  // nothing stored for such rows
      checkCountFits(e);
      if (any) {
        d.scalars.resize(e.properties.size());
        d.lists.resize(e.properties.size());
        for (size_t k = 0; k < e.properties.size(); ++k) {
          if (!kept[k]) continue;
          if (e.properties[k].isList) {
            d.lists[k].offsets.reserve(e.count + 1);
            d.lists[k].offsets.push_back(0);
          } else {
            d.scalars[k].reserve(e.count);
          }
        }
        if (d.ascii) d.rowLines.reserve(e.count);
      }
      if (d.ascii) asciiElement(e, d, kept);
      else binaryElement(e, d, kept, any);
    }
    finish();
    return out;
  }

 private:
  std::string_view bytes_;
  const Header& h_;
  const std::string& path_;
  const char* p_;
  const char* end_;
  bool swap_;
  int line_;

  size_t remaining() const { return size_t(end_ - p_); }
  size_t offset() const { return size_t(p_ - bytes_.data()); }

  /// Rejects counts the rest of the file cannot hold, before anything is allocated.
  void checkCountFits(const Element& e) {
    const size_t rest = remaining();
    if (h_.format == Format::Ascii) {
      // Every value is a token of at least one character (a loose bound on purpose: a file that
      // is merely short gets the precise row-level message from the row parser).
      const uint64_t perRow = e.properties.size();
      if (e.count > rest / perRow)
        throwBadInput(path_, lineAt(e.line),
                      "element " + e.name + " count " + std::to_string(e.count) +
                          " is larger than the file could hold (" + std::to_string(rest) + " bytes of body left)");
      return;
    }
    uint64_t minRow = 0;
    for (const Property& p : e.properties) minRow += uint64_t(typeSize(p.isList ? p.countType : p.type));
    if (e.count > rest / minRow) {
      const uint64_t fullRows = rest / minRow;
      throwBadInput(path_, "element " + e.name + " " + std::to_string(fullRows),
                    "truncated binary body: the header declares " + std::to_string(e.count) + " " + e.name +
                        " rows of at least " + std::to_string(minRow) + " bytes, but only " + std::to_string(rest) +
                        " bytes are left at byte " + std::to_string(offset()));
    }
  }

  [[noreturn]] void truncated(const Element& e, uint64_t row, const Property& p, uint64_t need) {
    throwBadInput(path_, "element " + e.name + " " + std::to_string(row),
                  "truncated binary body: property '" + p.name + "' needs " + std::to_string(need) + " bytes at byte " +
                      std::to_string(offset()) + ", but the file ends at byte " + std::to_string(bytes_.size()));
  }

  void checkFinite(double v, const Element& e, uint64_t row, const Property& p, const std::string* where = nullptr) {
    if (!std::isfinite(v))
      throwBadInput(path_, where ? *where : "element " + e.name + " " + std::to_string(row),
                    std::string(std::isnan(v) ? "NaN" : "infinite") + " value in property '" + p.name + "'" +
                        (where ? " of element " + e.name + " " + std::to_string(row) : std::string()));
    // Every model field is a float: a double beyond its range would become infinite.
    if (!isIntegral(p.type) && std::fabs(v) > double(std::numeric_limits<float>::max()))
      throwBadInput(path_, where ? *where : "element " + e.name + " " + std::to_string(row),
                    "value " + fmt::format("{:g}", v) + " in property '" + p.name + "'" +
                        (where ? " of element " + e.name + " " + std::to_string(row) : std::string()) +
                        " is too large for a 32-bit float (|v| > 3.4e38)");
  }

  void binaryElement(const Element& e, ElementData& d, const std::vector<char>& kept, bool any) {
    bool fixed = true;
    uint64_t rowSize = 0;
    for (const Property& p : e.properties) {
      fixed = fixed && !p.isList;
      rowSize += uint64_t(typeSize(p.type));
    }
    if (!any && fixed) {  // skip whole element (size already checked)
      p_ += rowSize * e.count;
      return;
    }
    const size_t np = e.properties.size();
    for (uint64_t row = 0; row < e.count; ++row) {
      for (size_t k = 0; k < np; ++k) {
        const Property& p = e.properties[k];
        if (!p.isList) {
          const int sz = typeSize(p.type);
          if (remaining() < size_t(sz)) truncated(e, row, p, uint64_t(sz));
          if (kept[k]) {
            double v = loadValue(p_, p.type, swap_);
            if (!isIntegral(p.type)) checkFinite(v, e, row, p);
            d.scalars[k].push_back(v);
          }
          p_ += sz;
          continue;
        }
        const int csz = typeSize(p.countType);
        if (remaining() < size_t(csz)) truncated(e, row, p, uint64_t(csz));
        double nd = loadValue(p_, p.countType, swap_);
        if (nd < 0)
          throwBadInput(path_, "element " + e.name + " " + std::to_string(row),
                        "negative list length " + std::to_string(int64_t(nd)) + " in property '" + p.name + "'");
        p_ += csz;
        const uint64_t n = uint64_t(nd);
        const int vsz = typeSize(p.type);
        if (n > remaining() / size_t(vsz)) truncated(e, row, p, n * uint64_t(vsz));
        if (kept[k]) {
          ListColumn& lc = d.lists[k];
          const bool fl = !isIntegral(p.type);
          for (uint64_t j = 0; j < n; ++j) {
            double v = loadValue(p_ + j * vsz, p.type, swap_);
            if (fl) checkFinite(v, e, row, p);
            lc.values.push_back(v);
          }
          lc.offsets.push_back(lc.values.size());
        }
        p_ += n * vsz;
      }
    }
  }

  // --- ascii -----------------------------------------------------------------------------------

  void skipBlank() {
    while (p_ < end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r')) ++p_;
  }
  /// Next token on the current line; empty at end of line / file.
  std::string_view token() {
    skipBlank();
    const char* b = p_;
    while (p_ < end_ && *p_ != ' ' && *p_ != '\t' && *p_ != '\r' && *p_ != '\n') ++p_;
    return std::string_view(b, size_t(p_ - b));
  }

  double parseAscii(std::string_view tok, Type t, const Element& e, uint64_t row, const Property& p) {
    const std::string where = lineAt(line_);
    std::string_view s = tok;
    if (s.size() > 1 && s[0] == '+' && s[1] != '-') s.remove_prefix(1);
    if (isIntegral(t)) {
      int64_t v = 0;
      auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
      if (ec != std::errc() || ptr != s.data() + s.size())
        throwBadInput(path_, where, "element " + e.name + " " + std::to_string(row) + ": " + quoted(tok) +
                                        " is not an integer (property '" + p.name + "')");
      double lo, hi;
      typeRange(t, lo, hi);
      if (double(v) < lo || double(v) > hi)
        throwBadInput(path_, where, "element " + e.name + " " + std::to_string(row) + ": value " + quoted(tok) +
                                        " out of range for " + typeName(t) + " (property '" + p.name + "')");
      return double(v);
    }
    double v = 0;
    if (!detail::parseReal(s, v)) {
      throwBadInput(path_, where, "element " + e.name + " " + std::to_string(row) + ": " + quoted(tok) +
                                      " is not a number (property '" + p.name + "')");
    }
    if (t == Type::Float32) v = double(float(v));
    checkFinite(v, e, row, p, &where);
    return v;
  }

  void asciiElement(const Element& e, ElementData& d, const std::vector<char>& kept) {
    const size_t np = e.properties.size();
    for (uint64_t row = 0; row < e.count; ++row) {
      // skip blank lines
      for (;;) {
        skipBlank();
        if (p_ < end_ && *p_ == '\n') {
          ++p_;
          ++line_;
          continue;
        }
        break;
      }
      if (p_ >= end_)
        throwBadInput(path_, lineAt(line_),
                      "file ends at element " + e.name + " " + std::to_string(row) + " (the header declares " +
                          std::to_string(e.count) + " rows)");
      if (!d.scalars.empty()) d.rowLines.push_back(uint32_t(line_));
      for (size_t k = 0; k < np; ++k) {
        const Property& p = e.properties[k];
        auto need = [&](std::string_view tok) {
          if (tok.empty())
            throwBadInput(path_, lineAt(line_), "element " + e.name + " " + std::to_string(row) +
                                                    ": too few values on the line (property '" + p.name + "' missing)");
        };
        std::string_view tok = token();
        need(tok);
        if (!p.isList) {
          double v = kept[k] ? parseAscii(tok, p.type, e, row, p) : 0.0;
          if (kept[k]) d.scalars[k].push_back(v);
          else parseAscii(tok, p.type, e, row, p);  // still validated
          continue;
        }
        double nd = parseAscii(tok, p.countType, e, row, p);
        if (nd < 0)
          throwBadInput(path_, lineAt(line_), "element " + e.name + " " + std::to_string(row) + ": negative list length " +
                                                  std::to_string(int64_t(nd)) + " (property '" + p.name + "')");
        const uint64_t n = uint64_t(nd);
        for (uint64_t j = 0; j < n; ++j) {
          std::string_view vt = token();
          need(vt);
          double v = parseAscii(vt, p.type, e, row, p);
          if (kept[k]) d.lists[k].values.push_back(v);
        }
        if (kept[k]) d.lists[k].offsets.push_back(d.lists[k].values.size());
      }
      skipBlank();
      if (p_ < end_ && *p_ != '\n')
        throwBadInput(path_, lineAt(line_), "element " + e.name + " " + std::to_string(row) +
                                                ": too many values on the line (expected " + std::to_string(np) +
                                                " properties)");
      if (p_ < end_) {
        ++p_;
        ++line_;
      }
    }
  }

  void finish() {
    if (h_.format == Format::Ascii) {
      while (p_ < end_ && (*p_ == ' ' || *p_ == '\t' || *p_ == '\r' || *p_ == '\n')) {
        if (*p_ == '\n') ++line_;
        ++p_;
      }
      if (p_ < end_)
        throwBadInput(path_, lineAt(line_), "unexpected data after the last element (wrong element counts?)");
      return;
    }
    // Tolerate trailing line breaks some writers append; anything else means wrong counts.
    const char* q = p_;
    while (q < end_ && (*q == '\n' || *q == '\r' || *q == ' ')) ++q;
    if (q < end_)
      throwBadInput(path_, "byte " + std::to_string(offset()),
                    std::to_string(remaining()) + " bytes of unexpected data after the last element (wrong element counts?)");
  }
};

}  // namespace

std::vector<ElementData> decodeBody(std::string_view bytes, const Header& header, const std::string& path,
                                    const KeepFn& keep) {
  return BodyDecoder(bytes, header, path).run(keep);
}

}  // namespace linesurf::ply
