#pragma once
/// Reading a point or hybrid model too large to hold, in chunks of rows. Each chunk is decoded by
/// the whole-file PLY reader (io/model_io.h) from the chunk's rows under the file's own header,
/// so a chunk holds exactly what readModel gives for those rows: the same acceptance rules,
/// attributes and values, and the chunks of a file, concatenated, are readModel's model. Binary
/// little-endian PLY with a vertex and/or a segment element (the outputs of `linesurf extract`
/// and of the out-of-core path); meshes and textured models are refused.
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "linesurf/core/model.h"

namespace linesurf {

class ModelChunkReader {
 public:
  /// Opens `path` and checks its header; throws Error (BadInput) naming the file when it is not a
  /// binary little-endian PLY of points and segments, or when its body is shorter than declared.
  explicit ModelChunkReader(const std::filesystem::path& path);
  ~ModelChunkReader();
  ModelChunkReader(const ModelChunkReader&) = delete;
  ModelChunkReader& operator=(const ModelChunkReader&) = delete;

  uint64_t points() const { return points_; }
  uint64_t segments() const { return segments_; }
  /// The next at most `maxRows` rows as a model (vertex rows first, then segment rows; a chunk
  /// holds rows of one element). Returns false, with `chunk` empty, at the end.
  bool next(HybridModel& chunk, size_t maxRows);
  /// Back to the first row.
  void rewind();
  /// Points and segments returned so far (the model index of the next chunk's first primitive).
  uint64_t pointsRead() const { return pointsRead_; }
  uint64_t segmentsRead() const { return segmentsRead_; }

 private:
  struct Element {
    std::string name;
    uint64_t count = 0;
    std::string properties;         ///< the header's property lines
    size_t fixedBytes = 0;          ///< bytes of a row without list items (the row size without lists)
    std::vector<int> listCountBytes;  ///< per list property: bytes of its count, then item bytes
    std::vector<int> listItemBytes;
    std::vector<size_t> listAt;     ///< byte offset of each list count within the scalar prefix
  };
  void readRows(Element& e, uint64_t rows, std::string& out);

  std::filesystem::path path_;
  std::string name_;
  std::FILE* f_ = nullptr;
  std::string headPrefix_;  ///< "ply", format, comments
  std::vector<Element> elements_;
  uint64_t bodyOffset_ = 0;
  size_t element_ = 0;
  uint64_t rowInElement_ = 0;
  uint64_t points_ = 0, segments_ = 0, pointsRead_ = 0, segmentsRead_ = 0;
  std::string buf_;
};

}  // namespace linesurf
