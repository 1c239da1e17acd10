// linesurf render MODEL -o out.png: software EWA splatting of point / hybrid models (thesis §4,
// §5, §6.2). Raw scans get normals and radii from the geometry stage (§6.1) first.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <sstream>

#include "command.h"
#include "drawable_model.h"
#include "linesurf/core/error.h"
#include "linesurf/core/timer.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/io/model_io.h"
#include "linesurf/io/model_validate.h"
#include "linesurf/render/camera.h"
#include "linesurf/render/mesh_render.h"
#include "linesurf/render/renderer.h"

namespace linesurf::cli {
namespace {

struct RenderArgs {
  std::string model, output = "render.png";
  std::string size = "512x512";
  float azimuth = 30, elevation = 20, distance = 0, fov = 30, zoom = 1;
  int views = 0;
  std::vector<float> eye, target, up;
  float alpha = -1;
  int layers = 4;
  float prefilter = 1.0f, cutoff = 2.0f, reconScale = 0.5f, radiusScale = 1.0f;
  std::string zMode = "primitive";
  float zThreshold = -1;
  float ambient = 0.25f, diffuse = 0.75f, specular = 0.2f, shininess = 24;
  std::vector<float> light, color;
  bool perPixel = false, noCull = false, worldLight = false;
  std::string background = "white";
  std::string upAxis = "y";
  std::string segmentMethod = "screen";
  std::string depthOut, alphaOut, normalOut;
  int k = 12;
  int tileSize = 64;
  std::string primitive = "auto";
  int supersampling = 4;
};

Vec3f vec3(const std::vector<float>& v, const char* name) {
  if (v.size() != 3) throwBadParameter(name, "needs three numbers x y z");
  return Vec3f(v[0], v[1], v[2]);
}

std::pair<int, int> parseSize(const std::string& s) {
  int w = 0, h = 0;
  char x = 0;
  std::istringstream in(s);
  if (!(in >> w >> x >> h) || (x != 'x' && x != 'X') || w < 1 || h < 1 || w > 16384 || h > 16384 || !in.eof())
    throwBadParameter("--size", "expected WIDTHxHEIGHT with 1..16384 pixels per side, got '" + s + "'");
  return {w, h};
}

Color parseBackground(const std::string& s) {
  if (s == "white") return Color(1, 1, 1, 1);
  if (s == "black") return Color(0, 0, 0, 1);
  if (s == "transparent" || s == "none") return Color(0, 0, 0, 0);
  std::vector<float> v;
  std::istringstream in(s);
  std::string tok;
  while (std::getline(in, tok, ',')) {
    try {
      v.push_back(std::stof(tok));
    } catch (...) {
      v.clear();
      break;
    }
  }
  if (v.size() == 3) v.push_back(1);
  if (v.size() != 4) throwBadParameter("--background", "expected white, black, transparent or R,G,B[,A] in [0,1]");
  return Color(v[0], v[1], v[2], v[3]);
}

std::filesystem::path viewPath(const std::filesystem::path& out, int i) {
  auto p = out;
  p.replace_filename(fmt::format("{}_{:03d}{}", out.stem().string(), i, out.extension().string()));
  return p;
}

std::filesystem::path bufferPath(const std::string& base, int view, int views) {
  return views > 0 ? viewPath(base, view) : std::filesystem::path(base);
}

// Depth as grey: near = white, far = dark, empty = transparent.
Image depthImage(const Image& depth) {
  float lo = INFINITY, hi = -INFINITY;
  for (const Color& c : depth.pixels)
    if (c.w() > 0) { lo = std::min(lo, c.x()); hi = std::max(hi, c.x()); }
  Image out(depth.width, depth.height);
  for (size_t i = 0; i < depth.pixels.size(); ++i) {
    const Color& c = depth.pixels[i];
    if (c.w() <= 0) continue;
    float g = hi > lo ? 1.0f - 0.8f * (c.x() - lo) / (hi - lo) : 1.0f;
    out.pixels[i] = Color(g, g, g, 1);
  }
  return out;
}

void run(const RenderArgs& a) {
  Timer total;
  auto [w, h] = parseSize(a.size);
  checkFiles({a.model}, {{"--output", a.output, {".png"}}, {"--depth-out", a.depthOut, {".png"}},
                         {"--alpha-out", a.alphaOut, {".png"}}, {"--normal-out", a.normalOut, {".png"}}});
  // Colour, depth, alpha, normal images (16 bytes a pixel each) and the Z3 fragment layers.
  checkSize("--size", double(w) * h * (16.0 * 4 + 48.0 * std::max(a.layers, 1)), "a " + a.size + " image");
  if (a.primitive != "auto" && a.primitive != "mesh" && a.primitive != "points")
    throwBadParameter("--primitive", "expected mesh, points or auto, got '" + a.primitive + "'");
  const bool isMesh = fileHoldsMesh(a.model);
  if (a.primitive == "mesh" && !isMesh)
    throwBadParameter("--primitive", "mesh needs a file with faces; " + a.model + " holds none");
  std::optional<TriangleMesh> triMesh;
  HybridModel model;
  if (isMesh && a.primitive != "points") {
    triMesh = readMesh(a.model);
    if (triMesh->faces.empty()) throw Error(Error::Kind::BadInput, a.model, "", "the mesh has no faces");
    say(fmt::format("{}: mesh, rasterising its {} triangles ({}x{} samples per pixel)", a.model, triMesh->faces.size(),
                    a.supersampling, a.supersampling));
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
  const float distance = float(a.distance / frame.scale);

  if (size_t n = estimateSegmentRadii(model))
    say(fmt::format("{} segments without a radius: estimated from the spacing of their neighbours", n));
  completePointGeometry(model, a.k);
  if (a.radiusScale != 1.0f) {
    for (Point& p : model.points) p.radius *= a.radiusScale;
    for (Segment& s : model.segments) s.radius *= a.radiusScale;
  }

  RenderOptions o;
  o.prefilterVariance = a.prefilter;
  o.cutoffRadius = a.cutoff;
  o.reconstructionScale = a.reconScale;
  if (a.zMode == "fixed") {
    o.zThresholdMode = ZThresholdMode::Fixed;
    o.zThreshold = a.zThreshold >= 0 ? a.zThreshold : 0.01f;
  } else if (a.zMode == "primitive") {
    o.zThresholdMode = ZThresholdMode::PerPrimitive;
    o.zThreshold = a.zThreshold >= 0 ? a.zThreshold : 0.5f;
  } else {
    throwBadParameter("--z-mode", "expected fixed or primitive");
  }
  o.layers = a.layers;
  o.material = {a.ambient, a.diffuse, a.specular, a.shininess};
  if (!a.light.empty()) o.light.direction = vec3(a.light, "--light");
  o.light.headlight = !a.worldLight;
  if (!a.color.empty()) o.defaultColor = Color(a.color.size() > 0 ? a.color[0] : 0, a.color.size() > 1 ? a.color[1] : 0,
                                                a.color.size() > 2 ? a.color[2] : 0, 1);
  if (!a.color.empty() && a.color.size() != 3) throwBadParameter("--color", "needs three numbers R G B in [0,1]");
  o.perPixelLighting = a.perPixel;
  o.alphaOverride = a.alpha;
  if (a.alpha > 1) throwBadParameter("--alpha", "must be in [0, 1]");
  o.background = parseBackground(a.background);
  o.backfaceCulling = !a.noCull;
  if (a.segmentMethod == "approx") o.segmentMethod = SegmentMethod::Approx;
  else if (a.segmentMethod == "screen") o.segmentMethod = SegmentMethod::ScreenSpace;
  else if (a.segmentMethod == "reference") o.segmentMethod = SegmentMethod::Reference;
  else throwBadParameter("--segment-method", "expected approx, screen or reference");
  o.depthBuffer = !a.depthOut.empty();
  o.alphaBuffer = !a.alphaOut.empty();
  o.normalBuffer = !a.normalOut.empty();
  o.tileSize = a.tileSize;
  o.progress = progressBar();
  if (!(a.zoom > 0) || !std::isfinite(a.zoom)) throwBadParameter("--zoom", "must be > 0");

  std::optional<Renderer> renderer;
  std::optional<MeshRenderer> meshRenderer;
  MeshRenderOptions mo;
  mo.supersampling = a.supersampling;
  if (triMesh) meshRenderer.emplace(*triMesh, o, mo);
  else renderer.emplace(model, o);
  const BoundingSphere& sphere = triMesh ? meshRenderer->sphere() : renderer->sphere();
  Vec3f upAxis;
  {
    std::string u = a.upAxis;
    float sign = 1;
    if (!u.empty() && (u[0] == '-' || u[0] == '+')) { sign = u[0] == '-' ? -1.f : 1.f; u = u.substr(1); }
    if (u == "x") upAxis = Vec3f(sign, 0, 0);
    else if (u == "y") upAxis = Vec3f(0, sign, 0);
    else if (u == "z") upAxis = Vec3f(0, 0, sign);
    else throwBadParameter("--up-axis", "expected x, y, z, -x, -y or -z, got '" + a.upAxis + "'");
  }
  std::vector<Camera> cams;
  if (!a.eye.empty() || !a.target.empty()) {
    Vec3f eye = a.eye.empty() ? Vec3f(sphere.center + Vec3f(0, 0, 3 * sphere.radius)) : frame.toNormalized(vec3(a.eye, "--eye"));
    Vec3f target = a.target.empty() ? sphere.center : frame.toNormalized(vec3(a.target, "--target"));
    Vec3f up = a.up.empty() ? Vec3f(0, 1, 0) : vec3(a.up, "--up");
    float dist = (eye - target).norm();
    // Name the options (the camera's own message would say "near/far").
    const char* which = !a.eye.empty() ? "--eye" : "--target";
    if (!eye.allFinite() || !target.allFinite() || !std::isfinite(dist))
      throwBadParameter(which, "--eye and --target must be finite points at a finite distance from each other");
    if (!(dist > 0)) throwBadParameter(which, "--eye must differ from --target");
    if (!up.allFinite() || !(up.cross(eye - target).norm() > 1e-6f * up.norm() * dist))
      throwBadParameter("--up", "must be a finite vector not parallel to the view direction");
    float nearD = std::max(1e-4f * dist, dist - 1.5f * sphere.radius);
    float farD = std::max(dist + 1.5f * sphere.radius, 2 * nearD);
    cams.push_back(Camera::lookAt(eye, target, up, a.fov, w, h, nearD, farD));
  } else if (a.views > 0) {
    for (const Vec2f& ang : Camera::spreadViewAngles(a.views)) {
      Camera c = Camera::orbit(sphere, ang.x(), ang.y(), distance, w, h, a.fov, upAxis);
      if (a.zoom != 1)
        c = Camera::orbit(sphere, ang.x(), ang.y(), (c.eye() - c.target()).norm() / a.zoom, w, h, a.fov, upAxis);
      cams.push_back(c);
    }
  } else {
    Camera c = Camera::orbit(sphere, a.azimuth, a.elevation, distance, w, h, a.fov, upAxis);
    if (a.zoom != 1)
      c = Camera::orbit(sphere, a.azimuth, a.elevation, (c.eye() - c.target()).norm() / a.zoom, w, h, a.fov, upAxis);
    cams.push_back(c);
  }

  RenderStats sum;
  uint64_t tris[5] = {0, 0, 0, 0, 0};
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
      tris[0] += m.stats.trianglesDrawn; tris[1] += m.stats.trianglesClipped; tris[2] += m.stats.trianglesCulled;
      tris[3] += m.stats.trianglesOutside; tris[4] += m.stats.trianglesDegenerate;
    } else {
      r = renderer->render(cams[i]);
    }
    const int vi = a.views > 0 ? int(i) : -1;
    std::filesystem::path out = vi >= 0 ? viewPath(a.output, vi) : std::filesystem::path(a.output);
    writePng(out, r.color, o.background.w() < 1);
    if (r.depth) writePng(bufferPath(a.depthOut, vi, a.views), depthImage(*r.depth));
    if (r.alpha) writePng(bufferPath(a.alphaOut, vi, a.views), *r.alpha);
    if (r.normal) writePng(bufferPath(a.normalOut, vi, a.views), *r.normal);
    const RenderStats& s = r.stats;
    if (cams.size() > 1)
      say(fmt::format("{}: {:.1f} ms, {} {} drawn", out.string(), 1000 * s.totalSeconds,
                      triMesh ? trianglesThisView : s.pointsDrawn + s.segmentsDrawn, triMesh ? "triangles" : "splats"));
    sum.pointsDrawn += s.pointsDrawn; sum.pointsClipped += s.pointsClipped; sum.pointsCulled += s.pointsCulled;
    sum.pointsOutside += s.pointsOutside; sum.pointsDegenerate += s.pointsDegenerate;
    sum.segmentsDrawn += s.segmentsDrawn; sum.segmentsClipped += s.segmentsClipped; sum.segmentsCulled += s.segmentsCulled;
    sum.segmentsOutside += s.segmentsOutside; sum.segmentsDegenerate += s.segmentsDegenerate;
    sum.segmentsFallback += s.segmentsFallback;
    sum.fragments += s.fragments; sum.merged += s.merged; sum.occluded += s.occluded; sum.compressed += s.compressed;
    sum.prepareSeconds += s.prepareSeconds; sum.binSeconds += s.binSeconds; sum.rasterSeconds += s.rasterSeconds;
    sum.totalSeconds += s.totalSeconds;
  }
  const std::string per = cams.size() > 1 ? fmt::format(" (over {} views)", cams.size()) : "";
  if (!model.points.empty())
    say(fmt::format("points{}: {} drawn ({} clipped), {} culled (back-facing), {} outside the view, {} degenerate", per,
                    sum.pointsDrawn, sum.pointsClipped, sum.pointsCulled, sum.pointsOutside, sum.pointsDegenerate));
  if (!model.segments.empty())
    say(fmt::format("segments{}: {} drawn ({} clipped), {} culled (back-facing), {} outside the view, {} degenerate, "
                    "{} approx fallbacks to screen-space", per, sum.segmentsDrawn, sum.segmentsClipped, sum.segmentsCulled,
                    sum.segmentsOutside, sum.segmentsDegenerate, sum.segmentsFallback));
  if (triMesh)
    say(fmt::format("triangles{}: {} drawn ({} clipped), {} culled (back-facing), {} outside the view, {} degenerate; "
                    "{} samples covered", per, tris[0], tris[1], tris[2], tris[3], tris[4], sum.fragments));
  else
  say(fmt::format("Z3 ({} layers): {} fragments, {} merged, {} occluded, {} compressions", o.layers, sum.fragments,
                  sum.merged, sum.occluded, sum.compressed));
  say(fmt::format("render {}x{}: {:.1f} ms (prepare {:.1f}, bin {:.1f}, raster+resolve {:.1f}); total {:.2f} s",
                  w, h, 1000 * sum.totalSeconds, 1000 * sum.prepareSeconds, 1000 * sum.binSeconds,
                  1000 * sum.rasterSeconds, total.seconds()));
  if (a.views > 0)
    say(fmt::format("wrote {} .. {}", viewPath(a.output, 0).string(), viewPath(a.output, int(cams.size()) - 1).string()));
  else
    say("wrote " + a.output);
}

RegisterCommand reg(40, [](CLI::App& app) {
  auto a = std::make_shared<RenderArgs>();
  CLI::App* sub = app.add_subcommand("render", "Render a point or hybrid model by EWA splatting (thesis §4-§6.2) to PNG");
  sub->add_option("MODEL", a->model, "Point cloud, hybrid model or mesh (.ply, .obj, .xyz); see --primitive")
      ->required();
  sub->add_option("-o,--output", a->output, "Output PNG (with --views N: OUT_000.png ...)")->capture_default_str();
  sub->add_option("--size", a->size, "Image size WIDTHxHEIGHT")->capture_default_str();
  auto* g = sub->add_option_group("camera", "Orbit view auto-framed on the bounding sphere, N views, or look-at");
  g->add_option("--azimuth", a->azimuth, "Orbit azimuth about +y, degrees (0 = from +z)")->capture_default_str();
  g->add_option("--elevation", a->elevation, "Orbit elevation, degrees in [-90, 90]")->capture_default_str();
  g->add_option("--distance", a->distance, "Orbit distance from the centre (0 = frame the model)")->capture_default_str();
  g->add_option("--zoom", a->zoom, "Divide the framed distance by this factor")->capture_default_str();
  g->add_option("--fov", a->fov, "Vertical field of view, degrees")->capture_default_str()->check(CLI::Range(1.0, 170.0));
  g->add_option("--views", a->views, "Render N views spread over the sphere (deterministic)")->check(CLI::Range(1, 10000));
  g->add_option("--up-axis", a->upAxis, "World up axis of the orbit: x, y, z, -x, -y, -z (santa, rockerarm: z)")->capture_default_str();
  g->add_option("--eye", a->eye, "Look-at camera position x y z")->expected(3);
  g->add_option("--target", a->target, "Look-at target x y z (default: model centre)")->expected(3);
  g->add_option("--up", a->up, "Look-at up vector (default 0 1 0)")->expected(3);
  auto* f = sub->add_option_group("filtering", "EWA resampling filter (§4.2.2)");
  f->add_option("--prefilter", a->prefilter, "Screen prefilter variance, pixels^2 (0 = none)")->capture_default_str();
  f->add_option("--cutoff", a->cutoff, "Resampling filter cut-off radius, standard deviations [1, 5]")->capture_default_str();
  f->add_option("--recon-scale", a->reconScale, "Reconstruction sigma as a fraction of the point radius")->capture_default_str();
  f->add_option("--radius-scale", a->radiusScale, "Multiply every primitive radius")->capture_default_str()->check(CLI::Range(1e-3, 1e3));
  auto* v = sub->add_option_group("visibility", "Modified Z^3 buffer (§6.2.3)");
  v->add_option("--layers", a->layers, "Fragment layers per pixel [1, 8]")->capture_default_str();
  v->add_option("--z-mode", a->zMode, "z threshold: primitive (delta-z, own depth extent) or fixed (thesis)")->capture_default_str();
  v->add_option("--z-threshold", a->zThreshold, "primitive: multiple of the depth extent (default 0.5); fixed: fraction of the bounding radius (default 0.01)");
  v->add_option("--alpha", a->alpha, "Alpha of every primitive in [0, 1] (order-independent transparency)");
  v->add_flag("--no-cull", a->noCull, "Keep back faces (two-sided lighting)");
  auto* s = sub->add_option_group("shading", "Phong lighting (§6.2.2); defaults suit unit-free scans");
  s->add_option("--ambient", a->ambient, "Ambient coefficient")->capture_default_str();
  s->add_option("--diffuse", a->diffuse, "Diffuse coefficient")->capture_default_str();
  s->add_option("--specular", a->specular, "Specular coefficient")->capture_default_str();
  s->add_option("--shininess", a->shininess, "Phong exponent")->capture_default_str();
  s->add_option("--light", a->light, "Direction towards the light x y z (camera space; world with --world-light)")->expected(3);
  s->add_flag("--world-light", a->worldLight, "--light is in world space instead of a headlight");
  s->add_option("--color", a->color, "Albedo R G B in [0,1] for models without colours")->expected(3);
  s->add_flag("--per-pixel-lighting", a->perPixel, "Light every fragment instead of Gouraud at the quad vertices");
  s->add_option("--background", a->background, "white, black, transparent or R,G,B[,A]")->capture_default_str();
  sub->add_option("--segment-method", a->segmentMethod, "Line-segment filter: approx (§5.2.3 quads), screen (erf), reference")->capture_default_str();
  sub->add_option("--depth-out", a->depthOut, "Also write the depth buffer as a grey PNG (near = white)");
  sub->add_option("--alpha-out", a->alphaOut, "Also write the coverage alpha as a PNG");
  sub->add_option("--normal-out", a->normalOut, "Also write camera-space normals as (n+1)/2 RGB");
  sub->add_option("--k", a->k, "Neighbours for normals/radii of raw scans (§6.1)")->capture_default_str()->check(CLI::Range(3, 200));
  sub->add_option("--primitive", a->primitive,
                  "What a mesh file is drawn as: mesh (anti-aliased triangles, the ground truth), points (its "
                  "vertices as splats) or auto (mesh when the file has faces)")->capture_default_str();
  sub->add_option("--supersampling", a->supersampling, "Mesh: samples per pixel side (S x S per pixel) [1, 16]")
      ->capture_default_str();
  sub->add_option("--tile-size", a->tileSize, "Screen tile side in pixels (does not change the image)")->capture_default_str();
  sub->callback([a] { run(*a); });
});

}  // namespace
}  // namespace linesurf::cli
