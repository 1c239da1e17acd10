// Streaming point I/O (see ooc/point_stream.h). The PLY header is parsed by the whole-file
// reader's parser (io/detail/ply_format.h), so header errors read the same; the body checks
// (truncation, non-finite values) use the same wording as its body decoder.
#include "linesurf/ooc/point_stream.h"

#include <sys/stat.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "io/detail/ply_format.h"
#include "io/detail/readers.h"
#include "linesurf/core/error.h"
#include "ooc/scan_hash.h"
#include "linesurf/io/atomic_file.h"

namespace linesurf::ooc {
namespace {

constexpr std::string_view kTextureKey = "TextureFile";

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::FILE* openInput(const std::string& path) {
  std::error_code ec;
  const auto st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st)) throwBadInput(path, "", "no such file");
  if (std::filesystem::is_directory(st)) throwBadInput(path, "", "is a directory, not a file");
  if (!std::filesystem::is_regular_file(st)) throwBadInput(path, "", "is not a regular file (a pipe, device or socket)");
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throwBadInput(path, "", std::string("cannot open: ") + std::strerror(errno));
  return f;
}

double decode(const char* p, ply::Type t) {
  switch (t) {
    case ply::Type::Int8: { int8_t v; std::memcpy(&v, p, 1); return v; }
    case ply::Type::UInt8: { uint8_t v; std::memcpy(&v, p, 1); return v; }
    case ply::Type::Int16: { int16_t v; std::memcpy(&v, p, 2); return v; }
    case ply::Type::UInt16: { uint16_t v; std::memcpy(&v, p, 2); return v; }
    case ply::Type::Int32: { int32_t v; std::memcpy(&v, p, 4); return v; }
    case ply::Type::UInt32: { uint32_t v; std::memcpy(&v, p, 4); return v; }
    case ply::Type::Float32: { float v; std::memcpy(&v, p, 4); return v; }
    case ply::Type::Float64: { double v; std::memcpy(&v, p, 8); return v; }
  }
  return 0;
}

}  // namespace

uint64_t fnv1a(const void* data, size_t n, uint64_t h) {
  const auto* b = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ull;
  return h;
}

FileIdentity fileIdentity(const std::filesystem::path& path) {
  FileIdentity id;
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) throwBadInput(path.string(), "", "no such file");
  id.size = uint64_t(st.st_size);
  id.mtimeNs = int64_t(st.st_mtim.tv_sec) * 1000000000ll + st.st_mtim.tv_nsec;
  // The whole content, not samples: an edit anywhere with the old mtime restored is seen.
  std::FILE* f = openInput(path.string());
  std::vector<char> buf(1 << 20);
  detail::Hasher h(id.size);
  for (size_t got; (got = std::fread(buf.data(), 1, buf.size(), f)) > 0;) h.add(buf.data(), got);
  const bool failed = std::ferror(f) != 0;
  std::fclose(f);
  if (failed) throwIo(path.string(), "read error while hashing the input");
  const uint64_t hv = h.finish();
  id.hash = hv;
  return id;
}

// ---------------------------------------------------------------------------------------------
PointReader::PointReader(const std::filesystem::path& path) : path_(path.string()) {
  const std::string ext = lower(path.extension().string());
  // LAS is read whole (io/las_io.h): its origin and colour rule need every record first, which
  // the chunked reader does not do yet, so a LAS input is refused here before any work.
  if (ext == ".las")
    throwBadInput(path_, "", "the out-of-core path does not stream LAS yet: raise --max-mb to read it in memory, or "
                             "'linesurf convert' it to binary .ply first");
  if (ext != ".ply" && ext != ".xyz")
    throwBadInput(path_, "", "the out-of-core path reads .ply (binary) and .xyz point files");
  ply_ = ext == ".ply";
  f_ = openInput(path_);
  if (!ply_) {
    // One pass: count and validate (the count goes into the output's header).
    std::vector<Vec3f> p, n;
    while (read(p, n, 1 << 20) > 0) info_.count += p.size();
    counted_ = true;
    if (info_.count == 0) throwBadInput(path_, "line " + std::to_string(std::max<uint64_t>(line_, 1)), "no points in the file");
    info_.normals = columns_ == 6;
    rewind();
    return;
  }
  // Header: read until end_header (a header is small; 16 MiB bounds a malformed one).
  std::string head;
  std::vector<char> chunk(65536);
  size_t endPos = std::string::npos;
  while (endPos == std::string::npos && head.size() < (16u << 20)) {
    const size_t got = std::fread(chunk.data(), 1, chunk.size(), f_);
    if (got == 0) break;
    head.append(chunk.data(), got);
    const size_t e = head.find("end_header");
    if (e != std::string::npos) {
      const size_t nl = head.find('\n', e);
      if (nl != std::string::npos) endPos = nl + 1;
    }
  }
  if (endPos != std::string::npos) head.resize(endPos);
  const ply::Header h = ply::parseHeader(head, path_);
  info_.header = head.substr(0, h.bodyOffset);
  if (h.format != ply::Format::BinaryLittleEndian)
    throwBadInput(path_, "line 2", "the out-of-core path reads binary little-endian PLY (convert the file with 'linesurf convert')");
  for (const std::string& c : h.comments)
    if (std::string_view(c).substr(0, kTextureKey.size()) != kTextureKey) info_.comments.push_back(c);
  const int vi = h.find("vertex");
  if (vi < 0) throwBadInput(path_, "", "no vertex element (no points)");
  for (size_t e = 0; e < h.elements.size(); ++e)
    if (int(e) != vi && h.elements[e].count > 0)
      throwBadInput(path_, "line " + std::to_string(h.elements[e].line),
                    "the out-of-core path reads points only, not element '" + h.elements[e].name + "'");
  const ply::Element& v = h.elements[size_t(vi)];
  if (vi != 0) throwBadInput(path_, "line " + std::to_string(v.line), "the vertex element must come first");
  size_t off = 0;
  int found[6] = {-1, -1, -1, -1, -1, -1};
  static const char* names[6] = {"x", "y", "z", "nx", "ny", "nz"};
  static const char* channels[4] = {"red", "green", "blue", "alpha"};
  Field colour[4] = {{0, -1, "red"}, {0, -1, "green"}, {0, -1, "blue"}, {0, -1, "alpha"}};
  std::vector<std::pair<std::string, Field>> props;
  for (const ply::Property& p : v.properties) {
    if (p.isList) throwBadInput(path_, "line " + std::to_string(p.line), "the out-of-core path reads no list properties ('" + p.name + "')");
    const Field here{off, int(p.type), nullptr};
    off += size_t(ply::typeSize(p.type));
    int which = -1;
    for (int c = 0; c < 6; ++c)
      if (p.name == names[c]) which = c;
    if (which >= 0) {
      found[which] = int(fields_.size());
      fields_.push_back({here.offset, here.type, names[which]});
      continue;
    }
    if (p.name == "radius") {
      // The radius `normals` writes: `normals` sets every radius again, `extract eps-delta`
      // keeps it (as in memory), so the output of `normals` goes on out of core.
      radius_ = {here.offset, here.type, "radius"};
      info_.radius = true;
      continue;
    }
    bool channel = false;
    for (int c = 0; c < 4; ++c)
      if (p.name == channels[c]) colour[c] = {here.offset, here.type, channels[c]}, channel = true;
    if (channel) continue;
    if (p.name == "snx" || p.name == "sny" || p.name == "snz")
      throwBadInput(path_, "line " + std::to_string(p.line),
                    "the out-of-core path does not carry shading normals (property '" + p.name + "')");
    if (!linesurf::detail::isPlyExtraPropertyName(p.name))
      throwBadInput(path_, "line " + std::to_string(p.line),
                    "property name '" + p.name + "' may hold only letters, digits, '_', '-' and '.'");
    props.emplace_back(p.name, here);
  }
  // Colour as the whole-file reader takes it: red green blue together, alpha with or without them.
  const int rgb = (colour[0].type >= 0) + (colour[1].type >= 0) + (colour[2].type >= 0);
  if (rgb > 0 && rgb < 3)
    for (int c = 0; c < 3; ++c)
      if (colour[c].type < 0)
        throwBadInput(path_, "line " + std::to_string(v.line),
                      std::string("element vertex has some but not all of the properties 'red green blue' (no '") + channels[c] + "')");
  info_.colors = rgb == 3 || colour[3].type >= 0;
  if (info_.colors)
    for (const Field& c : colour) attrs_.push_back({c, c.type >= 0 ? ply::channelScale(ply::Type(c.type)) : 1.0f});
  std::sort(props.begin(), props.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (const auto& pr : props) info_.properties.push_back(pr.first);
  for (size_t i = 0; i < props.size(); ++i)
    attrs_.push_back({{props[i].second.offset, props[i].second.type, info_.properties[i].c_str()}, 1.0f});
  for (int c = 0; c < 3; ++c)
    if (found[c] < 0) throwBadInput(path_, "line " + std::to_string(v.line), std::string("vertex element has no '") + names[c] + "' property");
  const bool anyN = found[3] >= 0 || found[4] >= 0 || found[5] >= 0;
  if (anyN && (found[3] < 0 || found[4] < 0 || found[5] < 0))
    throwBadInput(path_, "line " + std::to_string(v.line), "nx ny nz must come together");
  info_.normals = anyN;
  // fields_ in x y z nx ny nz order
  std::vector<Field> ordered;
  for (int c = 0; c < (anyN ? 6 : 3); ++c) ordered.push_back(fields_[size_t(found[c])]);
  fields_ = ordered;
  rowSize_ = off;
  info_.count = v.count;
  bodyOffset_ = h.bodyOffset;
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path_, ec);
  const uint64_t rest = size > bodyOffset_ ? size - bodyOffset_ : 0;
  if (rowSize_ > 0 && v.count > rest / rowSize_)
    throwBadInput(path_, "element vertex " + std::to_string(rest / rowSize_),
                  "truncated binary body: the header declares " + std::to_string(v.count) + " vertex rows of at least " +
                      std::to_string(rowSize_) + " bytes, but only " + std::to_string(rest) + " bytes are left at byte " +
                      std::to_string(bodyOffset_));
  rewind();
}

PointReader::~PointReader() {
  if (f_) std::fclose(f_);
}

void PointReader::rewind() {
  next_ = 0;
  line_ = 0;
  eof_ = false;
  pending_.clear();
  if (std::fseek(f_, long(ply_ ? bodyOffset_ : 0), SEEK_SET) != 0) throwBadInput(path_, "", "cannot seek");
}

size_t PointReader::read(std::vector<Vec3f>& pos, std::vector<Vec3f>& nrm, size_t max, std::vector<float>* rad,
                         std::vector<float>* attrs) {
  const size_t n = ply_ ? readPly(pos, nrm, max, rad, attrs) : readXyz(pos, nrm, max);
  if (!ply_ && rad) rad->clear();
  if (!ply_ && attrs) attrs->clear();
  return n;
}

size_t PointReader::readPly(std::vector<Vec3f>& pos, std::vector<Vec3f>& nrm, size_t max, std::vector<float>* rad,
                            std::vector<float>* attrs) {
  const size_t n = size_t(std::min<uint64_t>(max, info_.count - next_));
  pos.resize(n);
  nrm.resize(info_.normals ? n : 0);
  if (rad) rad->resize(info_.radius ? n : 0);
  const size_t na = attrs_.size();
  if (attrs) attrs->resize(n * na);
  if (n == 0) return 0;
  buf_.resize(n * rowSize_);
  const size_t got = std::fread(buf_.data(), 1, buf_.size(), f_);
  if (got != buf_.size()) {
    const uint64_t row = next_ + got / rowSize_;
    throwBadInput(path_, "element vertex " + std::to_string(row),
                  "truncated binary body: the file ends at byte " + std::to_string(bodyOffset_ + row * rowSize_ + got % rowSize_) +
                      (std::ferror(f_) ? " (read error)" : ""));
  }
  const size_t nf = fields_.size();
  // A value as the whole-file decoder takes it: finite and within float range.
  auto value = [&](const char* row, const Field& f, size_t r) {
    const double d = decode(row + f.offset, ply::Type(f.type));
    if (!std::isfinite(d))
      throwBadInput(path_, "element vertex " + std::to_string(next_ + r),
                    std::string(std::isnan(d) ? "NaN" : "infinite") + " value in property '" + f.name + "'");
    if (std::fabs(d) > double(std::numeric_limits<float>::max()))
      throwBadInput(path_, "element vertex " + std::to_string(next_ + r),
                    "value " + fmt::format("{:g}", d) + " in property '" + f.name + "' is too large for a 32-bit float (|v| > 3.4e38)");
    return float(d);
  };
  for (size_t r = 0; r < n; ++r) {
    const char* row = buf_.data() + r * rowSize_;
    float v[6];
    for (size_t c = 0; c < nf; ++c) v[c] = value(row, fields_[c], r);
    if (attrs)
      for (size_t a = 0; a < na; ++a)
        (*attrs)[r * na + a] = attrs_[a].field.type < 0 ? 1.0f : value(row, attrs_[a].field, r) / attrs_[a].scale;
    pos[r] = Vec3f(v[0], v[1], v[2]);
    if (nf == 6) nrm[r] = Vec3f(v[3], v[4], v[5]);
    if (rad && info_.radius) {
      const double d = decode(row + radius_.offset, ply::Type(radius_.type));
      if (!std::isfinite(d) || std::fabs(d) > double(std::numeric_limits<float>::max()))
        throwBadInput(path_, "element vertex " + std::to_string(next_ + r), "non-finite or too large value in property 'radius'");
      (*rad)[r] = float(d);
    }
  }
  next_ += n;
  return n;
}

size_t PointReader::readXyz(std::vector<Vec3f>& pos, std::vector<Vec3f>& nrm, size_t max) {
  pos.clear();
  nrm.clear();
  std::vector<char> chunk(1 << 20);
  size_t start = 0;  // parse position in pending_
  while (pos.size() < max) {
    size_t e = pending_.find('\n', start);
    if (e == std::string::npos) {
      if (eof_) {
        if (start >= pending_.size()) break;
        e = pending_.size();  // last line without a newline
      } else {
        pending_.erase(0, start);
        start = 0;
        const size_t got = std::fread(chunk.data(), 1, chunk.size(), f_);
        if (got == 0) eof_ = true;
        pending_.append(chunk.data(), got);
        continue;
      }
    }
    std::string_view text(pending_.data() + start, e - start);
    start = std::min(pending_.size(), e + 1);
    ++line_;
    const std::string where = "line " + std::to_string(line_);
    float v[6];
    const int n = linesurf::detail::parseXyzLine(text, path_, where, counted_ ? nullptr : &info_.comments, v);
    if (n == 0) continue;
    if (n != 3 && n != 6)
      throwBadInput(path_, where, "expected 3 (x y z) or 6 (x y z nx ny nz) numbers, found " + std::to_string(n));
    if (columns_ == 0) columns_ = n;
    if (n != columns_)
      throwBadInput(path_, where, std::to_string(n) + " numbers, but earlier lines have " + std::to_string(columns_));
    pos.emplace_back(v[0], v[1], v[2]);
    if (n == 6) nrm.emplace_back(v[3], v[4], v[5]);
  }
  pending_.erase(0, start);
  if (columns_ == 6 && nrm.size() != pos.size()) nrm.resize(pos.size());
  if (columns_ != 6) nrm.clear();
  next_ += pos.size();
  return pos.size();
}

// ---------------------------------------------------------------------------------------------
PlyPointWriter::PlyPointWriter(const std::filesystem::path& path, uint64_t count, const std::vector<std::string>& comments,
                               bool normals, bool radius, const std::string& moreElements,
                               const std::vector<std::string>& extra, bool colors)
    : path_(path.string()), out_(std::make_unique<AtomicFileWriter>(path)), count_(count), normals_(normals),
      radius_(radius), colors_(colors), extra_(extra.size()) {
  // The header exactly as writePlyModel (io/ply_model.cpp) writes it.
  std::string h = "ply\nformat binary_little_endian 1.0\n";
  for (const std::string& c : comments) {
    std::string line = c;
    std::replace(line.begin(), line.end(), '\n', ' ');
    std::replace(line.begin(), line.end(), '\r', ' ');
    const size_t s = line.find_first_not_of(" \t\v\f");
    if (s != std::string::npos && std::string_view(line).substr(s, kTextureKey.size()) == kTextureKey)
      line = "(" + line.substr(s) + ")";
    h += "comment " + line + "\n";
  }
  h += "element vertex " + std::to_string(count) + "\n";
  h += "property float x\nproperty float y\nproperty float z\n";
  if (normals) h += "property float nx\nproperty float ny\nproperty float nz\n";
  if (colors) h += "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n";
  if (radius) h += "property float radius\n";
  for (const std::string& e : extra) h += "property float " + e + "\n";
  h += moreElements;
  h += "end_header\n";
  put(h.data(), h.size());
}

PlyPointWriter::~PlyPointWriter() = default;  // an unfinished file's temporary goes with out_

void PlyPointWriter::put(const char* data, size_t n) {
  constexpr size_t kBuffer = size_t(8) << 20;
  if (buf_.size() + n >= kBuffer) {
    // Written as they come once the buffer would be full: a large piece is not copied into it.
    out_->write(buf_.data(), buf_.size());
    buf_.clear();
    if (n >= kBuffer) return out_->write(data, n);
  }
  buf_.append(data, n);
}

void PlyPointWriter::write(const Vec3f* pos, const Vec3f* nrm, const float* radius, size_t n, const float* extra,
                           const float* colors) {
  static_assert(std::endian::native == std::endian::little, "the binary writer assumes a little-endian host");
  if (written_ + n > count_) throw std::logic_error("PlyPointWriter: more rows than declared");
  if (colors_ && !colors) throw std::logic_error("PlyPointWriter: rows without the declared colours");
  const size_t rowFloats = 3 + (normals_ ? 3 : 0) + (radius_ ? 1 : 0) + extra_;
  // Encoded in slices, so that the rows' copy stays small whatever n is.
  constexpr size_t kSlice = size_t(1) << 16;
  for (size_t at = 0; at < n; at += kSlice) {
    const size_t end = std::min(n, at + kSlice);
    row_.resize((end - at) * (rowFloats * 4 + (colors_ ? 4 : 0)));
    char* o = row_.data();
    for (size_t i = at; i < end; ++i) {
      std::memcpy(o, pos[i].data(), 12), o += 12;
      if (normals_) std::memcpy(o, nrm[i].data(), 12), o += 12;
      if (colors_)
        for (int c = 0; c < 4; ++c) *o++ = char(ply::colorByte(colors[i * 4 + size_t(c)]));
      if (radius_) std::memcpy(o, &radius[i], 4), o += 4;
      if (extra_) std::memcpy(o, extra + i * extra_, 4 * extra_), o += 4 * extra_;
    }
    put(row_.data(), row_.size());
  }
  written_ += n;
}

void PlyPointWriter::writeRaw(const std::string& bytes) {
  if (written_ != count_) throw std::logic_error("PlyPointWriter: element rows before every vertex row");
  put(bytes.data(), bytes.size());
}

void PlyPointWriter::finish() {
  if (written_ != count_) throw std::logic_error("PlyPointWriter: fewer rows than declared");
  out_->write(buf_.data(), buf_.size());
  buf_.clear();
  out_->commit();
}

}  // namespace linesurf::ooc
