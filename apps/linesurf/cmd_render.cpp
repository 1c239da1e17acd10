// linesurf render MODEL -o out.png: software EWA splatting of point / hybrid models (thesis §4,
// §5, §6.2). Raw scans get normals and radii from the geometry stage (§6.1) first. Options bind
// straight to RenderOptions, ViewOptions, PrepareOptions and MeshRenderOptions (their defaults are
// the only ones). A mesh file is drawn as anti-aliased triangles (the ground truth) or its vertices.
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <optional>

#include "command.h"
#include "drawable_model.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/io/atomic_file.h"
#include "linesurf/io/las_io.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/io/model_io.h"
#include "linesurf/lod/lod.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/drawing.h"
#include "linesurf/render/mesh_render.h"
#include "linesurf/render/renderer.h"
#include "linesurf/surface/mesh_extract.h"
#include "options_bind.h"

namespace linesurf::cli {
namespace {

struct RenderArgs {
  std::string model, output = "render.png";
  std::string depthOut, alphaOut, normalOut;
  RenderOptions render;
  ViewOptions view;
  PrepareOptions prepare;
  MeshRenderOptions mesh;
  DrawingOptions drawing;  ///< a style other than splat: strokes from the segments (§9.4, §9.5)
  std::string primitive = "auto";
  uint64_t budget = 0;  ///< splats a view from a .lod hierarchy (0 = every leaf)
  const CLI::Option* upAxisFlag = nullptr;  ///< --up-axis: a file's recorded axis applies when not given
};

std::filesystem::path viewPath(const std::filesystem::path& out, int i) {
  auto p = out;
  p.replace_filename(fmt::format("{}_{:03d}{}", out.stem().string(), i, out.extension().string()));
  return p;
}

std::filesystem::path bufferPath(const std::string& base, int view, int views) {
  return views > 0 ? viewPath(base, view) : std::filesystem::path(base);
}

void run(RenderArgs& a) {
  Timer total;
  RenderOptions& o = a.render;
  o.depthBuffer = !a.depthOut.empty();
  o.alphaBuffer = !a.alphaOut.empty();
  o.normalBuffer = !a.normalOut.empty();
  o.progress = progressBar();
  o.facingCheck = true;  // say so when the normals face away and the picture comes out nearly empty
  a.prepare.progress = progressBar();
  // Every parameter is checked before the (long) geometry stage.
  validate(o);
  validate(a.view);
  validate(a.prepare);
  validate(a.mesh);
  validate(a.drawing);
  const bool drawing = a.drawing.style != DrawStyle::Splat;
  // A drawing strokes segments over a depth pass: which side its splats show is not its picture.
  if (drawing) o.facingCheck = false;

  const int w = a.view.width, h = a.view.height;
  // A hierarchy is read a view's nodes at a time: its budget is checked once its size is known.
  const bool isLod = lod::isLodFile(a.model);
  checkFiles({a.model}, {{"--output", a.output, drawing ? std::vector<std::string>{".png", ".svg"} : std::vector<std::string>{".png"}}, {"--depth-out", a.depthOut, {".png"}},
                         {"--alpha-out", a.alphaOut, {".png"}}, {"--normal-out", a.normalOut, {".png"}}},
             /*inputsHeldWhole=*/!isLod);
  // Colour, depth, alpha, normal images (16 bytes a pixel each) and the Z3 fragment layers.
  checkSize("--size", renderViewBytes(w, h, o.layers), fmt::format("a {}x{} image", w, h));
  {  // every image written, before the first one
    const int images = 1 + !a.depthOut.empty() + !a.alphaOut.empty() + !a.normalOut.empty();
    const int views = std::max(a.view.views, 1);
    checkSize(a.view.views > 0 ? "--views" : "--size", double(views) * images * pngFileBytes(w, h),
              fmt::format("writing {} image{} of {}x{}", views * images, views * images > 1 ? "s" : "", w, h));
  }
  if (a.primitive != "auto" && a.primitive != "mesh" && a.primitive != "points" && a.primitive != "surface")
    throwBadOption("primitive", "expected mesh, points, surface or auto, got '" + a.primitive + "'");
  const bool surface = a.primitive == "surface";
  if (surface && drawing) throwBadOption("style", "draws a model's own segments; it does not apply to --primitive surface");
  // A level-of-detail hierarchy (.lod) is already in its frame and prepared: each view draws the
  // nodes chosen for it within --budget.
  std::optional<lod::LodFile> lodFile;
  if (isLod) {
    lodFile.emplace(a.model);
    // One view holds its splats as a model (~100 bytes each with the renderer's setup).
    const uint64_t all = lodFile->header().points + lodFile->header().segments;
    // The root is drawn even over the budget (when its block is in the file: else it is not held).
    const uint64_t root = lodFile->inFile(0) ? lodFile->nodes()[0].count() : 0;
    const uint64_t drawn = a.budget > 0 ? std::min(std::max(a.budget, root), all) : all;
    checkSize(a.budget > 0 ? "--budget" : a.model, 100.0 * double(drawn),
              fmt::format("drawing {} splats a view{}", drawn, a.budget > 0 ? "" : " (every leaf; set --budget)"));
  }
  else if (a.budget > 0) throwBadOption("budget", "needs a level-of-detail hierarchy (linesurf lod build), got " + a.model);
  if (lodFile && a.primitive != "auto") throwBadOption("primitive", "does not apply to a .lod hierarchy");
  if (lodFile && drawing) throwBadOption("style", "draws a model's own segments; it does not apply to a .lod hierarchy");
  const bool isMesh = !lodFile && fileHoldsMesh(a.model);
  if (a.primitive == "mesh" && !isMesh)
    throwBadOption("primitive", "mesh needs a file with faces; " + a.model + " holds none");
  if (surface && isMesh)
    throwBadOption("primitive", "surface draws the MLS surface of points and segments; " + a.model +
                                    " is a mesh: draw it as it is (--primitive mesh)");
  std::optional<TriangleMesh> triMesh;
  HybridModel model;
  if (isMesh && a.primitive != "points") {
    triMesh = readMesh(a.model);
  }
  if (triMesh && drawing && !triMesh->faces.empty())
    throwBadOption("style", "draws a model's own segments; " + a.model +
                                " is a mesh: draw its contour lines (linesurf extract contour) or --primitive points");
  if (triMesh && triMesh->faces.empty()) {  // a mesh file without faces: its vertices are what it holds
    model = meshVerticesAsPoints(*triMesh);
    triMesh.reset();
    say(fmt::format("{}: no faces, rendering its {} vertices as points", a.model, model.points.size()));
  } else if (triMesh) {
    say(fmt::format("{}: mesh, rasterising its {} triangles ({}x{} samples per pixel)", a.model, triMesh->faces.size(),
                    a.mesh.supersampling, a.mesh.supersampling));
  } else if (isMesh) {
    model = meshVerticesAsPoints(readMesh(a.model));
    say(fmt::format("{}: mesh, rendering its {} vertices as points", a.model, model.points.size()));
  } else if (!lodFile) {
    model = readModel(a.model);
  }
  if (!triMesh && !lodFile && model.empty()) throw Error(Error::Kind::BadInput, a.model, "", "the model holds no points and no segments");
  // LAS is z-up, and a file made from one says so: orbit about its axis unless told otherwise.
  if (const std::string up = lodFile ? lodFile->header().upAxis : triMesh ? std::string() : recordedUpAxis(model);
      !up.empty() && a.upAxisFlag && a.upAxisFlag->count() == 0 && a.view.eye == std::nullopt && a.view.target == std::nullopt) {
    a.view.upAxis = parseUpAxis(up);
    say(fmt::format("{}: up axis {} (recorded in the file; --up-axis overrides)", a.model, up));
  }
  // Scale-free (model_frame.h): a model far from unit size is rendered in a normalised frame;
  // camera positions and distances given in object units are mapped into it.
  const ModelFrame frame =
      lodFile ? lodFile->header().frame : normalizingFrame(triMesh ? triMesh->bounds() : model.bounds());
  toFrame(model, frame);
  if (triMesh) toFrame(*triMesh, frame);

  if (!lodFile && !model.attributes.radii && !model.points.empty())
    checkGeometry(a.model, model.points.size(), a.prepare.k);
  const PrepareReport prep = lodFile ? PrepareReport{} : prepareForRendering(model, a.prepare);
  endProgress();
  if (prep.segmentRadiiEstimated)
    say(fmt::format("{} segments without a radius: estimated from the spacing of their neighbours",
                    prep.segmentRadiiEstimated));
  if (prep.computedRadii)
    say(fmt::format("geometry (§6.1): {} for {} points (k = {}) in {:.2f} s",
                    prep.computedNormals ? "normals + radii" : "radii", model.points.size(), a.prepare.k,
                    prep.geometrySeconds));

  // The model's MLS surface (§9.1) as a mesh, drawn by the mesh renderer under the splats' camera:
  // the reference without holes that the splat pictures are compared with.
  std::optional<BoundingSphere> surfaceSphere;
  if (surface) {
    MeshStats ms;
    Timer meshing;
    triMesh = blamingFiles({{"model", a.model}}, [&] { return extractMesh(model, MeshOptions{}, &ms, budget()); });
    if (triMesh->faces.empty())
      throw Error(Error::Kind::BadInput, a.model, "", fmt::format("its surface gives no triangles ({} cells visited)", ms.cells));
    surfaceSphere = boundingSphere(model);  // the camera the splat render of the same model gets
    say(fmt::format("{}: MLS surface (§9.1), {} triangles, {} boundary edges, meshed in {:.2f} s (linesurf mesh for its options)",
                    a.model, ms.triangles, ms.boundaryEdges, meshing.seconds()));
  }

  std::optional<Renderer> renderer;
  std::optional<MeshRenderer> meshRenderer;
  std::optional<lod::LodRenderer> lodRenderer;
  std::optional<DrawingRenderer> drawer;
  if (drawing && model.segments.empty()) {
    if (!a.drawing.silhouettes)
      throwBadOption("style", a.model + " has no segments and `silhouettes` is off: nothing to draw");
    say(a.model + ": no segments, the drawing holds its silhouettes only");
  }
  if (drawing) drawer.emplace(model, o, a.drawing);
  else if (triMesh) meshRenderer.emplace(*triMesh, o, a.mesh);
  else if (lodFile) lodRenderer.emplace(*lodFile, o, a.budget > 0 ? a.budget : UINT64_MAX, a.prepare.radiusScale);
  else renderer.emplace(model, o);
  const BoundingSphere sphere = surfaceSphere ? *surfaceSphere
                               : drawer     ? drawer->sphere()
                               : triMesh    ? meshRenderer->sphere()
                               : lodRenderer ? lodRenderer->sphere()
                                             : renderer->sphere();
  const std::vector<Camera> cams = viewCameras(sphere, a.view, frame);
  const int views = a.view.views;

  RenderStats sum;
  MeshRenderStats meshSum;
  for (size_t i = 0; i < cams.size(); ++i) {
    RenderResult r;
    uint64_t trianglesThisView = 0;
    bool svgWritten = false;
    const int vi = views > 0 ? int(i) : -1;
    std::filesystem::path out = vi >= 0 ? viewPath(a.output, vi) : std::filesystem::path(a.output);
    if (meshRenderer) {  // the mesh ground truth: same outputs, triangle counts in the summary
      MeshRenderResult m = meshRenderer->render(cams[i]);
      r.color = std::move(m.color);
      r.depth = std::move(m.depth);
      r.alpha = std::move(m.alpha);
      r.normal = std::move(m.normal);
      r.stats.fragments = m.stats.samplesCovered;
      r.stats.prepareSeconds = m.stats.prepareSeconds;
      r.stats.rasterSeconds = m.stats.rasterSeconds;
      r.stats.totalSeconds = m.stats.totalSeconds;
      trianglesThisView = m.stats.trianglesDrawn;
      meshSum += m.stats;
    } else if (lodRenderer) {
      lod::LodFrameResult f = lodRenderer->render(cams[i]);
      r = std::move(f.render);
      // A node that failed leaves its part of the picture empty; the rest is drawn (exit 0).
      for (const std::string& e : f.failures) std::fprintf(stderr, "warning: %s (not drawn)\n", e.c_str());
      say(fmt::format("{}: {} nodes, {} splats within the budget; select {:.1f} ms, load {:.1f} ms", a.model,
                      f.selection.nodes.size(), f.selection.primitives, 1000 * f.selectSeconds, 1000 * f.loadSeconds));
    } else if (drawer) {
      Drawing d = drawer->render(cams[i]);
      r = std::move(d.splat);
      r.color = std::move(d.image);
      if (a.depthOut.empty()) r.depth.reset();  // the drawing's own buffers, written only when asked
      if (a.normalOut.empty()) r.normal.reset();
      say(fmt::format("drawing: {} strokes ({} in between, {} across), {} drawn in {} visible runs, {} silhouette paths; strokes "
                      "{:.1f} ms, raster {:.1f} ms", d.stats.strokes, d.stats.inBetweenStrokes, d.stats.crossStrokes, d.stats.strokesDrawn,
                      d.stats.runs, d.stats.silhouettePaths, 1000 * d.stats.strokeSeconds, 1000 * d.stats.rasterSeconds));
      if (out.extension() == ".svg") {
        const std::string svg = drawingSvg(d, a.drawing);
        checkSize("--output", double(svg.size()), fmt::format("an SVG drawing of {} paths", d.runs.size()));
        writeFileAtomically(out, svg);
        svgWritten = true;
      }
    } else {
      r = renderer->render(cams[i], o.facingCheck && i == 0);  // the first view answers for the series
    }
    if (!svgWritten) writePng(out, r.color, drawing ? a.drawing.paper.w() < 1 : o.background.w() < 1);
    if (r.depth) writePng(bufferPath(a.depthOut, vi, views), depthAsGrey(*r.depth));
    if (r.alpha) writePng(bufferPath(a.alphaOut, vi, views), *r.alpha);
    if (r.normal) writePng(bufferPath(a.normalOut, vi, views), *r.normal);
    const RenderStats& s = r.stats;
    if (cams.size() > 1)
      say(fmt::format("{}: {:.1f} ms, {} {} drawn", out.string(), 1000 * s.totalSeconds,
                      triMesh ? trianglesThisView : s.pointsDrawn + s.segmentsDrawn, triMesh ? "triangles" : "splats"));
    sum += s;
  }
  const std::string per = cams.size() > 1 ? fmt::format(" (over {} views)", cams.size()) : "";
  if (!model.points.empty() || lodFile)
    say(fmt::format("points{}: {} drawn ({} clipped), {} culled (back-facing), {} outside the view, {} degenerate", per,
                    sum.pointsDrawn, sum.pointsClipped, sum.pointsCulled, sum.pointsOutside, sum.pointsDegenerate));
  if (!model.segments.empty() || (lodFile && lodFile->header().segments > 0))
    say(fmt::format("segments{}: {} drawn ({} clipped), {} culled (back-facing), {} outside the view, {} degenerate, "
                    "{} approx fallbacks to screen-space, {} drawn as point splats (--segment-lod)", per,
                    sum.segmentsDrawn, sum.segmentsClipped, sum.segmentsCulled, sum.segmentsOutside,
                    sum.segmentsDegenerate, sum.segmentsFallback, sum.segmentsLod));
  if (triMesh)
    say(fmt::format("triangles{}: {} drawn ({} clipped), {} culled (back-facing), {} outside the view, {} degenerate; "
                    "{} samples covered", per, meshSum.trianglesDrawn, meshSum.trianglesClipped, meshSum.trianglesCulled,
                    meshSum.trianglesOutside, meshSum.trianglesDegenerate, sum.fragments));
  else
    say(fmt::format("Z3 ({} layers): {} fragments, {} merged, {} occluded, {} compressions", o.layers, sum.fragments,
                  sum.merged, sum.occluded, sum.compressed));
  say(fmt::format("render {}x{}: {:.1f} ms (prepare {:.1f}, bin {:.1f}, raster+resolve {:.1f}){}; total {:.2f} s",
                  w, h, 1000 * sum.totalSeconds, 1000 * sum.prepareSeconds, 1000 * sum.binSeconds,
                  1000 * sum.rasterSeconds,
                  sum.facingPixels ? fmt::format("; facing check {:.1f} ms ({:.1f}% back)", 1000 * sum.facingSeconds,
                                                 100 * sum.backFacingShare())
                                   : std::string(),
                  total.seconds()));
  if (const std::string w = backFacingWarning(sum, a.model); !w.empty()) std::fprintf(stderr, "warning: %s\n", w.c_str());
  if (views > 0)
    say(fmt::format("wrote {} .. {}", viewPath(a.output, 0).string(), viewPath(a.output, int(cams.size()) - 1).string()));
  else
    say("wrote " + a.output);
}

RegisterCommand reg(40, [](CLI::App& app) {
  auto a = std::make_shared<RenderArgs>();
  RenderOptions& o = a->render;
  ViewOptions& v = a->view;
  CLI::App* sub = app.add_subcommand("render", "Render a point or hybrid model by EWA splatting (thesis §4-§6.2) to PNG");
  sub->add_option("MODEL", a->model, "Point cloud, hybrid model or mesh (.ply, .obj, .xyz); see --primitive")->type_name("FILE")
      ->required();
  sub->add_option("-o,--output", a->output, "Output PNG, or SVG with --style lines / hatch (with --views N: OUT_000.png ...)")->type_name("FILE")->capture_default_str();
  // Every flag of the camera, the preparation, the renderer and the mesh rasteriser comes from
  // the option tables (pipeline/option_tables.h).
  a->upAxisFlag = bindOptions(sub, v).option("upAxis");
  bindOptions(sub, a->prepare);
  bindOptions(sub, o);
  bindOptions(sub, a->mesh);
  bindOptions(sub, a->drawing);
  // Read as every table option is (options_bind.h): a decimal integer in range, so that -1, 2^64,
  // "" or 0x10 are refused naming the flag instead of read as something else.
  sub->add_option_function<std::string>("--budget", [a](const std::string& t) {
        a->budget = parseNumber<uint64_t>(OptionSpec{"budget", "", closedRange(0, 1e15)}, t);
        requireRange("budget", double(a->budget), 0, 1e15, "splats (0 = every leaf)");
      },
      "With a .lod hierarchy: draw at most N splats a view, nodes chosen coarse to fine by their projected "
      "size (0, the default: every leaf, the full model), [0, 1e15]")
      ->type_name("N");
  sub->add_option("--depth-out", a->depthOut, "Also write the depth buffer as a grey PNG (near = white)")->type_name("FILE");
  sub->add_option("--alpha-out", a->alphaOut, "Also write the coverage alpha as a PNG")->type_name("FILE");
  sub->add_option("--normal-out", a->normalOut, "Also write camera-space normals as (n+1)/2 RGB")->type_name("FILE");
  sub->add_option("--primitive", a->primitive,
                  "What a mesh file is drawn as: mesh (anti-aliased triangles, the ground truth), points (its "
                  "vertices as splats) or auto (mesh when the file has faces); surface: a cloud's or hybrid's MLS "
                  "surface meshed (§9.1, linesurf mesh) and drawn as a mesh, the reference without holes")->capture_default_str();
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
