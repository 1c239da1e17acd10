#pragma once
/// Normal-variation clustering of a point cloud, thesis §3.2.2-§3.2.3: the surface is cut into
/// connected clusters C whose members all stay within the normal variation tolerance of the
/// cluster's seeding normal n(C):  ||n(C) - n_j||^2 <= delta_n  (the L^{2,1} idea of
/// Cohen-Steiner, Alliez and Desbrun 2004, [CAD04]).
///   - clusterGreedy:       §3.2.3.1, flooding in increasing order of surface variation V_s.
///   - clusterHierarchical: §3.2.3.2, recursive two-way distortion-minimising splits (Lloyd
///                          iterations with a priority queue) until every cluster meets delta_n.
/// Clusters grow through the local Delaunay neighbours of PointGeometry (stage 3, made symmetric);
/// when the geometry has none they grow through its k nearest neighbours.
#include <cstdint>
#include <span>
#include <vector>

#include "linesurf/core/math.h"
#include "linesurf/core/model.h"
#include "linesurf/core/progress.h"

namespace linesurf {

struct PointGeometry;

/// How a hierarchical split picks its two initial seeds (§3.2.3.2).
enum class SplitSeeding {
  Random,          ///< two random members, as the thesis states
  NormalExtremes,  ///< random start r; t farthest in normal from r; s farthest from t (default)
};

struct ClusteringOptions {
  /// Normal variation tolerance delta_n: bound on ||n(C) - n_j||^2 = 2 - 2 cos(angle) for every
  /// member j. Default 0.008 (§7.2, about 5.1 degrees). Must lie in (0, 2): at 2 a member normal
  /// may stand at 90 degrees to n(C) and the §3.2.4.1 projection folds (docs/decisions.md).
  float deltaN = 0.008f;
  /// Hierarchical only: cap on the reseeding iterations of one two-way split (§3.2.3.2), >= 1.
  int maxIterations = 16;  ///< [1, kMaxClusteringIterations]
  /// Hierarchical only: seed of the random initial seed pairs. Same seed, same clusters, for any
  /// thread count.
  uint64_t seed = 1;
  /// Hierarchical only: initial seeds of a split (docs/decisions.md: random seeds make splits
  /// peel off a few points at a time, quadratic time and more clusters).
  SplitSeeding seeding = SplitSeeding::NormalExtremes;
  ProgressFn progress;  ///< optional progress callback
};

/// A partition of the cloud's points into clusters. Cluster ids are dense, 0 .. size()-1, and
/// ordered by their smallest member index (so the order does not depend on the algorithm's
/// processing order or the thread count).
struct Clustering {
  std::vector<uint32_t> labels;        ///< per point: its cluster id
  std::vector<uint32_t> offsets;       ///< CSR, size()+1 entries
  std::vector<uint32_t> members;       ///< CSR: point indices of each cluster, increasing
  std::vector<Vec3f> seedingNormals;   ///< per cluster: n(C), unit
  std::vector<uint32_t> seeds;         ///< per cluster: the seed point
  std::vector<float> maxVariation;     ///< per cluster: V_n,max = max_j ||n(C) - n_j||^2 <= delta_n

  // Diagnostics.
  size_t splits = 0;            ///< hierarchical: two-way splits performed
  size_t iterations = 0;        ///< hierarchical: growth iterations over all splits
  size_t capReached = 0;        ///< hierarchical: splits stopped by maxIterations, not convergence
  size_t components = 0;        ///< connected components of the neighbour graph
  size_t zeroNormals = 0;       ///< points without a usable normal (singleton clusters)

  size_t size() const { return seedingNormals.size(); }
  std::span<const uint32_t> membersOf(size_t c) const {
    return {members.data() + offsets[c], offsets[c + 1] - offsets[c]};
  }
  size_t clusterSize(size_t c) const { return offsets[c + 1] - offsets[c]; }
};

/// Largest ClusteringOptions::maxIterations: far beyond convergence, small enough to end in seconds.
inline constexpr int kMaxClusteringIterations = 1000;
/// Throws OptionError (core/options.h) naming the first bad field (deltaN, maxIterations).
void validate(const ClusteringOptions& options);

/// §3.2.3.1 greedy clustering: points are taken in increasing order of surface variation (ties by
/// index); each point not yet clustered seeds a cluster with its own normal as n(C), which grows
/// breadth-first through neighbours not yet clustered whose normal passes the delta_n test.
/// Throws linesurf::Error (BadParameter) for deltaN outside (0, 2).
Clustering clusterGreedy(const PointGeometry& geometry, const ClusteringOptions& options = {});

/// §3.2.3.2 hierarchical distortion-minimised clustering. Each connected component starts as one
/// cluster; a cluster whose V_n,max exceeds delta_n (against both its seeding normal and its
/// average normal) is split in two: two random members seed two clusters that grow through a
/// priority queue keyed by ||n_k - n(C_b)||^2; both are reseeded from their average normal
/// n'(C_b) (new seed: the member closest to it) until the seeds stop changing or maxIterations
/// growths were made. Splits of one level run in parallel, each with its own random stream
/// derived from (seed, smallest member index), so the result is the same for any thread count.
/// Throws linesurf::Error (BadParameter) for deltaN outside (0, 2) or maxIterations < 1.
Clustering clusterHierarchical(const PointGeometry& geometry, const ClusteringOptions& options = {});

/// Largest ||n(C) - n_j||^2 over the members of cluster c, recomputed from the geometry's
/// normals (for checking the invariant).
float clusterMaxVariation(const Clustering& clustering, const PointGeometry& geometry, size_t c);

/// A deterministic colour for cluster `id`: hues spaced by the golden angle with three
/// saturation/value levels, so neighbouring ids get clearly different colours (thesis Figure 22).
Color clusterColor(size_t id);

/// The cloud's points coloured by cluster (normals from the geometry), for looking at a
/// segmentation: the `--clusters-out` file of `linesurf extract shape-approx`.
HybridModel colorByCluster(const HybridModel& cloud, const PointGeometry& geometry, const Clustering& clustering);

}  // namespace linesurf
