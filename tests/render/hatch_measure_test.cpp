// The drawing's tone and coherence figures of docs/results.md (thesis §9.4): skipped unless
// LINESURF_DRAWING_MEASURE names a folder for the images, as it takes a minute (Igea's
// shape-approximation hybrid is extracted through the CLI).
//   tone: ink luminance blurred by a Gaussian of sigma = the projected stroke spacing in pixels,
//   against the target tone (the shaded render's luminance quantised to 8 levels), on pixels at
//   least 2 sigma inside the silhouette: mean absolute error, and the mean drawn tone per level;
//   coherence: two views 3 degrees apart, the visible length kept by stroke id.
// Igea is drawn from its shape-approximation hybrid and from its lines of curvature (§9.2).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>

#include "linesurf/core/timer.h"
#include "linesurf/extract/contour.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/io/model_io.h"
#include "linesurf/pipeline/render_job.h"
#include "linesurf/render/drawing.h"
#include "shapes.h"
#include "test_util.h"

namespace linesurf {
namespace {

float luminance(const Color& c) { return 0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z(); }

TriangleMesh torusMesh(float R, float r, int nu, int nv) {
  TriangleMesh m;
  const float pi = 3.14159265358979f;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const float u = 2 * pi * float(i) / float(nu), v = 2 * pi * float(j) / float(nv);
      m.positions.push_back(Vec3f((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v)));
      m.normals.push_back(Vec3f(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v)));
    }
  auto id = [&](int i, int j) { return uint32_t(((i + nu) % nu) * nv + (j + nv) % nv); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

std::vector<float> blur(const std::vector<float>& img, int w, int h, float sigma) {
  const int r = int(std::ceil(3 * sigma));
  std::vector<float> k(2 * r + 1);
  float sum = 0;
  for (int i = -r; i <= r; ++i) sum += k[i + r] = std::exp(-0.5f * float(i * i) / (sigma * sigma));
  for (float& x : k) x /= sum;
  std::vector<float> tmp(img.size()), out(img.size());
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float a = 0;
      for (int i = -r; i <= r; ++i) a += k[i + r] * img[size_t(y) * w + std::clamp(x + i, 0, w - 1)];
      tmp[size_t(y) * w + x] = a;
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      float a = 0;
      for (int i = -r; i <= r; ++i) a += k[i + r] * tmp[size_t(std::clamp(y + i, 0, h - 1)) * w + x];
      out[size_t(y) * w + x] = a;
    }
  return out;
}

struct ToneFigures {
  double mae = 0, sigma = 0;
  std::array<double, 8> levelTone{}, levelTarget{};
  std::array<size_t, 8> levelCount{};
  size_t pixels = 0;
};

ToneFigures toneError(const Drawing& d, const Camera& cam, float spacing) {
  const Image& depth = *d.splat.depth;
  const int w = depth.width, h = depth.height;
  // the projected spacing at the covered pixels' median depth
  std::vector<float> z;
  for (const Color& c : depth.pixels)
    if (c.w() > 0.5f) z.push_back(c.x());
  std::nth_element(z.begin(), z.begin() + long(z.size() / 2), z.end());
  ToneFigures f;
  f.sigma = spacing * cam.focalPixels() / z[z.size() / 2];
  std::vector<float> ink(d.image.pixels.size());
  for (size_t i = 0; i < ink.size(); ++i) ink[i] = luminance(d.image.pixels[i]);
  const std::vector<float> b = blur(ink, w, h, float(f.sigma));
  const int reach = int(std::ceil(2 * f.sigma));
  double err = 0;
  for (int y = reach; y < h - reach; ++y)
    for (int x = reach; x < w - reach; ++x) {
      if (!(depth.at(x, y).w() > 0.5f)) continue;
      bool inside = true;  // at least 2 sigma from every uncovered pixel
      for (int dy = -reach; dy <= reach && inside; ++dy)
        for (int dx = -reach; dx <= reach && inside; ++dx)
          if (dx * dx + dy * dy <= reach * reach && !(depth.at(x + dx, y + dy).w() > 0.5f)) inside = false;
      if (!inside) continue;
      const float t = drawingTone(d.splat.color.at(x, y), 8);
      const float got = b[size_t(y) * w + x];
      err += std::abs(got - t);
      const int level = std::min(7, int(t * 8));
      f.levelTone[level] += got, f.levelTarget[level] += t, ++f.levelCount[level];
      ++f.pixels;
    }
  f.mae = f.pixels ? err / double(f.pixels) : 0;
  for (int i = 0; i < 8; ++i)
    if (f.levelCount[i]) f.levelTone[i] /= double(f.levelCount[i]), f.levelTarget[i] /= double(f.levelCount[i]);
  return f;
}

void measure(const std::string& name, HybridModel model, const std::filesystem::path& dir, const Vec3f& up, int size,
             const DrawingOptions& o) {
  const ModelFrame frame = normalizingFrame(model.bounds());
  toFrame(model, frame);
  prepareForRendering(model, {});
  Timer build;
  const DrawingRenderer r(model, {}, o);
  const double buildSeconds = build.seconds();
  ViewOptions v;
  v.width = v.height = size;
  v.upAxis = up;
  const Camera a = viewCameras(r.sphere(), v, frame).front();
  v.azimuth += 3;
  const Camera b = viewCameras(r.sphere(), v, frame).front();
  const Drawing da = r.render(a), db = r.render(b);
  const ToneFigures f = toneError(da, a, r.strokes().typicalSpacing());
  double drawn = 0, kept = 0;
  size_t idsA = 0, idsBoth = 0;
  for (size_t i = 0; i < da.visibleLength.size(); ++i) {
    drawn += da.visibleLength[i], kept += std::min(da.visibleLength[i], db.visibleLength[i]);
    idsA += da.visibleLength[i] > 0, idsBoth += da.visibleLength[i] > 0 && db.visibleLength[i] > 0;
  }
  std::string levels;
  bool increasing = true;
  double last = -1;
  for (int i = 0; i < 8; ++i) {
    if (!f.levelCount[i]) continue;
    levels += fmt::format(" {}:{:.3f}/{:.3f}", i, f.levelTone[i], f.levelTarget[i]);
    increasing = increasing && f.levelTone[i] > last;
    last = f.levelTone[i];
  }
  std::printf("%s\n", fmt::format("| {} | {}² | w {:g}{} | {} strokes + {} between + {} across | MAE {:.3f} (σ {:.2f} px, {} px) | "
                                  "increasing {} | kept by id {:.3f} (ids {:.3f}) | set {:.2f} s, frame {:.0f} ms (splat {:.0f}, "
                                  "strokes {:.0f}, raster {:.0f}) |{}",
                                  name, size, o.strokeWidth, std::string(o.inBetween ? "" : " no in-between") + (o.crossHatch ? "" : " no cross"), r.strokes().mainStrokes(),
                                  r.strokes().inBetweenStrokes(),
                                  r.strokes().strokes().size() - r.strokes().mainStrokes() - r.strokes().inBetweenStrokes(), f.mae, f.sigma, f.pixels,
                                  increasing ? "yes" : "no", drawn > 0 ? kept / drawn : 0.0,
                                  idsA ? double(idsBoth) / double(idsA) : 0.0, buildSeconds, 1000 * da.stats.totalSeconds,
                                  1000 * da.stats.splatSeconds, 1000 * da.stats.strokeSeconds,
                                  1000 * da.stats.rasterSeconds, levels)
                           .c_str());
  const std::string stem = fmt::format("{}_{}_w{:g}{}{}", name, size, o.strokeWidth, o.inBetween ? "" : "_nobetween",
                                       o.crossHatch ? "" : "_nocross");
  writePng(dir / (stem + ".png"), da.image, false);
  writePng(dir / (stem + "_shaded.png"), da.splat.color, false);
  std::ofstream(dir / (stem + ".svg")) << drawingSvg(da, o);
}

/// A 60-frame orbit, 3 degrees a frame: the visible length kept by id from frame to frame (mean
/// and least over the 59 pairs), and the flicker: the blurred ink of frame t + 1 against frame t's
/// at the same surface point (frame t + 1's pixels reprojected into t through its depth buffer;
/// pixels whose point is hidden or off frame t are left out), mean absolute difference.
void orbit(const std::string& name, HybridModel model, const Vec3f& up, const DrawingOptions& o, bool headlight) {
  const ModelFrame frame = normalizingFrame(model.bounds());
  toFrame(model, frame);
  prepareForRendering(model, {});
  RenderOptions ro;
  ro.light.headlight = headlight;  // off: the light, so the tone, stays put on the surface
  const DrawingRenderer r(model, ro, o);
  ViewOptions v;
  v.width = v.height = 512;
  v.upAxis = up;
  std::vector<Camera> cams;
  for (int f = 0; f < 60; ++f, v.azimuth += 3) cams.push_back(viewCameras(r.sphere(), v, frame).front());
  Drawing prev = r.render(cams[0]);
  const float sigma = r.strokes().typicalSpacing() * cams[0].focalPixels() / (cams[0].eye() - r.sphere().center).norm();
  auto blurred = [&](const Drawing& d) {
    std::vector<float> ink(d.image.pixels.size());
    for (size_t i = 0; i < ink.size(); ++i) ink[i] = luminance(d.image.pixels[i]);
    return blur(ink, 512, 512, sigma);
  };
  std::vector<float> prevBlur = blurred(prev);
  double keptSum = 0, keptMin = 1, flickerSum = 0;
  for (int f = 1; f < 60; ++f) {
    Drawing cur = r.render(cams[f]);
    std::vector<float> curBlur = blurred(cur);
    double drawn = 0, kept = 0;
    for (size_t i = 0; i < cur.visibleLength.size(); ++i)
      drawn += prev.visibleLength[i], kept += std::min(prev.visibleLength[i], cur.visibleLength[i]);
    keptSum += kept / drawn, keptMin = std::min(keptMin, kept / drawn);
    const Image& z = *cur.splat.depth;
    const Image& zp = *prev.splat.depth;
    const Mat4f worldFromCamera = cams[f].cameraFromWorld().inverse();
    double diff = 0;
    size_t n = 0;
    for (int y = 0; y < 512; ++y)
      for (int x = 0; x < 512; ++x) {
        if (!(z.at(x, y).w() > 0.5f)) continue;
        const Vec3f pc = cams[f].rayThrough(x + 0.5f, y + 0.5f) * z.at(x, y).x();
        const Vec3f pw = (worldFromCamera * pc.homogeneous()).head<3>();
        const Vec3f q = cams[f - 1].project(cams[f - 1].toCamera(pw));
        const int qx = int(std::floor(q.x())), qy = int(std::floor(q.y()));
        if (qx < 0 || qy < 0 || qx >= 512 || qy >= 512 || !(zp.at(qx, qy).w() > 0.5f)) continue;
        if (std::abs(zp.at(qx, qy).x() - q.z()) > 0.01f * q.z()) continue;  // hidden in frame t
        diff += std::abs(curBlur[size_t(y) * 512 + x] - prevBlur[size_t(qy) * 512 + qx]), ++n;
      }
    flickerSum += n ? diff / double(n) : 0;
    prev = std::move(cur), prevBlur = std::move(curBlur);
  }
  std::printf("%s\n", fmt::format("| {} orbit, {} | length kept by id: mean {:.3f}, least {:.3f} | flicker {:.4f} (σ {:.2f} px) |",
                                  name, headlight ? "headlight" : "world light", keptSum / 59, keptMin, flickerSum / 59, sigma).c_str());
}

TEST(DrawingMeasure, Orbit) {
  if (!std::getenv("LINESURF_DRAWING_MEASURE")) GTEST_SKIP() << "set LINESURF_DRAWING_MEASURE to a folder to measure";
  const std::filesystem::path dir(std::getenv("LINESURF_DRAWING_MEASURE"));
  const DrawingOptions o{.style = DrawStyle::Hatch};
  for (bool headlight : {true, false}) {
    orbit("sphere", extractContour(shapes::sphereMesh(1, 5)), Vec3f(0, 1, 0), o, headlight);
    orbit("torus", extractContour(torusMesh(1, 0.4f, 160, 64)), Vec3f(0, 0, 1), o, headlight);
    if (std::filesystem::exists(dir / "igea_curvature_lines.ply"))
      orbit("igea-curvature-lines", readModel(dir / "igea_curvature_lines.ply"), Vec3f(0, 1, 0), o, headlight);
  }
}

TEST(DrawingMeasure, ToneAndCoherence) {
  const char* out = std::getenv("LINESURF_DRAWING_MEASURE");
  if (!out) GTEST_SKIP() << "set LINESURF_DRAWING_MEASURE to a folder to measure";
  const std::filesystem::path dir(out);
  std::filesystem::create_directories(dir);
  const HybridModel sphere = extractContour(shapes::sphereMesh(1, 5));
  const HybridModel torus = extractContour(torusMesh(1, 0.4f, 160, 64));
  const auto igeaPath = dir / "igea_shape_approx.ply";
  if (!std::filesystem::exists(igeaPath)) {
    ASSERT_EQ(test::runCli("-q extract shape-approx " + (test::bundledData() / "igea_points.ply").string() + " -o " +
                           igeaPath.string()).exitCode, 0);
  }
  const HybridModel igea = readModel(igeaPath);
  // and its lines of curvature (§9.2), chains with shared endpoints over 95 % of the points
  const auto linesPath = dir / "igea_curvature_lines.ply";
  if (!std::filesystem::exists(linesPath)) {
    ASSERT_EQ(test::runCli("-q extract curvature-lines " + (test::bundledData() / "igea_points.ply").string() + " -o " +
                           linesPath.string()).exitCode, 0);
  }
  const HybridModel igeaLines = readModel(linesPath);
  const int sizes[] = {512, 1024};
  for (int size : sizes)
    for (float w : {1.25f, 2.0f}) {
      DrawingOptions o{.style = DrawStyle::Hatch, .strokeWidth = w};
      measure("sphere", sphere, dir, Vec3f(0, 1, 0), size, o);
      measure("torus", torus, dir, Vec3f(0, 0, 1), size, o);
      measure("igea", igea, dir, Vec3f(0, 1, 0), size, o);
      measure("igea-curvature-lines", igeaLines, dir, Vec3f(0, 1, 0), size, o);
      if (size == 512 && w == 1.25f) {  // the model's own strokes alone, then with in-between ones
        o.crossHatch = o.inBetween = false;
        for (int i = 0; i < 2; ++i, o.inBetween = true) {
          measure("sphere", sphere, dir, Vec3f(0, 1, 0), size, o);
          measure("torus", torus, dir, Vec3f(0, 0, 1), size, o);
          measure("igea", igea, dir, Vec3f(0, 1, 0), size, o);
        }
      }
    }
}

}  // namespace
}  // namespace linesurf
