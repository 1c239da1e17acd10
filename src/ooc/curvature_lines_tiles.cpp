// Lines of curvature (thesis §9.2) out of core: the method the tile pipeline runs per tile (see
// tile_extract.h), and its entry point (linesurf/ooc/ooc_extract.h).
#include <cstdio>

#include "linesurf/ooc/ooc_extract.h"
#include "ooc/pipeline.h"
#include "ooc/tile_extract.h"

namespace linesurf::ooc {
namespace {

using nlohmann::json;

const char* familyName(CurvatureFamily f) {
  return f == CurvatureFamily::Min ? "min" : f == CurvatureFamily::Max ? "max" : "both";
}

class CurvatureLineTiles final : public detail::TileExtraction {
 public:
  explicit CurvatureLineTiles(const CurvatureLineOptions& o) : o_(o) {}
  std::string_view stage() const override { return "curvature-lines tiles"; }
  json arguments() const override {
    return json{{"epsilon", o_.epsilon},       {"epsilon_relative", o_.epsilonRelative},
                {"delta", o_.delta},           {"family", familyName(o_.family)},
                {"separation", o_.separation}, {"min_separation", o_.minSeparation},
                {"width_scale", o_.widthScale}, {"step", o_.step},
                {"min_length", o_.minLength},  {"smoothing_iterations", o_.smoothingIterations},
                {"field_data_weight", o_.fieldDataWeight}, {"support_scale", o_.supportScale}};
  }
  bool usesCurvature() const override { return false; }  // the tile's MLS surface gives it
  // The thesis's ε is relative to the spacing of the whole cloud, not of a tile.
  double epsilon(float avg) const override { return o_.epsilon > 0 ? o_.epsilon : o_.epsilonRelative * double(avg); }
  HybridModel extract(const HybridModel& cloud, const PointGeometry& geometry, double epsilon,
                      detail::ExtractStats& stats) const override {
    CurvatureLineOptions co = o_;
    co.epsilon = epsilon;
    co.provenance = true;
    co.progress = {};
    CurvatureLineStats st;
    HybridModel x = extractCurvatureLines(cloud, geometry, co, &st);
    // The counters are integers: the chains' length goes in as millionths of an object unit.
    stats = {st.lines, st.closedLines, st.shortLines, st.prunedLines, uint64_t(st.lineLength * 1e6), st.steps,
             st.stopSeparation, st.stopSingularity, st.stopBoundary, st.stopClosed};
    return x;
  }
  std::vector<std::string> comments(double epsilon, const detail::Run& r) const override {
    char buf[200];
    std::snprintf(buf, sizeof buf, "curvature-lines: epsilon=%.9g delta=%.9g separation=%.9g family=%s", epsilon,
                  o_.delta, o_.separation, familyName(o_.family));
    return {buf, std::string("curvature-lines: normals=") + (r.normalsIn && !r.o.geometry.recomputeNormals ? "file" : "computed")};
  }
  bool endpointNormals() const override { return true; }
  bool provenance() const override { return o_.provenance; }

 private:
  const CurvatureLineOptions& o_;
};

}  // namespace

OocCurvatureLineReport extractCurvatureLinesOutOfCore(const std::filesystem::path& in, const std::filesystem::path& out,
                                                      const OocNormalsOptions& o, const CurvatureLineOptions& extract) {
  validate(extract);
  OocCurvatureLineReport cr;
  detail::ExtractTotals et;
  const CurvatureLineTiles method(extract);
  cr.geometry = detail::runPipeline(in, out, o, &method, &et);
  cr.keptPoints = et.kept, cr.segments = et.segments, cr.replacedPoints = cr.geometry.points - et.kept;
  cr.epsilon = et.epsilon;
  cr.lines = et.stats[0], cr.closedLines = et.stats[1], cr.shortLines = et.stats[2], cr.prunedLines = et.stats[3];
  cr.lineLength = double(et.stats[4]) * 1e-6;
  cr.steps = et.stats[5];
  cr.stopSeparation = et.stats[6], cr.stopSingularity = et.stats[7], cr.stopBoundary = et.stats[8], cr.stopClosed = et.stats[9];
  cr.tExtract = et.tExtract, cr.tWrite = et.tWrite;
  return cr;
}

}  // namespace linesurf::ooc
