// Drawings from the segments (thesis §9.4, §9.5; render/drawing.h): chaining, nested priorities
// (a darker tone never removes a stroke), hidden strokes, stroke width, the SVG against the runs,
// thread independence, and the CLI's refusals. Each test draws at most 160^2.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "linesurf/core/parallel.h"
#include "linesurf/extract/contour.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_io.h"
#include "linesurf/render/drawing.h"
#include "shapes.h"
#include "test_util.h"

namespace linesurf {
namespace {

float luminance(const Color& c) { return 0.2126f * c.x() + 0.7152f * c.y() + 0.0722f * c.z(); }

/// A unit sphere's contour lines (about 150 per pole-to-pole).
const HybridModel& sphereLines() {
  static const HybridModel m = [] {
    ContourOptions o;
    o.spacing = 0.02f;
    return extractContour(shapes::sphereMesh(1, 4), o);
  }();
  return m;
}

Camera view(const HybridModel& m, int size, float azimuth = 30, float elevation = 20) {
  return Camera::orbit(boundingSphere(m), azimuth, elevation, 0, size, size);
}

TEST(Strokes, SegmentsSharingBitEqualEndpointsChainIntoOneStroke) {
  HybridModel m;
  auto seg = [&](Vec3f a, Vec3f b) {
    Segment s;
    s.p0 = a, s.p1 = b, s.normal = Vec3f(0, 0, 1), s.radius = 0.05f;
    m.segments.push_back(s);
  };
  // a polyline of three pieces given out of order and with one piece reversed, and a lone strip
  seg(Vec3f(1, 0, 0), Vec3f(2, 0, 0));
  seg(Vec3f(5, 5, 0), Vec3f(6, 5, 0));
  seg(Vec3f(0, 0, 0), Vec3f(1, 0, 0));
  seg(Vec3f(3, 0, 0), Vec3f(2, 0, 0));
  const StrokeSet s(m, {});
  ASSERT_EQ(s.strokes().size(), 2u);
  const StrokeSet::Stroke& chain = s.strokes()[0];
  ASSERT_EQ(chain.count, 3u);
  for (uint32_t i = chain.first; i + 1 < chain.first + chain.count; ++i)
    EXPECT_EQ(s.pieces()[i].b, s.pieces()[i + 1].a) << "pieces run end to start";
  EXPECT_EQ(s.strokes()[1].count, 1u);
  // priorities are the share of the length ranked before: in (0, 1], the longer stroke's wider
  for (const auto& st : s.strokes()) EXPECT_TRUE(st.priority > 0 && st.priority <= 1);
}

TEST(Strokes, ContourLinesChainAndPrioritiesSpreadEvenly) {
  const StrokeSet s(sphereLines(), {});
  // contour lines meet at bit-equal points: far fewer strokes than segments
  EXPECT_LT(s.strokes().size() * 4, sphereLines().segments.size());
  // the strokes of priority below 1/4 hold about a quarter of the length
  double total = 0, low = 0;
  for (const auto& st : s.strokes()) {
    float l = 0;
    for (uint32_t i = st.first; i < st.first + st.count; ++i) l += (s.pieces()[i].b - s.pieces()[i].a).norm();
    total += l;
    low += st.priority <= 0.25f ? l : 0;
  }
  EXPECT_NEAR(low / total, 0.25, 0.05);
  // d on the planes, cut at d / 2 on triangles the planes meet at less than 90 degrees: between
  EXPECT_GT(s.typicalSpacing(), 0.4f * 0.02f) << "the contour spacing, measured across the lines";
  EXPECT_LT(s.typicalSpacing(), 0.02f);
}

TEST(Hatch, ADarkerLightAddsStrokesAndNeverRemovesOne) {
  DrawingOptions d{.style = DrawStyle::Hatch};
  RenderOptions bright, dark;
  dark.light.color = Vec3f(0.55f, 0.55f, 0.55f);
  const DrawingRenderer a(sphereLines(), bright, d), b(sphereLines(), dark, d);
  const Camera cam = view(sphereLines(), 128);
  const Drawing da = a.render(cam), db = b.render(cam);
  size_t more = 0;
  for (size_t i = 0; i < da.visibleLength.size(); ++i) {
    // a stroke drawn in the bright light is drawn at least as long in the dark (half-pixel samples)
    EXPECT_GE(db.visibleLength[i], da.visibleLength[i] - 1.0f) << "stroke " << i;
    more += db.visibleLength[i] > da.visibleLength[i] + 1.0f;
  }
  EXPECT_GT(more, 20u);
  double inkA = 0, inkB = 0;
  for (size_t i = 0; i < da.image.pixels.size(); ++i) {
    inkA += 1 - luminance(da.image.pixels[i]), inkB += 1 - luminance(db.image.pixels[i]);
    // an inked pixel stays inked (up to where one run of the dark view replaces two of the bright)
    EXPECT_GE(1 - luminance(db.image.pixels[i]), 1 - luminance(da.image.pixels[i]) - 0.35f) << i;
  }
  EXPECT_GT(inkB, 1.3 * inkA);
}

TEST(Hatch, StrokesBehindTheSurfaceAreNotDrawn) {
  // strips in z = 0 facing the camera, half of them behind a square of points at z = 0.3
  HybridModel m = test::squareStrips(0.6f);
  HybridModel front = shapes::plane(1.0f, 2.2f, 21, 45);
  for (Point p : front.points) {
    p.position += Vec3f(-0.5f, 0, 0.3f);
    m.points.push_back(p);
  }
  m.attributes.radii = m.attributes.normals = true;
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 5), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 30, 160, 160);
  const DrawingRenderer r(m, {}, {.style = DrawStyle::Lines, .silhouettes = false});
  const Drawing d = r.render(cam);
  ASSERT_FALSE(d.runs.empty());
  // the front square covers x < 0 in the strips' plane; seen from z = 5 its edge x = 0 (at z = 0.3)
  // projects to the image centre
  const float edge = cam.project(cam.toCamera(Vec3f(0, 0, 0.3f))).x();
  size_t drawnRight = 0;
  for (const StrokeRun& run : d.runs)
    for (const Vec2f& p : run.points) {
      EXPECT_GT(p.x(), edge - 2.0f) << "a run point behind the front square";
      drawnRight += p.x() > edge + 10;
    }
  EXPECT_GT(drawnRight, 30u);
}

TEST(Hatch, StrokeWidthInPixels) {
  // 41 strips 5 px apart seen straight on: the ink across a column is 41 x the width
  const HybridModel m = test::squareStrips(0.6f);
  const Camera cam = Camera::lookAt(Vec3f(0, 0, 4.0f), Vec3f(0, 0, 0), Vec3f(0, 1, 0), 30, 160, 160);
  for (float w : {1.0f, 1.25f, 2.5f}) {
    const DrawingRenderer r(m, {}, {.style = DrawStyle::Lines, .strokeWidth = w, .silhouettes = false});
    const Drawing d = r.render(cam);
    for (int x : {60, 80, 97}) {
      double ink = 0;
      for (int y = 0; y < 160; ++y) ink += 1 - luminance(d.image.at(x, y));
      EXPECT_NEAR(ink / 41.0, w, 0.05 * w) << "width " << w << " column " << x;
    }
  }
}

TEST(Hatch, SvgHoldsOnePathPerVisibleRun) {
  const DrawingOptions o{.style = DrawStyle::Hatch, .paper = Color(1, 1, 0.9f, 1)};
  const DrawingRenderer r(sphereLines(), {}, o);
  const Drawing d = r.render(view(sphereLines(), 96));
  const std::string svg = drawingSvg(d, o);
  ASSERT_EQ(svg.rfind("<?xml", 0), 0u);
  EXPECT_NE(svg.find("<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"96\" height=\"96\" viewBox=\"0 0 96 96\">"),
            std::string::npos);
  EXPECT_NE(svg.find("fill=\"#ffffe6\""), std::string::npos) << "the paper";
  EXPECT_NE(svg.find("stroke-width=\"1.25\""), std::string::npos);
  size_t paths = 0, closedPaths = 0;
  for (size_t at = svg.find("<path"); at != std::string::npos; at = svg.find("<path", at + 1)) {
    ++paths;
    const size_t end = svg.find('>', at);
    closedPaths += end != std::string::npos && svg[end - 1] == '/' && svg.compare(at, 9, "<path d=\"") == 0;
  }
  EXPECT_EQ(paths, d.runs.size());
  EXPECT_EQ(closedPaths, paths);
  EXPECT_EQ(d.runs.size(), d.stats.runs + d.stats.silhouettePaths);
  EXPECT_GT(d.stats.silhouettePaths, 0u);
  EXPECT_NE(svg.find("</g>\n</svg>\n"), std::string::npos);
}

TEST(Hatch, SameDrawingForOneAndManyThreads) {
  const DrawingOptions o{.style = DrawStyle::Hatch};
  const Camera cam = view(sphereLines(), 96, 70, -10);
  Drawing one, many;
  {
    ThreadLimit limit(1);
    one = DrawingRenderer(sphereLines(), {}, o).render(cam);
  }
  many = DrawingRenderer(sphereLines(), {}, o).render(cam);
  ASSERT_EQ(one.runs.size(), many.runs.size());
  EXPECT_EQ(test::maxAbsDiff(one.image, many.image), 0.0f);
  EXPECT_EQ(drawingSvg(one, o), drawingSvg(many, o));
}

TEST(Hatch, StrokesStayOnTheSurfaceAsTheCameraMoves) {
  // two views 3 degrees apart: the strokes drawn in both are the same strokes (by id), and
  // those that change are few
  const DrawingRenderer r(sphereLines(), {}, {.style = DrawStyle::Hatch});
  const Drawing a = r.render(view(sphereLines(), 128, 30)), b = r.render(view(sphereLines(), 128, 33));
  double drawnA = 0, kept = 0;
  for (size_t i = 0; i < a.visibleLength.size(); ++i) {
    drawnA += a.visibleLength[i];
    kept += std::min(a.visibleLength[i], b.visibleLength[i]);
  }
  EXPECT_GT(kept / drawnA, 0.8) << "visible length kept by id";
}

// ---------------------------------------------------------------------------------------------
// The CLI.

std::string writeSphereLines(const std::filesystem::path& dir) {
  const auto path = dir / "sphere_lines.ply";
  test::runCli("-q extract contour " + (dir / "sphere.ply").string() + " -o " + path.string());
  return path.string();
}

TEST(HatchCli, AbsurdStrokeWidthsAreRefusedNamingTheFlag) {
  const std::string model = (test::bundledData() / "santa_points.ply").string();
  auto dir = test::scratchDir("hatch_cli_bad");
  for (const char* bad : {"0", "-1", "nan", "1e9"}) {
    auto r = test::runCli("render " + model + " -o " + (dir / "x.png").string() + " --style hatch --stroke-width " + bad);
    EXPECT_EQ(r.exitCode, 1) << bad << ": " << r.out;
    EXPECT_NE(r.out.find("--stroke-width"), std::string::npos) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  }
  for (const char* bad : {"--style sketch", "--ink purple", "--paper 1,2,3", "--ink transparent"}) {
    auto r = test::runCli("render " + model + " -o " + (dir / "x.png").string() + " " + bad);
    EXPECT_EQ(r.exitCode, 1) << bad << ": " << r.out;
  }
  // an SVG needs a drawing style
  auto r = test::runCli("render " + model + " -o " + (dir / "x.svg").string());
  EXPECT_EQ(r.exitCode, 1) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "x.svg"));
}

TEST(HatchCli, APointCloudDrawsItsSilhouettesOnly) {
  const std::string model = (test::bundledData() / "santa_points.ply").string();
  auto dir = test::scratchDir("hatch_cli_points");
  auto r = test::runCli("render " + model + " --up-axis z --size 64x64 --style hatch -o " + (dir / "s.svg").string());
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("silhouettes only"), std::string::npos) << r.out;
  std::ifstream in(dir / "s.svg");
  std::stringstream ss;
  ss << in.rdbuf();
  EXPECT_NE(ss.str().find("<path"), std::string::npos);
  r = test::runCli("render " + model + " --size 64x64 --style lines --no-silhouettes -o " + (dir / "t.png").string());
  EXPECT_EQ(r.exitCode, 1) << r.out;
  EXPECT_NE(r.out.find("--style"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "t.png"));
}

TEST(HatchCli, AMeshFileIsRefusedWithTheWayToItsLines) {
  auto r = test::runCli("render " + (test::bundledData() / "al_mesh.ply").string() + " --style lines -o " +
                        (test::scratchDir("hatch_cli_mesh") / "a.png").string());
  EXPECT_EQ(r.exitCode, 1) << r.out;
  EXPECT_NE(r.out.find("extract contour"), std::string::npos) << r.out;
}

TEST(HatchCli, TheDefaultStyleKeepsItsBytes) {
  // the splat render of a small scan, as written before the drawing styles existed
  const std::string model = (test::bundledData() / "santa_points.ply").string();
  auto dir = test::scratchDir("hatch_cli_default");
  const std::string args = " --up-axis z --size 48x40 -o ";
  ASSERT_EQ(test::runCli("-q render " + model + args + (dir / "a.png").string()).exitCode, 0);
  ASSERT_EQ(test::runCli("-q render " + model + args + (dir / "b.png").string() + " --style splat --stroke-width 3").exitCode, 0);
  auto bytes = [](const std::filesystem::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  EXPECT_EQ(bytes(dir / "a.png"), bytes(dir / "b.png"));
  EXPECT_EQ(bytes(dir / "a.png"), bytes(test::testData() / "render" / "santa_default_48x40.png"));
}

TEST(HatchCli, ContourLinesToPngAndSvg) {
  auto dir = test::scratchDir("hatch_cli_lines");
  writeMesh(dir / "sphere.ply", shapes::sphereMesh(1, 3));
  const std::string model = writeSphereLines(dir);
  ASSERT_TRUE(std::filesystem::exists(model));
  auto r = test::runCli("render " + model + " --size 96x96 --style hatch --ink \'#202040\' -o " + (dir / "h.svg").string());
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("drawing:"), std::string::npos) << r.out;
  r = test::runCli("-q render " + model + " --size 96x96 --style lines -o " + (dir / "l.png").string());
  ASSERT_EQ(r.exitCode, 0) << r.out;
  const Image im = readImage(dir / "l.png");
  size_t inked = 0;
  for (const Color& c : im.pixels) inked += luminance(c) < 0.5f;
  EXPECT_GT(inked, 500u);
}

}  // namespace
}  // namespace linesurf
