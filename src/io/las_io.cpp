// LAS 1.0-1.4 point files (las_io.h): the public header block, the VLRs, the extra-bytes
// descriptors and point data formats 0-10, decoded and encoded by hand (Debian packages no LAS
// library; docs/decisions.md "LAS without a library").
#include "linesurf/io/las_io.h"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <set>
#include <vector>

#include "io/detail/readers.h"
#include "linesurf/core/error.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/io/model_validate.h"

namespace linesurf {

namespace {

static_assert(std::endian::native == std::endian::little, "the LAS reader and writer assume a little-endian host");

/// Sizes and field places of the point data formats (LAS 1.4 R15, tables 7-17). Formats 6-10
/// ("extended") move the classification to its own byte and widen the scan angle.
struct PointFormat {
  int size;      ///< bytes of the standard fields
  int rgb;       ///< offset of red, green, blue (uint16 each), or -1
  bool extended; ///< formats 6-10
};
constexpr std::array<PointFormat, 11> kFormats = {{{20, -1, false}, {28, -1, false}, {26, 20, false}, {34, 28, false},
                                                   {57, -1, false}, {63, 28, false}, {30, -1, true}, {36, 30, true},
                                                   {38, 30, true}, {59, -1, true}, {67, 30, true}}};

constexpr size_t kVlrHeader = 54;
constexpr size_t kExtraDescriptor = 192;
constexpr uint16_t kExtraBytesRecord = 4;
constexpr uint16_t kCommentsRecord = 1;  ///< our VLR (user "linesurf"): the model's comments
constexpr size_t kHeader14 = 375;
constexpr std::string_view kLazHint = "decompress it first, e.g. with laszip/PDAL, to .las";

/// Largest |coordinate| / scale that float32 positions still resolve to a quarter step: beyond
/// it the reader subtracts an origin so that the records come back bit-exact.
constexpr double kFloatSteps = 4194304.0;  // 2^22

template <class T>
T get(std::string_view b, size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof(T));
  return v;
}

template <class T>
void put(std::string& b, size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof(T));
}

/// A NUL-padded fixed-size text field.
std::string fixedText(std::string_view field) { return std::string(field.substr(0, std::min(field.find('\0'), field.size()))); }

std::string printableName(std::string_view s) {
  std::string out = "'";
  for (size_t i = 0; i < s.size() && i < 40; ++i) out += (s[i] >= 32 && s[i] < 127) ? s[i] : '?';
  return out + "'";
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

bool isKey(std::string_view comment, std::string_view key) {
  return comment.substr(0, key.size()) == key && (comment.size() == key.size() || comment[key.size()] == ' ');
}

bool isReservedComment(std::string_view c) {
  return isKey(c, kOriginComment) || isKey(c, kLasScaleComment) || isKey(c, kLasOffsetComment) || isKey(c, kUpAxisComment) ||
         isKey(c, kLasCrsComment);
}

/// A coordinate reference system record (user "LASF_Projection": GeoTIFF keys, WKT) as the
/// comment "linesurf_las_crs RECORD HEX"; larger ones than this are not kept.
constexpr size_t kMaxCrsBytes = 32768;
constexpr uint16_t kWktRecord = 2112;

std::string crsComment(uint16_t record, std::string_view payload) {
  static constexpr char digits[] = "0123456789abcdef";
  std::string c = fmt::format("{} {} ", kLasCrsComment, record);
  for (unsigned char ch : payload) c += digits[ch >> 4], c += digits[ch & 15];
  return c;
}

/// The record and payload of a crsComment; throws BadParameter when malformed.
std::pair<uint16_t, std::string> parseCrsComment(std::string_view c) {
  const std::string_view rest = c.substr(std::min(c.size(), kLasCrsComment.size() + 1));
  const size_t space = rest.find(' ');
  const std::string_view hex = space == std::string_view::npos ? std::string_view() : rest.substr(space + 1);
  uint16_t record = 0;
  const auto [end, ec] = std::from_chars(rest.data(), rest.data() + std::min(space, rest.size()), record);
  bool ok = space != std::string_view::npos && ec == std::errc() && end == rest.data() + space && hex.size() % 2 == 0 && hex.size() / 2 <= kMaxCrsBytes;
  auto nibble = [](char x) { return x >= '0' && x <= '9' ? x - '0' : x >= 'a' && x <= 'f' ? x - 'a' + 10 : -1; };
  std::string payload;
  for (size_t k = 0; ok && k < hex.size(); k += 2) {
    const int hi = nibble(hex[k]), lo = nibble(hex[k + 1]);
    ok = hi >= 0 && lo >= 0;
    payload += char(hi * 16 + lo);
  }
  if (!ok) throwBadParameter("comment " + std::string(kLasCrsComment), "expected a record number and lower-case hex bytes");
  return {record, payload};
}

/// The three numbers of comment `key` ("KEY A B C"): false when the model has no such comment.
bool commentTriple(const HybridModel& m, std::string_view key, Vec3d& v) {
  for (const std::string& c : m.comments) {
    if (!isKey(c, key)) continue;
    std::string_view rest = std::string_view(c).substr(key.size());
    int n = 0;
    size_t i = 0;
    while (n <= 3) {
      while (i < rest.size() && rest[i] == ' ') ++i;
      if (i >= rest.size()) break;
      const size_t b = i;
      while (i < rest.size() && rest[i] != ' ') ++i;
      double d = 0;
      if (n == 3 || !detail::parseReal(rest.substr(b, i - b), d) || !std::isfinite(d)) n = 4;
      else v[n++] = d;
    }
    if (n != 3) throwBadParameter("comment " + std::string(key), "expected three finite numbers, found '" + c + "'");
    return true;
  }
  return false;
}

// ---------------------------------------------------------------------------------------------
// Reading

struct Header {
  int minor = 0;
  uint16_t headerSize = 0;
  uint32_t pointOffset = 0, vlrCount = 0;
  int format = 0;
  uint16_t recordLength = 0;
  uint64_t count = 0;
  Vec3d scale, offset;
};

/// One scalar extra-bytes field of the point record.
struct ExtraField {
  std::string name;
  int type = 0;       ///< LAS data type 1-10
  size_t offset = 0;  ///< in the record
  double scale = 1, add = 0;
};

Header parseHeader(std::string_view b, const std::string& name) {
  const std::string where = "header";
  if (b.size() < 4 || b.substr(0, 4) != "LASF") throwBadInput(name, where, "no 'LASF' signature at the start (not a LAS file)");
  if (b.size() < 227)
    throwBadInput(name, where, fmt::format("the file has {} bytes, fewer than the 227 of a LAS header (truncated)", b.size()));
  // LAZ marks its compressed records in the top bits of the format byte (laszip's convention).
  const uint8_t formatByte = get<uint8_t>(b, 104);
  if (formatByte & 0xC0) throwBadInput(name, where, "the points are compressed (LAZ); " + std::string(kLazHint));
  Header h;
  const int major = get<uint8_t>(b, 24);
  h.minor = get<uint8_t>(b, 25);
  if (major != 1 || h.minor > 4) throwBadInput(name, where, fmt::format("LAS version {}.{} is not one of 1.0-1.4", major, h.minor));
  const size_t need = h.minor < 3 ? 227 : h.minor == 3 ? 235 : kHeader14;
  h.headerSize = get<uint16_t>(b, 94);
  if (h.headerSize < need)
    throwBadInput(name, where, fmt::format("header size {} is less than the {} bytes of LAS 1.{}", h.headerSize, need, h.minor));
  if (h.headerSize > b.size())
    throwBadInput(name, where, fmt::format("header size {} runs past the end of the file ({} bytes; truncated)", h.headerSize, b.size()));
  h.pointOffset = get<uint32_t>(b, 96);
  if (h.pointOffset < h.headerSize)
    throwBadInput(name, where, fmt::format("offset to point data {} lies inside the {}-byte header", h.pointOffset, h.headerSize));
  if (h.pointOffset > b.size())
    throwBadInput(name, where, fmt::format("offset to point data {} lies past the end of the file ({} bytes; truncated)",
                                           h.pointOffset, b.size()));
  h.vlrCount = get<uint32_t>(b, 100);
  h.format = formatByte;
  if (h.format > 10) throwBadInput(name, where, fmt::format("unknown point data format {} (LAS defines 0-10)", h.format));
  h.recordLength = get<uint16_t>(b, 105);
  const int base = kFormats[size_t(h.format)].size;
  if (h.recordLength < base)
    throwBadInput(name, where, fmt::format("point record length {} is shorter than the {} bytes of point data format {}",
                                           h.recordLength, base, h.format));
  h.count = get<uint32_t>(b, 107);
  if (h.minor >= 4)
    if (const uint64_t wide = get<uint64_t>(b, 247); wide != 0) h.count = wide;  // 1.4: the 64-bit count wins
  for (int a = 0; a < 3; ++a) {
    h.scale[a] = get<double>(b, 131 + 8 * size_t(a));
    h.offset[a] = get<double>(b, 155 + 8 * size_t(a));
    if (!std::isfinite(h.scale[a]) || h.scale[a] == 0)
      throwBadInput(name, where, fmt::format("scale factor {} of {} is zero or not finite", h.scale[a], "xyz"[a]));
    if (!std::isfinite(h.offset[a]))
      throwBadInput(name, where, fmt::format("offset {} of {} is not finite", h.offset[a], "xyz"[a]));
  }
  // The records must lie in the file before anything is allocated from the count.
  if (h.count > (b.size() - h.pointOffset) / h.recordLength)
    throwBadInput(name, where, fmt::format("{} points of {} bytes from byte {} do not fit the file's {} bytes "
                                           "(truncated, or the point count is wrong)",
                                           h.count, h.recordLength, h.pointOffset, b.size()));
  return h;
}

int scalarSize(int type) {
  static constexpr int sizes[11] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 4, 8};
  return type >= 1 && type <= 10 ? sizes[type] : 0;
}

double scalarAt(const char* p, int type) {
  switch (type) {
    case 1: { uint8_t v; std::memcpy(&v, p, 1); return v; }
    case 2: { int8_t v; std::memcpy(&v, p, 1); return v; }
    case 3: { uint16_t v; std::memcpy(&v, p, 2); return v; }
    case 4: { int16_t v; std::memcpy(&v, p, 2); return v; }
    case 5: { uint32_t v; std::memcpy(&v, p, 4); return v; }
    case 6: { int32_t v; std::memcpy(&v, p, 4); return v; }
    case 7: { uint64_t v; std::memcpy(&v, p, 8); return double(v); }
    case 8: { int64_t v; std::memcpy(&v, p, 8); return double(v); }
    case 9: { float v; std::memcpy(&v, p, 4); return v; }
    default: { double v; std::memcpy(&v, p, 8); return v; }
  }
}

/// The extra-bytes VLR: every descriptor must fit the bytes the record has beyond the format's.
std::vector<ExtraField> parseExtraBytes(std::string_view payload, const Header& h, const std::string& name,
                                        const std::string& where) {
  if (payload.size() % kExtraDescriptor != 0)
    throwBadInput(name, where, fmt::format("extra-bytes record of {} bytes is not a whole number of 192-byte descriptors",
                                           payload.size()));
  std::vector<ExtraField> out;
  size_t at = size_t(kFormats[size_t(h.format)].size);
  for (size_t d = 0; d * kExtraDescriptor < payload.size(); ++d) {
    const std::string_view e = payload.substr(d * kExtraDescriptor, kExtraDescriptor);
    const int type = get<uint8_t>(e, 2), options = get<uint8_t>(e, 3);
    const std::string field = fixedText(e.substr(4, 32));
    size_t size = 0;
    if (type == 0) size = size_t(options);  // undocumented bytes: `options` holds their count
    else if (type <= 10) size = size_t(scalarSize(type));
    else if (type <= 20) size = 2 * size_t(scalarSize(type - 10));  // deprecated 2- and 3-vectors
    else if (type <= 30) size = 3 * size_t(scalarSize(type - 20));
    else throwBadInput(name, where, fmt::format("extra-bytes descriptor {} ({}) has unknown data type {}", d, printableName(field), type));
    if (size == 0) throwBadInput(name, where, fmt::format("extra-bytes descriptor {} ({}) describes 0 bytes", d, printableName(field)));
    if (at + size > h.recordLength)
      throwBadInput(name, where, fmt::format("extra-bytes descriptors {}-{} need {} bytes a point, the point record has {} "
                                             "(format {}: {} standard bytes)",
                                             0, d, at + size, h.recordLength, h.format, kFormats[size_t(h.format)].size));
    if (type >= 1 && type <= 10) {
      ExtraField f{field, type, at};
      if (options & 0x08) f.scale = get<double>(e, 112);
      if (options & 0x10) f.add = get<double>(e, 136);
      out.push_back(f);
    }
    at += size;
  }
  return out;
}

/// The model property name of an extra-bytes field: characters the PLY writer refuses become
/// '_', a standard PLY name (x, red, ...) gets "las_" in front and a repeated one "_2", "_3" ...
/// at its end, within the 32 bytes the LAS writer can give it back in.
std::string propertyName(std::string raw, const HybridModel& m) {
  for (char& c : raw)
    if (!(std::isalnum((unsigned char)c) || c == '_' || c == '-' || c == '.')) c = '_';
  if (!detail::isPlyExtraPropertyName(raw)) raw = "las_" + raw;
  raw.resize(std::min<size_t>(raw.size(), 32));
  std::string name = raw;
  for (int k = 2; m.pointProperties.count(name); ++k) {
    const std::string suffix = "_" + std::to_string(k);
    name = raw.substr(0, 32 - suffix.size()) + suffix;
  }
  return name;
}

int findExtra(const std::vector<ExtraField>& extras, std::initializer_list<const char*> names) {
  for (size_t i = 0; i < extras.size(); ++i)
    for (const char* n : names)
      if (lower(extras[i].name) == n) return int(i);
  return -1;
}

}  // namespace

namespace detail {

HybridModel lasToModel(std::string_view b, const std::string& name) {
  const Header h = parseHeader(b, name);
  const PointFormat& pf = kFormats[size_t(h.format)];
  std::vector<ExtraField> extras;
  std::vector<std::string> keptComments, crs;
  size_t at = h.headerSize;
  for (uint32_t i = 0; i < h.vlrCount; ++i) {
    const std::string where = fmt::format("VLR {}", i);
    if (h.pointOffset - at < kVlrHeader)
      throwBadInput(name, where, fmt::format("its header at byte {} runs past the offset to point data ({}): the header's "
                                             "count of {} VLRs is wrong",
                                             at, h.pointOffset, h.vlrCount));
    const std::string user = fixedText(b.substr(at + 2, 16));
    const uint16_t record = get<uint16_t>(b, at + 18), length = get<uint16_t>(b, at + 20);
    if (h.pointOffset - at - kVlrHeader < length)
      throwBadInput(name, where, fmt::format("its {} bytes at byte {} run past the offset to point data ({})", length,
                                             at + kVlrHeader, h.pointOffset));
    const std::string_view payload = b.substr(at + kVlrHeader, length);
    if (user == "laszip encoded") throwBadInput(name, where, "the points are compressed (LAZ); " + std::string(kLazHint));
    if (user == "LASF_Spec" && record == kExtraBytesRecord) extras = parseExtraBytes(payload, h, name, where);
    if (user == "linesurf" && record == kCommentsRecord) {
      for (size_t p = 0; p <= payload.size();) {
        const size_t e = std::min(payload.find('\n', p), payload.size());
        const std::string_view c = payload.substr(p, e - p);
        if (!c.empty() && !isReservedComment(c)) keptComments.emplace_back(c);
        p = e + 1;
      }
    }
    if (user == "LASF_Projection" && length <= kMaxCrsBytes) crs.push_back(crsComment(record, payload));
    at += kVlrHeader + length;
  }
  // LAS 1.4 may put the CRS (a long WKT, say) in an extended VLR after the points.
  const uint32_t evlrs = h.minor >= 4 ? get<uint32_t>(b, 243) : 0;
  uint64_t eat = h.minor >= 4 ? get<uint64_t>(b, 235) : 0;
  for (uint32_t i = 0; i < evlrs; ++i) {
    const std::string where = fmt::format("EVLR {}", i);
    if (eat > b.size() || b.size() - eat < 60)
      throwBadInput(name, where, fmt::format("its header at byte {} runs past the end of the file ({} bytes): the header's "
                                             "start or count of extended VLRs is wrong",
                                             eat, b.size()));
    const std::string user = fixedText(b.substr(size_t(eat) + 2, 16));
    const uint16_t record = get<uint16_t>(b, size_t(eat) + 18);
    const uint64_t length = get<uint64_t>(b, size_t(eat) + 20);
    if (b.size() - eat - 60 < length)
      throwBadInput(name, where, fmt::format("its {} bytes at byte {} run past the end of the file ({} bytes)", length, eat + 60,
                                             b.size()));
    if (user == "LASF_Projection" && length <= kMaxCrsBytes) crs.push_back(crsComment(record, b.substr(size_t(eat) + 60, size_t(length))));
    eat += 60 + length;
  }

  HybridModel m;
  const size_t n = size_t(h.count), len = h.recordLength;
  const char* rec = b.data() + h.pointOffset;
  auto record = [&](size_t i) { return rec + i * len; };
  auto i32 = [&](size_t i, int a) {
    int32_t v;
    std::memcpy(&v, record(i) + 4 * a, 4);
    return v;
  };
  // Far from the origin, subtract the record range's centre (a whole number of steps, so the
  // writer recovers the integers) before positions become float32.
  std::array<int64_t, 3> lo{0, 0, 0}, hi{0, 0, 0}, k{0, 0, 0};
  bool shift = false;
  if (n > 0) {
    for (int a = 0; a < 3; ++a) lo[size_t(a)] = hi[size_t(a)] = i32(0, a);
    for (size_t i = 1; i < n; ++i)
      for (int a = 0; a < 3; ++a) {
        const int64_t v = i32(i, a);
        lo[size_t(a)] = std::min(lo[size_t(a)], v), hi[size_t(a)] = std::max(hi[size_t(a)], v);
      }
    for (int a = 0; a < 3; ++a) {
      const double s = h.scale[a], o = h.offset[a];
      const double far = std::max(std::abs(double(lo[size_t(a)]) * s + o), std::abs(double(hi[size_t(a)]) * s + o));
      shift = shift || far > kFloatSteps * std::abs(s);
    }
  }
  Vec3d origin = Vec3d::Zero();
  if (shift)
    for (int a = 0; a < 3; ++a) {
      k[size_t(a)] = (lo[size_t(a)] + hi[size_t(a)]) / 2;
      origin[a] = h.offset[a] + double(k[size_t(a)]) * h.scale[a];
    }
  m.points.resize(n);
  for (size_t i = 0; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      const double v = shift ? double(int64_t(i32(i, a)) - k[size_t(a)]) * h.scale[a] : double(i32(i, a)) * h.scale[a] + h.offset[a];
      m.points[i].position[a] = float(v);
    }

  if (pf.rgb >= 0 && n > 0) {
    uint16_t top = 0;
    for (size_t i = 0; i < n; ++i)
      for (int c = 0; c < 3; ++c) top = std::max(top, get<uint16_t>(std::string_view(record(i), len), size_t(pf.rgb + 2 * c)));
    // All zero: the format's colour fields are unused. All <= 255: 8-bit values stored in the
    // 16-bit fields (many writers do so); else 16-bit colour, kept whole in the float colour.
    if (top > 0) {
      const float div = top <= 255 ? 255.0f : 65535.0f;
      for (size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c)
          m.points[i].color[c] = float(get<uint16_t>(std::string_view(record(i), len), size_t(pf.rgb + 2 * c))) / div;
      m.attributes.colors = true;
    }
  }
  // Intensity and class come in as point properties when any point has one (all zero: unused).
  std::vector<float> intensity(n), cls(n);
  bool anyIntensity = false, anyClass = false;
  for (size_t i = 0; i < n; ++i) {
    const std::string_view r(record(i), len);
    intensity[i] = float(get<uint16_t>(r, 12));
    cls[i] = float(pf.extended ? get<uint8_t>(r, 16) : get<uint8_t>(r, 15) & 0x1F);
    anyIntensity = anyIntensity || intensity[i] != 0;
    anyClass = anyClass || cls[i] != 0;
  }
  if (anyIntensity) m.pointProperties["intensity"] = std::move(intensity);
  if (anyClass) m.pointProperties["classification"] = std::move(cls);

  auto extraValues = [&](const ExtraField& f, auto&& set) {
    for (size_t i = 0; i < n; ++i) set(i, scalarAt(record(i) + f.offset, f.type) * f.scale + f.add);
  };
  std::vector<bool> used(extras.size());
  const int ex = findExtra(extras, {"nx", "normalx", "normal_x"}), ey = findExtra(extras, {"ny", "normaly", "normal_y"}),
            ez = findExtra(extras, {"nz", "normalz", "normal_z"});
  if (ex >= 0 && ey >= 0 && ez >= 0) {
    int c = 0;
    for (int e : {ex, ey, ez}) {
      extraValues(extras[size_t(e)], [&](size_t i, double v) { m.points[i].normal[c] = float(v); });
      used[size_t(e)] = true, ++c;
    }
    m.attributes.normals = true;
  }
  if (const int er = findExtra(extras, {"radius"}); er >= 0) {
    extraValues(extras[size_t(er)], [&](size_t i, double v) {
      if (v < 0) throwBadInput(name, fmt::format("point {}", i), fmt::format("radius {:g} is negative (0 = unknown)", v));
      m.points[i].radius = float(v);
    });
    used[size_t(er)] = true;
    m.attributes.radii = true;
  }
  for (size_t e = 0; e < extras.size(); ++e) {
    if (used[e]) continue;
    std::vector<float>& p = m.pointProperties[propertyName(extras[e].name, m)];
    p.resize(n);
    extraValues(extras[e], [&](size_t i, double v) { p[i] = float(v); });
  }

  m.comments = std::move(keptComments);
  if (shift) m.comments.push_back(fmt::format("{} {} {} {}", kOriginComment, origin.x(), origin.y(), origin.z()));
  m.comments.push_back(fmt::format("{} {} {} {}", kLasScaleComment, h.scale.x(), h.scale.y(), h.scale.z()));
  m.comments.push_back(fmt::format("{} {} {} {}", kLasOffsetComment, h.offset.x(), h.offset.y(), h.offset.z()));
  m.comments.push_back(std::string(kUpAxisComment) + " z");
  for (std::string& c : crs) m.comments.push_back(std::move(c));
  return m;
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------
// Writing

namespace {

/// A point property written in a standard field when every value fits it, else as extra bytes.
bool fitsField(const std::vector<float>& v, float top) {
  return std::all_of(v.begin(), v.end(), [&](float x) { return x >= 0 && x <= top && x == std::floor(x); });
}

struct Quantization {
  Vec3d scale = Vec3d::Constant(0.001), offset = Vec3d::Zero();
  std::vector<int32_t> xyz;  ///< 3 per point
};

/// The records of the kept scale and offset, or false when a record would not fit int32.
bool quantizeKept(const HybridModel& m, const Vec3d& origin, Quantization& q) {
  const size_t n = m.points.size();
  q.xyz.resize(3 * n);
  for (int a = 0; a < 3; ++a) {
    const double s = q.scale[a];
    if (!std::isfinite(s) || s == 0) return false;
    const double base = (origin[a] - q.offset[a]) / s, whole = std::round(base);
    // A whole number of steps between origin and offset (as the reader makes it) is added as an
    // integer, so the float position alone is rounded.
    const bool integral = std::abs(base - whole) < 1e-3 && std::abs(whole) < 9e15;
    for (size_t i = 0; i < n; ++i) {
      const double steps = double(m.points[i].position[a]) / s;
      const double r = integral ? whole + std::round(steps) : std::round(base + steps);
      if (!(r >= -2147483648.0 && r <= 2147483647.0)) return false;
      q.xyz[3 * i + size_t(a)] = int32_t(r);
    }
  }
  return true;
}

/// The finest decimal scale at which the reader keeps the positions without an origin
/// (10^ceil(log10(M / 2^22)) for the largest |coordinate| M), offsets at the centres.
void quantizeFresh(const HybridModel& m, const Vec3d& origin, Quantization& q) {
  Vec3d lo = Vec3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const Point& p : m.points) lo = lo.cwiseMin(p.position.cast<double>()), hi = hi.cwiseMax(p.position.cast<double>());
  if (m.points.empty()) lo = hi = Vec3d::Zero();
  const double far = std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
  const double s = far > 0 ? std::pow(10.0, std::ceil(std::log10(far / kFloatSteps))) : 0.001;
  q.scale = Vec3d::Constant(s);
  q.xyz.resize(3 * m.points.size());
  for (int a = 0; a < 3; ++a) {
    const double centre = std::round(0.5 * (lo[a] + hi[a]) / s) * s;
    q.offset[a] = origin[a] + centre;
    for (size_t i = 0; i < m.points.size(); ++i)
      q.xyz[3 * i + size_t(a)] = int32_t(std::llround((double(m.points[i].position[a]) - centre) / s));
  }
}

void putText(std::string& b, size_t at, size_t size, std::string_view text) {
  std::memcpy(b.data() + at, text.data(), std::min(size, text.size()));
}

/// One VLR: its 54-byte header and payload.
std::string vlr(std::string_view user, uint16_t record, std::string_view description, std::string_view payload) {
  std::string v(kVlrHeader, '\0');
  putText(v, 2, 16, user);
  put<uint16_t>(v, 18, record);
  put<uint16_t>(v, 20, uint16_t(payload.size()));
  putText(v, 22, 32, description);
  v.append(payload);
  return v;
}

}  // namespace

Vec3d modelOrigin(const HybridModel& model) {
  Vec3d o = Vec3d::Zero();
  commentTriple(model, kOriginComment, o);
  return o;
}

std::string lasBytes(const HybridModel& m, const LasWriteOptions& options, const std::string& name) {
  if (!m.segments.empty())
    throwBadParameter(name, fmt::format("a LAS file holds points only, and the model has {} line segments (write .ply)",
                                        m.segments.size()));
  const int format = options.pointFormat < 0 ? (m.attributes.colors ? 7 : 6) : options.pointFormat;
  if (format > 10) throwBadParameter("pointFormat", fmt::format("{} is not a LAS point data format (0-10)", format));
  const PointFormat& pf = kFormats[size_t(format)];
  const size_t n = m.points.size();
  for (const auto& [prop, values] : m.pointProperties)
    if (values.size() != n)
      throwBadParameter("pointProperties['" + prop + "']", fmt::format("has {} values for {} points", values.size(), n));

  // Standard fields, and what goes into extra bytes (float32 each).
  const std::vector<float>* intensity = nullptr;
  const std::vector<float>* cls = nullptr;
  if (auto it = m.pointProperties.find("intensity"); it != m.pointProperties.end() && fitsField(it->second, 65535))
    intensity = &it->second;
  if (auto it = m.pointProperties.find("classification");
      it != m.pointProperties.end() && fitsField(it->second, pf.extended ? 255 : 31))
    cls = &it->second;
  std::vector<std::pair<std::string, std::function<float(size_t)>>> extras;
  if (m.attributes.normals)
    for (int c = 0; c < 3; ++c)
      extras.emplace_back(std::string("n") + "xyz"[c], [&m, c](size_t i) { return m.points[i].normal[c]; });
  if (m.attributes.radii) extras.emplace_back("radius", [&m](size_t i) { return m.points[i].radius; });
  for (const auto& [prop, values] : m.pointProperties) {
    if ((intensity && &values == intensity) || (cls && &values == cls)) continue;
    if (prop.size() > 32)
      throwBadParameter("pointProperties['" + prop + "']", "name is longer than the 32 bytes of a LAS extra-bytes field");
    extras.emplace_back(prop, [v = &values](size_t i) { return (*v)[i]; });
  }
  const size_t recordLength = size_t(pf.size) + 4 * extras.size();
  if (recordLength > 65535)
    throwBadParameter(name, fmt::format("{} point properties do not fit a LAS point record (65535 bytes)", extras.size()));

  const Vec3d origin = modelOrigin(m);
  Quantization q;
  if (!(commentTriple(m, kLasScaleComment, q.scale) && commentTriple(m, kLasOffsetComment, q.offset) &&
        quantizeKept(m, origin, q)))
    quantizeFresh(m, origin, q);

  std::string vlrs;
  uint32_t vlrCount = 0;
  if (!extras.empty()) {
    std::string d(kExtraDescriptor * extras.size(), '\0');
    for (size_t e = 0; e < extras.size(); ++e) {
      put<uint8_t>(d, e * kExtraDescriptor + 2, 9);  // float
      putText(d, e * kExtraDescriptor + 4, 32, extras[e].first);
    }
    vlrs += vlr("LASF_Spec", kExtraBytesRecord, "extra bytes", d);
    ++vlrCount;
  }
  std::string text;
  for (const std::string& c : m.comments) {
    if (isReservedComment(c)) continue;
    std::string line = c;
    std::replace(line.begin(), line.end(), '\n', ' ');
    if (text.size() + line.size() + 1 > 65535) break;  // a VLR holds 65535 bytes: later comments are dropped
    text += (text.empty() ? "" : "\n") + line;
  }
  if (!text.empty()) {
    vlrs += vlr("linesurf", kCommentsRecord, "comments", text);
    ++vlrCount;
  }
  bool wkt = false;
  for (const std::string& c : m.comments) {
    if (!isKey(c, kLasCrsComment)) continue;
    const auto [record, payload] = parseCrsComment(c);
    vlrs += vlr("LASF_Projection", record, "", payload);
    ++vlrCount;
    wkt = wkt || record == kWktRecord;
  }

  std::string b(kHeader14, '\0');
  b.replace(0, 4, "LASF");
  // Formats 6-10 require the WKT bit (1.4 R15 table 4); the others set it for a WKT record.
  if (pf.extended || wkt) put<uint16_t>(b, 6, 0x10);
  put<uint8_t>(b, 24, 1);
  put<uint8_t>(b, 25, 4);
  putText(b, 26, 32, "OTHER");
  putText(b, 58, 32, "linesurf");
  // Creation day and year stay 0 (unknown) so that one model always gives the same bytes.
  put<uint16_t>(b, 94, uint16_t(kHeader14));
  put<uint32_t>(b, 96, uint32_t(kHeader14 + vlrs.size()));
  put<uint32_t>(b, 100, vlrCount);
  put<uint8_t>(b, 104, uint8_t(format));
  put<uint16_t>(b, 105, uint16_t(recordLength));
  if (!pf.extended && n <= 0xFFFFFFFFu) {
    put<uint32_t>(b, 107, uint32_t(n));
    put<uint32_t>(b, 111, uint32_t(n));  // every point is return 1 of 1
  }
  Vec3d lo = Vec3d::Zero(), hi = Vec3d::Zero();
  for (int a = 0; a < 3; ++a) {
    put<double>(b, 131 + 8 * size_t(a), q.scale[a]);
    put<double>(b, 155 + 8 * size_t(a), q.offset[a]);
    if (n == 0) continue;
    int32_t rl = q.xyz[size_t(a)], rh = rl;
    for (size_t i = 1; i < n; ++i) rl = std::min(rl, q.xyz[3 * i + size_t(a)]), rh = std::max(rh, q.xyz[3 * i + size_t(a)]);
    lo[a] = double(rl) * q.scale[a] + q.offset[a], hi[a] = double(rh) * q.scale[a] + q.offset[a];
  }
  for (int a = 0; a < 3; ++a) {
    put<double>(b, 179 + 16 * size_t(a), hi[a]);
    put<double>(b, 187 + 16 * size_t(a), lo[a]);
  }
  put<uint64_t>(b, 247, n);
  put<uint64_t>(b, 255, n);
  b += vlrs;

  const size_t start = b.size();
  b.resize(start + n * recordLength, '\0');
  for (size_t i = 0; i < n; ++i) {
    const size_t r = start + i * recordLength;
    for (int a = 0; a < 3; ++a) put<int32_t>(b, r + 4 * size_t(a), q.xyz[3 * i + size_t(a)]);
    if (intensity) put<uint16_t>(b, r + 12, uint16_t((*intensity)[i]));
    const uint8_t c = cls ? uint8_t((*cls)[i]) : 0;
    if (pf.extended) {
      put<uint8_t>(b, r + 14, 0x11);  // return 1 of 1
      put<uint8_t>(b, r + 16, c);
    } else {
      put<uint8_t>(b, r + 14, 0x09);
      put<uint8_t>(b, r + 15, c);
    }
    if (pf.rgb >= 0 && m.attributes.colors)
      for (int k = 0; k < 3; ++k) {
        const float v = std::clamp(m.points[i].color[k], 0.0f, 1.0f);
        put<uint16_t>(b, r + size_t(pf.rgb + 2 * k), uint16_t(std::lround(double(v) * 65535.0)));
      }
    for (size_t e = 0; e < extras.size(); ++e) put<float>(b, r + size_t(pf.size) + 4 * e, extras[e].second(i));
  }
  return b;
}

void writeLasModel(const std::filesystem::path& path, const HybridModel& model, const LasWriteOptions& options) {
  writeFileAtomically(path, lasBytes(model, options, path.string()));
}

HybridModel readLasModelFromMemory(std::string_view bytes, const std::string& nameForMessages) {
  HybridModel m = detail::lasToModel(bytes, nameForMessages);
  validateModel(m, nameForMessages);
  return m;
}

}  // namespace linesurf
