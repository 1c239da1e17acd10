#pragma once
// Byte layout of .lod files (docs/file-format.md, "Level-of-detail hierarchy (.lod)"), shared by
// the writer and the reader. Little-endian; every record is written field by field.
#include <bit>
#include <cstdint>
#include <cstring>
#include <string>

#include "linesurf/core/model.h"

namespace linesurf::lod::format {

static_assert(std::endian::native == std::endian::little, "the .lod layout is little-endian");

inline constexpr char kMagic[8] = {'L', 'I', 'N', 'E', 'S', 'L', 'O', 'D'};
inline constexpr char kBlockMagic[8] = {'L', 'S', 'L', 'O', 'D', 'N', 'D', '1'};
inline constexpr uint32_t kVersion = 2;  // written; version 1 (no table checksum) is still read
inline constexpr uint32_t kOldestVersion = 1;
inline constexpr size_t kPreambleBytes = 32;  // magic, version u32, json bytes u32, id u64, nodes u64
inline constexpr size_t kRecordBytes = 88;
// Version 2: the table is followed by lodChecksum of every byte before it (preamble, JSON with the
// id filled in, table), so that an edited bound, count or flag is refused, not drawn.
inline constexpr size_t kTableChecksumBytes = 8;
/// Bytes between the table's end and the first block, by format version.
inline constexpr uint64_t tableTrailerBytes(uint32_t version) { return version >= 2 ? kTableChecksumBytes : 0; }
inline constexpr size_t kBlockHeaderBytes = 32;  // magic, id u64, node u32, points u32, segments u32, 0 u32
inline constexpr size_t kPointBytes = 64;
inline constexpr size_t kSegmentBytes = 100;

inline void put(std::string& out, const void* p, size_t n) { out.append(static_cast<const char*>(p), n); }
template <class T>
void put(std::string& out, T v) {
  put(out, &v, sizeof v);
}
inline void putVec(std::string& out, const Vec3f& v) {
  for (int k = 0; k < 3; ++k) put(out, v[k]);
}
template <class T>
T get(const char* p) {
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}
inline Vec3f getVec(const char* p) { return Vec3f(get<float>(p), get<float>(p + 4), get<float>(p + 8)); }

inline void putPoint(std::string& out, const Point& pt, const Vec3f& shading, float mass, uint32_t index) {
  putVec(out, pt.position);
  putVec(out, pt.normal);
  putVec(out, shading);
  for (int k = 0; k < 4; ++k) put(out, pt.color[k]);
  put(out, pt.radius);
  put(out, mass);
  put(out, index);
}
inline void getPoint(const char* p, Point& pt, Vec3f& shading, float& mass, uint32_t& index) {
  pt.position = getVec(p);
  pt.normal = getVec(p + 12);
  shading = getVec(p + 24);
  for (int k = 0; k < 4; ++k) pt.color[k] = get<float>(p + 36 + 4 * k);
  pt.radius = get<float>(p + 52);
  mass = get<float>(p + 56);
  index = get<uint32_t>(p + 60);
}
inline void putSegment(std::string& out, const Segment& s, uint32_t index) {
  putVec(out, s.p0);
  putVec(out, s.p1);
  putVec(out, s.normal);
  putVec(out, s.normal0);
  putVec(out, s.normal1);
  for (int k = 0; k < 4; ++k) put(out, s.color[k]);
  put(out, s.radius);
  put(out, s.uv0.x()), put(out, s.uv0.y()), put(out, s.uv1.x()), put(out, s.uv1.y());
  put(out, index);
}
inline void getSegment(const char* p, Segment& s, uint32_t& index) {
  s.p0 = getVec(p);
  s.p1 = getVec(p + 12);
  s.normal = getVec(p + 24);
  s.normal0 = getVec(p + 36);
  s.normal1 = getVec(p + 48);
  for (int k = 0; k < 4; ++k) s.color[k] = get<float>(p + 60 + 4 * k);
  s.radius = get<float>(p + 76);
  s.uv0 = Vec2f(get<float>(p + 80), get<float>(p + 84));
  s.uv1 = Vec2f(get<float>(p + 88), get<float>(p + 92));
  index = get<uint32_t>(p + 96);
}

}  // namespace linesurf::lod::format
