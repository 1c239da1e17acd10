#pragma once
// Which side of a surface its normals face. The thesis's MST propagation (§6.1) makes the normals
// of a connected component agree with each other; which of the component's two sides they face
// is a rule of its own (beyond the thesis; docs/decisions.md "Orientation"):
//   auto      the columns' votes below, with the view from above counted twice: right for closed
//             objects, and for terrain and roofs, which are scanned from above;
//   outward   the columns' votes alone (closed objects);
//   up        the normals' mean points up (+z);
//   towards   the normals face a viewpoint (a room scanned from inside, a facade from the street);
//   away-from the normals face away from it.
// The columns: the bounding box cut into columns along each of the six axis directions (64 cells
// along the longest axis); in every column the component's point farthest along the direction
// is seen from that direction, so its outward normal faces it: the column votes round(1024 n.d).
// Every vote is an integer, so summaries of a component's pieces (the tiles of an out-of-core
// run) add up in any order to the whole component's, and both paths choose the same side.
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "linesurf/core/math.h"
#include "linesurf/geometry/point_geometry.h"

namespace linesurf::detail {

/// The six column directions: +z, -z, +x, -x, +y, -y (a key's top byte).
inline const std::array<Vec3f, 6> kSideDirections = {Vec3f(0, 0, 1), Vec3f(0, 0, -1), Vec3f(1, 0, 0),
                                                     Vec3f(-1, 0, 0), Vec3f(0, 1, 0), Vec3f(0, -1, 0)};

/// The columns over a cloud's bounding box.
class SideGrid {
 public:
  SideGrid() = default;
  explicit SideGrid(const Bounds3f& bounds);
  /// p's column along direction dir (0..5): dir << 24 | cell.
  uint32_t key(const Vec3f& p, int dir) const;

 private:
  int cellOf(float v, int axis) const;
  Vec3f lo_ = Vec3f::Zero();
  float cell_ = 1;
  std::array<int, 3> dims_{1, 1, 1};
};

/// A column's farthest point of a component.
struct SideEntry {
  uint32_t key = 0;
  float value = 0;     ///< position along the column's direction
  uint64_t index = 0;  ///< input index (ties: the lower wins)
  int32_t vote = 0;    ///< round(1024 n.d) under the summary's orientation
};

/// What a component, or a piece of one, says about its side, under the orientation its normals
/// have now.
struct SideSummary {
  int64_t vote = 0;                  ///< up, towards, away-from: sum of round(1024 n.v)
  std::vector<SideEntry> envelope;   ///< auto, outward: per column, ascending keys
  uint64_t firstIndex = UINT64_MAX;  ///< the lowest input index (a tie's rule)
  Vec3f firstNormal = Vec3f::Zero();
  bool empty() const { return firstIndex == UINT64_MAX; }
};

/// The summaries of `components` components: point t has component comp[t], position pos[t],
/// normal normal[t], input index index[t] (index empty: t); only the points with take[t] count
/// (take empty: all).
std::vector<SideSummary> sideSummaries(OrientSide rule, const Vec3f& viewpoint, const SideGrid& grid, std::span<const Vec3f> pos,
                                       std::span<const Vec3f> normal, std::span<const uint32_t> comp, size_t components,
                                       std::span<const uint64_t> index = {}, std::span<const uint8_t> take = {});

/// a becomes the summary of both pieces; b's normals negated first when flip.
void mergeSides(SideSummary& a, const SideSummary& b, bool flip);

/// Whether the component's normals must be negated to face the rule's side. A tie (or a
/// component without votes) is broken by the lowest-index point: its normal's largest
/// component positive.
bool flipForSide(const SideSummary& s, OrientSide rule);

}  // namespace linesurf::detail
