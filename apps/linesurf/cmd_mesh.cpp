// linesurf mesh MODEL -o MESH.ply: a triangle mesh of the MLS surface a cloud, hybrid or line
// model implies (thesis §9.1; surface/mesh_extract.h). Options bind straight to MeshOptions.
#include <fmt/format.h>

#include "command.h"
#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "linesurf/io/model_io.h"
#include "linesurf/surface/mesh_extract.h"
#include "options_bind.h"

namespace linesurf::cli {
namespace {

struct MeshArgs {
  std::string in, out;
  MeshOptions mesh;
};

void run(MeshArgs& a) {
  Timer total;
  validate(a.mesh);
  checkFiles({a.in}, {{"--output", a.out, {".ply", ".obj"}}});
  HybridModel model = readModel(a.in);
  const double readSeconds = total.seconds();
  if (model.points.empty() && model.segments.empty()) throw Error(Error::Kind::BadInput, a.in, "", "holds no points and no segments");
  if (!model.points.empty() && !model.attributes.normals)
    throw Error(Error::Kind::BadInput, a.in, "", "has no normals (the surface needs oriented points: run `linesurf normals` first)");
  a.mesh.progress = progressBar();
  MeshStats st;
  // What the surface refuses in the model (a non-finite point, coincident points) is the file's fault.
  TriangleMesh mesh = blamingFiles({{"model", a.in}}, [&] { return extractMesh(model, a.mesh, &st, budget()); });
  endProgress();
  if (mesh.faces.empty())
    throw Error(Error::Kind::BadInput, a.in, "",
                fmt::format("its surface gives no triangles ({} cells visited, {} crossed by the surface but out of reach)",
                            st.cells, st.openCells));
  // A binary PLY row: position and normal (24 bytes) a vertex, 13 a face.
  checkSize("--output", double(mesh.positions.size()) * 24 + double(mesh.faces.size()) * 13 + 4096,
            fmt::format("writing {} vertices and {} triangles to '{}'", mesh.positions.size(), mesh.faces.size(), a.out));
  Timer write;
  writeMesh(a.out, mesh);
  const double writeSeconds = write.seconds();
  say(fmt::format("{}: {} sources ({} points, {} segments), median spacing {:.6g}, {} threads", a.in, st.sources,
                  model.points.size(), model.segments.size(), st.medianSpacing, currentThreadCount()));
  say(fmt::format("grid           cell {:.6g} ({} x spacing), support {} x spacing; {} seed cells, {} visited, {} on the "
                  "surface, {} left open (a corner out of reach)",
                  st.cellSize, a.mesh.cellScale, a.mesh.mls.supportScale, st.seedCells, st.cells, st.surfaceCells,
                  st.openCells));
  say(fmt::format("mesh           {} vertices, {} triangles, {} boundary edges{}", st.vertices, st.triangles, st.boundaryEdges,
                  st.boundaryEdges ? "" : " (closed)"));
  say(fmt::format("time (s)       read {:.3f}  surface {:.3f}  grid {:.3f}  mesh {:.3f}  write {:.3f}  total {:.3f}", readSeconds,
                  st.surfaceSeconds, st.gridSeconds, st.meshSeconds, writeSeconds, total.seconds()));
  say("wrote " + a.out);
}

RegisterCommand reg(25, [](CLI::App& app) {
  auto a = std::make_shared<MeshArgs>();
  CLI::App* sub = app.add_subcommand("mesh", "Triangle mesh of the model's MLS surface, open where the data is (thesis §9.1)");
  sub->add_option("MODEL", a->in, "Input cloud, hybrid or line model with normals (.ply, .xyz)")->type_name("FILE")->required();
  sub->add_option("-o,--output", a->out, "The mesh (.ply binary, .obj)")->type_name("FILE")->required();
  bindOptions(sub, a->mesh);
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
