// (ε,δ) extraction (thesis §3.1) out of core: the method the tile pipeline runs per tile (see
// tile_extract.h), and its entry point (linesurf/ooc/ooc_extract.h).
#include <cstdio>

#include "linesurf/ooc/ooc_extract.h"

#include "linesurf/core/error.h"
#include "ooc/pipeline.h"
#include "ooc/tile_extract.h"

namespace linesurf::ooc {
namespace {

using nlohmann::json;

class EpsDeltaTiles final : public detail::TileExtraction {
 public:
  explicit EpsDeltaTiles(const EpsDeltaOptions& o) : o_(o) {}
  std::string_view stage() const override { return "eps-delta tiles"; }
  json arguments() const override {
    return json{{"epsilon", o_.epsilon}, {"epsilon_relative", o_.epsilonRelative}, {"delta", o_.delta},
                {"min_replaced", o_.minReplaced}, {"max_replaced", o_.maxReplaced}, {"endpoint_normals", o_.endpointNormals}};
  }
  bool usesCurvature() const override { return false; }
  // The thesis's ε is relative to the spacing of the whole cloud, not of a tile.
  double epsilon(float avg) const override { return o_.epsilon > 0 ? o_.epsilon : o_.epsilonRelative * double(avg); }
  HybridModel extract(const HybridModel& cloud, const PointGeometry& geometry, double epsilon,
                      detail::ExtractStats& stats) const override {
    EpsDeltaOptions eo = o_;
    eo.epsilon = epsilon;
    eo.provenance = true;
    eo.progress = {};
    EpsDeltaStats st;
    HybridModel x = extractEpsDelta(cloud, geometry, eo, &st);
    stats = {st.seedDirections, st.candidateDirections, st.candidateMembers, st.degenerateNeighbours};
    return x;
  }
  std::vector<std::string> comments(double epsilon, const detail::Run& r) const override {
    char buf[160];
    std::snprintf(buf, sizeof buf, "eps-delta: epsilon=%.9g delta=%.9g k=%d", epsilon, o_.delta, r.o.geometry.k);
    return {buf, std::string("eps-delta: normals=") + (r.normalsIn && !r.o.geometry.recomputeNormals ? "file" : "computed")};
  }
  bool endpointNormals() const override { return o_.endpointNormals; }
  bool provenance() const override { return o_.provenance; }

 private:
  const EpsDeltaOptions& o_;
};

}  // namespace

OocEpsDeltaReport extractEpsDeltaOutOfCore(const std::filesystem::path& in, const std::filesystem::path& out,
                                           const OocNormalsOptions& o, const EpsDeltaOptions& extract) {
  validate(extract);
  // The noise is a median over samples of the whole cloud; tiles would each see their own.
  if (extract.epsilonNoise > 0)
    throwBadParameter("epsilonNoise", "needs the whole cloud in memory; out of core, give epsilon in object units");
  OocEpsDeltaReport er;
  detail::ExtractTotals et;
  const EpsDeltaTiles method(extract);
  er.geometry = detail::runPipeline(in, out, o, &method, &et);
  er.keptPoints = et.kept, er.segments = et.segments, er.replacedPoints = er.geometry.points - et.kept;
  er.epsilon = et.epsilon;
  er.seedDirections = et.stats[0], er.candidateDirections = et.stats[1];
  er.tExtract = et.tExtract, er.tWrite = et.tWrite;
  return er;
}

}  // namespace linesurf::ooc
