#pragma once
// The pieces of the hierarchy build (src/lod/lod_build.cpp) shared by the in-memory build and the
// streamed one (lod_stream_build.cpp), so that both write the same bytes for the same model.
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "linesurf/lod/lod.h"

namespace linesurf::lod::detail {

constexpr int kMaxLevel = 21;  // 21 bits per axis in the 63-bit Morton key

/// The Morton key of `p` quantised in the root cube (rootMin, side).
uint64_t mortonKey(const Vec3f& p, const Vec3f& rootMin, float side);
/// The root cube of the key positions' bounds: {min corner, side}.
std::pair<Vec3f, float> rootCube(Bounds3f keyBounds);

struct BNode {
  size_t begin = 0, end = 0;  // range of the sorted keys
  int level = 0;
  Vec3f cubeMin = Vec3f::Zero();
  float side = 0;
  uint32_t firstChild = 0;
  uint8_t childCount = 0;
  bool leaf = false;
  Bounds3f bounds;
};

/// Splits nodes[from..] breadth first over the sorted (key, index) pairs (children contiguous,
/// after their parent, in octant order; a node of at most leafSize keys is a leaf).
void splitBreadthFirst(std::vector<BNode>& nodes, size_t from, const std::vector<std::pair<uint64_t, uint32_t>>& keys,
                       int leafSize);
/// The child of `parent` in octant o (0..7).
BNode childCube(const BNode& parent, uint32_t octant);

NodeData mergeChildren(const std::vector<const NodeData*>& children, const Vec3f& cubeMin, float side, int grid,
                       bool shading);
std::string serializeBlock(const NodeData& d, uint32_t node, bool shading);
/// A node block's header (its records follow).
std::string blockHeader(uint32_t node, uint32_t points, uint32_t segments);
Bounds3f contentBounds(const NodeData& d);
Bounds3f unite(Bounds3f a, const Bounds3f& b);
void extendPoint(Bounds3f& b, const Vec3f& p, float r);

/// What the header records of a hierarchy.
struct HeaderFacts {
  uint64_t points = 0, segments = 0;
  uint32_t nodes = 0;
  int depth = 0;
  ModelFrame frame;
  BoundingSphere sphere;
  float maxRadius = 0;
  Attributes attributes;
  bool shading = false, masses = false;
  std::string upAxis;  ///< the model's recorded up axis ("z" for LAS), empty when none
};
/// The JSON part of the header, padded so that the table starts 8-aligned, and where the
/// hierarchy id's placeholder is in the file.
struct HeaderJson {
  std::string json;
  size_t idAt = 0;
};
/// Throws Error (BadInput, naming `path`) for facts the readers would refuse (validateHeader).
HeaderJson headerJson(const HeaderFacts& facts, const BuildOptions& options, const std::string& path);
/// The hierarchy id from the blocks' checksums (id field zero) and the build parameters.
uint64_t hierarchyId(std::vector<uint64_t> sums, const BuildOptions& options);
/// The file's first bytes: preamble, JSON (id filled in) and node table.
std::string headerBytes(const HeaderJson& hj, uint64_t id, const std::vector<BNode>& nodes,
                        const std::vector<uint64_t>& offsets, const std::vector<uint64_t>& sizes,
                        const std::vector<uint64_t>& sums, const std::vector<uint32_t>& nPoints,
                        const std::vector<uint32_t>& nSegments);

}  // namespace linesurf::lod::detail
