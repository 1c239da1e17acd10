#pragma once
/// Outliers of a scanned point cloud (beyond the thesis, which assumes clean scans): points that
/// lie off the surface their neighbours describe, points far sparser than their own neighbours,
/// and floaters (sparse scattered points, far sparser than the scan). From the §6.1 geometry of
/// the cloud (kNN, normals, spacing, surface variation); see docs/decisions.md "Outliers".
#include <cstdint>
#include <vector>

#include "linesurf/geometry/point_geometry.h"

namespace linesurf {

/// Neighbours the outlier tests want (GeometryOptions::k of the geometry they read): a group of
/// more than k/2 outliers vouches for itself, and groups of a few clusters do meet.
inline constexpr int kOutlierNeighbours = 30;

struct OutlierOptions {
  /// Off the surface: the lower quartile of the distances to the neighbours' tangent planes
  /// exceeds this many sample spacings of the neighbourhood (a point 3 spacings off a clean
  /// surface is out; one on an edge is seen in plane by the neighbours on its own side).
  float offSurface = 2.0f;
  /// Isolated: the point's spacing exceeds this many times its neighbours' median spacing.
  float isolated = 4.0f;
  /// Floater: the point's spacing exceeds this many times the cloud's median spacing and its
  /// neighbourhood is not a surface (surface variation above `floaterVariation`).
  float sparse = 8.0f;
  float floaterVariation = 0.1f;
};

/// Throws Error(BadParameter) naming the field.
void validate(const OutlierOptions& o);

enum OutlierKind : uint8_t { kNotOutlier = 0, kOffSurface = 1, kIsolatedPoint = 2, kFloater = 4 };

struct OutlierReport {
  std::vector<uint8_t> kind;  ///< per point, OutlierKind bits
  size_t offSurface = 0, isolated = 0, floaters = 0, total = 0;
};

/// Classifies every point of a cloud from its geometry (computePointGeometry, k =
/// kOutlierNeighbours, with at least the neighbours, normals, spacing and surface variation).
/// Deterministic for any thread count.
OutlierReport findOutliers(const PointGeometry& geometry, const std::vector<Vec3f>& positions, const OutlierOptions& o = {});

/// The cloud without the points `report` marks, or with `outliers` those points alone (attributes
/// kept; segments refused: a hybrid model's provenance would no longer match).
HybridModel withoutOutliers(const HybridModel& cloud, const OutlierReport& report, bool outliers = false);

}  // namespace linesurf
