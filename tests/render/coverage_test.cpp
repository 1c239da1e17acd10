// Coverage alpha (RenderOptions::coverageGain; beyond the thesis): interiors stay opaque,
// silhouettes get the soft edge of a box-filtered surface instead of the normalised alpha's fringe,
// a partly covered layer keeps what lies behind it, and the SIMD rows agree with the pixel resolve.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "render/coverage.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "shapes.h"
#include "linesurf/render/renderer.h"
#include "render/z3_buffer.h"
#include "test_util.h"

namespace linesurf {
namespace {

using test::maxAbsDiff;
using test::squareStrips;

// Grid samples jittered by this fraction of the spacing (Gaussian): troughs between them.
constexpr float kJitter = 0.4f;
shapes::SampleOptions jittered() {
  shapes::SampleOptions o;
  o.noise = kJitter;
  return o;
}

// A square 2 x 2 as points on a grid, or as strips along x at the same spacing (test_util.h).
HybridModel squarePoints() { return shapes::plane(2, 2, 41, 41); }

// A closed surface's silhouette where the kernels are wide against its curvature (Al's arms and
// fingers): a cylinder of radius kR along z (|z| <= 1.5) as points on a grid or as strips along its
// generatrices, radius = spacing, seen from +x: its silhouette is |y| = kR.
constexpr float kR = 0.15f;
HybridModel cylinder(bool strips) {
  const int around = 12, along = 41;
  const float h = 2 * 3.14159265f * kR / around;  // spacing around (0.079), ~ along (3 / 40)
  HybridModel m;
  for (int i = 0; i < around; ++i) {
    const float t = h * float(i);  // arc length
    const Vec3f n(std::cos(t / kR), std::sin(t / kR), 0), c = kR * n;
    if (strips) {
      Segment s;
      s.p0 = c - Vec3f(0, 0, 1.5f), s.p1 = c + Vec3f(0, 0, 1.5f), s.normal = n, s.radius = h;
      m.segments.push_back(s);
      continue;
    }
    for (int j = 0; j < along; ++j) {
      Point p;
      p.position = c + Vec3f(0, 0, -1.5f + 3.0f * float(j) / float(along - 1)), p.normal = n, p.radius = h;
      m.points.push_back(p);
    }
  }
  m.attributes = {true, false, true, false};
  return m;
}

// Pixels of the cylinder's image (|z| < 1 only) by their distance outside (> 0) or inside (< 0)
// its silhouette, in pixels.
struct EdgeStats {
  int interior = 0, interiorTranslucent = 0;  // >= 3 px inside
  float fringe = 0;                           // alpha summed 0.5 to 3 px outside (a box filter: 0)
};
EdgeStats edgeStats(const Image& alpha, const Camera& cam) {
  EdgeStats s;
  const Vec3f eye = cam.eye();
  const Mat3f toWorld = cam.rotation().transpose();
  for (int y = 0; y < cam.height(); ++y)
    for (int x = 0; x < cam.width(); ++x) {
      const Vec3f d = (toWorld * cam.rayThrough(x + 0.5f, y + 0.5f)).normalized();
      // the ray's distance to the z axis (its closest approach in the xy plane) and the z there
      const Vec2f e(eye.x(), eye.y()), dd(d.x(), d.y());
      const float t = -e.dot(dd) / dd.squaredNorm();
      const float dist = (e + t * dd).norm(), z = eye.z() + t * d.z();
      if (std::abs(z) > 1) continue;
      const float px = t * d.norm() / cam.focalPixels();  // world units per pixel there
      const float out = (dist - kR) / px;
      const float a = alpha.at(x, y).w();
      if (out <= -3) {
        ++s.interior;
        s.interiorTranslucent += a < 0.999f;
      } else if (out >= 0.5f && out <= 3) {
        s.fringe += a;
      }
    }
  return s;
}

TEST(Coverage, InteriorOpaqueAndNoFringeForPointsAndStrips) {
  const Camera cam = Camera::lookAt(Vec3f(3, 0.02f, 0.05f), Vec3f(0, 0, 0), Vec3f(0, 0, 1), 40, 160, 160);
  for (bool strips : {false, true}) {
    const HybridModel m = cylinder(strips);
    RenderOptions o;
    o.alphaBuffer = true;
    const EdgeStats plain = edgeStats(*renderImage(m, cam, o).alpha, cam);
    o.coverageGain = 1.5f;
    const EdgeStats cov = edgeStats(*renderImage(m, cam, o).alpha, cam);
    std::printf("%s: interior %d (translucent %d), alpha 0.5-3 px outside: normalised alpha %.1f, coverage %.1f\n",
                strips ? "strips" : "points", cov.interior, cov.interiorTranslucent, plain.fringe, cov.fringe);
    EXPECT_GT(cov.interior, 1000);
    EXPECT_EQ(cov.interiorTranslucent, 0);
    EXPECT_GT(plain.fringe, 100);  // the normalised alpha paints the kernels' tails opaque
    EXPECT_LT(2 * cov.fringe, plain.fringe);  // measured: points 341 -> 127, strips 432 -> 97
  }
}

TEST(Coverage, ConstantsInvertTheKernelDensity) {
  // a regular grid: every interior point's constant is the same, and the kernel sum at a point
  // times its constant is 1 by construction; points on the edge see half the neighbours
  HybridModel m = squarePoints();
  const float h = 2.0f / 40;
  for (Point& p : m.points) p.radius = 1.5f * h;  // neighbours well inside the cut-off
  const std::vector<float> c = detail::coverageConstants(m, 0.5f, 2.0f);
  ASSERT_EQ(c.size(), m.points.size());
  auto at = [&](float x, float y) {
    size_t best = 0;
    for (size_t i = 0; i < m.points.size(); ++i)
      if ((m.points[i].position - Vec3f(x, y, 0)).norm() < (m.points[best].position - Vec3f(x, y, 0)).norm()) best = i;
    return c[best];
  };
  const float centre = at(0, 0), inner = at(0.5f, -0.4f), corner = at(-1, -1);
  EXPECT_NEAR(inner / centre, 1.0f, 1e-4f);
  // an edge's ring reaches off the surface: a corner's least density is far lower
  EXPECT_GT(corner, 3 * centre);
  // the density of a grid of spacing h is 2 pi / h^2 (each kernel integrates to 2 pi; cut off
  // at 2 sigma it keeps 86% of its mass), least between the samples: c h^-2 2 pi just above 1
  EXPECT_GT(centre * 2 * 3.14159265f / (h * h), 1.0f);
  EXPECT_LT(centre * 2 * 3.14159265f / (h * h), 1.4f);
  // strips of the same spacing and radius (a strip weighs as length / radius points): the same
  HybridModel strips = squareStrips();
  for (Segment& s : strips.segments) s.radius = 1.5f * h;
  const std::vector<float> cs = detail::coverageConstants(strips, 0.5f, 2.0f);
  EXPECT_NEAR(cs[20] / centre, 1.0f, 0.35f);  // measured 1.28
  // c_k times the density at the primitive's centre is >= 1 (the least of centre and ring)
}

// At silhouettes only, c_k inverts the mean density around k, not the least (coverage.h): the
// soft edge of a sampled square ends where its samples' cells end. The alpha summed outside the
// square (grid points on its edge, spacing h) against a box-filtered square grown by the half cell
// h / 2: within half of it for points and strips with the mean; the least density (coverage
// everywhere) puts the points' edge farther out.
TEST(Coverage, SilhouetteEdgesEndWithTheSamplesCells) {
  const int size = 128;
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 4), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, size, size);
  const float half = cam.focalPixels() / 4;  // the square's half side in pixels (x = 1 at depth 4)
  auto fringe = [&](const HybridModel& m, int reach) {
    RenderOptions o;
    o.alphaBuffer = true;
    o.coverageGain = 1.25f;
    o.coverageReach = reach;
    const Image a = *renderImage(m, cam, o).alpha;
    float sum = 0;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const float dx = std::abs(float(x) + 0.5f - 0.5f * size), dy = std::abs(float(y) + 0.5f - 0.5f * size);
        if (std::max(dx, dy) > half) sum += a.at(x, y).w();
      }
    return sum;
  };
  const HybridModel points = squarePoints(), strips = squareStrips();
  const float cellPx = 0.5f * (2.0f / 40) * half;             // h / 2 in pixels
  const float ideal = 8 * half * cellPx + 4 * cellPx * cellPx;  // the grown square's area outside
  const float pl = fringe(points, 0), pm = fringe(points, 2), sm = fringe(strips, 2);
  std::printf("alpha outside the square (box-filtered grown square %.0f): points %.1f (least density %.1f), strips %.1f\n",
              ideal, pm, pl, sm);
  EXPECT_NEAR(pm, ideal, 0.5f * ideal);
  EXPECT_NEAR(sm, ideal, 0.5f * ideal);
  EXPECT_GT(pl, 1.5f * ideal);
  EXPECT_LT(pm, 0.85f * pl);
}

TEST(Coverage, PartlyCoveredLayerKeepsWhatIsBehind) {
  // one pixel: an opaque far surface (blue, fully covered) and a near one (red) covering 30%
  const PixelRect rect{0, 0, 1, 1};
  const float blue[Z3Tile::kAttrs] = {0, 0, 1, 1, 1, 0, 0, 1}, red[Z3Tile::kAttrs] = {1, 0, 0, 1, 1, 0, 0, 1};
  for (bool nearFirst : {false, true}) {
    Z3Tile t(rect, 4);
    t.setCoverageScale(1);
    // coverage = weight * alpha attribute * scale: 2 * 0.5 = 1 (far), 0.6 * 0.5 = 0.3 (near)
    float b[Z3Tile::kAttrs], r[Z3Tile::kAttrs];
    std::copy(blue, blue + Z3Tile::kAttrs, b), std::copy(red, red + Z3Tile::kAttrs, r);
    b[Z3Tile::kA] = r[Z3Tile::kA] = 0.5f;
    if (nearFirst) t.insert(0, 0, 1.0f, 0.01f, 0.6f, r);
    t.insert(0, 0, 2.0f, 0.01f, 2.0f, b);
    if (!nearFirst) t.insert(0, 0, 1.0f, 0.01f, 0.6f, r);
    const ResolvedPixel p = t.resolve(0, 0);
    EXPECT_NEAR(p.color.x(), 0.3f, 1e-5f) << nearFirst;
    EXPECT_NEAR(p.color.z(), 0.7f, 1e-5f) << nearFirst;
    EXPECT_NEAR(p.color.w(), 1.0f, 1e-5f) << nearFirst;
    // a fragment behind the covered far layer is occluded
    t.insert(0, 0, 3.0f, 0.01f, 1.0f, r);
    EXPECT_NEAR(t.resolve(0, 0).color.z(), 0.7f, 1e-5f);
  }
  // the thesis's alpha: the near opaque fragment frees the far layer, whatever its weight
  Z3Tile t(rect, 4);
  t.insert(0, 0, 2.0f, 0.01f, 2.0f, blue);
  t.insert(0, 0, 1.0f, 0.01f, 0.6f, red);
  EXPECT_NEAR(t.resolve(0, 0).color.x(), 1.0f, 1e-6f);
  EXPECT_NEAR(t.resolve(0, 0).color.z(), 0.0f, 1e-6f);
}

// Coverage at silhouettes only (RenderOptions::coverageReach): a square of jittered grid samples,
// whose coverage has troughs inside, is translucent inside only next to a real hole (a pixel no
// splat reaches: a silhouette too), and its edge is as soft as with coverage everywhere.
TEST(Coverage, SilhouettesOnlyKeepInteriorGapsOpaque) {
  HybridModel m = shapes::plane(2, 2, 41, 41, jittered());
  for (Point& p : m.points) p.position.z() = 0;  // jittered in the plane only: no depth steps
  const int size = 128, reach = 2;
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 4), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, size, size);
  const float half = cam.focalPixels() / 4;  // the square's half side in pixels (44)
  struct Stats {
    int interior = 0, translucent = 0, awayFromHoles = 0;  // >= 3 px inside; alpha < 1; no empty pixel within reach
    float outside = 0;                                      // alpha summed outside the square
  };
  auto stats = [&](int coverageReach) {
    RenderOptions o;
    o.alphaBuffer = true;
    o.coverageGain = 1.5f;
    o.coverageReach = coverageReach;
    const Image a = *renderImage(m, cam, o).alpha;
    auto emptyNear = [&](int x, int y) {
      for (int v = std::max(0, y - reach); v <= std::min(size - 1, y + reach); ++v)
        for (int u = std::max(0, x - reach); u <= std::min(size - 1, x + reach); ++u)
          if (a.at(u, v).w() == 0) return true;
      return false;
    };
    Stats s;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const float dx = std::abs(float(x) + 0.5f - 0.5f * size), dy = std::abs(float(y) + 0.5f - 0.5f * size);
        const float inside = half - std::max(dx, dy);  // pixels inside the edge
        if (inside >= 3 && ++s.interior && a.at(x, y).w() < 0.999f) ++s.translucent, s.awayFromHoles += !emptyNear(x, y);
        if (inside < 0) s.outside += a.at(x, y).w();
      }
    return s;
  };
  const Stats everywhere = stats(0), edges = stats(reach);
  std::printf("interior %d: translucent with coverage everywhere %d (%d away from holes), at silhouettes %d (%d); "
              "alpha outside %.1f, %.1f\n", edges.interior, everywhere.translucent, everywhere.awayFromHoles,
              edges.translucent, edges.awayFromHoles, everywhere.outside, edges.outside);
  EXPECT_GT(edges.interior, 5000);
  EXPECT_GT(everywhere.awayFromHoles, 50);  // the troughs show with coverage everywhere (measured 87)
  EXPECT_EQ(edges.awayFromHoles, 0);
  EXPECT_GT(everywhere.outside, 100.0f);
  // the soft edge is kept, narrower: at silhouettes only c_k inverts the mean density, not the least
  EXPECT_LT(edges.outside, everywhere.outside);
  EXPECT_GT(edges.outside, 0.6f * everywhere.outside);  // measured 660 against 803
}

// Coverage at silhouettes keeps no layer behind a front one (an opaque frame's layers: the frame
// costs what an opaque one does) but sums what it drops per pixel (Z3Tile::resolveBehind), so a
// partly covered edge is composited over the surface behind it, not over the background: a red
// sphere in front of a blue square on a green background shows no green along its outline inside
// the square, and the outline is still soft (red and blue mixed).
TEST(Coverage, InnerSilhouettesCompositeOverWhatLiesBehind) {
  HybridModel m = shapes::sphere(0.5f, 20000, jittered());
  for (Point& p : m.points) p.color = Color(1, 0, 0, 1), p.position.z() += 1.0f;
  HybridModel square = shapes::plane(3, 3, 81, 81);
  for (Point& p : square.points) p.color = Color(0, 0, 1, 1), m.points.push_back(p);
  const int size = 160;
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 6), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, size, size);
  RenderOptions o;
  o.coverageGain = 1.5f;
  o.coverageReach = 2;
  o.background = Color(0, 1, 0, 1);
  o.material.specular = 0;
  o.alphaBuffer = true;
  const RenderResult r = renderImage(m, cam, o);
  // the sphere's outline lies ~ 0.5 / 5 of the focal length from the centre; the square reaches
  // 1.5 / 6: pixels within 0.6 of the sphere's radius on either side of its outline
  const float f = cam.focalPixels(), rs = 0.5f / 5.0f * f;
  int ring = 0, mixed = 0;
  float green = 0;
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x) {
      const float dx = float(x) + 0.5f - 0.5f * size, dy = float(y) + 0.5f - 0.5f * size;
      const float d = std::sqrt(dx * dx + dy * dy);
      if (std::abs(d - rs) > 3) continue;
      const Color& c = r.color.at(x, y);
      ++ring;
      green = std::max(green, c.y());
      mixed += c.x() > 0.1f && c.z() > 0.1f;
      EXPECT_NEAR(r.alpha->at(x, y).w(), 1.0f, 1e-5f) << x << "," << y;  // the square behind covers it
    }
  std::printf("ring %d pixels (radius %.1f px): %d red and blue mixed, most green %.4f\n", ring, rs, mixed, green);
  EXPECT_GT(ring, 200);
  EXPECT_GT(mixed, 40);         // soft: the sphere's edge is partly covered
  EXPECT_LT(green, 0.02f);      // and composited over the blue square, never over the background
}

TEST(Coverage, SimdRowsMatchThePixelResolveAndThreads) {
  // a sphere of points in front of a strip plane: several layers, partly covered edges
  HybridModel m = shapes::sphere(0.6f, 20000, jittered());
  const HybridModel strips = squareStrips();
  m.segments = strips.segments;
  for (Point& p : m.points) p.position.z() += 0.8f;
  const Camera cam = Camera::lookAt(Vec3f(0.3f, 0.2f, 5), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 120, 90);
  Image byReach[2];  // tile 16's image: tile 64 draws the same
  for (int tile : {16, 64}) for (int reach : {0, 2}) {
    RenderOptions o;
    o.coverageGain = 2;
    o.coverageReach = reach;
    o.tileSize = tile;
    const RenderResult simd = renderImage(m, cam, o);
    o.alphaBuffer = true;  // every pixel through Z3Tile::resolve
    const RenderResult pixel = renderImage(m, cam, o);
    EXPECT_LT(maxAbsDiff(simd.color, pixel.color), 1e-6) << tile;
    int partial = 0;
    for (const Color& c : pixel.alpha->pixels) partial += c.w() > 0.01f && c.w() < 0.99f;
    EXPECT_GT(partial, 100) << tile;  // soft edges exist
    RenderResult one;
    {
      ThreadLimit single(1);
      one = renderImage(m, cam, o);
    }
    EXPECT_EQ(maxAbsDiff(one.color, pixel.color), 0.0f) << tile;
    Image& first = byReach[reach > 0];
    if (first.pixels.empty()) first = pixel.color;
    else EXPECT_EQ(maxAbsDiff(first, pixel.color), 0.0f) << reach;
  }
  EXPECT_GT(maxAbsDiff(byReach[0], byReach[1]), 0.01f);  // the reach matters here (measured 0.03)
}

TEST(Coverage, TranslucentModelsKeepTheThesisAlpha) {
  HybridModel m = squarePoints();
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 4), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 40, 64, 64);
  RenderOptions o;
  o.alphaOverride = 0.5f;
  const Image plain = renderImage(m, cam, o).color;
  o.coverageGain = 2;
  EXPECT_EQ(maxAbsDiff(renderImage(m, cam, o).color, plain), 0.0f);
  RenderOptions bad;
  bad.coverageGain = -1;
  EXPECT_THROW(Renderer(m, bad), Error);
}

}  // namespace
}  // namespace linesurf
