// One view of a drawing (thesis §9.4, §9.5; render/drawing.h): the splat render of the view,
// each stroke sampled along its projection against the splat depth (hidden parts) and the tone
// (density), the visible runs and silhouettes rasterised. Strokes are sampled in parallel, each
// into its own slot, and concatenated in stroke order: the same runs for any thread count.
#include "linesurf/render/drawing.h"

#include <algorithm>
#include <cmath>

#include "linesurf/core/options.h"
#include "linesurf/core/parallel.h"
#include "linesurf/core/timer.h"
#include "stroke_raster.h"

namespace linesurf {

void validate(const DrawingOptions& o) {
  requireRange("strokeWidth", o.strokeWidth, 0.1, 64, "pixels");
  auto channels = [](const char* field, const Color& c) {
    if (!c.allFinite() || (c.array() < 0).any() || (c.array() > 1).any())
      throwBadOption(field, "channels must be in [0, 1]");
  };
  channels("paper", o.paper);
  channels("ink", o.ink);
  if (!(o.ink.w() > 0)) throwBadOption("ink", "must not be transparent (alpha > 0)");
  requireRange("toneLevels", o.toneLevels, 0, 256, "(0 = continuous)");
  if (!(o.strokeDepthTolerance > 0 && o.strokeDepthTolerance <= 100))
    throwBadOption("strokeDepthTolerance", "must be in (0, 100] segment radii, got " + numberText(o.strokeDepthTolerance));
}

float drawingTone(const Color& c, int levels) {
  const float l = std::clamp(0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z(), 0.0f, 1.0f);
  if (levels <= 0) return l;
  return (std::min(float(levels - 1), std::floor(l * float(levels))) + 0.5f) / float(levels);
}

namespace {

struct StrokeContext {
  const StrokeSet& set;
  const Camera& cam;
  const RenderResult& splat;
  const DrawingOptions& o;
};

/// The screen distance between neighbouring strokes of a piece's family at its midpoint: the
/// object-space offset `offset` projected, perpendicular to the piece's screen direction `dir`.
float projectedAcross(const Camera& cam, const Vec3f& midCam, const Vec3f& offsetCam, const Vec2f& dir) {
  const Vec3f q = midCam + offsetCam;
  if (-q.z() <= cam.nearDepth()) return 0;
  const Vec3f a = cam.project(midCam), b = cam.project(q);
  const Vec2f d(b.x() - a.x(), b.y() - a.y());
  return (d - d.dot(dir) * dir).norm();
}

/// §9.4: whether the tone at a pixel asks for a piece of this family and priority. The main
/// family draws the strokes of priority below f = D s / w (D the darkness, s the projected
/// spacing, w the width: coverage w / s at full density), the in-between strokes those below
/// f - 1; the cross family draws where the main family at full density (C1 = w / s1; with the
/// in-between strokes 1 - (1 - w / s1)^2, as they fall independently of the strokes they copy
/// where chains of two sides meet) is lighter than the tone, for the rest: 1 - D = (1 - C1)(1 - C2).
bool toneWants(float darkness, float priority, uint8_t family, float ownSpacing, float mainSpacing, float w,
               bool inBetween) {
  if (family == StrokeSet::Stroke::kMain) return priority <= darkness * ownSpacing / w;
  if (family == StrokeSet::Stroke::kInBetween) return priority + 1 <= darkness * ownSpacing / w;
  const float one = mainSpacing > 0 ? std::min(1.0f, w / mainSpacing) : 1.0f;
  const float c1 = inBetween ? 1 - (1 - one) * (1 - one) : one;
  if (darkness <= c1 || c1 >= 1) return false;
  const float c2 = (darkness - c1) / (1 - c1);
  return priority <= c2 * ownSpacing / w;
}

/// The visible runs of one stroke (§9.4): its pieces sampled every half pixel on screen; a
/// sample is drawn where it lies on the visible surface (within the tolerance of the splat
/// depth) and, for Hatch, where the tone wants its priority. Returns its visible length.
float strokeRuns(const StrokeContext& c, uint32_t si, std::vector<StrokeRun>& out) {
  const StrokeSet::Stroke& s = c.set.strokes()[si];
  const Image& depth = *c.splat.depth;
  const Image& color = c.splat.color;
  const Camera& cam = c.cam;
  const bool hatch = c.o.style == DrawStyle::Hatch, cross = s.family == StrokeSet::Stroke::kCross;
  const bool inBetween = c.set.inBetweenStrokes() > 0;
  const Mat3f& rot = cam.rotation();
  StrokeRun run;
  run.stroke = si;
  Vec2f lastPass(0, 0);
  bool lastPushed = true;
  float visible = 0;
  auto close = [&] {
    if (!run.points.empty() && !lastPushed) run.points.push_back(lastPass);
    if (run.points.size() >= 2) {
      for (size_t k = 0; k + 1 < run.points.size(); ++k) visible += (run.points[k + 1] - run.points[k]).norm();
      out.push_back(run);
    }
    run.points.clear();
    lastPushed = true;
  };
  for (uint32_t i = s.first; i < s.first + s.count; ++i) {
    const StrokeSet::Piece& p = c.set.pieces()[i];
    Vec3f a = cam.toCamera(p.a), b = cam.toCamera(p.b);
    const Vec3f n = rot * p.normal;
    const float nearZ = -cam.nearDepth();
    // back faces are hidden; the near plane clips
    if (n.dot(-0.5f * (a + b)) < 0 || (a.z() > nearZ && b.z() > nearZ)) { close(); continue; }
    if (a.z() > nearZ) a = b + (a - b) * ((b.z() - nearZ) / (b.z() - a.z()));
    if (b.z() > nearZ) b = a + (b - a) * ((a.z() - nearZ) / (a.z() - b.z()));
    const Vec3f sa = cam.project(a), sb = cam.project(b);
    Vec2f dir(sb.x() - sa.x(), sb.y() - sa.y());
    const float len = dir.norm();
    dir = len > 1e-6f ? Vec2f(dir / len) : Vec2f(1, 0);
    float own = 0, main = 0;
    if (hatch) {
      const Vec3f mid = 0.5f * (a + b), t = (b - a).normalized();
      const Vec3f across = n.cross(t).normalized();
      // every family's neighbours lie across it (n x t); a cross stroke spans one main spacing
      own = projectedAcross(cam, mid, across * p.spacing, dir);
      main = cross ? len : own;
    }
    const int steps = std::max(1, int(std::ceil(len / 0.5f)));
    const float tol = c.o.strokeDepthTolerance * p.radius;
    for (int j = i == s.first ? 0 : 1; j <= steps; ++j) {
      const Vec3f q = a + (b - a) * (float(j) / float(steps));
      const Vec3f sq = cam.project(q);
      const int x = int(std::floor(sq.x())), y = int(std::floor(sq.y()));
      bool pass = x >= 0 && y >= 0 && x < depth.width && y < depth.height;
      if (pass) {
        const Color& z = depth.at(x, y);
        pass = z.w() > 0.5f && std::abs(sq.z() - z.x()) <= tol;
      }
      if (pass && hatch)
        pass = toneWants(1 - drawingTone(color.at(x, y), c.o.toneLevels), s.priority, s.family, own, main,
                         c.o.strokeWidth, inBetween);
      const Vec2f pt(sq.x(), sq.y());
      if (!pass) {
        close();
        continue;
      }
      if (run.points.empty() || j == steps) run.points.push_back(pt), lastPushed = true;
      else lastPass = pt, lastPushed = false;
    }
  }
  close();
  return visible;
}

}  // namespace

Drawing drawStrokes(const StrokeSet& set, const Camera& cam, const RenderResult& splat, const DrawingOptions& o) {
  validate(o);
  if (!splat.depth) throwBadOption("depthBuffer", "a drawing needs the splat render's depth buffer");
  Timer total;
  Drawing d;
  const StrokeContext c{set, cam, splat, o};
  const size_t n = set.strokes().size();
  std::vector<std::vector<StrokeRun>> perStroke(n);
  d.visibleLength.assign(n, 0.0f);
  parallelFor(0, n, [&](size_t i) { d.visibleLength[i] = strokeRuns(c, uint32_t(i), perStroke[i]); }, 64);
  for (size_t i = 0; i < n; ++i) {
    d.stats.strokesDrawn += !perStroke[i].empty();
    for (StrokeRun& r : perStroke[i]) d.runs.push_back(std::move(r));
  }
  d.stats.strokes = set.mainStrokes();
  d.stats.inBetweenStrokes = set.inBetweenStrokes();
  d.stats.crossStrokes = n - set.mainStrokes() - set.inBetweenStrokes();
  d.stats.runs = d.runs.size();
  d.stats.strokeSeconds = total.seconds();
  if (o.silhouettes) {
    std::vector<StrokeRun> sil =
        detail::traceSilhouettes(*splat.depth, splat.normal ? *splat.normal : Image(), cam.focalPixels());
    d.stats.silhouettePaths = sil.size();
    for (StrokeRun& r : sil) d.runs.push_back(std::move(r));
  }
  Timer raster;
  d.image = detail::rasterRuns(d.runs, cam.width(), cam.height(), o.strokeWidth, o.paper, o.ink);
  d.stats.rasterSeconds = raster.seconds();
  d.stats.totalSeconds = total.seconds();
  return d;
}

RenderOptions DrawingRenderer::withBuffers(RenderOptions o) {
  o.depthBuffer = o.normalBuffer = true;
  return o;
}

DrawingRenderer::DrawingRenderer(const HybridModel& model, const RenderOptions& render, const DrawingOptions& drawing)
    : renderer_(model, withBuffers(render)), options_(drawing), strokes_((validate(drawing), model), drawing) {}

Drawing DrawingRenderer::render(const Camera& camera) const {
  Timer t;
  RenderResult splat = renderer_.render(camera);
  const double splatSeconds = t.seconds();
  Drawing d = drawStrokes(strokes_, camera, splat, options_);
  d.stats.splatSeconds = splatSeconds;
  d.stats.totalSeconds += splatSeconds;
  d.splat = std::move(splat);
  return d;
}

}  // namespace linesurf
