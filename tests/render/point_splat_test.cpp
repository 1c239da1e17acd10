// EWA point splatting (thesis §4.2.2, §6.2): hole-free flat planes, anti-aliasing against an
// analytically supersampled checkerboard (thesis Figure 4), order-independent transparency,
// identical images for any thread count.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <utility>

#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/io/image_io.h"
#include "linesurf/render/renderer.h"
#include "test_util.h"

namespace linesurf {
namespace {

// Mean absolute difference over RGB (tiny local helper; the project metrics live in eval/).
double meanAbsDiff(const Image& a, const Image& b) {
  double s = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) s += (a.pixels[i].head<3>() - b.pixels[i].head<3>()).cwiseAbs().sum();
  return s / (3.0 * double(a.pixels.size()));
}
using test::maxAbsDiff;

// Unlit material: the rendered colour is the albedo, so images compare with analytic ones.
RenderOptions unlit() {
  RenderOptions o;
  o.material = {1.0f, 0.0f, 0.0f, 1.0f};
  return o;
}

// Optional: write test images for docs/images/points/ when LINESURF_RENDER_IMAGES names a folder.
void maybeWrite(const char* name, const Image& im) {
  if (const char* dir = std::getenv("LINESURF_RENDER_IMAGES")) writePng(std::filesystem::path(dir) / name, im, false);
}

TEST(EwaPoint, FlatPlaneRendersHoleFreeAndUniform) {
  HybridModel plane = shapes::plane(2, 2, 101, 101);  // radius = spacing
  RenderOptions o;
  o.material.specular = 0;  // flat lighting: diffuse under a directional light is constant
  o.alphaBuffer = true;
  const Camera views[] = {
      Camera::lookAt(Vec3f(0, 0, 3), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 30, 96, 96),
      // tilted 60 degrees, still filling the view
      Camera::lookAt(Vec3f(0, -2.0f * std::sin(1.047f), 2.0f * std::cos(1.047f)), Vec3f(0, -0.2f, 0), Vec3f(0, 0, 1), 16, 96, 64)};
  int view = 0;
  for (const Camera& cam : views) {
    RenderResult r = renderImage(plane, cam, o);
    maybeWrite(view++ == 0 ? "plane_front.png" : "plane_tilted.png", r.color);
    ASSERT_EQ(r.color.width, cam.width());
    Vec4f mean = Vec4f::Zero();
    for (const Color& c : r.color.pixels) mean += c;
    mean /= float(r.color.pixels.size());
    double worst = 0, minAlpha = 1;
    for (size_t i = 0; i < r.color.pixels.size(); ++i) {
      worst = std::max(worst, double((r.color.pixels[i] - mean).cwiseAbs().maxCoeff()));
      minAlpha = std::min(minAlpha, double(r.alpha->pixels[i].w()));
    }
    EXPECT_GT(minAlpha, 0.999) << "hole in the plane, view " << view;
    EXPECT_LT(worst, 2e-3) << "colour not uniform (tolerance 2e-3, half a grey level)";
    EXPECT_EQ(r.stats.pointsDegenerate, 0u);
    EXPECT_GT(r.stats.pointsDrawn, 1000u);
  }
}

TEST(EwaPoint, IrregularSamplingStaysHoleFree) {
  shapes::SampleOptions so;
  so.irregular = true;
  so.seed = 7;
  HybridModel plane = shapes::plane(2, 2, 90, 90, so);
  for (Point& p : plane.points) p.radius *= 1.5f;  // irregular spacing needs larger discs
  RenderOptions o;
  o.material.specular = 0;
  o.alphaBuffer = true;
  Camera cam = Camera::lookAt(Vec3f(0, 0, 3), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 30, 80, 80);
  RenderResult r = renderImage(plane, cam, o);
  for (const Color& a : r.alpha->pixels) ASSERT_GT(a.w(), 0.999f);
}

// Checkerboard plane z = 0 of unit squares over [-kX, kX] x [kY0, kY1], spacing kH.
constexpr float kX = 20, kY0 = -2, kY1 = 48, kH = 0.125f;
bool insideChecker(const Vec3f& p) { return p.x() >= -kX && p.x() <= kX && p.y() >= kY0 && p.y() <= kY1; }
float checker(const Vec3f& p) { return ((int(std::floor(p.x())) + int(std::floor(p.y()))) & 1) ? 0.9f : 0.1f; }

HybridModel checkerPlane() {
  HybridModel m;
  const int nx = int(std::lround(2 * kX / kH)), ny = int(std::lround((kY1 - kY0) / kH));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      Point p;
      p.position = Vec3f(-kX + i * kH, kY0 + j * kH, 0);
      p.normal = Vec3f(0, 0, 1);
      p.radius = kH;
      float g = checker(p.position);
      p.color = Color(g, g, g, 1);
      m.points.push_back(p);
    }
  m.attributes = {true, true, true, false};
  return m;
}

// Analytic reference: the continuous checkerboard convolved with a Gaussian pixel filter of
// variance `variance` px^2 (pbrt's GaussianFilter; the ideal image EWA approximates), evaluated
// by supersampling: 12x12 stratified samples over +-2.5 sigma, Gaussian-weighted.
Image checkerReference(const Camera& cam, const Color& background, float variance) {
  Image out(cam.width(), cam.height());
  const Mat3f rt = cam.rotation().transpose();
  const Vec3f eye = cam.eye();
  const int n = 12;
  const float sigma = std::sqrt(variance), half = 2.5f * sigma;
  for (int y = 0; y < cam.height(); ++y)
    for (int x = 0; x < cam.width(); ++x) {
      Vec3f sum = Vec3f::Zero();
      float wsum = 0;
      for (int sy = 0; sy < n; ++sy)
        for (int sx = 0; sx < n; ++sx) {
          const float ox = -half + 2 * half * (sx + 0.5f) / n, oy = -half + 2 * half * (sy + 0.5f) / n;
          const float w = std::exp(-0.5f * (ox * ox + oy * oy) / variance);
          Vec3f dir = rt * cam.rayThrough(x + 0.5f + ox, y + 0.5f + oy);
          Vec3f c = background.head<3>();
          if (dir.z() < 0) {
            Vec3f p = eye + (-eye.z() / dir.z()) * dir;
            if (insideChecker(p)) c = Vec3f::Constant(checker(p));
          }
          sum += w * c;
          wsum += w;
        }
      sum /= wsum;
      out.at(x, y) = Color(sum.x(), sum.y(), sum.z(), 1);
    }
  return out;
}

// Mean absolute error of the grazing checkerboard (thesis Figure 4) against the analytic
// reference filtered alike, rendered with the screen prefilter of `variance` px^2 and without
// one: {with, without}. Squares shrink below a pixel towards the horizon while the samples stay
// 8 per square.
std::pair<double, double> checkerboardErrors(float variance, const char* tag) {
  const HybridModel plane = checkerPlane();
  const Camera cam = Camera::lookAt(Vec3f(0.3f, -2, 3), Vec3f(0.3f, 30, 0), Vec3f(0, 0, 1), 20, 160, 100, 0.1f, 200);
  RenderOptions ewa = unlit();
  ewa.prefilterVariance = variance;
  RenderOptions noPrefilter = unlit();
  noPrefilter.prefilterVariance = 0;
  const Image ref = checkerReference(cam, ewa.background, ewa.prefilterVariance);
  const Image a = renderImage(plane, cam, ewa).color;
  const Image b = renderImage(plane, cam, noPrefilter).color;
  maybeWrite((std::string("checker_reference") + tag + ".png").c_str(), ref);
  maybeWrite((std::string("checker_ewa") + tag + ".png").c_str(), a);
  maybeWrite("checker_no_prefilter.png", b);
  const double errEwa = meanAbsDiff(a, ref), errPlain = meanAbsDiff(b, ref);
  std::printf("checkerboard, prefilter variance %.2f: mean abs error EWA %.4f, without prefilter %.4f (ratio %.2f)\n",
              variance, errEwa, errPlain, errPlain / errEwa);
  return {errEwa, errPlain};
}

TEST(EwaPoint, PrefilterAntiAliasesCheckerboardAtGrazingAngle) {
  const auto [errEwa, errPlain] = checkerboardErrors(RenderOptions{}.prefilterVariance, "");
  EXPECT_LT(2 * errEwa, errPlain);  // measured at the default variance 0.25: 0.0485 vs 0.1036 (2.14x)
  EXPECT_LT(errEwa, 0.06);
}

// The thesis's identity prefilter (the checkerboard criterion: at least 3x lower error than
// without; docs/decisions.md "Screen prefilter").
TEST(EwaPoint, IdentityPrefilterAntiAliasesCheckerboardThreeTimesBetter) {
  const auto [errEwa, errPlain] = checkerboardErrors(1.0f, "_identity");
  EXPECT_LT(3 * errEwa, errPlain);  // measured: 3.4x
  EXPECT_LT(errEwa, 0.06);
}

// Two overlapping transparent planes (and an opaque one behind): the image must not depend on
// the order of the primitives in the model.
TEST(EwaPoint, TransparencyIsOrderIndependent) {
  HybridModel m;
  auto add = [&](float z, Color c) {
    HybridModel p = shapes::plane(2, 2, 61, 61);
    for (Point& q : p.points) { q.position.z() = z; q.color = c; }
    m.points.insert(m.points.end(), p.points.begin(), p.points.end());
  };
  add(0.0f, Color(1, 0, 0, 0.5f));
  add(-0.5f, Color(0, 0, 1, 0.5f));
  add(-1.0f, Color(0, 1, 0, 1.0f));
  m.attributes = {true, true, true, false};
  const Camera cam = Camera::lookAt(Vec3f(0.2f, 0.1f, 4), Vec3f(0, 0, -0.5f), Vec3f(0, 1, 0), 20, 64, 64);
  const RenderOptions o = unlit();
  const Image base = renderImage(m, cam, o).color;
  // red over blue over green: 0.5 r + 0.25 b + 0.25 g
  const Color centre = base.at(32, 32);
  EXPECT_NEAR(centre.x(), 0.5f, 0.01f);
  EXPECT_NEAR(centre.y(), 0.25f, 0.01f);
  EXPECT_NEAR(centre.z(), 0.25f, 0.01f);

  HybridModel reversed = m;
  std::reverse(reversed.points.begin(), reversed.points.end());
  HybridModel shuffled = m;
  std::mt19937 rng(3);
  std::shuffle(shuffled.points.begin(), shuffled.points.end(), rng);
  EXPECT_LT(maxAbsDiff(base, renderImage(reversed, cam, o).color), 1e-4);
  EXPECT_LT(maxAbsDiff(base, renderImage(shuffled, cam, o).color), 1e-4);
}

// Tail layers (RenderOptions::tailLayers, beyond the thesis; docs/decisions.md "Tail layers"): a
// grazing splat in front of a facing plane hides it only where its rays meet its own disc, not
// where only its screen prefilter's tail reaches (there the tail's depth is its plane's,
// extrapolated: the fold speckles); alone over the background its tails still anti-alias its
// silhouette.
TEST(EwaPoint, TailLayersKeepAGrazingSplatsTailFromHidingThePlaneBehind) {
  HybridModel plane = shapes::plane(2, 2, 61, 61);
  for (Point& q : plane.points) q.color = Color(0, 1, 0, 1), q.position.z() = -0.5f;  // beyond its z threshold
  HybridModel grazing;
  Point g;
  g.position = Vec3f(0, 0.0074f, 0.3f);  // on a row of pixel centres
  g.normal = Vec3f(0, std::sin(1.5359f), std::cos(1.5359f));  // 88 degrees from the view direction
  g.radius = 0.05f;
  g.color = Color(1, 0, 0, 1);
  grazing.points.push_back(g);
  grazing.attributes = plane.attributes;
  HybridModel both = plane;
  both.points.push_back(g);
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 3), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 20, 64, 64);
  RenderOptions off = unlit(), on = unlit();
  off.tailLayers = false, on.tailLayers = true;
  off.tailCoverage = on.tailCoverage = 0;  // tail layers alone: tail coverage would fade the tails' alpha
  auto redRows = [](const Image& im) {  // the rows where the splat shows
    int n = 0;
    for (int y = 0; y < im.height; ++y) {
      bool red = false;
      for (int x = 0; x < im.width; ++x) red = red || im.at(x, y).x() > im.at(x, y).y();
      n += red;
    }
    return n;
  };
  // its disc is a fraction of a pixel tall on the screen, its prefilter's tails reach a row beyond it
  EXPECT_GE(redRows(renderImage(both, cam, off).color), 2);
  EXPECT_EQ(redRows(renderImage(both, cam, on).color), 1);  // the disc's own row only
  // alone, the tails are its silhouette's anti-aliasing: the same image
  EXPECT_EQ(renderImage(grazing, cam, on).color.pixels, renderImage(grazing, cam, off).color.pixels);
  // and the plane alone (no tail in front of anything) renders as without tail layers, up to rounding
  EXPECT_LT(maxAbsDiff(renderImage(plane, cam, on).color, renderImage(plane, cam, off).color), 1e-5);
}

TEST(EwaPoint, ImageIdenticalForOneAndManyThreads) {
  HybridModel s = shapes::sphere(1, 20000);
  RenderOptions o;
  o.depthBuffer = o.normalBuffer = true;
  o.tileSize = 16;  // many tiles
  const Camera cam = Camera::orbit(boundingSphere(s), 20, 30, 0, 120, 90);
  RenderResult many = renderImage(s, cam, o);
  RenderResult one;
  {
    ThreadLimit limit(1);
    one = renderImage(s, cam, o);
  }
  EXPECT_EQ(many.color.pixels, one.color.pixels);
  EXPECT_EQ(many.depth->pixels, one.depth->pixels);
  EXPECT_EQ(many.normal->pixels, one.normal->pixels);
  // tile size does not change the image either
  o.tileSize = 64;
  EXPECT_EQ(renderImage(s, cam, o).color.pixels, one.color.pixels);
  EXPECT_GT(many.stats.pointsCulled, 5000u);  // the back half
  // with tail layers (RenderOptions::tailLayers) too
  o.tailLayers = true;
  o.tileSize = 16;
  const RenderResult tails = renderImage(s, cam, o);
  {
    ThreadLimit limit(1);
    EXPECT_EQ(renderImage(s, cam, o).color.pixels, tails.color.pixels);
  }
}

// The resolve of one-layer pixels in SIMD rows (taken unless lighting is deferred or another
// buffer is written) gives the colours of the pixel-by-pixel resolve: opaque sphere and
// translucent planes (one, two and more layers), backgrounds opaque, transparent and half, tiles
// whose width is not a multiple of the vector (the pixels past the last whole vector: scalar).
TEST(EwaPoint, SimdResolveMatchesThePixelResolve) {
  HybridModel m = shapes::sphere(1, 20000);
  HybridModel glass = shapes::plane(3, 3, 71, 71);
  for (Point& q : glass.points) q.position.z() += 1.2f, q.color = Color(0.2f, 0.6f, 0.9f, 0.4f);
  m.points.insert(m.points.end(), glass.points.begin(), glass.points.end());
  const Camera cam = Camera::lookAt(Vec3f(0.3f, 0.2f, 5), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 100, 70);
  for (const Color& bg : {Color(1, 1, 1, 1), Color(0, 0, 0, 0), Color(0.2f, 0.4f, 0.6f, 0.5f)})
    for (int tile : {16, 24, 64}) {
      RenderOptions o;
      o.background = bg;
      o.tileSize = tile;
      const RenderResult simd = renderImage(m, cam, o);
      o.alphaBuffer = true;  // another buffer: every pixel through Z3Tile::resolve
      const RenderResult pixel = renderImage(m, cam, o);
      EXPECT_LT(maxAbsDiff(simd.color, pixel.color), 1e-6) << tile;
      EXPECT_GT(simd.stats.allocated, simd.stats.fragments / 100);  // layers in front of layers
      int covered = 0;
      for (const Color& c : pixel.alpha->pixels) covered += c.w() > 0;
      EXPECT_GT(covered, 3000) << tile;
    }
}

TEST(EwaPoint, DegenerateAndOutsidePrimitivesAreCounted) {
  HybridModel m = shapes::plane(1, 1, 10, 10);
  m.points[0].radius = 0;
  m.points[1].position = Vec3f(NAN, 0, 0);
  m.points[2].position = Vec3f(100, 0, 0);  // far outside the view
  m.points[3].normal = Vec3f(0, 0, -1);     // back-facing
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 3), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 30, 32, 32);
  RenderResult r = renderImage(m, cam);
  EXPECT_EQ(r.stats.pointsDegenerate, 2u);
  EXPECT_EQ(r.stats.pointsOutside, 1u);
  EXPECT_EQ(r.stats.pointsCulled, 1u);
  EXPECT_EQ(r.stats.pointsDrawn, 96u);
  for (const Color& c : r.color.pixels) ASSERT_TRUE(c.allFinite());
}

TEST(EwaPoint, AbsurdOptionsThrow) {
  HybridModel m = shapes::plane(1, 1, 4, 4);
  RenderOptions o;
  o.layers = 0;
  EXPECT_THROW(Renderer(m, o), Error);
  o = {};
  o.cutoffRadius = 0.1f;
  EXPECT_THROW(Renderer(m, o), Error);
  o = {};
  o.prefilterVariance = -1;
  EXPECT_THROW(Renderer(m, o), Error);
  o = {};
  o.zThreshold = NAN;
  EXPECT_THROW(Renderer(m, o), Error);
}

}  // namespace
}  // namespace linesurf
