// The tiny valid files of tests/data/ok (made by make_ok.py) read to the values written there,
// and convert between formats through the CLI.
#include <gtest/gtest.h>

#include "linesurf/core/error.h"
#include "linesurf/io/model_io.h"
#include "linesurf/io/model_stats.h"
#include "test_util.h"

using namespace linesurf;
namespace fs = std::filesystem;

namespace {
fs::path ok(const char* name) { return test::testData() / "ok" / name; }
}  // namespace

TEST(OkFiles, AsciiPointsWithEveryAttribute) {
  HybridModel m = readModel(ok("points_ascii.ply"));
  ASSERT_EQ(m.points.size(), 3u);
  EXPECT_TRUE(m.attributes.normals && m.attributes.colors && m.attributes.radii);
  EXPECT_EQ(m.points[2].position, Vec3f(0, 1, 0.5f));
  EXPECT_EQ(m.points[2].normal, Vec3f(0, 1, 0));
  EXPECT_EQ(m.points[0].color, Color(1, 0, 0, 1));
  EXPECT_EQ(m.points[1].color, Color(0, 1, 0, 128 / 255.0f));
  EXPECT_EQ(m.points[2].radius, 0.125f);
  EXPECT_EQ(m.pointProperties.at("k_min"), (std::vector<float>{-1.5f, 0, 2.5e-3f}));
  EXPECT_EQ(m.comments, std::vector<std::string>{"source: hand-written test file"});
  EXPECT_FALSE(fileHoldsMesh(ok("points_ascii.ply")));
}

TEST(OkFiles, BigEndianMixedTypesSkipsVertexLists) {
  HybridModel m = readModel(ok("points_be.ply"));
  ASSERT_EQ(m.points.size(), 3u);
  EXPECT_EQ(m.points[2].position, Vec3f(0, 1, 0.5f));
  EXPECT_EQ(m.pointProperties.at("quality"), (std::vector<float>{7, 8, 65535}));
  EXPECT_EQ(m.pointProperties.count("junk"), 0u);
}

TEST(OkFiles, LittleEndianAliasesAndUnknownElements) {
  HybridModel m = readModel(ok("points_le.ply"));
  ASSERT_EQ(m.points.size(), 2u);
  EXPECT_EQ(m.points[1].position, Vec3f(4, 5, 6));
  EXPECT_EQ(m.pointProperties.at("a"), (std::vector<float>{-5, 5}));
  EXPECT_EQ(m.pointProperties.at("b"), (std::vector<float>{600, 0}));
  EXPECT_EQ(m.pointProperties.at("c"), (std::vector<float>{-70000, 70000}));
  EXPECT_EQ(m.pointProperties.at("d"), (std::vector<float>{4e9f, 0}));
  EXPECT_EQ(m.pointProperties.at("e"), (std::vector<float>{0.125f, -0.5f}));
}

TEST(OkFiles, HybridSegmentsWithProvenanceAndTexture) {
  HybridModel m = readModel(ok("hybrid_segments.ply"));
  ASSERT_EQ(m.points.size(), 1u);
  ASSERT_EQ(m.segments.size(), 2u);
  const Segment& s = m.segments[1];
  EXPECT_EQ(s.p0, Vec3f(0, 1, 0));
  EXPECT_EQ(s.p1, Vec3f(0, 2, 0));
  EXPECT_EQ(s.normal, Vec3f(1, 0, 0));  // read even though the point has none
  EXPECT_FALSE(m.attributes.normals);   // ...so the model as a whole does not claim normals
  EXPECT_EQ(s.color, Color(0, 0, 1, 1));
  EXPECT_EQ(s.radius, 0.02f);
  EXPECT_EQ(s.uv1, Vec2f(0.75f, 0.75f));
  EXPECT_TRUE(m.attributes.texcoords);
  ASSERT_EQ(m.provenance.size(), 2u);
  EXPECT_EQ(m.provenance[0], (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_TRUE(m.provenance[1].empty());
  ASSERT_TRUE(m.texture);
  EXPECT_EQ(m.texture->at(0, 0), Color(1, 0, 0, 1));
  EXPECT_TRUE(m.comments.empty());  // the TextureFile comment is consumed
}

TEST(OkFiles, PlyAndObjQuadMeshesAgree) {
  TriangleMesh p = readMesh(ok("mesh_texcoords.ply"));
  TriangleMesh o = readMesh(ok("quad.obj"));
  for (const TriangleMesh* m : {&p, &o}) {
    ASSERT_EQ(m->positions.size(), 4u);
    ASSERT_EQ(m->faces.size(), 2u);  // the quad is fan-triangulated
    ASSERT_EQ(m->cornerUVs.size(), 2u);
    ASSERT_TRUE(m->texture);
    EXPECT_EQ(m->texture->at(1, 1), Color(1, 1, 1, 1));
    ASSERT_EQ(m->normals.size(), 4u);
    EXPECT_EQ(m->normals[2], Vec3f(0, 0, 1));
    // Every corner's uv equals its vertex position in this quad.
    for (size_t f = 0; f < 2; ++f)
      for (int k = 0; k < 3; ++k) EXPECT_EQ(m->cornerUVs[f][k], m->positions[m->faces[f][k]].head<2>());
  }
  // (tinyobjloader splits the quad along the other diagonal; both are valid triangulations)
  EXPECT_EQ(p.comments, std::vector<std::string>{"a unit quad"});
}

TEST(OkFiles, XyzWithCommentsAndBlankLines) {
  HybridModel m = readModel(ok("points.xyz"));
  ASSERT_EQ(m.points.size(), 3u);
  EXPECT_EQ(m.points[2].normal, Vec3f(0, 1, 0));
  EXPECT_EQ(m.comments, std::vector<std::string>{"three points with normals"});
}

TEST(OkFiles, AverageSpacingOfKnownPoints) {
  ModelSummary s = summarizeFile(ok("points_ascii.ply"));
  // nearest distances: 1, 1, |(0,1,0.5)-(0,0,0)| = sqrt(1.25)
  EXPECT_NEAR(s.averageSpacing, (2 + std::sqrt(1.25)) / 3, 1e-6);
  EXPECT_EQ(s.kind, "points");
  EXPECT_EQ(averageSpacing({Vec3f(1, 1, 1), Vec3f(1, 1, 1)}), 0.0);
  EXPECT_EQ(averageSpacing({Vec3f(1, 1, 1)}), 0.0);
}

TEST(OkFiles, RadiusSpreadOfAModelWithRadii) {
  HybridModel m;
  for (int i = 0; i < 21; ++i) m.points.push_back({.position = Vec3f(float(i), 0, 0), .radius = i == 20 ? 50.0f : 1.0f + 0.1f * float(i % 3)});
  m.attributes.radii = true;
  const auto dir = test::scratchDir("io_radii");
  writeModel(dir / "r.ply", m);
  const ModelSummary s = summarizeFile(dir / "r.ply");
  EXPECT_FLOAT_EQ(s.radiusMin, 1.0f);
  EXPECT_FLOAT_EQ(s.radiusMedian, 1.1f);
  EXPECT_FLOAT_EQ(s.radiusMax, 50.0f);
  EXPECT_EQ(s.radiiAbove10xMedian, 1u);
  EXPECT_EQ(summarizeFile(ok("points.xyz")).radiusMax, 0.0f);  // no radii: no spread
  const test::CliResult r = test::runCli("info '" + (dir / "r.ply").string() + "'");
  EXPECT_NE(r.out.find("1 above 10 x the median"), std::string::npos) << r.out;
}

TEST(OkFiles, CliInfoTextAndJson) {
  test::CliResult r = test::runCli("info '" + ok("mesh_texcoords.ply").string() + "'");
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("kind:       mesh"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("faces:      2"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("texture:    2x2"), std::string::npos) << r.out;
  r = test::runCli("info --json '" + ok("hybrid_segments.ply").string() + "'");
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("\"kind\": \"hybrid\""), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"segments\": 2"), std::string::npos) << r.out;
}

TEST(OkFiles, CliConvertBetweenFormats) {
  auto dir = test::scratchDir("io_convert");
  auto run = [](const std::string& args) { return test::runCli("-q convert " + args); };
  EXPECT_EQ(run("'" + ok("quad.obj").string() + "' '" + (dir / "q.ply").string() + "' --ascii").exitCode, 0);
  TriangleMesh q = readMesh(dir / "q.ply");
  EXPECT_EQ(q.faces.size(), 2u);
  EXPECT_TRUE(q.texture);  // texture written beside as q_texture.png
  EXPECT_EQ(run("'" + (dir / "q.ply").string() + "' '" + (dir / "q.xyz").string() + "'").exitCode, 0);
  EXPECT_EQ(readModel(dir / "q.xyz").points.size(), 4u);  // mesh -> points as vertices
  EXPECT_EQ(run("'" + ok("points_ascii.ply").string() + "' '" + (dir / "p.ply").string() + "'").exitCode, 0);
  EXPECT_EQ(readModel(dir / "p.ply").pointProperties.at("k_min").size(), 3u);
  test::CliResult bad = run("'" + ok("points_ascii.ply").string() + "' '" + (dir / "p.obj").string() + "'");
  EXPECT_EQ(bad.exitCode, 1) << bad.out;
  EXPECT_FALSE(fs::exists(dir / "p.obj"));
}
