#pragma once
/// Shape-approximation based line-segment extraction, thesis §3.2: the cloud is clustered by
/// normal variation (§3.2.3, extract/clustering.h), then every cluster of more than 3 points gives
/// a bunch of nearly parallel segments along its anisotropic direction (§3.2.4):
///   §3.2.4.1 centroid and Householder frame of the seeding normal, projection onto its xy plane;
///   §3.2.4.2 shape direction from the minimum-area enclosing rectangle (rotating calipers, CGAL),
///            replaced by the average minimum-curvature direction when they differ by > 45 degrees;
///   §3.2.4.3 average projected neighbour spacings along x and y;
///   §3.2.4.4 non-uniform grid: uniform x-slices, equal-count y-slices, occupied/influenced tags;
///   §3.2.4.5 runs of influenced squares along each y-slice with >= 4 points become segments.
/// Points of small clusters and of short runs stay points. Choices where the text is ambiguous
/// are in docs/decisions.md, "Shape-approximation extraction (§3.2)".
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"
#include "linesurf/extract/clustering.h"

namespace linesurf {

struct PointGeometry;

enum class ClusteringMethod { Greedy, Hierarchical };

struct ShapeApproxOptions {
  ClusteringMethod method = ClusteringMethod::Greedy;  ///< §3.2.3.1 or §3.2.3.2
  ClusteringOptions clustering;  ///< delta_n (default 0.008, §7.2), seed, iteration cap
  /// Clusters with fewer points stay points (§3.2.4.1: "more than 3 points"), >= 2.
  int minClusterSize = 4;
  /// Runs of influenced squares holding fewer points stay points (§3.2.4.5: 4), >= 2.
  int minRunPoints = 4;
  /// §3.2.4.2: the average minimum-curvature direction replaces the rectangle's direction when
  /// they differ by more than this angle (degrees, in [0, 90]; 90 never replaces).
  float curvatureSwitchDegrees = 45.0f;
  /// The curvature directions of a cluster are used only when their axial mean is coherent:
  /// |mean of (cos 2a, sin 2a)| >= this (in [0, 1]); 1 never uses them.
  float curvatureCoherence = 0.5f;
  /// Without point radii in the cloud: segment half-width as a multiple of the cluster's average
  /// spacing across the segments (d_avg,x); > 0. With radii the strips cover the replaced points'
  /// Voronoi cells instead (docs/decisions.md "Hybrid segment widths") and this is not used.
  float radiusScale = 1.0f;
  bool provenance = false;  ///< fill HybridModel::provenance with the points each segment replaced
  /// Smooth line models (beyond the thesis): each segment also carries the normals of the
  /// points at its two ends (Segment::normal0/normal1, made perpendicular to it).
  bool endpointNormals = true;
  ProgressFn progress;      ///< optional progress callback
};

/// Throws OptionError (core/options.h) naming the first bad field (clustering fields included).
void validate(const ShapeApproxOptions& options);

struct ShapeApproxStats {
  size_t inputPoints = 0;
  size_t clusters = 0;
  size_t smallClusters = 0;          ///< clusters below minClusterSize (their points stay)
  size_t clustersWithSegments = 0;
  size_t curvatureDirectionUsed = 0; ///< clusters whose direction came from k_min (§3.2.4.2)
  size_t degenerateClusters = 0;     ///< collinear/coincident projections or zero spacing: kept as points
  size_t degenerateRuns = 0;         ///< runs whose endpoints coincide or whose normal vanished
  size_t segments = 0;
  size_t pointsReplaced = 0;
  size_t pointsKept = 0;
  /// Cluster sizes: counts of clusters of size 1, 2-3, 4-9, 10-99, 100-999, >= 1000.
  std::array<size_t, 6> sizeHistogram{};
  static constexpr std::array<const char*, 6> kHistogramLabels = {"1", "2-3", "4-9", "10-99", "100-999", ">=1000"};
  size_t largeClusters = 0;          ///< clusters of more than 100 points (§7.2.1)
  size_t largeClusterPoints = 0;     ///< points in them
  size_t splits = 0, iterations = 0; ///< hierarchical clustering diagnostics
  double clusteringSeconds = 0, extractionSeconds = 0;
  /// §7.2.2 data reduction: 1 - (6 * points + 9 * segments) / (6 * input points).
  double dataReduction() const {
    return inputPoints ? 1.0 - (6.0 * double(pointsKept) + 9.0 * double(segments)) / (6.0 * double(inputPoints)) : 0.0;
  }
};

/// Runs the clustering chosen by options.method on the geometry.
Clustering clusterShapeApprox(const PointGeometry& geometry, const ShapeApproxOptions& options = {});

/// Full §3.2 pipeline: clusters the cloud, then extracts segments per cluster.
/// @param cloud     the point cloud (points only); its colours and radii are kept for points
/// @param geometry  computePointGeometry(cloud): normals, local Delaunay neighbours, k_min directions
/// @return the hybrid model: the points no segment replaced (input order), then the segments in
///         cluster order. A segment runs from p_s to p_e (§3.2.4.5) moved sideways to the middle
///         of its run's spread (beyond the thesis). Deterministic for any thread count.
/// Throws linesurf::Error (BadParameter) for absurd options or a geometry of another size.
HybridModel extractShapeApprox(const HybridModel& cloud, const PointGeometry& geometry,
                               const ShapeApproxOptions& options = {}, ShapeApproxStats* stats = nullptr);

/// §3.2.4 only, on a given clustering (e.g. one also written with colorByCluster).
HybridModel extractShapeApprox(const HybridModel& cloud, const PointGeometry& geometry, const Clustering& clustering,
                               const ShapeApproxOptions& options = {}, ShapeApproxStats* stats = nullptr);

/// A rectangle in the plane: centre, unit direction of its longer edges, and edge lengths.
struct Rectangle2 {
  Vec2d center = Vec2d::Zero();
  Vec2d longAxis = Vec2d::UnitX();  ///< unit, along the longer edges
  double longLength = 0, shortLength = 0;
  double area() const { return longLength * shortLength; }
};

/// Minimum-area enclosing rectangle of planar points (convex hull + rotating calipers,
/// [Toussaint 1983], via CGAL's min_rectangle_2). Collinear input gives a rectangle of zero width
/// along the line; empty input gives the default rectangle.
Rectangle2 minAreaRectangle(std::span<const Vec2d> points);

}  // namespace linesurf
