// Chunked reading of large binary PLY models (include/linesurf/io/model_stream.h).
#include "linesurf/io/model_stream.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

#include "detail/ply_format.h"
#include "detail/readers.h"
#include "linesurf/core/error.h"
#include "linesurf/io/atomic_file.h"

namespace linesurf {

ModelChunkReader::ModelChunkReader(const std::filesystem::path& path) : path_(path), name_(path.string()) {
  noteInput(path);
  std::error_code ec;
  const uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throwBadInput(name_, "", "cannot read the file (" + ec.message() + ")");
  // The header: its first MiB, or up to 64 MiB for a header with very many properties.
  std::string head = detail::readFileBytes(path, size_t(1) << 20);
  if (head.find("end_header") == std::string::npos && head.size() < size)
    head = detail::readFileBytes(path, size_t(64) << 20);
  if (head.compare(0, 3, "ply") != 0)
    throwBadInput(name_, "", "streamed reading takes binary little-endian PLY only (convert it with `linesurf convert`)");
  const ply::Header h = ply::parseHeader(head, name_);
  if (h.format != ply::Format::BinaryLittleEndian)
    throwBadInput(name_, "", "streamed reading takes binary little-endian PLY only (convert it with `linesurf convert`)");
  headPrefix_ = "ply\nformat binary_little_endian 1.0\n";
  for (const std::string& c : h.comments) {
    if (c.rfind("TextureFile", 0) == 0) throwBadInput(name_, "", "textured models have no streamed form");
    headPrefix_ += "comment " + c + "\n";
  }
  uint64_t fixedBody = 0;
  bool anyList = false;
  for (const ply::Element& pe : h.elements) {
    if (pe.name != "vertex" && pe.name != "segment")
      throwBadInput(name_, fmt::format("line {}", pe.line),
                    "element '" + pe.name + "': streamed reading takes vertex and segment elements only");
    Element e;
    e.name = pe.name;
    e.count = pe.count;
    for (const ply::Property& p : pe.properties) {
      if (p.isList) {
        e.properties += fmt::format("property list {} {} {}\n", ply::typeName(p.countType), ply::typeName(p.type), p.name);
        e.listAt.push_back(e.fixedBytes);
        e.listCountBytes.push_back(ply::typeSize(p.countType));
        e.listItemBytes.push_back(ply::typeSize(p.type));
        e.fixedBytes += size_t(ply::typeSize(p.countType));
      } else {
        e.properties += fmt::format("property {} {}\n", ply::typeName(p.type), p.name);
        e.fixedBytes += size_t(ply::typeSize(p.type));
      }
    }
    if (e.name == "vertex") points_ = e.count;
    else segments_ = e.count;
    fixedBody += e.count * e.fixedBytes;
    anyList |= !e.listAt.empty();
    elements_.push_back(std::move(e));
  }
  if (elements_.empty()) throwBadInput(name_, "", "no 'vertex' or 'segment' element (nothing to read as points)");
  bodyOffset_ = h.bodyOffset;
  if (size < bodyOffset_ + fixedBody)
    throwBadInput(name_, "", fmt::format("truncated: the header declares {} bytes of rows{}, the file holds {}", fixedBody,
                                         anyList ? " at least" : "", size - std::min<uintmax_t>(size, bodyOffset_)));
  f_ = std::fopen(name_.c_str(), "rb");
  if (!f_) throwBadInput(name_, "", std::string("cannot open: ") + std::strerror(errno));
  std::setvbuf(f_, nullptr, _IOFBF, size_t(1) << 20);
  rewind();
}

ModelChunkReader::~ModelChunkReader() {
  if (f_) std::fclose(f_);
}

void ModelChunkReader::rewind() {
  if (std::fseek(f_, long(bodyOffset_), SEEK_SET) != 0) throwBadInput(name_, "", "cannot seek in the file");
  element_ = 0;
  rowInElement_ = 0;
  pointsRead_ = segmentsRead_ = 0;
}

void ModelChunkReader::readRows(Element& e, uint64_t rows, std::string& out) {
  auto fail = [&] {
    throwBadInput(name_, fmt::format("{} {}", e.name, rowInElement_), "truncated (the file ends inside the rows)");
  };
  if (e.listAt.empty()) {
    const size_t n = size_t(rows) * e.fixedBytes, at = out.size();
    out.resize(at + n);
    if (std::fread(out.data() + at, 1, n, f_) != n) fail();
    return;
  }
  // Rows with lists: each row's scalar prefix, then its list items after each count.
  for (uint64_t r = 0; r < rows; ++r) {
    size_t from = 0;
    for (size_t l = 0; l <= e.listAt.size(); ++l) {
      const size_t to = l < e.listAt.size() ? e.listAt[l] + size_t(e.listCountBytes[l]) : e.fixedBytes;
      const size_t at = out.size();
      out.resize(at + (to - from));
      if (to > from && std::fread(out.data() + at, 1, to - from, f_) != to - from) fail();
      if (l < e.listAt.size()) {
        uint64_t count = 0;
        std::memcpy(&count, out.data() + out.size() - size_t(e.listCountBytes[l]), size_t(e.listCountBytes[l]));
        if (count > (uint64_t(1) << 24)) throwBadInput(name_, fmt::format("{} {}", e.name, rowInElement_ + r), "absurd list length");
        const size_t items = size_t(count) * size_t(e.listItemBytes[l]), at2 = out.size();
        out.resize(at2 + items);
        if (items && std::fread(out.data() + at2, 1, items, f_) != items) fail();
      }
      from = to;
    }
  }
}

bool ModelChunkReader::next(HybridModel& chunk, size_t maxRows) {
  chunk = HybridModel();
  while (element_ < elements_.size() && rowInElement_ >= elements_[element_].count) ++element_, rowInElement_ = 0;
  if (element_ >= elements_.size()) return false;
  Element& e = elements_[element_];
  const uint64_t rows = std::min<uint64_t>(std::max<size_t>(maxRows, 1), e.count - rowInElement_);
  buf_ = headPrefix_;
  for (const Element& o : elements_)
    buf_ += fmt::format("element {} {}\n", o.name, &o == &e ? rows : 0) + o.properties;
  buf_ += "end_header\n";
  readRows(e, rows, buf_);
  chunk = detail::plyToModel(buf_, name_, nullptr);
  rowInElement_ += rows;
  if (e.name == "vertex") pointsRead_ += rows;
  else segmentsRead_ += rows;
  return true;
}

}  // namespace linesurf
