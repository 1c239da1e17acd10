// XYZ text point clouds: one point per line, "x y z" or "x y z nx ny nz"; '#' starts a comment.
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include "io/detail/readers.h"
#include "linesurf/core/error.h"
#include "linesurf/io/atomic_file.h"

namespace linesurf::detail {

bool parseReal(std::string_view s, double& v) {
  auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ptr != s.data() + s.size() || (ec != std::errc() && ec != std::errc::result_out_of_range)) return false;
  if (ec == std::errc::result_out_of_range) {
    // from_chars leaves v unset: strtod tells underflow (0 or a subnormal) from overflow (inf).
    const std::string copy(s);
    v = std::strtod(copy.c_str(), nullptr);
    if (std::abs(v) == HUGE_VAL) v = std::copysign(std::numeric_limits<double>::infinity(), v);
  }
  return true;
}

int parseXyzLine(std::string_view text, const std::string& name, const std::string& where,
                 std::vector<std::string>* comments, float v[6]) {
  const size_t hash = text.find('#');
  if (hash != std::string_view::npos) {
    if (comments) {
      std::string_view c = text.substr(hash + 1);
      while (!c.empty() && (c.front() == ' ' || c.front() == '\t')) c.remove_prefix(1);
      while (!c.empty() && (c.back() == '\r' || c.back() == ' ')) c.remove_suffix(1);
      comments->emplace_back(c);
    }
    text = text.substr(0, hash);
  }
  int n = 0;
  size_t i = 0;
  for (;;) {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t' || text[i] == '\r' || text[i] == ',')) ++i;
    if (i >= text.size()) break;
    size_t b = i;
    while (i < text.size() && text[i] != ' ' && text[i] != '\t' && text[i] != '\r' && text[i] != ',') ++i;
    std::string_view tok = text.substr(b, i - b);
    if (n == 6) throwBadInput(name, where, "more than 6 numbers on the line (expected x y z [nx ny nz])");
    std::string_view s = tok;
    if (s.size() > 1 && s[0] == '+') s.remove_prefix(1);
    double d = 0;
    if (!parseReal(s, d)) throwBadInput(name, where, "'" + std::string(tok.substr(0, 40)) + "' is not a number");
    v[n] = float(d);  // a value below float's range reads as 0, as in an ASCII PLY
    if (!std::isfinite(v[n]))
      throwBadInput(name, where, "non-finite or out-of-range value '" + std::string(tok.substr(0, 40)) + "'");
    ++n;
  }
  return n;
}

HybridModel xyzToModel(std::string_view bytes, const std::string& name) {
  HybridModel m;
  int line = 0, columns = 0;
  size_t pos = 0;
  while (pos < bytes.size()) {
    size_t e = bytes.find('\n', pos);
    if (e == std::string_view::npos) e = bytes.size();
    std::string_view text = bytes.substr(pos, e - pos);
    pos = e + 1;
    ++line;
    const std::string where = "line " + std::to_string(line);
    float v[6];
    const int n = parseXyzLine(text, name, where, &m.comments, v);
    if (n == 0) continue;
    if (n != 3 && n != 6)
      throwBadInput(name, where, "expected 3 (x y z) or 6 (x y z nx ny nz) numbers, found " + std::to_string(n));
    if (columns == 0) columns = n;
    if (n != columns)
      throwBadInput(name, where, std::to_string(n) + " numbers, but earlier lines have " + std::to_string(columns));
    Point p;
    p.position = Vec3f(v[0], v[1], v[2]);
    if (n == 6) p.normal = Vec3f(v[3], v[4], v[5]);
    m.points.push_back(p);
  }
  if (m.points.empty()) throwBadInput(name, "line " + std::to_string(std::max(line, 1)), "no points in the file");
  m.attributes.normals = columns == 6;
  return m;
}

void writeXyz(const std::filesystem::path& path, const HybridModel& model) {
  std::string out;
  for (const std::string& c : model.comments) out += "# " + c + "\n";
  out.reserve(out.size() + model.points.size() * 60);
  char buf[32];
  auto put = [&](float v, char sep) {
    auto r = std::to_chars(buf, buf + sizeof buf, v);
    out.append(buf, r.ptr);
    out += sep;
  };
  for (const Point& p : model.points) {
    put(p.position.x(), ' ');
    put(p.position.y(), ' ');
    if (model.attributes.normals) {
      put(p.position.z(), ' ');
      put(p.normal.x(), ' ');
      put(p.normal.y(), ' ');
      put(p.normal.z(), '\n');
    } else {
      put(p.position.z(), '\n');
    }
  }
  writeFileAtomically(path, out);
}

}  // namespace linesurf::detail
