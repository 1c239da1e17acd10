// Shape-approximation extraction (thesis §3.2) out of core: the method the tile pipeline runs per
// tile (see tile_extract.h), and its entry point (linesurf/ooc/ooc_extract.h).
#include "linesurf/ooc/ooc_extract.h"
#include "ooc/pipeline.h"
#include "ooc/tile_extract.h"

namespace linesurf::ooc {
namespace {

using detail::floatBits;
using nlohmann::json;

// The counters of a tile extraction file, in this order.
detail::ExtractStats statsOf(const ShapeApproxStats& st) {
  detail::ExtractStats v{st.clusters, st.smallClusters, st.clustersWithSegments, st.curvatureDirectionUsed,
                         st.degenerateClusters, st.degenerateRuns};
  for (size_t b = 0; b < 6; ++b) v[6 + b] = st.sizeHistogram[b];
  v[12] = st.largeClusters, v[13] = st.largeClusterPoints, v[14] = st.splits, v[15] = st.iterations;
  return v;
}

ShapeApproxStats shapeApproxStats(const detail::ExtractTotals& t, uint64_t points) {
  ShapeApproxStats st;
  const auto& v = t.stats;
  st.inputPoints = points, st.pointsKept = t.kept, st.pointsReplaced = points - t.kept, st.segments = t.segments;
  st.clusters = v[0], st.smallClusters = v[1], st.clustersWithSegments = v[2], st.curvatureDirectionUsed = v[3];
  st.degenerateClusters = v[4], st.degenerateRuns = v[5];
  for (size_t b = 0; b < 6; ++b) st.sizeHistogram[b] = v[6 + b];
  st.largeClusters = v[12], st.largeClusterPoints = v[13], st.splits = v[14], st.iterations = v[15];
  return st;
}

class ShapeApproxTiles final : public detail::TileExtraction {
 public:
  explicit ShapeApproxTiles(const ShapeApproxOptions& o) : o_(o) {}
  std::string_view stage() const override { return "shape-approx tiles"; }
  json arguments() const override {
    const ClusteringOptions& c = o_.clustering;
    return json{{"method", o_.method == ClusteringMethod::Hierarchical ? "hierarchical" : "greedy"},
                {"delta_n_bits", floatBits(c.deltaN)},
                {"max_iterations", c.maxIterations},
                {"seed", c.seed},
                {"seeding", int(c.seeding)},
                {"min_cluster_size", o_.minClusterSize},
                {"min_run_points", o_.minRunPoints},
                {"curvature_switch_bits", floatBits(o_.curvatureSwitchDegrees)},
                {"curvature_coherence_bits", floatBits(o_.curvatureCoherence)},
                {"radius_scale_bits", floatBits(o_.radiusScale)},
                {"endpoint_normals", o_.endpointNormals}};
  }
  // The k_min directions of §3.2.4.2, where geometry.curvature asks for them.
  bool usesCurvature() const override { return true; }
  HybridModel extract(const HybridModel& cloud, const PointGeometry& geometry, double /*epsilon*/,
                      detail::ExtractStats& stats) const override {
    ShapeApproxOptions so = o_;
    so.provenance = true;
    so.progress = {};
    so.clustering.progress = {};
    ShapeApproxStats st;
    HybridModel x = extractShapeApprox(cloud, geometry, so, &st);
    stats = statsOf(st);
    return x;
  }
  std::vector<std::string> comments(double /*epsilon*/, const detail::Run& /*r*/) const override {
    return {std::string("linesurf: shape-approximation extraction (§3.2), ") +
            (o_.method == ClusteringMethod::Hierarchical ? "hierarchical" : "greedy") + " clustering, delta_n " +
            std::to_string(o_.clustering.deltaN)};
  }
  bool endpointNormals() const override { return o_.endpointNormals; }
  bool provenance() const override { return o_.provenance; }

 private:
  const ShapeApproxOptions& o_;
};

}  // namespace

OocShapeApproxReport extractShapeApproxOutOfCore(const std::filesystem::path& in, const std::filesystem::path& out,
                                                 const OocNormalsOptions& o, const ShapeApproxOptions& extract) {
  validate(extract);
  OocShapeApproxReport sr;
  detail::ExtractTotals et;
  const ShapeApproxTiles method(extract);
  sr.geometry = detail::runPipeline(in, out, o, &method, &et);
  sr.stats = shapeApproxStats(et, sr.geometry.points);
  sr.tExtract = et.tExtract, sr.tWrite = et.tWrite;
  return sr;
}

}  // namespace linesurf::ooc
