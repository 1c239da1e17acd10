// linesurf render MODEL -o out.png: software EWA splatting of point / hybrid models (thesis §4,
// §5, §6.2). Raw scans get normals and radii from the geometry stage (§6.1) first. Options bind
// straight to RenderOptions, ViewOptions, PrepareOptions and MeshRenderOptions (their defaults are
// the only ones). A mesh file is drawn as anti-aliased triangles (the ground truth) or its vertices.
#include <fmt/format.h>

#include <cstdio>
#include <filesystem>

#include "command.h"
#include "drawable_model.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/io/model_io.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/mesh_render.h"
#include "linesurf/render/renderer.h"
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
  std::string primitive = "auto";
  bool worldLight = false, noCull = false;
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
  o.light.headlight = !a.worldLight;
  o.backfaceCulling = !a.noCull;
  o.depthBuffer = !a.depthOut.empty();
  o.alphaBuffer = !a.alphaOut.empty();
  o.normalBuffer = !a.normalOut.empty();
  o.progress = progressBar();
  a.prepare.progress = progressBar();
  // Every parameter is checked before the (long) geometry stage.
  validate(o);
  validate(a.view);
  validate(a.prepare);

  const int w = a.view.width, h = a.view.height;
  checkFiles({a.model}, {{"--output", a.output, {".png"}}, {"--depth-out", a.depthOut, {".png"}},
                         {"--alpha-out", a.alphaOut, {".png"}}, {"--normal-out", a.normalOut, {".png"}}});
  // Colour, depth, alpha, normal images (16 bytes a pixel each) and the Z3 fragment layers.
  checkSize("--size", double(w) * h * (16.0 * 4 + 48.0 * std::max(o.layers, 1)), fmt::format("a {}x{} image", w, h));
  if (a.primitive != "auto" && a.primitive != "mesh" && a.primitive != "points")
    throwBadOption("primitive", "expected mesh, points or auto, got '" + a.primitive + "'");
  const bool isMesh = fileHoldsMesh(a.model);
  if (a.primitive == "mesh" && !isMesh)
    throwBadOption("primitive", "mesh needs a file with faces; " + a.model + " holds none");
  std::optional<TriangleMesh> triMesh;
  HybridModel model;
  if (isMesh && a.primitive != "points") {
    triMesh = readMesh(a.model);
    if (triMesh->faces.empty()) throw Error(Error::Kind::BadInput, a.model, "", "the mesh has no faces");
    say(fmt::format("{}: mesh, rasterising its {} triangles ({}x{} samples per pixel)", a.model, triMesh->faces.size(),
                    a.mesh.supersampling, a.mesh.supersampling));
  } else if (isMesh) {
    model = meshVerticesAsPoints(readMesh(a.model));
    say(fmt::format("{}: mesh, rendering its {} vertices as points", a.model, model.points.size()));
  } else {
    model = readModel(a.model);
  }
  if (!triMesh && model.empty()) throw Error(Error::Kind::BadInput, a.model, "", "the model holds no points and no segments");
  // Scale-free (model_frame.h): a model far from unit size is rendered in a normalised frame;
  // camera positions and distances given in object units are mapped into it.
  const ModelFrame frame = normalizingFrame(triMesh ? triMesh->bounds() : model.bounds());
  toFrame(model, frame);
  if (triMesh) toFrame(*triMesh, frame);

  const PrepareReport prep = prepareForRendering(model, a.prepare);
  endProgress();
  if (prep.segmentRadiiEstimated)
    say(fmt::format("{} segments without a radius: estimated from the spacing of their neighbours",
                    prep.segmentRadiiEstimated));
  if (prep.computedRadii)
    say(fmt::format("geometry (§6.1): {} for {} points (k = {}) in {:.2f} s",
                    prep.computedNormals ? "normals + radii" : "radii", model.points.size(), a.prepare.k,
                    prep.geometrySeconds));

  std::optional<Renderer> renderer;
  std::optional<MeshRenderer> meshRenderer;
  if (triMesh) meshRenderer.emplace(*triMesh, o, a.mesh);
  else renderer.emplace(model, o);
  const BoundingSphere& sphere = triMesh ? meshRenderer->sphere() : renderer->sphere();
  const std::vector<Camera> cams = viewCameras(sphere, a.view, frame);
  const int views = a.view.views;

  RenderStats sum;
  MeshRenderStats meshSum;
  for (size_t i = 0; i < cams.size(); ++i) {
    RenderResult r;
    uint64_t trianglesThisView = 0;
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
    } else {
      r = renderer->render(cams[i]);
    }
    const int vi = views > 0 ? int(i) : -1;
    std::filesystem::path out = vi >= 0 ? viewPath(a.output, vi) : std::filesystem::path(a.output);
    writePng(out, r.color, o.background.w() < 1);
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
  if (!model.points.empty())
    say(fmt::format("points{}: {} drawn ({} clipped), {} culled (back-facing), {} outside the view, {} degenerate", per,
                    sum.pointsDrawn, sum.pointsClipped, sum.pointsCulled, sum.pointsOutside, sum.pointsDegenerate));
  if (!model.segments.empty())
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
  say(fmt::format("render {}x{}: {:.1f} ms (prepare {:.1f}, bin {:.1f}, raster+resolve {:.1f}); total {:.2f} s",
                  w, h, 1000 * sum.totalSeconds, 1000 * sum.prepareSeconds, 1000 * sum.binSeconds,
                  1000 * sum.rasterSeconds, total.seconds()));
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
  sub->add_option("MODEL", a->model, "Point cloud, hybrid model or mesh (.ply, .obj, .xyz); see --primitive")
      ->required();
  sub->add_option("-o,--output", a->output, "Output PNG (with --views N: OUT_000.png ...)")->capture_default_str();
  sub->add_option_function<std::string>("--size", [&v](const std::string& s) {
        int w = 0, h = 0;
        char x = 0, extra = 0;
        if (std::sscanf(s.c_str(), "%d%c%d%c", &w, &x, &h, &extra) != 3 || (x != 'x' && x != 'X'))
          throwBadOption("size", "expected WIDTHxHEIGHT, got '" + s + "'");
        v.width = w, v.height = h;
      }, "Image size WIDTHxHEIGHT, 1..16384 pixels per side")->default_str("512x512");
  auto* g = sub->add_option_group("camera", "Orbit view auto-framed on the bounding sphere, N views, or look-at");
  bind(g, "azimuth", v.azimuth, "Orbit azimuth about the up axis, degrees (0 = from +z)");
  bind(g, "elevation", v.elevation, "Orbit elevation, degrees in [-90, 90]");
  bind(g, "distance", v.distance, "Orbit distance from the centre (0 = frame the model)");
  bind(g, "zoom", v.zoom, "Divide the framed distance by this factor (> 0)");
  bind(g, "fov", v.fov, "Vertical field of view, degrees in [1, 170]");
  g->add_option_function<int>(flagName("views"), [&v](int n) {
        if (n < 1) throwBadOption("views", "must be in [1, 10000] (leave it out for one view), got " + std::to_string(n));
        v.views = n;
      }, "Render N views spread over the sphere (deterministic), [1, 10000]");
  g->add_option_function<std::string>(flagName("upAxis"), [&v](const std::string& s) { v.upAxis = parseUpAxis(s); },
                                      "World up axis of the orbit: x, y, z, -x, -y, -z (santa, rockerarm: z)")
      ->default_str("y");
  bindVec3(g, "eye", v.eye, "Look-at camera position x y z");
  bindVec3(g, "target", v.target, "Look-at target x y z (default: model centre)");
  bindVec3(g, "up", v.up, "Look-at up vector (default 0 1 0)");
  auto* f = sub->add_option_group("filtering", "EWA resampling filter (§4.2.2)");
  bind(f, "prefilterVariance", o.prefilterVariance, "Screen prefilter variance, pixels^2 in [0, 100] (0 = none)", "--prefilter");
  bind(f, "cutoffRadius", o.cutoffRadius, "Resampling filter cut-off radius, standard deviations [1, 5]", "--cutoff");
  bind(f, "reconstructionScale", o.reconstructionScale, "Reconstruction sigma as a fraction of the point radius, (0, 4]",
       "--recon-scale");
  bind(f, "radiusScale", a->prepare.radiusScale, "Multiply every primitive radius, [1e-3, 1e3]");
  bind(f, "coverageGain", o.coverageGain,
       "Coverage alpha at silhouettes (beyond the thesis): alpha = gain x the kernel sum over the model's kernel "
       "density, [0, 100] (0 = the thesis's normalised alpha; 1.25 for contour models at silhouettes, 1.5 with --coverage-reach 0)");
  bind(f, "coverageReach", o.coverageReach,
       "Coverage alpha only at silhouettes: pixels within this many pixels of the background or of a farther "
       "layer, [0, 16] (0 = everywhere)");
  auto* vis = sub->add_option_group("visibility", "Modified Z^3 buffer (§6.2.3)");
  bind(vis, "layers", o.layers, "Fragment layers per pixel [1, 8]");
  vis->add_flag(flagName("tailLayers") + ",!--no-tail-layers", o.tailLayers,
                "Tail layers (beyond the thesis): a fragment outside 1.5x its primitive's own disc or strip (a prefilter "
                "tail) occludes nothing and is composited only over the background (fewer fold speckles; point frames up to 3% slower; default on)");
  bind(vis, "tailCoverage", o.tailCoverage,
       "Tail coverage (beyond the thesis): a pixel past a silhouette reached only by tails takes alpha gain x its kernel "
       "sum over the model's median kernel density, [0, 100] (0 = the normalised alpha 1)");
  bindEnum(vis, "zThresholdMode", o.zThresholdMode,
           {{"primitive", ZThresholdMode::PerPrimitive}, {"fixed", ZThresholdMode::Fixed}},
           "z threshold: primitive (delta-z, own depth extent) or fixed (thesis)", "--z-mode");
  vis->add_option_function<float>(flagName("zThreshold"), [a](float z) { a->render.zThreshold = z; },
                                  fmt::format("primitive: multiple of the depth extent (default {:g}); fixed: fraction "
                                              "of the bounding radius (default {:g})",
                                              defaultZThreshold(ZThresholdMode::PerPrimitive),
                                              defaultZThreshold(ZThresholdMode::Fixed)));
  vis->add_option(flags("alphaOverride", "--alpha"), o.alphaOverride,
                  "Alpha of every primitive in [0, 1] (order-independent transparency)");
  vis->add_flag("--no-cull", a->noCull, "Keep back faces (two-sided lighting)");
  auto* s = sub->add_option_group("shading", "Phong lighting (§6.2.2); defaults suit unit-free scans");
  bind(s, "ambient", o.material.ambient, "Ambient coefficient [0, 1]");
  bind(s, "diffuse", o.material.diffuse, "Diffuse coefficient [0, 1]");
  bind(s, "specular", o.material.specular, "Specular coefficient [0, 1]");
  bind(s, "shininess", o.material.shininess, "Phong exponent (0, 10000]");
  bindVec3(s, "light", o.light.direction, "Direction towards the light x y z (camera space; world with --world-light)");
  s->add_flag("--world-light", a->worldLight, "--light is in world space instead of a headlight");
  s->add_option_function<std::vector<float>>(
       flags("defaultColor", "--color"), [&o](const std::vector<float>& c) { o.defaultColor = Color(c[0], c[1], c[2], 1); },
       "Albedo R G B in [0,1] for models without colours")
      ->expected(3);
  s->add_flag(flagName("perPixelLighting"), o.perPixelLighting, "Light every fragment instead of Gouraud at the quad vertices");
  s->add_option_function<std::string>("--background", [&o](const std::string& b) { o.background = parseBackground(b); },
                                      "white, black, transparent or R,G,B[,A]")
      ->default_str("white");
  bindEnum(sub, "segmentMethod", o.segmentMethod,
           {{"approx", SegmentMethod::Approx}, {"screen", SegmentMethod::ScreenSpace}, {"reference", SegmentMethod::Reference}},
           "Line-segment filter: approx (§5.2.3 quads), screen (erf), reference");
  bind(sub, "segmentLod", o.segmentLod,
       "Draw screen segments at most this many kernel sigmas long as one moment-matched point splat, [0, 4] "
       "(0 = every segment exact)");
  sub->add_option("--depth-out", a->depthOut, "Also write the depth buffer as a grey PNG (near = white)");
  sub->add_option("--alpha-out", a->alphaOut, "Also write the coverage alpha as a PNG");
  sub->add_option("--normal-out", a->normalOut, "Also write camera-space normals as (n+1)/2 RGB");
  bind(sub, "k", a->prepare.k, "Neighbours for normals/radii of raw scans (§6.1), [3, 256]");
  sub->add_option("--primitive", a->primitive,
                  "What a mesh file is drawn as: mesh (anti-aliased triangles, the ground truth), points (its "
                  "vertices as splats) or auto (mesh when the file has faces)")->capture_default_str();
  bind(sub, "supersampling", a->mesh.supersampling, "Mesh: samples per pixel side (S x S per pixel) [1, 16]");
  bind(sub, "tileSize", o.tileSize, "Screen tile side in pixels, [8, 1024] (does not change the image)");
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
