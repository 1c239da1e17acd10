// The drawing's tone and coherence figures of docs/results.md (thesis §9.4): skipped unless
// LINESURF_DRAWING_MEASURE names a folder for the images, as it takes a minute (Igea's
// shape-approximation hybrid is extracted through the CLI).
//   tone: ink luminance blurred by a Gaussian of sigma = the projected stroke spacing in pixels,
//   against the target tone (the shaded render's luminance quantised to 8 levels), on pixels at
//   least 2 sigma inside the silhouette: mean absolute error, and the mean drawn tone per level;
//   coherence: two views 3 degrees apart, the visible length kept by stroke id.
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
  const int sizes[] = {512, 1024};
  for (int size : sizes)
    for (float w : {1.25f, 2.0f}) {
      DrawingOptions o{.style = DrawStyle::Hatch, .strokeWidth = w};
      measure("sphere", sphere, dir, Vec3f(0, 1, 0), size, o);
      measure("torus", torus, dir, Vec3f(0, 0, 1), size, o);
      measure("igea", igea, dir, Vec3f(0, 1, 0), size, o);
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
