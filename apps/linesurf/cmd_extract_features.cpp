// linesurf extract features IN -o OUT [--angle DEG]: a cloud's creases as a line model (thesis
// §9.5), whose segments `render --style lines` strokes. Options bind to FeatureLineOptions.
#include <fmt/format.h>

#include "command.h"
#include "extract_common.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/feature_lines.h"
#include "options_bind.h"

namespace linesurf::cli {
namespace {

struct FeatureArgs {
  std::string input, output;
  GeometryOptions geometry = [] {
    GeometryOptions g;
    g.curvature = false;  // normals (when the file has none) and spacing only
    g.delaunayNeighbours = false;
    return g;
  }();
  FeatureLineOptions extract;
  bool ascii = false;
};

void run(FeatureArgs& a) {
  Timer total;
  validate(a.extract);
  validate(a.geometry);
  checkFiles({a.input}, {{"--output", a.output, {".ply"}}}, false);
  CloudWithGeometry in = readCloudWithGeometry(a.input, a.geometry);
  if (!in.normalsFromFile) {  // the §6.1 normals, into the cloud the surface is built from
    for (size_t i = 0; i < in.cloud.points.size(); ++i) in.cloud.points[i].normal = in.geometry.normals[i];
    in.cloud.attributes.normals = true;
  }
  FeatureLineStats st;
  HybridModel out = blamingFiles({{"model", a.input}}, [&] { return extractFeatureLines(in.cloud, a.extract, &st); });
  if (out.segments.empty())  // a smooth cloud: said, not written as an empty model
    throw Error(Error::Kind::BadInput, a.input, "",
                fmt::format("no crease sharper than {} degrees ({} neighbour pairs across one, {} samples); nothing written",
                            a.extract.angle, st.creasePairs, st.samples));
  out.comments.push_back(fmt::format("features: normals={}", in.normalsFromFile ? "file" : "computed"));
  Timer t;
  writeExtracted(a.output, out, a.ascii);
  const double writeSeconds = t.seconds();
  say(fmt::format("creases      {} neighbour pairs across {} degrees, {} samples (median spacing {:.6g})", st.creasePairs,
                  a.extract.angle, st.samples, st.spacing));
  say(fmt::format("output       {} segments in {} polylines, {:.6g} long ({:.1f} spacings) -> {}", st.segments, st.polylines,
                  st.length, st.spacing > 0 ? st.length / st.spacing : 0.0, a.output));
  say(fmt::format("times        read {:.3f} s, geometry {:.3f} s, normals {:.3f} s, samples {:.3f} s, chains {:.3f} s, "
                  "write {:.3f} s, total {:.3f} s",
                  in.readSeconds, in.geometrySeconds, st.normalSeconds, st.sampleSeconds, st.chainSeconds, writeSeconds,
                  total.seconds()));
}

RegisterCommand reg(36, [](CLI::App& app) {
  auto a = std::make_shared<FeatureArgs>();
  CLI::App* sub = extractCommand(app)->add_subcommand(
      "features", "Feature lines: a cloud's creases as a line model (thesis §9.5); render --style lines strokes them");
  sub->add_option("IN", a->input, "Input point cloud (.ply, .xyz, .las; normals computed when it has none)")
      ->type_name("FILE")
      ->required();
  sub->add_option("-o,--output", a->output, "Output line model (.ply)")->type_name("FILE")->required();
  bindOptions(sub, a->extract);
  bindGeometryOptions(sub, a->geometry);
  sub->add_flag("--ascii", a->ascii, "Write ASCII PLY");
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
