// The tile folder's files and records (see tile_store.h; format in docs/file-format.md "Tile folder").
#include "ooc/tile_store.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>

#include "linesurf/core/error.h"

namespace linesurf::ooc::detail {

uint32_t floatBits(float f) {
  uint32_t u;
  std::memcpy(&u, &f, 4);
  return u;
}
float bitsFloat(uint32_t u) {
  float f;
  std::memcpy(&f, &u, 4);
  return f;
}

namespace {

struct ProofRecord {  // 64 bytes on disk, after the payload
  char magic[8];
  uint32_t stage, format;
  uint64_t input, args;
  uint32_t tile, folderVersion;
  uint64_t length, checksum, self;
};
static_assert(sizeof(ProofRecord) == kProofBytes);

ProofRecord expected(const Run& r, Stage stage, uint32_t tile) {
  ProofRecord p{};
  std::memcpy(p.magic, "LSPROOF1", 8);
  p.stage = uint32_t(stage), p.format = kProofFormat, p.input = r.inputHash, p.args = r.argsHash;
  p.tile = tile, p.folderVersion = uint32_t(kVersion);
  return p;
}

}  // namespace

std::string sealed(const Run& r, Stage stage, uint32_t tile, std::string payload) {
  ProofRecord p = expected(r, stage, tile);
  p.length = payload.size();
  p.checksum = hash64(payload.data(), payload.size(), uint64_t(stage));
  p.self = hash64(reinterpret_cast<const char*>(&p), offsetof(ProofRecord, self));
  putRaw(payload, p);
  return payload;
}

bool proven(const Run& r, Stage stage, uint32_t tile, const fs::path& path) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  bool ok = false;
  if (std::fseek(f, 0, SEEK_END) == 0) {
    const long size = std::ftell(f);
    ProofRecord p;
    if (size >= long(kProofBytes) && std::fseek(f, size - long(kProofBytes), SEEK_SET) == 0 &&
        std::fread(&p, 1, kProofBytes, f) == kProofBytes) {
      ProofRecord want = expected(r, stage, tile);
      want.length = uint64_t(size) - kProofBytes, want.checksum = p.checksum;
      want.self = hash64(reinterpret_cast<const char*>(&want), offsetof(ProofRecord, self));
      if (std::memcmp(&want, &p, kProofBytes) == 0 && std::fseek(f, 0, SEEK_SET) == 0) {
        Hasher x{uint64_t(stage)};
        std::vector<char> buf(1 << 20);
        uint64_t left = want.length;
        while (left > 0) {
          const size_t got = std::fread(buf.data(), 1, size_t(std::min<uint64_t>(left, buf.size())), f);
          if (got == 0) break;
          x.add(buf.data(), got), left -= got;
        }
        ok = left == 0 && x.finish() == p.checksum;
      }
    }
  }
  std::fclose(f);
  return ok;
}

void writeWhole(const fs::path& path, const std::string& bytes) {
  const fs::path tmp = path.string() + ".tmp";
  std::FILE* f = std::fopen(tmp.c_str(), "wb");
  if (!f) throwIo(tmp.string(), std::string("cannot create file: ") + std::strerror(errno));
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  const int e = errno;
  if (std::fclose(f) != 0 || !ok) {
    ::unlink(tmp.c_str());
    throwIo(path.string(), std::string("write failed: ") + std::strerror(ok ? errno : e));
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) throwIo(path.string(), std::string("rename failed: ") + std::strerror(errno));
}

void appendBytes(const fs::path& path, const char* data, size_t n) {
  std::FILE* f = std::fopen(path.c_str(), "ab");
  if (!f) throwIo(path.string(), std::string("cannot open: ") + std::strerror(errno));
  const bool ok = std::fwrite(data, 1, n, f) == n;
  const int e = errno;
  if (std::fclose(f) != 0 || !ok) throwIo(path.string(), std::string("write failed: ") + std::strerror(ok ? errno : e));
}

std::string readRange(const fs::path& path, uint64_t offset, uint64_t n) {
  std::string out(n, '\0');
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) throwIo(path.string(), std::string("cannot open: ") + std::strerror(errno));
  const bool ok = std::fseek(f, long(offset), SEEK_SET) == 0 && std::fread(out.data(), 1, n, f) == n;
  std::fclose(f);
  if (!ok) throwIo(path.string(), "tile file shorter than its manifest says (the folder was changed during the run?)");
  return out;
}

void decodeRecords(const std::string& bytes, bool normals, bool radius, size_t attrs, Points& out, bool keepAttrs) {
  const size_t rs = recordSize(normals, radius, attrs), n = bytes.size() / rs;
  const char* p = bytes.data();
  if (keepAttrs) out.att.reserve(out.att.size() + n * attrs);
  for (size_t i = 0; i < n; ++i) {
    out.idx.push_back(getRaw<uint64_t>(p));
    Vec3f v;
    std::memcpy(v.data(), p, 12), p += 12;
    out.pos.push_back(v);
    if (normals) {
      std::memcpy(v.data(), p, 12), p += 12;
      out.nrm.push_back(v);
    }
    if (radius) out.rad.push_back(getRaw<float>(p));
    if (keepAttrs) {
      const size_t at = out.att.size();
      out.att.resize(at + attrs);
      if (attrs) std::memcpy(out.att.data() + at, p, 4 * attrs);
    }
    p += 4 * attrs;
  }
}

namespace {

/// The refinement whose children include tile t (t at or above the grid's tiles).
const Refinement& refinementOf(const Run& r, uint32_t t) {
  auto it = std::upper_bound(r.refinements.begin(), r.refinements.end(), t,
                             [](uint32_t v, const Refinement& x) { return v < x.firstId; });
  if (it == r.refinements.begin() || t - (it - 1)->firstId >= (it - 1)->count())
    throwIo((r.dir / "manifest.json").string(), "tile " + std::to_string(t) + " belongs to no grid");
  return *(it - 1);
}

}  // namespace

uint32_t Run::tileOf(const Vec3f& p) const {
  uint32_t t = grid.tileOf(p);
  for (auto it = refinedOf.find(t); it != refinedOf.end(); it = refinedOf.find(t)) {
    const Refinement& x = refinements[it->second];
    t = x.firstId + x.grid.tileOf(p);
  }
  return t;
}

void Run::tileBox(uint32_t t, Vec3d& bmin, Vec3d& bmax) const {
  if (t < gridTiles()) return grid.box(t, bmin, bmax);
  const Refinement& x = refinementOf(*this, t);
  x.grid.box(t - x.firstId, bmin, bmax);
}

double Run::tileWidth(uint32_t t) const { return t < gridTiles() ? grid.width() : refinementOf(*this, t).grid.width(); }

uint32_t Run::gridAncestor(uint32_t t) const {
  while (t >= gridTiles()) t = refinementOf(*this, t).parent;
  return t;
}

fs::path Run::cellPath(uint32_t t) const { return dir / "cells" / fmt::format("cell_{:06d}.bin", t); }
fs::path Run::resultPath(uint32_t t) const { return dir / "results" / fmt::format("tile_{:06d}.res", t); }
fs::path Run::extractPath(uint32_t t) const { return dir / "results" / fmt::format("extract_{:06d}.res", t); }
fs::path Run::curvaturePath(uint32_t t) const { return dir / "results" / fmt::format("curv_{:06d}.res", t); }
fs::path Run::ownGeometryPath(uint32_t t) const { return dir / "results" / fmt::format("geom_{:06d}.bin", t); }

/// shared (halo) points per owner tile.
std::string encodeResult(const TileSummary& s, const std::vector<InteriorResult>& r, const std::vector<SideSummary>& sides,
                         const std::map<uint32_t, std::vector<SharedPoint>>& shared) {
  std::string b;
  b.append("LSTILE02", 8);
  putRaw(b, s);
  for (const InteriorResult& x : r) {
    putRaw(b, x.normal), putRaw(b, x.cover), putRaw(b, x.spacing), putRaw(b, x.component), putRaw(b, x.flags);
    b.append(3, '\0');
  }
  for (const SideSummary& side : sides) {
    putRaw(b, side.vote), putRaw(b, side.firstIndex), putRaw(b, side.firstNormal), putRaw(b, uint32_t(side.envelope.size()));
    for (const auto& e : side.envelope) putRaw(b, e.key), putRaw(b, e.value), putRaw(b, e.index), putRaw(b, e.vote);
  }
  putRaw(b, uint32_t(shared.size()));
  for (const auto& [owner, pts] : shared) {
    putRaw(b, owner), putRaw(b, uint32_t(pts.size()));
    for (const SharedPoint& p : pts) putRaw(b, p.index), putRaw(b, p.component), putRaw(b, p.normal);
  }
  return b;
}

ResultView decodeResultMeta(const std::string& b, const fs::path& path, bool withShared) {
  ResultView v;
  if (b.size() < 8 + sizeof(TileSummary) || b.compare(0, 8, "LSTILE02") != 0) throwIo(path.string(), "not a tile result file");
  const char* p = b.data() + 8;
  v.summary = getRaw<TileSummary>(p);
  v.interiorOffset = kResultHeader;
  p += size_t(v.summary.interior) * kResultRecord;
  auto need = [&](size_t bytes) {
    if (size_t(p - b.data()) + bytes > b.size()) throwIo(path.string(), "truncated tile result file");
  };
  v.sides.resize(v.summary.components);
  for (SideSummary& side : v.sides) {
    need(kSideRecord);
    side.vote = getRaw<int64_t>(p), side.firstIndex = getRaw<uint64_t>(p), side.firstNormal = getRaw<Vec3f>(p);
    const uint32_t entries = getRaw<uint32_t>(p);
    need(size_t(entries) * kSideEntryRecord);
    side.envelope.resize(entries);
    for (auto& e : side.envelope)
      e.key = getRaw<uint32_t>(p), e.value = getRaw<float>(p), e.index = getRaw<uint64_t>(p), e.vote = getRaw<int32_t>(p);
  }
  need(4);
  if (!withShared) return v;
  const uint32_t sections = getRaw<uint32_t>(p);
  for (uint32_t s = 0; s < sections; ++s) {
    const uint32_t owner = getRaw<uint32_t>(p), n = getRaw<uint32_t>(p);
    if (size_t(p - b.data()) + size_t(n) * kSharedRecord > b.size()) throwIo(path.string(), "truncated tile result file");
    auto& out = v.shared[owner];
    out.resize(n);
    for (SharedPoint& sp : out) sp.index = getRaw<uint64_t>(p), sp.component = getRaw<uint32_t>(p), sp.normal = getRaw<Vec3f>(p);
  }
  return v;
}

InteriorResult decodeInterior(const char* p) {
  InteriorResult r;
  r.normal = getRaw<Vec3f>(p), r.cover = getRaw<float>(p), r.spacing = getRaw<float>(p), r.component = getRaw<uint32_t>(p);
  r.flags = getRaw<uint8_t>(p);
  return r;
}

TileSummary readSummary(const fs::path& path) {
  TileSummary s;
  const std::string b = readRange(path, 8, sizeof(TileSummary));
  std::memcpy(&s, b.data(), sizeof s);
  return s;
}

namespace {

template <class T>
void putColumn(std::string& s, const std::vector<T>& v) {
  s.append(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

template <class T>
void getColumn(const std::string& s, size_t& at, size_t n, std::vector<T>& v, const fs::path& path) {
  if (at + n * sizeof(T) > s.size()) throwIo(path.string(), "tile geometry file is truncated");
  v.resize(n);
  if (n) std::memcpy(static_cast<void*>(v.data()), s.data() + at, n * sizeof(T));
  at += n * sizeof(T);
}

}  // namespace

std::string encodeOwnGeometry(const OwnGeometry& og) {
  std::string s = "LSGEO001";
  putRaw(s, uint64_t(og.size())), putRaw(s, uint64_t(og.star.size())), putRaw(s, uint8_t(!og.minDir.empty()));
  putColumn(s, og.idx), putColumn(s, og.pos), putColumn(s, og.normal), putColumn(s, og.radius), putColumn(s, og.spacing);
  putColumn(s, og.variation), putColumn(s, og.component), putColumn(s, og.flags), putColumn(s, og.minDir);
  putColumn(s, og.maxDir), putColumn(s, og.starOffsets), putColumn(s, og.star), putColumn(s, og.attrs);
  return s;
}

OwnGeometry decodeOwnGeometry(const fs::path& path, size_t attrFloats) {
  const uint64_t size = fs::file_size(path);
  if (size < kProofBytes) throwIo(path.string(), "not a tile geometry file");
  const std::string s = readRange(path, 0, size - kProofBytes);
  if (s.size() < 25 || s.compare(0, 8, "LSGEO001") != 0) throwIo(path.string(), "not a tile geometry file");
  const char* q = s.data() + 8;
  const uint64_t m = getRaw<uint64_t>(q), stars = getRaw<uint64_t>(q);
  const bool curvature = getRaw<uint8_t>(q) != 0;
  if (m > s.size() || stars > s.size()) throwIo(path.string(), "tile geometry file is damaged");
  size_t at = 25;
  OwnGeometry og;
  getColumn(s, at, m, og.idx, path), getColumn(s, at, m, og.pos, path), getColumn(s, at, m, og.normal, path);
  getColumn(s, at, m, og.radius, path), getColumn(s, at, m, og.spacing, path), getColumn(s, at, m, og.variation, path);
  getColumn(s, at, m, og.component, path), getColumn(s, at, m, og.flags, path);
  getColumn(s, at, curvature ? m : 0, og.minDir, path), getColumn(s, at, curvature ? m : 0, og.maxDir, path);
  getColumn(s, at, m + 1, og.starOffsets, path), getColumn(s, at, stars, og.star, path);
  getColumn(s, at, m * attrFloats, og.attrs, path);
  if (at != s.size() || og.starOffsets.back() != stars) throwIo(path.string(), "tile geometry file is damaged");
  for (size_t j = 0; j < m; ++j)
    if (og.starOffsets[j] > og.starOffsets[j + 1]) throwIo(path.string(), "tile geometry file is damaged");
  for (uint32_t v : og.star)
    if (v >= m) throwIo(path.string(), "tile geometry file is damaged");
  return og;
}

void writeOrientation(const Run& r, const std::vector<size_t>& nodeOffset, const std::vector<uint8_t>& flip, float avg) {
  std::string b;
  putRaw(b, uint64_t(nodeOffset.size()));
  for (size_t v : nodeOffset) putRaw(b, uint64_t(v));
  b.append(reinterpret_cast<const char*>(flip.data()), flip.size());
  putRaw(b, avg);
  writeWhole(r.orientationPath(), sealed(r, Stage::Orientation, 0, std::move(b)));
}

void readOrientation(const Run& r, std::vector<size_t>& nodeOffset, std::vector<uint8_t>& flip, float& avg) {
  const fs::path p = r.orientationPath();
  if (!proven(r, Stage::Orientation, 0, p)) throwIo(p.string(), "the orientation file is not this run's (changed during the run?)");
  const std::string b = readRange(p, 0, fs::file_size(p));
  const char* q = b.data();
  nodeOffset.resize(size_t(getRaw<uint64_t>(q)));
  for (size_t& v : nodeOffset) v = size_t(getRaw<uint64_t>(q));
  flip.assign(q, q + nodeOffset.back());
  q += nodeOffset.back();
  avg = getRaw<float>(q);
}

}  // namespace linesurf::ooc::detail
