// linesurf convert IN OUT [--ascii] [--points]: between the supported formats (mesh -> mesh,
// points -> points, mesh -> points as its vertices). Formats follow the extensions.
#include <fmt/format.h>

#include <algorithm>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/io/model_io.h"

namespace linesurf::cli {
namespace {

struct ConvertArgs {
  std::string in, out;
  bool ascii = false, points = false;
};

std::string lowerExt(const std::string& p) {
  std::string e = std::filesystem::path(p).extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

void runConvert(const ConvertArgs& a) {
  WriteOptions wo;
  wo.encoding = a.ascii ? PlyEncoding::Ascii : PlyEncoding::BinaryLittleEndian;
  const std::string outExt = lowerExt(a.out);
  checkFiles({a.in}, {{"output", a.out, {".ply", ".obj", ".xyz", ".las"}}});
  const char* enc = outExt == ".ply" ? (a.ascii ? " (ascii PLY)" : " (binary PLY)") : "";
  // .xyz and .las hold points: a mesh written so keeps its vertices.
  if (fileHoldsMesh(a.in) && !a.points && outExt != ".xyz" && outExt != ".las") {
    TriangleMesh m = readMesh(a.in);
    checkSize("output", modelFileBytes(m.positions.size(), 0, a.ascii) + double(m.faces.size()) * (a.ascii ? 40.0 : 13.0),
              fmt::format("writing a mesh of {} vertices and {} faces", m.positions.size(), m.faces.size()));
    writeMesh(a.out, m, wo);
    say(fmt::format("wrote {}: mesh, {} vertices, {} faces{}{}", a.out, m.positions.size(), m.faces.size(),
                    m.cornerUVs.empty() ? "" : ", texcoords", enc));
    return;
  }
  if (outExt == ".obj") throwBadParameter(a.out, "points and segments are written as .ply, .xyz or .las, not .obj");
  HybridModel m = readModel(a.in);
  checkSize("output", modelFileBytes(m.points.size(), m.segments.size(), outExt == ".xyz" || a.ascii),
            fmt::format("writing {} points and {} segments", m.points.size(), m.segments.size()));
  writeModel(a.out, m, wo);
  say(fmt::format("wrote {}: {} points, {} segments{}", a.out, m.points.size(), m.segments.size(), enc));
}

RegisterCommand reg(11, [](CLI::App& app) {
  auto args = std::make_shared<ConvertArgs>();
  CLI::App* sub = app.add_subcommand("convert", "Convert between .ply, .obj, .xyz and .las (mesh->mesh, points->points, mesh->points)");
  sub->add_option("input", args->in, "Input model (.ply, .obj, .xyz, .las)")->type_name("FILE")->required();
  sub->add_option("output", args->out, "Output model (.ply, .obj, .xyz, .las); a mesh written as .xyz or .las keeps its vertices")->required();
  sub->add_flag("--ascii", args->ascii, "Write ascii PLY instead of binary little-endian");
  sub->add_flag("--points", args->points, "Write a mesh's vertices as a point cloud (drop the faces)");
  sub->callback([args] { runConvert(*args); });
});

}  // namespace
}  // namespace linesurf::cli
