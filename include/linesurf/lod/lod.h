#pragma once
/// A level-of-detail hierarchy of a hybrid point + line-segment model (beyond the thesis; the
/// splatting of §4-§6.2 drawn from a bounded number of primitives a frame, as point viewers do
/// with octrees). An octree over the points and the segments (a segment lives where its midpoint
/// lies); leaves hold the original primitives with their indices, inner nodes hold coarser
/// representatives of their subtree: the points and short segments of each cell of a grid over
/// the node merged into one splat whose radius covers them, segments still longer than the
/// grid's spacing kept whole. The file layout (one file, header + node table + one contiguous
/// block per node) is in docs/file-format.md, "Level-of-detail hierarchy (.lod)".
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/renderer.h"

namespace linesurf::lod {

struct BuildOptions {
  /// A node with at most this many primitives is a leaf, [16, 1 << 20].
  int leafSize = 4096;
  /// An inner node merges its subtree into the cells of a grid x grid x grid grid over its cube,
  /// [2, 256]: at most one merged point a cell (the node's spacing is side / grid).
  int grid = 32;
};
void validate(const BuildOptions& options);  ///< throws BadParameter

struct BuildReport {
  uint64_t primitives = 0;       ///< original points + segments (all in the leaves)
  uint64_t representatives = 0;  ///< primitives of the inner nodes
  uint32_t nodes = 0, leaves = 0, depth = 0;
  uint64_t bytes = 0;
  uint64_t hierarchyId = 0;
  uint32_t chunks = 0;  ///< subtrees built one at a time (buildLodStreaming)
};

/// Builds the hierarchy of `model` into the bytes of a .lod file. `model` must already be in its
/// rendering frame and prepared for rendering (radii and normals; pipeline/render_job.h), as
/// `linesurf render` would draw it: the file stores `frame` and the model's bounding sphere so
/// that a render of every leaf is today's render of the model. Textures, provenance and point
/// properties other than the point mass are not kept. Deterministic for any thread count.
std::string buildLod(const HybridModel& model, const ModelFrame& frame, const BuildOptions& options = {},
                     BuildReport* report = nullptr);

/// How buildLodStreaming may use memory and disk.
struct StreamBuildOptions {
  /// Resident bytes the build aims to stay within (it sizes its subtrees to a third of it; a
  /// subtree of one top cell that alone exceeds it is still built whole).
  double memoryBytes = 1.5e9;
  /// Where its working files go (about the model's size again, removed at the end); empty: the
  /// output's folder.
  std::filesystem::path workDir;
  ProgressFn progress;
};

/// buildLod for a model file too large to hold: reads `input` (binary little-endian PLY of points
/// and segments that carry every normal and radius, as `linesurf extract` writes them; see
/// io/model_stream.h) in chunks, moves it into its normalising frame (io/model_frame.h) and
/// writes the .lod file at `output` (atomically). The file is byte for byte the one buildLod
/// makes from the same model read whole, framed and prepared. Throws Error (BadInput) for a
/// model whose primitives lack normals or radii, Error (Io) when the disk is full.
BuildReport buildLodStreaming(const std::filesystem::path& input, const std::filesystem::path& output,
                              const BuildOptions& options, const StreamBuildOptions& streamOptions);

/// One node of the table.
struct NodeInfo {
  uint64_t offset = 0, size = 0;  ///< byte range of the node's block in the file
  uint64_t checksum = 0;          ///< of the block's bytes (lodChecksum)
  Vec3f cubeMin = Vec3f::Zero();
  float side = 0;
  /// Box holding the subtree's primitives with their radii (segments reach out of the cube)
  Vec3f boundsMin = Vec3f::Zero(), boundsMax = Vec3f::Zero();
  uint32_t points = 0, segments = 0;
  uint32_t firstChild = 0;  ///< children are contiguous in the table
  uint8_t childCount = 0, level = 0;
  bool leaf = false;
  uint64_t count() const { return uint64_t(points) + segments; }
};

struct LodHeader {
  uint64_t hierarchyId = 0;
  uint32_t version = 0;  ///< the file's format version (1 has no node-table checksum)
  ModelFrame frame;
  BoundingSphere sphere;  ///< of the whole prepared model, in the rendering frame
  float maxRadius = 0;    ///< largest primitive radius (part of sphere.radius)
  Attributes attributes;
  bool pointMasses = false;  ///< the original points carry masses
  std::string upAxis;        ///< the model's recorded up axis (x, y or z; "z" for LAS), empty when none
  uint64_t points = 0, segments = 0;
  BuildOptions options;
};

/// The primitives of one node. Leaves: the originals with their indices in the model (points
/// and segments counted separately); inner nodes: representatives (index kNoIndex).
struct NodeData {
  std::vector<Point> points;
  std::vector<Vec3f> shadingNormals;  ///< one per point when the header's attributes have them
  std::vector<float> masses;          ///< one per point
  std::vector<uint32_t> pointIndex;
  std::vector<Segment> segments;
  std::vector<uint32_t> segmentIndex;
};
inline constexpr uint32_t kNoIndex = 0xffffffffu;

/// The one validation of a hierarchy, run by every reader (LodFile: render, view, Python, info)
/// before anything is sized from the file: the header's values (a power-of-two frame scale, a
/// bounding sphere the cameras can frame: radius in [2^-30, 2^21], centre within 2^11 max(1, radius)
/// of the origin, as the normalising frame leaves every model; finite maximum radius; primitive
/// counts; build parameters in range) and the node table against itself and the header: one tree
/// (every node but the root the child of exactly one node, one level below it, in its own octant
/// of its parent's cube, its box inside its parent's), block sizes that match their counts, blocks
/// that start after the table (`blocksBegin`) and do not overlap, leaves that add up to the
/// header's counts. Throws Error (BadInput, "PATH: WHERE: WHAT", WHERE "header", "node I" or
/// "node table"). Blocks themselves are checked when read (LodFile::readBlock).
void validateHierarchy(const LodHeader& header, const std::vector<NodeInfo>& nodes, uint64_t blocksBegin,
                       const std::string& path);
/// The header's part of validateHierarchy; the writers run it on what they are about to write,
/// so that nothing is written that the readers refuse.
void validateHeader(const LodHeader& header, const std::string& path);

/// A .lod file opened for reading nodes by byte range.
class LodFile {
 public:
  /// Reads the header and the node table and validates them (validateHierarchy); throws Error
  /// (BadInput) when they are not a valid hierarchy. A node's block is only checked when read; a
  /// block that lies past the file's end (a truncated file) is a node that fails to load.
  explicit LodFile(const std::filesystem::path& path);
  const LodHeader& header() const { return header_; }
  const std::vector<NodeInfo>& nodes() const { return nodes_; }
  const std::filesystem::path& path() const { return path_; }
  uint64_t fileBytes() const { return fileSize_; }
  /// Whether node `i`'s block lies within the file (else reading it fails: nothing is sized by
  /// its counts).
  bool inFile(uint32_t i) const {
    return i < nodes_.size() && nodes_[i].size <= fileSize_ && nodes_[i].offset <= fileSize_ - nodes_[i].size;
  }
  /// Reads node `i`'s block. Throws Error (BadInput, WHERE = "node i") when it is missing or
  /// truncated, belongs to another hierarchy, or does not match its checksum.
  NodeData readNode(uint32_t i) const;
  /// Reads node `i`'s block into `buf` (grown as needed) and checks it as readNode does, indices
  /// and masses included.
  void readBlock(uint32_t i, std::vector<char>& buf) const;

 private:
  std::filesystem::path path_;
  LodHeader header_;
  std::vector<NodeInfo> nodes_;
  uint64_t fileSize_ = 0;
};

/// Whether `path` starts with the .lod magic (false when it cannot be read).
bool isLodFile(const std::filesystem::path& path);

/// The nodes drawn for a view: a cut through the tree (every original primitive stands for
/// itself or through exactly one selected ancestor), refined coarse to fine, largest projected
/// node first (so closest first), while the total stays within the budget. With a budget at
/// least the model's primitive count every leaf is selected (frustum culling included: the
/// picture is then the full model's). Otherwise nodes wholly outside the view are dropped, and
/// the root is drawn even when it alone exceeds the budget.
struct Selection {
  std::vector<uint32_t> nodes;  ///< ascending
  uint64_t primitives = 0;      ///< their point + segment count
};
Selection selectNodes(const LodFile& file, const Camera& camera, uint64_t budget);

/// One frame of a hierarchy: the selected nodes' primitives as one model (originals first, in
/// model order when every leaf is selected, else in node order; then representatives in node
/// order), and the nodes that failed to load (their primitives left out).
struct Assembled {
  HybridModel model;
  std::vector<std::string> failures;  ///< one "PATH: node N: WHAT" line per failed node
  uint32_t representativeNodes = 0;
};
/// radiusScale multiplies every radius (render --radius-scale).
Assembled assemble(const LodFile& file, const Selection& selection, float radiusScale = 1);

/// Renders hierarchies with a budget through the public Renderer.
struct LodFrameResult {
  RenderResult render;
  Selection selection;
  std::vector<std::string> failures;
  double selectSeconds = 0, loadSeconds = 0;
};
class LodRenderer {
 public:
  LodRenderer(const LodFile& file, const RenderOptions& options, uint64_t budget, float radiusScale = 1);
  /// The whole model's bounding sphere (in the rendering frame, radius scaled): frame views on it.
  BoundingSphere sphere() const;
  LodFrameResult render(const Camera& camera) const;

 private:
  const LodFile& file_;
  RenderOptions options_;
  uint64_t budget_;
  float radiusScale_;
};

/// The 64-bit checksum of node blocks (four FNV-1a-like lanes over little-endian 64-bit words).
uint64_t lodChecksum(const void* data, size_t bytes);

}  // namespace linesurf::lod
