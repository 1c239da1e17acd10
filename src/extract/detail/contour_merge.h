#pragma once
// Merging of contour polylines (beyond the thesis): consecutive segments of one contour
// polyline (same plane family and plane, chained through shared mesh edges) become one segment
// when that segment stays on the surface. Used by extractContour (src/extract/contour.cpp); the
// rules and the measured tolerances are in docs/decisions.md, "Polyline merging".
#include <cstddef>
#include <cstdint>
#include <vector>

#include "linesurf/core/model.h"

namespace linesurf::detail {

/// Where a contour segment's endpoint lies: on mesh edge (lo, hi) (global vertex indices,
/// lo < hi), on plane `plane / 2^level` (units of d) of `family`, with `plane` odd unless level
/// is 0, so that the same plane reached from two faces of different levels has one key.
struct ContourEndKey {
  uint32_t lo = 0, hi = 0;
  int64_t plane = 0;
  uint8_t level = 0, family = 0;
  friend bool operator==(const ContourEndKey&, const ContourEndKey&) = default;
  friend auto operator<=>(const ContourEndKey&, const ContourEndKey&) = default;
};

/// The key of a crossing of plane k of a face of `level` with edge (va, vb).
ContourEndKey contourEndKey(uint32_t va, uint32_t vb, int64_t k, int level, int family);

struct ContourMergeLimits {
  double normalDeviation = 0;   ///< largest distance of an original vertex from the merged
                                ///< segment along the surface normal there, object units
  double tangentDeviation = 0;  ///< the same across the segment within the surface, object units
  double cosAngle = 1;          ///< cos of the largest normal angle (see contour.h)
  double cosStripAngle = 1;     ///< cos of the largest strip-plane tilt (smooth: mergeStripAngle, flat: cosAngle)
  int maxPieces = 1;            ///< most original segments in one merged segment
  double uvTolerance = 0;       ///< textured models: largest uv deviation from linear (0: no texture)
  float colorTolerance = 0;     ///< largest colour channel deviation from the merged colour
  bool smooth = false;          ///< segments carry normal0/normal1
  bool alongNormals = false;    ///< normal0/normal1 keep their component along the segment
};

struct ContourMergeCounts {
  size_t polylines = 0;        ///< chains of linked segments (a lone segment is one)
  size_t closedPolylines = 0;  ///< of which closed loops
  size_t before = 0, after = 0;
};

/// Merges `segments` in place. keys[2 i + e] and vertexNormals[2 i + e] belong to end e (0: p0,
/// 1: p1) of segment i; vertexNormals are the unit interpolated vertex normals there (zero when
/// unknown: the segment normals are used). Two ends are linked only when exactly two ends share a
/// key and their positions are equal. Merged segments are ordered by their lowest original index;
/// `faces` (when not empty) is compacted alongside (the face of the first piece). Deterministic:
/// sequential, no thread count involved.
ContourMergeCounts mergeContourPolylines(std::vector<Segment>& segments, const std::vector<ContourEndKey>& keys,
                                         const std::vector<Vec3f>& vertexNormals, const ContourMergeLimits& limits,
                                         std::vector<uint32_t>* faces);

}  // namespace linesurf::detail
