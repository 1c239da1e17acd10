// linesurf extract contour MESH -o OUT: contour-plane extraction of a line-segment (or hybrid, or
// point) model from a triangle mesh, thesis §3.3.
#include <fmt/format.h>

#include <algorithm>

#include "command.h"
#include "options_bind.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/extract/contour.h"
#include "linesurf/io/model_io.h"

namespace linesurf::cli {
namespace {

struct ContourArgs {
  std::string mesh, output;
  ContourOptions extract;
  bool ascii = false;
};

void run(ContourArgs& a) {
  Timer total, t;
  ContourOptions& o = a.extract;
  validate(o);  // before reading the mesh
  checkFiles({a.mesh}, {{"--output", a.output, o.allPoints ? std::vector<std::string>{".ply", ".xyz"} : std::vector<std::string>{".ply"}}});
  const TriangleMesh mesh = readMesh(a.mesh);
  const double readSeconds = t.seconds();
  say(fmt::format("{}: {} vertices, {} faces{}{} ({:.2f} s)", a.mesh, mesh.positions.size(), mesh.faces.size(),
                  mesh.cornerUVs.empty() ? "" : ", per-corner uvs", mesh.texture ? ", texture" : "", readSeconds));
  if (mesh.faces.empty()) throwBadInput(a.mesh, "", "the file holds no faces: contour extraction needs a triangle mesh");
  // Size guard before any cutting: a face of longest edge L meets about L/d + 1 planes; with
  // --all-points a segment of length l gives l/d + 1 points (about area/d^2 over the mesh).
  {
    double edgeSum = 0, longest = 0, area = 0;
    size_t edges = 0;
    for (const auto& f : mesh.faces) {
      const Vec3d p0 = mesh.positions[f[0]].cast<double>(), p1 = mesh.positions[f[1]].cast<double>(),
                  p2 = mesh.positions[f[2]].cast<double>();
      const double l[3] = {(p1 - p0).norm(), (p2 - p1).norm(), (p0 - p2).norm()};
      edgeSum += l[0] + l[1] + l[2];
      edges += 3;
      longest += std::max({l[0], l[1], l[2]});
      area += 0.5 * (p1 - p0).cross(p2 - p0).norm();
    }
    const Bounds3f box = mesh.bounds();
    bool capped = false;
    const double d = contourSpacing(o, edgeSum / double(std::max<size_t>(edges, 1)),
                                    box.empty() ? 0.0 : double(box.diagonal().norm()), &capped);
    if (d > 0) {
      const double segments = longest / d + double(mesh.faces.size());
      const double points = o.allPoints || o.pointsBelow > 0 ? area / (d * d) + segments : 0;
      const char* flag = o.spacing > 0                          ? "--spacing"
                         : capped && o.spacingScale == 1.0f ? "--diagonal-divisions"
                                                            : "--spacing-scale";
      checkSize(flag, 120.0 * segments + 60.0 * points,
                fmt::format("contour output at d = {:.3g} (about {:.3g} segments{})", d, segments,
                            points > 0 ? fmt::format(", {:.3g} points", points) : std::string()));
    }
  }
  o.progress = progressBar();
  ContourStats s;
  HybridModel model = extractContour(mesh, o, &s);
  endProgress();
  if (o.radiusScale <= 0.5f)
    say(fmt::format("warning: --radius-scale {} <= 0.5: d >= 2R, the model may render with holes (§3.3)", o.radiusScale));

  t.reset();
  WriteOptions w;
  w.encoding = a.ascii ? PlyEncoding::Ascii : PlyEncoding::BinaryLittleEndian;
  writeModel(a.output, model, w);
  const double writeSeconds = t.seconds();

  say(fmt::format("contour planes (§3.3): d = {:.6g}{}, radius {:.6g}, seed {}", s.spacing,
                  o.spacing > 0             ? ""
                  : s.spacingFromDiagonal ? fmt::format(" ({} x diagonal {:.6g} / {}; mean edge {:.6g})", o.spacingScale,
                                                        s.diagonal, o.diagonalDivisions, s.meanEdgeLength)
                                          : fmt::format(" ({} x mean edge {:.6g})", o.spacingScale, s.meanEdgeLength),
                  s.radius, o.seed));
  say(fmt::format("faces: {} cut by P=, {} by P|| ({} at d/2 or finer), {} between planes, {} degenerate skipped",
                  s.cutByFamily[0], s.cutByFamily[1], s.halvedSpacing, s.uncutTriangles, s.degenerateTriangles));
  say(fmt::format("output: {} segments, {} points{}{}", s.segments, s.points,
                  s.convertedSegments ? fmt::format(" (from {} segments)", s.convertedSegments) : std::string(),
                  s.polylines ? fmt::format("; {} segments merged into {} along {} contour polylines",
                                            s.segmentsBeforeMerge, s.segments, s.polylines)
                              : std::string()));
  say(fmt::format("time: read {:.2f} s, extract {:.3f} s, write {:.2f} s, total {:.2f} s", readSeconds, s.seconds,
                  writeSeconds, total.seconds()));
  say("wrote " + a.output);
}

RegisterCommand reg(33, [](CLI::App& app) {
  CLI::App* extract = extractCommand(app);
  auto a = std::make_shared<ContourArgs>();
  ContourOptions& o = a->extract;
  CLI::App* sub = extract->add_subcommand(
      "contour", "Cut a triangle mesh with two perpendicular families of contour planes (thesis §3.3)");
  sub->add_option("MESH", a->mesh, "Triangle mesh (.ply, or .obj with .mtl and texture image)")->type_name("FILE")->required();
  sub->add_option("-o,--output", a->output, "Output model (.ply)")->type_name("FILE")->required();
  bindOptions(sub, o);  // --flat: the thesis's one normal per segment (--no-endpoint-normals)
  sub->add_flag("--ascii", a->ascii, "Write ASCII PLY instead of binary");
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
