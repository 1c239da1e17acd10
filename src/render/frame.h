#pragma once
/// One frame of the splatting pipeline (thesis §6.2; renderer.h): the layout and buffers its stages
/// share, and the stages in the order a frame runs them (Renderer::render, renderer.cpp):
///  1. prepare (frame_prepare.cpp): every primitive culled, transformed, warped, clipped and lit,
///     in parallel (points: point_setup.h, §4.2.2; segments: segment_setup.h, §5), and counted per
///     screen tile its bounds touch;
///  2. bin (frame_bin.cpp): every visible primitive listed in each tile it touches, in primitive
///     order (points, then segments): the image does not depend on the threads;
///  3. rasterise a tile (frame_tile.cpp): its primitives' fragments into a Z^3 tile (z3_buffer.h,
///     §6.2.3; point_rows.h, segment_rows.h), tiles in parallel;
///  4. resolve the tile (frame_tile.cpp; resolve.h): its layers back to front over the background;
/// then the beyond-thesis passes over the whole frame, each in a room of its own: silhouette
/// coverage (silhouette_coverage.h) and tail coverage (tail_coverage.h). Internal to src/render.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <mutex>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#include "linesurf/core/model.h"
#include "linesurf/render/render_stats.h"
#include "point_setup.h"
#include "segment_setup.h"
#include "segment_lod.h"
#include "segment_splat.h"
#include "silhouette_coverage.h"
#include "splat_context.h"
#include "tail_coverage.h"

namespace linesurf::detail {

/// The screen tiles a primitive touches: columns x0 .. x1, rows y0 .. y1 (inclusive).
struct TileSpan {
  uint16_t x0, y0, x1, y1;
};

/// Storage for up to capacity() objects of T that the user constructs slot by slot (placement
/// new; T is trivially destructible): a first frame touches, and so faults in, only the pages of
/// the slots it writes. (Transparent huge pages were tried: direct compaction made the first
/// frame of the dragon 6x slower.)
template <class T>
class SlotBuffer {
  static_assert(std::is_trivially_destructible_v<T>);

 public:
  SlotBuffer() = default;
  SlotBuffer(const SlotBuffer&) = delete;
  SlotBuffer& operator=(const SlotBuffer&) = delete;
  ~SlotBuffer() { std::free(data_); }
  /// Makes room for n slots (the contents are lost when the buffer grows).
  void reserve(size_t n) {
    if (n <= capacity_) return;
    std::free(data_);
    data_ = nullptr, capacity_ = 0;
    const size_t align = std::max<size_t>(64, alignof(T));
    const size_t bytes = (n * sizeof(T) + align - 1) / align * align;
    data_ = static_cast<T*>(std::aligned_alloc(align, bytes));
    if (!data_) throw std::bad_alloc();
    capacity_ = n;
  }
  T* data() const { return data_; }
  size_t capacity() const { return capacity_; }

 private:
  T* data_ = nullptr;
  size_t capacity_ = 0;
};

/// Per-frame buffers, kept from one frame to the next (no allocation, page faults or zeroing of
/// the prepared primitives per frame); one render() at a time uses them, a concurrent one its own.
struct FrameBuffers {
  std::mutex mutex;
  SlotBuffer<PreparedPoint> pts;      ///< point slots' hot records: per chunk, its visible points first
  SlotBuffer<PixelRect> pointBounds;  ///< the point slots' screen bounds
  SlotBuffer<PointCold> pointCold;    ///< the point slots' normals and indices
  SlotBuffer<PointGouraud> gouraud;   ///< the Gouraud colours of the point slots that need them
  std::vector<TileSpan> pointTiles;   ///< tiles each point slot touches
  std::vector<PreparedSegment> segs;
  std::vector<PrimitiveStatus> segStatus;
  std::vector<TileSpan> segTiles;     ///< tiles each visible segment touches (dense: binning reads no record)
  /// Segment level of detail (RenderOptions::segmentLod): per segment slot, whether it is drawn as
  /// the point splat in the lod* slots below (same slot), not as a segment
  std::vector<uint8_t> segLod;
  SlotBuffer<PreparedPoint> lodPts;
  SlotBuffer<PixelRect> lodBounds;
  SlotBuffer<PointCold> lodCold;
  SlotBuffer<PointGouraud> lodGouraud;
  std::vector<uint32_t> chunkVisible;
  std::vector<double> chunkSeconds;   ///< thread CPU time per chunk (prepare, then binning)
  std::vector<PointSetupCounts> chunkCounts;
  std::vector<uint32_t> counts;       ///< per chunk and tile: bins
  std::vector<size_t> tileStart, offset;
  std::vector<uint32_t> refs;         ///< tile lists: point slot, or pointSlots + segment index
  /// Coverage at silhouettes only (RenderOptions::coverageReach): the front depths of the frame,
  /// and per tile its partly covered pixels (silhouette_coverage.h)
  std::vector<float> frontZ;
  std::vector<std::vector<SilhouettePixel>> silhouette;
  std::vector<uint8_t> partial;  ///< 1 where a pixel's front layer is partly covered
  /// Tail coverage (RenderOptions::tailCoverage): 1 where a pixel holds a layer, and per tile its
  /// tail-only pixels with their faded alpha (tail_coverage.h)
  std::vector<uint8_t> covered;
  std::vector<std::vector<TailPixel>> tailPixels;

  /// The point slots (prepared points) and the segment level of detail's point slots.
  PointSlots pointSlots() const { return {pts.data(), pointBounds.data(), pointCold.data(), gouraud.data()}; }
  PointSlots lodSlots() const { return {lodPts.data(), lodBounds.data(), lodCold.data(), lodGouraud.data()}; }
};

/// What the renderer knows of a model before any frame (Renderer's members): the beyond-thesis
/// modes' inputs.
struct ModelFacts {
  /// coverage alpha: the primitives' coverage constants (points, then segments; coverage.h), and
  /// their largest (0: coverage alpha off)
  const float* coverage = nullptr;
  float coverageMax = 0;
  /// tail coverage: the model's median coverage constant
  float tailCoverageC = 0;
  /// every primitive opaque (no colour alpha < 1, no texture)
  bool opaque = true;
};

/// The layout of one frame: its tiles, the prepare stage's chunks and slots, and which
/// beyond-thesis modes are on.
struct FramePlan {
  int tileSize = 0, tilesX = 0, tilesY = 0;
  /// tileSize's log2 when a power of two (the default), else -1
  int tileShift = -1;
  size_t tiles = 0;
  size_t np = 0, ns = 0;  ///< the model's points and segments
  /// Points go in chunks of chunkPoints (whole batches of kSetupBatch); a chunk writes its
  /// visible points densely into its own range of slots and counts them per tile. Chunks are
  /// fixed (not a function of the thread count), so the bins are too. Segments: one slot each,
  /// in chunks of segChunkSize for the counts.
  size_t chunkPoints = 0, pointChunks = 0;
  size_t segChunkSize = 8192, segChunks = 0, chunks = 0;
  size_t pointSlots = 0;  ///< refs below pointSlots are points
  /// refs from lodBase on are segments drawn as point splats (RenderOptions::segmentLod; not for
  /// models too large for those refs)
  size_t lodBase = 0;
  bool lod = false;
  /// Coverage alpha (RenderOptions::coverageGain): a primitive's alpha attribute becomes its
  /// coverage constant g c_k (coverage.h), stored as c_k invC = c_k / (2 cMax) (at most 1/2: no
  /// fragment is opaque on its own) with the tile's scale coverageScale = 2 g cMax
  /// (Z3Tile::setCoverageScale).
  bool coverage = false;
  float coverageScale = 0, invC = 0;
  /// every fragment of the frame opaque (tail layers, Z3Tile::setTailLayers, assume it)
  bool opaqueFrame = false;
  /// coverage at silhouettes only (silhouette_coverage.h)
  bool silhouettes = false;
  /// tail layers in this frame (Z3Tile::setTailLayers), and tail coverage's scale s: a tail-only
  /// pixel's alpha is min(1, s W) where it borders an empty pixel (tail_coverage.h)
  bool tailsOn = false;
  float tailScale = 0;

  /// The tiles a primitive's bounds touch (bounds are clamped to the view: non-negative).
  TileSpan tileSpan(const PixelRect& b) const {
    const int T = tileSize;
    if (tileShift >= 0)
      return TileSpan{uint16_t(b.x0 >> tileShift), uint16_t(b.y0 >> tileShift), uint16_t((b.x1 - 1) >> tileShift),
                      uint16_t((b.y1 - 1) >> tileShift)};
    return TileSpan{uint16_t(b.x0 / T), uint16_t(b.y0 / T), uint16_t((b.x1 - 1) / T), uint16_t((b.y1 - 1) / T)};
  }
  /// Adds one bin to each tile of span s in the per-tile counts cnt.
  void countSpan(uint32_t* cnt, const TileSpan& s) const {
    for (int ty = s.y0; ty <= s.y1; ++ty)
      for (int tx = s.x0; tx <= s.x1; ++tx) ++cnt[size_t(ty) * size_t(tilesX) + size_t(tx)];
  }
  /// The pixels of tile `tile` in a w x h frame.
  PixelRect tileRect(size_t tile, int w, int h) const {
    const int T = tileSize;
    const int tx = int(tile % size_t(tilesX)), ty = int(tile / size_t(tilesX));
    return PixelRect{tx * T, ty * T, std::min(w, (tx + 1) * T), std::min(h, (ty + 1) * T)};
  }
};

/// The frame's layout for `camera` and the options, for a model of np points and ns segments.
/// Throws BadParameter when the tiles are too small for the image.
FramePlan planFrame(const Camera& camera, const RenderOptions& options, size_t np, size_t ns, const ModelFacts& model);

/// Whether the prepare stage drew a primitive (clipped ones included).
inline bool visible(PrimitiveStatus s) { return s == PrimitiveStatus::Drawn || s == PrimitiveStatus::Clipped; }

/// Stage 1: prepares every primitive of `model` into `buf` and counts the bins of each chunk;
/// the prepare counters and times go to `stats`.
void prepareFrame(const FramePlan& plan, const FrameContext& frame, const HybridModel& model, const ModelFacts& facts,
                  FrameBuffers& buf, RenderStats& stats);

/// Stage 2: the tiles' lists of primitives (buf.tileStart, buf.refs); stats.tileBins and the
/// binning times.
void binFrame(const FramePlan& plan, FrameBuffers& buf, RenderStats& stats);

/// Where the tiles write: the images of the frame, and the frame-wide buffers of the
/// beyond-thesis passes (null when off).
struct FrameTargets {
  Image* color = nullptr;
  Image* depth = nullptr;
  Image* alpha = nullptr;
  Image* normal = nullptr;
  float* frontZ = nullptr;    ///< silhouette coverage: the front depths (+inf where empty)
  uint8_t* covered = nullptr; ///< tail coverage: 1 where a pixel holds a layer
};

/// What one tile reports: its Z^3 counters and the thread time of its stages 3 and 4.
struct TileReport {
  Z3Counters counters;
  double rasterSeconds = 0, resolveSeconds = 0;
};

/// Stages 3 and 4 for one tile: its primitives rasterised into a Z^3 tile, resolved into the
/// targets (and the beyond-thesis passes' per-tile candidates kept in buf).
TileReport renderTile(size_t tile, const FramePlan& plan, const FrameContext& frame, FrameBuffers& buf,
                      const FrameTargets& out);

}  // namespace linesurf::detail
