#pragma once
/// Geometry processing of point clouds, thesis §6.1: the five stages computed once per cloud and
/// shared by every later stage (extraction §3.1/§3.2, rendering of raw scans):
///   1. spatial index and exact k nearest neighbours,
///   2. PCA normals (Hoppe 1992) with eigenvalues / surface variation, consistently oriented by a
///      minimum spanning tree over the neighbour graph,
///   3. local Delaunay neighbours on each tangent plane,
///   4. curvature by Taubin's method (§6.1.2) with local-Delaunay triangle-area weights,
///   5. average spacing, global and per point.
#include <cstdint>
#include <span>
#include <vector>

#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"

namespace linesurf {

/// How stage 4 turns the directional curvatures kappa_j of the local Delaunay star into
/// principal curvatures.
enum class CurvatureFit {
  /// Taubin 1995 / thesis §6.1.2: eigenvalues m1 >= m2 of M = sum w_j kappa_j T_j T_j^T give
  /// kappa_max = 3 m1 - m2, kappa_min = 3 m2 - m1 (exact only for evenly spread directions).
  Taubin,
  /// Least-squares fit of the height function h = (a u^2 + 2b uv + c v^2)/2 + e u + f v over the k
  /// nearest neighbours in the tangent frame (an osculating quadric); the linear terms absorb the
  /// error of the estimated normal, which dominates Taubin's kappa_j on irregular samples. Falls
  /// back to Taubin when the fit is ill-conditioned.
  Quadric,
};

/// Which side of each connected component its oriented normals face (the MST of stage 2 makes
/// them agree within the component; docs/decisions.md "Orientation").
enum class OrientSide {
  /// Outward for closed objects, up for terrain and roofs scanned from above: per column of the
  /// bounding box along each axis direction, the farthest point votes that its normal faces that
  /// direction; the view from above counts twice.
  Auto,
  /// The column votes alone, every direction alike (closed objects).
  Outward,
  /// The mean normal points up (+z).
  Up,
  /// The normals face `viewpoint` (a room scanned from inside, a facade from the street).
  Towards,
  /// The normals face away from `viewpoint`.
  AwayFrom,
};

struct GeometryOptions {
  int k = 12;                      ///< neighbours per point (stage 1), >= 3
  bool recomputeNormals = false;   ///< recompute even when the cloud has normals
  bool orientNormals = true;       ///< MST orientation of computed normals (stage 2)
  /// MST edge weight = 1 - |n_i.n_j| + orientationPenalty |n_i.d||n_j.d| (d = unit p_j - p_i):
  /// discourages edges along the normals, i.e. across thin parts between two sheets. 0 gives
  /// Hoppe's weight. Default 0.5 (docs/decisions.md).
  float orientationPenalty = 0.5f;
  OrientSide orient = OrientSide::Auto;     ///< the side each component's normals face
  Vec3f viewpoint = Vec3f::Zero();          ///< for OrientSide::Towards and AwayFrom (the sensor)
  bool delaunayNeighbours = true;  ///< stage 3
  bool curvature = true;           ///< stage 4 (needs stage 3)
  /// Hole-free radii (docs/decisions.md "Spacing and the cover radius"): PointGeometry::coverRadius
  /// from the local Delaunay star (runs stage 3 even when delaunayNeighbours is off; its neighbour
  /// lists are then not kept).
  bool coverRadius = true;
  CurvatureFit curvatureFit = CurvatureFit::Taubin;  ///< stage 4 formula
  /// Stage 3 with CGAL::Delaunay_triangulation_2 per point instead of the default star by
  /// inversion (same neighbours except on co-circular sets; see docs/decisions.md). For comparison.
  bool cgalDelaunay = false;
  ProgressFn progress;             ///< optional progress callback
};

/// Per-point degeneracy flags (bit set), reported as counts by the CLI.
enum PointFlag : uint8_t {
  kPointOk = 0,
  kPointDuplicate = 1,        ///< coincides with another point (within 1e-6 of the bbox diagonal)
  kPointFewNeighbours = 2,    ///< fewer than 3 distinct neighbours
  kPointFlatNeighbourhood = 4,///< collinear neighbourhood: normal undefined, a fallback was used
  kPointIsolated = 8,         ///< no neighbour within the graph (own component of size 1)
  kPointNoStar = 16,          ///< local Delaunay star without a triangle: curvature set to 0
};

struct GeometryStageTimes {
  double neighbours = 0, normals = 0, orientation = 0, delaunay = 0, curvature = 0, spacing = 0;
};

/// Everything §6.1 derives per point. Arrays are indexed like the cloud's points.
struct PointGeometry {
  int k = 0;
  /// Stage 1: row i holds the k nearest other points of i, nearest first: neighbours[i*k + j].
  /// When the cloud has fewer than k+1 points, rows are padded with kNoNeighbour (distance
  /// +infinity). Equal distances are ordered by index.
  std::vector<uint32_t> neighbours;
  std::vector<float> neighbourDistances;  ///< Euclidean distances, same layout
  static constexpr uint32_t kNoNeighbour = UINT32_MAX;

  /// Stage 2: unit normals (consistently oriented when requested), PCA eigenvalues
  /// λ0 <= λ1 <= λ2 of the neighbourhood covariance and surface variation λ0/(λ0+λ1+λ2) (§3.2.3.1).
  std::vector<Vec3f> normals;
  std::vector<Vec3f> eigenvalues;
  std::vector<float> surfaceVariation;
  size_t orientationComponents = 0;  ///< MST seeds used (one per connected component)
  size_t orientationFlips = 0;       ///< normals flipped by the orientation pass

  /// Stage 3: local Delaunay neighbours in CSR form: delaunayOf(i).
  std::vector<uint32_t> delaunayOffsets;  ///< size n+1
  std::vector<uint32_t> delaunayIndices;
  /// Normalised triangle-area weights w_ik of §6.1.2, same layout as delaunayIndices (sum 1 per
  /// point with a star). Each row lists the neighbours counter-clockwise around the normal.
  std::vector<float> delaunayWeights;
  std::span<const uint32_t> delaunayOf(size_t i) const {
    return {delaunayIndices.data() + delaunayOffsets[i], delaunayOffsets[i + 1] - delaunayOffsets[i]};
  }
  std::span<const float> delaunayWeightsOf(size_t i) const {
    return {delaunayWeights.data() + delaunayOffsets[i], delaunayOffsets[i + 1] - delaunayOffsets[i]};
  }

  /// Stage 4: principal curvature values and unit directions (tangent to the surface).
  /// Sign convention: positive where the surface bends away from its normal (a sphere of radius
  /// r with outward normals has kMin = kMax = 1/r); kMin <= kMax. Directions are canonicalised
  /// so that their largest-magnitude component is positive.
  std::vector<float> kMin, kMax;
  std::vector<Vec3f> minCurvatureDir, maxCurvatureDir;

  /// Stage 5: mean distance to the k nearest neighbours, per point and over the cloud.
  std::vector<float> spacing;
  float averageSpacing = 0;

  /// Hole-free radius per point (beyond the thesis): 1.1 x the largest circumradius of the
  /// triangles of its local Delaunay star (tangent plane), capped at 3 x spacing. The Voronoi
  /// cell of a point is the polygon of its star triangles' circumcentres, so a disc of this
  /// radius covers the cell, and the discs of all points cover the surface. 0 where the point
  /// has no star triangle; empty unless GeometryOptions::coverRadius.
  std::vector<float> coverRadius;

  std::vector<uint8_t> flags;  ///< PointFlag bits per point
  GeometryStageTimes times;

  size_t size() const { return normals.size(); }
  size_t countFlag(PointFlag f) const;
};

/// Throws OptionError (core/options.h) naming the first bad field (k in [3, 256], orientationPenalty).
void validate(const GeometryOptions& options);

/// Runs the §6.1 stages on the cloud's points. Normals present in the model are kept (and only
/// oriented if needed) unless options.recomputeNormals. Deterministic for any thread count.
/// Throws linesurf::Error (BadParameter) for k < 3; handles clouds of any size >= 1.
PointGeometry computePointGeometry(const HybridModel& cloud, const GeometryOptions& options = {});

/// Writes the geometry's normals into the model's points, and radii where the model has none:
/// coverRadius where positive, else the per-point spacing, else the average spacing (radius rule
/// in docs/decisions.md), setting the attribute flags.
void applyGeometry(HybridModel& cloud, const PointGeometry& geometry);

/// Adds the curvature of `geometry` to cloud.pointProperties as "k_min", "k_max", "dmin_x",
/// "dmin_y", "dmin_z" (minimum-curvature direction). Requires geometry.kMin to be filled.
void addCurvatureProperties(HybridModel& cloud, const PointGeometry& geometry);

}  // namespace linesurf
