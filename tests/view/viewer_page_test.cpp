// The viewer page of `linesurf view`: what it embeds and what it refuses. The page's
// drawing is tested in a browser (tests/browser/viewer_test.sh).
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>

#include "linesurf/core/error.h"
#include "linesurf/lod/lod.h"
#include "linesurf/render/camera.h"
#include "linesurf/view/viewer_page.h"
#include "test_util.h"

namespace linesurf {
namespace {

using json = nlohmann::json;

HybridModel smallHybrid() {
  HybridModel m;
  for (int i = 0; i < 5; ++i) {
    Point p;
    p.position = Vec3f(float(i), 2.0f, -1.0f);
    p.normal = Vec3f(0, 0, 1);
    p.radius = 0.5f;
    m.points.push_back(p);
  }
  Segment s;
  s.p0 = Vec3f(0, 0, 0);
  s.p1 = Vec3f(4, 0, 0);
  s.normal = Vec3f(0, 0, 1);
  s.radius = 0.25f;
  m.segments.push_back(s);
  m.attributes.normals = m.attributes.radii = true;
  return m;
}

// The text between `<script id="ID" ...>` and `</script>`.
std::string scriptText(const std::string& page, const std::string& id) {
  const size_t tag = page.find("<script id=\"" + id + "\"");
  EXPECT_NE(tag, std::string::npos) << id;
  const size_t start = page.find('>', tag) + 1;
  return page.substr(start, page.find("</script>", start) - start);
}

std::vector<uint8_t> fromBase64(const std::string& s) {
  auto val = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
  };
  std::vector<uint8_t> out;
  uint32_t acc = 0;
  int bits = 0;
  for (char c : s) {
    const int v = val(c);
    if (v < 0) continue;
    acc = acc << 6 | uint32_t(v);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out.push_back(uint8_t(acc >> bits));
    }
  }
  return out;
}

TEST(ViewerPage, EmbedsEveryPrimitiveRelativeToTheBoundingSphere) {
  const HybridModel m = smallHybrid();
  ViewerPageStats st;
  const std::string page = viewerPage(m, {.name = "small.ply"}, &st);
  EXPECT_EQ(st.points, 5u);
  EXPECT_EQ(st.segments, 1u);
  EXPECT_EQ(st.bytes, page.size());
  for (const char* marker : {"@META@", "@DATA@", "@VIEWER_JS@"}) EXPECT_EQ(page.find(marker), std::string::npos);
  EXPECT_NE(page.find("getContext('webgl2'"), std::string::npos);  // the viewer's script is inlined
  const json meta = json::parse(scriptText(page, "linesurf-meta"));
  const std::vector<uint8_t> data = fromBase64(scriptText(page, "linesurf-data"));
  ASSERT_EQ(data.size(), meta["bytes"].get<size_t>());
  EXPECT_EQ(meta["points"]["count"], 5);
  EXPECT_EQ(meta["segments"]["count"], 1);
  const BoundingSphere sphere = boundingSphere(m);
  EXPECT_NEAR(meta["sphere"]["radius"].get<float>(), sphere.radius, 1e-6f);
  // point 3's position, float32 at the position array's offset
  float p3[3];
  std::memcpy(p3, data.data() + meta["points"]["position"]["offset"].get<size_t>() + 3 * 12, 12);
  const Vec3f expect = (m.points[3].position - sphere.center) / sphere.radius;
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(p3[c], expect[c], 1e-6f);
  float r;
  std::memcpy(&r, data.data() + meta["segments"]["radius"]["offset"].get<size_t>(), 4);
  EXPECT_NEAR(r, 0.25f / sphere.radius, 1e-7f);
  // the defaults are the renderer's (one source of truth: RenderOptions; tests/options checks all)
  const RenderOptions ro;
  EXPECT_FLOAT_EQ(meta["defaults"]["cutoffRadius"].get<float>(), ro.cutoffRadius);
  EXPECT_FLOAT_EQ(meta["defaults"]["ambient"].get<float>(), ro.material.ambient);
  EXPECT_FLOAT_EQ(meta["defaults"]["zThreshold"].get<float>(), zThresholdOf(ro));
}

TEST(ViewerPage, LeavesOutAndCountsUndrawablePrimitives) {
  HybridModel m = smallHybrid();
  m.points[1].radius = 0;
  m.points[2].position.x() = NAN;
  m.segments[0].p1 = m.segments[0].p0;  // zero length
  ViewerPageStats st;
  const std::string page = viewerPage(m, {}, &st);
  EXPECT_EQ(st.points, 3u);
  EXPECT_EQ(st.skippedPoints, 2u);
  EXPECT_EQ(st.segments, 0u);
  EXPECT_EQ(st.skippedSegments, 1u);
  const json meta = json::parse(scriptText(page, "linesurf-meta"));
  EXPECT_EQ(meta["points"]["count"], 3);
  EXPECT_FALSE(meta.contains("segments"));
}

TEST(ViewerPage, RefusesAModelOverTheBudgetOrWithNothingToDraw) {
  const HybridModel m = smallHybrid();
  try {
    viewerPage(m, {.name = "big.ply", .maxPrimitives = 5});
    FAIL() << "a model over the budget must be refused";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadInput);
    EXPECT_EQ(e.path(), "big.ply");
    EXPECT_NE(std::string(e.what()).find("budget of 5"), std::string::npos) << e.what();
  }
  HybridModel none = m;
  for (Point& p : none.points) p.radius = 0;
  none.segments.clear();
  EXPECT_THROW(viewerPage(none), Error);
  EXPECT_THROW(viewerPage(m, {.view = {.fov = 0}}), Error);
}

TEST(ViewerPage, NameCannotCloseTheScriptElement) {
  const std::string page = viewerPage(smallHybrid(), {.name = "a</script><b>.ply"});
  const std::string meta = scriptText(page, "linesurf-meta");
  EXPECT_EQ(json::parse(meta)["name"], "a</script><b>.ply");
  EXPECT_EQ(page.find("a</script>"), std::string::npos);
}

TEST(ViewerPage, CarriesEndpointNormalsAndClusterIds) {
  HybridModel m = smallHybrid();
  m.attributes.endpointNormals = true;
  m.segments[0].normal0 = Vec3f(0, 0.6f, 0.8f);
  m.segments[0].normal1 = Vec3f(0, -0.6f, 0.8f);
  m.pointProperties["cluster"] = {0, 0, 1, 1, 2};
  const json meta = json::parse(scriptText(viewerPage(m), "linesurf-meta"));
  EXPECT_TRUE(meta["segments"].contains("normal0"));
  EXPECT_TRUE(meta["segments"].contains("normal1"));
  EXPECT_TRUE(meta["points"].contains("cluster"));
}

// Points' shading normals go into the page (unit, int16) beside their plane normals, in
// the order of the points drawn (skipped points leave theirs out), and only when the model has them.
TEST(ViewerPage, CarriesPointShadingNormals) {
  HybridModel m = smallHybrid();
  EXPECT_FALSE(json::parse(scriptText(viewerPage(m), "linesurf-meta"))["points"].contains("shadingNormal"));
  for (size_t i = 0; i < m.points.size(); ++i)
    m.pointShadingNormals.push_back(Vec3f(0.1f * float(i), 0.0f, 1.0f).normalized());
  EXPECT_FALSE(json::parse(scriptText(viewerPage(m), "linesurf-meta"))["points"].contains("shadingNormal"))
      << "without attributes.shadingNormals the renderer ignores them, and so does the page";
  m.attributes.shadingNormals = true;
  m.pointShadingNormals[4] = Vec3f(0, 3, 0);  // not unit: normalised
  m.points[1].radius = 0;                     // left out with its shading normal
  const std::string page = viewerPage(m);
  const json meta = json::parse(scriptText(page, "linesurf-meta"));
  const std::vector<uint8_t> data = fromBase64(scriptText(page, "linesurf-data"));
  ASSERT_EQ(meta["points"]["count"], 4);
  const json& sn = meta["points"]["shadingNormal"];
  ASSERT_EQ(sn["type"], "i16");
  ASSERT_EQ(sn["components"], 3);
  const size_t drawn[] = {0, 2, 3, 4};
  for (size_t k = 0; k < 4; ++k) {
    int16_t q[3];
    std::memcpy(q, data.data() + sn["offset"].get<size_t>() + k * 6, 6);
    const Vec3f expect = m.pointShadingNormals[drawn[k]].normalized();
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(q[c] / 32767.0f, expect[c], 1e-4f) << "point " << drawn[k];
  }
}

TEST(ViewerPage, CarriesPointMasses) {
  HybridModel m = smallHybrid();
  EXPECT_FALSE(json::parse(scriptText(viewerPage(m), "linesurf-meta"))["points"].contains("mass"));
  std::vector<float>& mass = m.pointProperties[kPointMassProperty];
  for (size_t i = 0; i < m.points.size(); ++i) mass.push_back(0.5f + float(i));
  m.points[1].radius = 0;  // left out with its mass
  const std::string page = viewerPage(m);
  const json meta = json::parse(scriptText(page, "linesurf-meta"));
  const std::vector<uint8_t> data = fromBase64(scriptText(page, "linesurf-data"));
  ASSERT_EQ(meta["points"]["count"], 4);
  const json& jm = meta["points"]["mass"];
  ASSERT_EQ(jm["type"], "f32");
  ASSERT_EQ(jm["components"], 1);
  const size_t drawn[] = {0, 2, 3, 4};
  for (size_t k = 0; k < 4; ++k) {
    float v;
    std::memcpy(&v, data.data() + jm["offset"].get<size_t>() + k * 4, 4);
    EXPECT_EQ(v, mass[drawn[k]]) << "point " << drawn[k];
  }
}

TEST(ViewCli, WritesAPageAndRefusesBadInput) {
  const auto dir = test::scratchDir("view_cli");
  auto ok = test::runCli("view " + (test::bundledData() / "rockerarm_points.ply").string() + " -o " +
                         (dir / "r.html").string() + " --up-axis z");
  EXPECT_EQ(ok.exitCode, 0) << ok.out;
  EXPECT_TRUE(std::filesystem::exists(dir / "r.html"));
  // a mesh is drawn as its vertices: the page's render line says --primitive points
  auto mesh = test::runCli("view " + (test::bundledData() / "al_mesh.ply").string() + " -o " + (dir / "m.html").string());
  EXPECT_EQ(mesh.exitCode, 0) << mesh.out;
  std::ifstream in(dir / "m.html");
  const std::string page((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(page.find("\"renderArguments\":\"--primitive points\""), std::string::npos);
  auto missing = test::runCli("view " + (dir / "missing.ply").string());
  EXPECT_NE(missing.exitCode, 0);
  std::ofstream(dir / "bad.ply") << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nend_header\n1\n";
  auto bad = test::runCli("view " + (dir / "bad.ply").string() + " -o " + (dir / "bad.html").string());
  EXPECT_EQ(bad.exitCode, 2) << bad.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.html"));
  auto over = test::runCli("view " + (test::bundledData() / "rockerarm_points.ply").string() + " -o " +
                           (dir / "over.html").string() + " --max-primitives 10");
  EXPECT_EQ(over.exitCode, 2) << over.out;
  EXPECT_NE(over.out.find("budget"), std::string::npos) << over.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "over.html"));
}

// A hierarchy's page holds no primitives: it names the hierarchy, where to read it and the
// initial budget, and the page's usual defaults and frame (the file's bounding sphere).
TEST(ViewerPage, LodModeDescribesTheHierarchyAndEmbedsNoPrimitives) {
  const HybridModel m = smallHybrid();
  const std::string bytes = lod::buildLod(m, ModelFrame{}, {.leafSize = 16, .grid = 4});
  const auto path = test::scratchDir("view_lod") / "small.lod";
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  const lod::LodFile file(path);
  const std::string page =
      lodViewerPage(file.header(), {.url = "/model.lod", .fileBytes = bytes.size(), .budget = 1234}, {.name = "small.lod"});
  const json meta = json::parse(scriptText(page, "linesurf-meta"));
  EXPECT_EQ(meta["format"], "linesurf-view");
  EXPECT_EQ(meta["lod"]["url"], "/model.lod");
  EXPECT_EQ(meta["lod"]["budget"], 1234);
  EXPECT_EQ(meta["lod"]["bytes"], bytes.size());
  EXPECT_EQ(meta["lod"]["points"], 5);
  EXPECT_EQ(meta["lod"]["segments"], 1);
  char id[17];
  std::snprintf(id, sizeof id, "%016llx", static_cast<unsigned long long>(file.header().hierarchyId));
  EXPECT_EQ(meta["lod"]["hierarchy"], id);
  EXPECT_FLOAT_EQ(meta["sphere"]["radius"].get<float>(), file.header().sphere.radius);
  EXPECT_TRUE(meta.contains("defaults"));
  EXPECT_TRUE(meta["constants"].contains("maxPointMass"));
  EXPECT_EQ(scriptText(page, "linesurf-data"), "");
  EXPECT_THROW(lodViewerPage(file.header(), {.budget = 0}), Error);
}

// `view X.lod` checks the hierarchy before serving (a bad one: exit 2, one line naming it);
// the server's options need a hierarchy, and a hierarchy is served, not written.
TEST(ViewCli, RefusesBadHierarchiesAndServerOptionsOfPlainModels) {
  const auto dir = test::scratchDir("view_lod_cli");
  std::ofstream(dir / "bad.lod", std::ios::binary) << "LINESLOD and nothing else";
  auto bad = test::runCli("view " + (dir / "bad.lod").string() + " --port 0");
  EXPECT_EQ(bad.exitCode, 2) << bad.out;
  EXPECT_NE(bad.out.find("bad.lod"), std::string::npos) << bad.out;
  const std::string model = (test::bundledData() / "rockerarm_points.ply").string();
  auto port = test::runCli("view " + model + " -o " + (dir / "r.html").string() + " --budget 1000");
  EXPECT_EQ(port.exitCode, 1) << port.out;
  EXPECT_NE(port.out.find("--budget"), std::string::npos) << port.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "r.html"));
}

}  // namespace
}  // namespace linesurf
