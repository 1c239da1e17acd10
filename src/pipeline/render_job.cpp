// The steps of `linesurf render` around the renderer (thesis §6.1 for raw scans, §6.2.2 camera).
#include "linesurf/pipeline/render_job.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include "linesurf/core/error.h"
#include "linesurf/core/options.h"
#include "linesurf/core/timer.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/io/model_validate.h"

namespace linesurf {

namespace {
void requireVector(const char* field, const std::optional<Vec3f>& v) {
  if (v && !v->allFinite()) throwBadOption(field, "needs three finite numbers x y z");
}
}  // namespace

void validate(const ViewOptions& o) {
  if (o.width < 1 || o.height < 1 || o.width > 16384 || o.height > 16384)
    throwBadOption("size", fmt::format("expected WIDTHxHEIGHT with 1..16384 pixels per side, got {}x{}", o.width, o.height));
  requireFinite("azimuth", o.azimuth);
  requireRange("elevation", o.elevation, -90, 90, "degrees");
  requireRange("distance", o.distance, 0, 1e30);
  requireRange("zoom", o.zoom, 1e-3, 1e3);  // beyond: the model shrinks to nothing or fills past the view
  requireRange("fov", o.fov, 1, 170, "degrees");
  requireRange("views", o.views, 0, 10000);
  if (!o.upAxis.allFinite() || o.upAxis.norm() == 0) throwBadOption("upAxis", "must be a finite non-zero axis");
  requireVector("eye", o.eye);
  requireVector("target", o.target);
  requireVector("up", o.up);
  if (o.up && o.up->norm() == 0) throwBadOption("up", "must be a non-zero vector");
}

Vec3f parseUpAxis(const std::string& text) {
  std::string u = text;
  float sign = 1;
  if (!u.empty() && (u[0] == '-' || u[0] == '+')) {
    sign = u[0] == '-' ? -1.f : 1.f;
    u = u.substr(1);
  }
  if (u == "x") return Vec3f(sign, 0, 0);
  if (u == "y") return Vec3f(0, sign, 0);
  if (u == "z") return Vec3f(0, 0, sign);
  throwBadOption("upAxis", "expected x, y, z, -x, -y or -z, got '" + text + "'");
}

Color parseBackground(const std::string& s) { return parseColor("background", s); }

Color parseColor(const std::string& field, const std::string& s) {
  if (s.size() == 7 && s[0] == '#' && s.find_first_not_of("0123456789abcdefABCDEF", 1) == std::string::npos) {
    const unsigned long v = std::strtoul(s.c_str() + 1, nullptr, 16);
    return Color(float((v >> 16) & 255) / 255.0f, float((v >> 8) & 255) / 255.0f, float(v & 255) / 255.0f, 1);
  }
  if (s == "white") return Color(1, 1, 1, 1);
  if (s == "black") return Color(0, 0, 0, 1);
  if (s == "transparent" || s == "none") return Color(0, 0, 0, 0);
  std::vector<float> v;
  size_t start = 0;
  while (start <= s.size()) {
    size_t end = s.find(',', start);
    if (end == std::string::npos) end = s.size();
    const std::string tok = s.substr(start, end - start);
    char* stop = nullptr;
    const float x = std::strtof(tok.c_str(), &stop);
    if (tok.empty() || *stop != 0 || !(x >= 0 && x <= 1)) {
      v.clear();
      break;
    }
    v.push_back(x);
    start = end + 1;
  }
  if (v.size() == 3) v.push_back(1);
  if (v.size() != 4) throwBadOption(field, "expected white, black, transparent, #rrggbb or R,G,B[,A] in [0,1], got '" + s + "'");
  return Color(v[0], v[1], v[2], v[3]);
}

std::vector<Camera> viewCameras(const BoundingSphere& sphere, const ViewOptions& o, const ModelFrame& frame) {
  validate(o);
  const float distance = float(o.distance / frame.scale);
  std::vector<Camera> cams;
  const int w = o.width, h = o.height;
  if (o.eye || o.target) {
    Vec3f eye = o.eye ? frame.toNormalized(*o.eye) : Vec3f(sphere.center + Vec3f(0, 0, 3 * sphere.radius));
    Vec3f target = o.target ? frame.toNormalized(*o.target) : sphere.center;
    Vec3f up = o.up ? *o.up : Vec3f(0, 1, 0);
    float dist = (eye - target).norm();
    const char* which = o.eye ? "eye" : "target";
    if (!eye.allFinite() || !target.allFinite() || !std::isfinite(dist))
      throwBadOption(which, "`eye` and `target` must be finite points at a finite distance from each other");
    if (!(dist > 0)) throwBadOption(which, "`eye` must differ from `target`");
    if (!up.allFinite() || !(up.cross(eye - target).norm() > 1e-6f * up.norm() * dist))
      throwBadOption("up", "must be a finite vector not parallel to the view direction");
    float nearD = std::max(1e-4f * dist, dist - 1.5f * sphere.radius);
    float farD = std::max(dist + 1.5f * sphere.radius, 2 * nearD);
    cams.push_back(Camera::lookAt(eye, target, up, o.fov, w, h, nearD, farD));
    return cams;
  }
  auto orbit = [&](float azimuth, float elevation) {
    Camera c = Camera::orbit(sphere, azimuth, elevation, distance, w, h, o.fov, o.upAxis);
    if (o.zoom != 1)
      c = Camera::orbit(sphere, azimuth, elevation, (c.eye() - c.target()).norm() / o.zoom, w, h, o.fov, o.upAxis);
    return c;
  };
  if (o.views > 0)
    for (const Vec2f& a : Camera::spreadViewAngles(o.views)) cams.push_back(orbit(a.x(), a.y()));
  else
    cams.push_back(orbit(o.azimuth, o.elevation));
  return cams;
}

void validate(const PrepareOptions& o) {
  requireRange("k", o.k, 3, 256);
  requireRange("radiusScale", o.radiusScale, 1e-3, 1e3);
}

void validate(const MeshRenderOptions& o) { requireRange("supersampling", o.supersampling, 1, 16, "samples per pixel side"); }

void estimateMissingPointGeometry(HybridModel& model, int k, PrepareReport& report, const ProgressFn& progress) {
  const bool pointWithoutRadius =
      std::any_of(model.points.begin(), model.points.end(), [](const Point& p) { return p.radius == 0.0f; });
  if (model.points.empty() || (model.attributes.normals && model.attributes.radii && !pointWithoutRadius)) return;
  Timer t;
  report.computedNormals = !model.attributes.normals;
  report.computedRadii = true;
  GeometryOptions go;
  go.k = k;
  go.delaunayNeighbours = false;
  go.curvature = false;
  go.progress = progress;
  PointGeometry geo = computePointGeometry(model, go);
  applyGeometry(model, geo);
  for (size_t i = 0; i < model.points.size() && i < geo.spacing.size(); ++i)  // hybrid: radii on segments only
    if (model.points[i].radius == 0.0f) model.points[i].radius = geo.spacing[i] > 0 ? geo.spacing[i] : geo.averageSpacing;
  report.geometrySeconds = t.seconds();
}

PrepareReport prepareForRendering(HybridModel& model, const PrepareOptions& o) {
  validate(o);
  PrepareReport r;
  r.segmentRadiiEstimated = estimateSegmentRadii(model);
  estimateMissingPointGeometry(model, o.k, r, o.progress);
  if (o.radiusScale != 1.0f) {
    for (Point& p : model.points) p.radius *= o.radiusScale;
    for (Segment& s : model.segments) s.radius *= o.radiusScale;
  }
  return r;
}

std::string backFacingWarning(const RenderStats& stats, const std::string& what) {
  const double share = stats.backFacingShare();
  if (!(share > kBackFacingWarnShare)) return {};
  return fmt::format(
      "{}: {:.0f}% of the pixels it covers show the back of its surface ({:.0f}% nothing at all): its normals face away "
      "from the viewer; re-orient them (linesurf normals IN -o OUT --recompute --orient up for terrain, --orient towards "
      "X Y Z for a room seen from inside) or draw both sides with --no-cull",
      what, 100 * share, 100 * double(stats.facingEmptyPixels) / double(stats.facingPixels));
}

Image depthAsGrey(const Image& depth) {
  float lo = INFINITY, hi = -INFINITY;
  for (const Color& c : depth.pixels)
    if (c.w() > 0) {
      lo = std::min(lo, c.x());
      hi = std::max(hi, c.x());
    }
  Image out(depth.width, depth.height);
  for (size_t i = 0; i < depth.pixels.size(); ++i) {
    const Color& c = depth.pixels[i];
    if (c.w() <= 0) continue;
    float g = hi > lo ? 1.0f - 0.8f * (c.x() - lo) / (hi - lo) : 1.0f;
    out.pixels[i] = Color(g, g, g, 1);
  }
  return out;
}

}  // namespace linesurf
