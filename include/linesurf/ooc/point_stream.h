#pragma once
/// Streaming point I/O for clouds larger than memory: a reader that passes a binary PLY or XYZ
/// file through in chunks, and a binary PLY writer that writes rows as they come and puts the
/// file in place only when complete. The whole-file readers of io/model_io.h stay for models
/// that fit; these handle only what the out-of-core pipeline needs: points with x y z, optionally
/// nx ny nz and radius, and the attributes the whole-file reader keeps (colour and further scalar
/// properties such as intensity or class), as the same floats it makes of them. Errors are the
/// whole-file readers' (linesurf::Error, `PATH: WHERE: WHAT`).
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <memory>
#include <vector>

#include "linesurf/io/atomic_file.h"

#include "linesurf/core/math.h"

namespace linesurf::ooc {

/// What a streamed point file holds.
struct PointFileInfo {
  uint64_t count = 0;                 ///< points
  bool normals = false;               ///< nx ny nz present
  bool radius = false;                ///< radius present (binary PLY)
  /// red green blue and/or alpha present (binary PLY): a point's colour is 4 floats in [0, 1]
  /// as readModel makes them (channel / the type's maximum; a missing channel 1).
  bool colors = false;
  /// The further scalar vertex properties (binary PLY), sorted by name as HybridModel's
  /// pointProperties holds them: one float each.
  std::vector<std::string> properties;
  /// Floats of a point's attributes: the colour (4, when `colors`), then `properties`.
  size_t attributeFloats() const { return (colors ? 4 : 0) + properties.size(); }
  std::vector<std::string> comments;  ///< kept like the whole-file reader keeps them
  std::string header;                 ///< the PLY header bytes (empty for XYZ), for identity hashes
};

class PointReader {
 public:
  /// Opens `path` (.ply binary little-endian, or .xyz) and checks its header and size: a
  /// truncated binary body is reported here, before any work. An XYZ file is read through once
  /// to count and validate its points.
  explicit PointReader(const std::filesystem::path& path);
  ~PointReader();
  PointReader(const PointReader&) = delete;
  PointReader& operator=(const PointReader&) = delete;

  const PointFileInfo& info() const { return info_; }
  /// Reads up to `max` points from the current position (positions into `pos`, normals into
  /// `nrm`, radii into `*rad` and attributes into `*attrs`, info().attributeFloats() a point,
  /// when the file has them; each resized to the number read, or emptied). Returns 0 at the end.
  size_t read(std::vector<Vec3f>& pos, std::vector<Vec3f>& nrm, size_t max, std::vector<float>* rad = nullptr,
              std::vector<float>* attrs = nullptr);
  /// Back to the first point.
  void rewind();
  /// Index of the next point read().
  uint64_t position() const { return next_; }

 private:
  void openBody();
  size_t readPly(std::vector<Vec3f>& pos, std::vector<Vec3f>& nrm, size_t max, std::vector<float>* rad,
                 std::vector<float>* attrs);
  size_t readXyz(std::vector<Vec3f>& pos, std::vector<Vec3f>& nrm, size_t max);

  std::string path_;
  std::FILE* f_ = nullptr;
  PointFileInfo info_;
  bool ply_ = true;
  // PLY layout
  uint64_t bodyOffset_ = 0;
  size_t rowSize_ = 0;
  struct Field { size_t offset; int type; const char* name; };
  std::vector<Field> fields_;  ///< x y z [nx ny nz]
  Field radius_{0, 0, "radius"};
  /// The attributes in PointFileInfo's order: colour channels (type -1: absent, 1) and properties;
  /// `scale` divides the value (the colour channel rule of the whole-file reader).
  struct AttrField { Field field; float scale; };
  std::vector<AttrField> attrs_;
  std::vector<char> buf_;
  // XYZ state
  std::string pending_;
  uint64_t line_ = 0;
  int columns_ = 0;
  bool eof_ = false;
  bool counted_ = false;  ///< comments are collected on the first (counting) pass only
  uint64_t next_ = 0;
};

/// Writes a binary little-endian PLY of points with x y z [nx ny nz] [red green blue alpha]
/// [radius] [further float properties], row by row, byte for byte as io/model_io.h's writeModel
/// writes the same points. The rows go to a
/// temporary file beside `path` (io/atomic_file.h: removed on signals too); finish() puts it in
/// place, or stages it in the command's transaction, once every declared row is written;
/// destroying an unfinished writer removes it, so no partial output is ever left.
class PlyPointWriter {
 public:
  /// `moreElements`: header lines of elements after the vertices (e.g. "element segment N\n
  /// property ..."), whose rows follow through writeRaw() once every vertex row is written.
  /// `extra`: names of further float vertex properties after radius (written through write()'s
  /// `extra` rows), in the order writeModel writes them (sorted). `colors`: uchar red green blue
  /// alpha after the normals, from write()'s `colors` rows (4 floats in [0, 1] a point).
  PlyPointWriter(const std::filesystem::path& path, uint64_t count, const std::vector<std::string>& comments,
                 bool normals, bool radius, const std::string& moreElements = "",
                 const std::vector<std::string>& extra = {}, bool colors = false);
  ~PlyPointWriter();
  PlyPointWriter(const PlyPointWriter&) = delete;
  PlyPointWriter& operator=(const PlyPointWriter&) = delete;
  /// Appends n rows (nrm / radius ignored when the file has none).
  void write(const Vec3f* pos, const Vec3f* nrm, const float* radius, size_t n, const float* extra = nullptr,
             const float* colors = nullptr);
  /// Rows of the further elements, already encoded.
  void writeRaw(const std::string& bytes);
  void finish();

 private:
  void put(const char* data, size_t n);
  std::string path_;
  std::unique_ptr<AtomicFileWriter> out_;
  std::string buf_;
  uint64_t count_ = 0, written_ = 0;
  bool normals_ = false, radius_ = false, colors_ = false;
  size_t extra_ = 0;
  std::string row_;
};

/// Identity of an input for a tile folder: size, modification time and a 64-bit hash of the
/// header and of 16 evenly spaced 64 KiB chunks (so a rewritten file of the same size is told
/// apart without reading all of it).
struct FileIdentity {
  uint64_t size = 0;
  int64_t mtimeNs = 0;
  uint64_t hash = 0;
  bool operator==(const FileIdentity&) const = default;
};
FileIdentity fileIdentity(const std::filesystem::path& path);

/// FNV-1a, 64 bit.
uint64_t fnv1a(const void* data, size_t n, uint64_t h = 1469598103934665603ull);

}  // namespace linesurf::ooc
