// Round trips and schema checks of the model readers/writers (PLY, OBJ, XYZ).
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <random>

#include "linesurf/core/error.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

using namespace linesurf;
namespace fs = std::filesystem;

namespace {

HybridModel randomModel(size_t nPoints, size_t nSegments, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> U(-10, 10), C(0, 1);
  HybridModel m;
  for (size_t i = 0; i < nPoints; ++i) {
    Point p;
    p.position = Vec3f(U(rng), U(rng), U(rng));
    p.normal = Vec3f(U(rng), U(rng), U(rng)).normalized();
    p.color = Color(std::round(C(rng) * 255) / 255, std::round(C(rng) * 255) / 255, std::round(C(rng) * 255) / 255, 1);
    p.radius = C(rng);
    m.points.push_back(p);
  }
  for (size_t i = 0; i < nSegments; ++i) {
    Segment s;
    s.p0 = Vec3f(U(rng), U(rng), U(rng));
    s.p1 = Vec3f(U(rng), U(rng), U(rng));
    s.normal = Vec3f(U(rng), U(rng), U(rng)).normalized();
    s.color = Color(std::round(C(rng) * 255) / 255, 0, 1, std::round(C(rng) * 255) / 255);
    s.radius = C(rng) * 1e-3f;
    s.uv0 = Vec2f(C(rng), C(rng));
    s.uv1 = Vec2f(C(rng), C(rng));
    m.segments.push_back(s);
  }
  m.attributes = {true, true, true, true};
  m.comments = {"source: unit test", "second comment"};
  std::vector<float> k(nPoints);
  for (float& v : k) v = U(rng) * 1e-7f;
  m.pointProperties["k_min"] = k;
  m.pointProperties["k_max"] = std::vector<float>(nPoints, 3.25f);
  return m;
}

void expectSameModel(const HybridModel& a, const HybridModel& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  ASSERT_EQ(a.segments.size(), b.segments.size());
  for (size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].position, b.points[i].position) << i;
    if (a.attributes.normals) { EXPECT_EQ(a.points[i].normal, b.points[i].normal) << i; }
    if (a.attributes.colors) { EXPECT_EQ(a.points[i].color, b.points[i].color) << i; }
    if (a.attributes.radii) { EXPECT_EQ(a.points[i].radius, b.points[i].radius) << i; }
  }
  for (size_t i = 0; i < a.segments.size(); ++i) {
    const Segment &s = a.segments[i], &t = b.segments[i];
    EXPECT_EQ(s.p0, t.p0);
    EXPECT_EQ(s.p1, t.p1);
    if (a.attributes.normals) { EXPECT_EQ(s.normal, t.normal); }
    if (a.attributes.colors) { EXPECT_EQ(s.color, t.color); }
    if (a.attributes.radii) { EXPECT_EQ(s.radius, t.radius); }
    if (a.attributes.texcoords) {
      EXPECT_EQ(s.uv0, t.uv0);
      EXPECT_EQ(s.uv1, t.uv1);
    }
  }
  EXPECT_EQ(a.pointProperties, b.pointProperties);
  EXPECT_EQ(a.provenance, b.provenance);
  EXPECT_EQ(a.comments, b.comments);
  EXPECT_EQ(a.attributes.normals, b.attributes.normals);
  EXPECT_EQ(a.attributes.colors, b.attributes.colors);
  EXPECT_EQ(a.attributes.radii, b.attributes.radii);
  EXPECT_EQ(a.attributes.texcoords, b.attributes.texcoords);
}

TriangleMesh quadMesh() {
  TriangleMesh m;
  m.positions = {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(1, 1, 0), Vec3f(0, 1, 0.5f)};
  m.faces = {{0, 1, 2}, {0, 2, 3}};
  m.normals = {Vec3f(0, 0, 1), Vec3f(0, 0, 1), Vec3f(0, 0, 1), Vec3f(0, 0, 1)};
  m.cornerUVs = {{Vec2f(0, 0), Vec2f(1, 0), Vec2f(1, 1)}, {Vec2f(0, 0), Vec2f(1, 1), Vec2f(0.125f, 1)}};
  m.comments = {"a quad"};
  return m;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

}  // namespace

TEST(ModelIo, PlyRoundTripBinaryIsExact) {
  auto dir = test::scratchDir("io_rt_bin");
  HybridModel m = randomModel(200, 50, 7);
  m.provenance.resize(50);
  for (uint32_t i = 0; i < 50; ++i) m.provenance[i] = {i, i + 1, 4000000000u};
  m.provenance[3].clear();
  writeModel(dir / "m.ply", m);
  EXPECT_EQ(slurp(dir / "m.ply").substr(0, 36), "ply\nformat binary_little_endian 1.0\n");
  expectSameModel(m, readModel(dir / "m.ply"));
}

TEST(ModelIo, PlyRoundTripAsciiIsExact) {
  auto dir = test::scratchDir("io_rt_ascii");
  HybridModel m = randomModel(100, 30, 8);
  writeModel(dir / "m.ply", m, {.encoding = PlyEncoding::Ascii});
  EXPECT_EQ(slurp(dir / "m.ply").substr(0, 23), "ply\nformat ascii 1.0\nco");
  expectSameModel(m, readModel(dir / "m.ply"));  // shortest round-trip float text
}

TEST(ModelIo, AttributesControlWhatIsWritten) {
  auto dir = test::scratchDir("io_attr");
  HybridModel m = randomModel(10, 3, 9);
  m.pointProperties.clear();
  m.attributes = {false, false, false, false};
  writeModel(dir / "plain.ply", m, {.encoding = PlyEncoding::Ascii});
  std::string text = slurp(dir / "plain.ply");
  for (const char* absent : {"nx", "red", "alpha", "radius", "u0", "provenance"})
    EXPECT_EQ(text.find(std::string("property float ") + absent), std::string::npos) << absent;
  EXPECT_EQ(text.find("property uchar red"), std::string::npos);
  HybridModel r = readModel(dir / "plain.ply");
  EXPECT_FALSE(r.attributes.normals || r.attributes.colors || r.attributes.radii || r.attributes.texcoords);
  EXPECT_EQ(r.points[0].normal, Vec3f::Zero());
  EXPECT_EQ(r.points[0].color, Color(1, 1, 1, 1));
  EXPECT_EQ(r.segments[2].p1, m.segments[2].p1);

  m.attributes.colors = true;
  writeModel(dir / "col.ply", m);
  text = slurp(dir / "col.ply");
  EXPECT_NE(text.find("property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha"), std::string::npos);
  EXPECT_TRUE(readModel(dir / "col.ply").attributes.colors);
}

TEST(ModelIo, PointsOnlyFileUsesStandardVertexNames) {
  auto dir = test::scratchDir("io_std");
  HybridModel m = randomModel(5, 0, 1);
  m.pointProperties.clear();
  writeModel(dir / "p.ply", m, {.encoding = PlyEncoding::Ascii});
  std::string t = slurp(dir / "p.ply");
  EXPECT_NE(t.find("element vertex 5\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\n"),
            std::string::npos);
  EXPECT_EQ(t.find("element segment"), std::string::npos);
}

TEST(ModelIo, MeshRoundTripKeepsTexcoordsNormalsComments) {
  auto dir = test::scratchDir("io_mesh");
  TriangleMesh m = quadMesh();
  for (auto enc : {PlyEncoding::BinaryLittleEndian, PlyEncoding::Ascii}) {
    writeMesh(dir / "q.ply", m, {.encoding = enc});
    TriangleMesh r = readMesh(dir / "q.ply");
    EXPECT_EQ(r.positions, m.positions);
    EXPECT_EQ(r.faces, m.faces);
    EXPECT_EQ(r.normals, m.normals);
    EXPECT_EQ(r.cornerUVs, m.cornerUVs);
    EXPECT_EQ(r.comments, m.comments);
    EXPECT_TRUE(fileHoldsMesh(dir / "q.ply"));
    HybridModel pts = readModel(dir / "q.ply");  // a mesh read as points: its vertices
    ASSERT_EQ(pts.points.size(), 4u);
    EXPECT_EQ(pts.points[3].position, m.positions[3]);
    EXPECT_TRUE(pts.attributes.normals);
  }
}

TEST(ModelIo, MeshTextureWrittenBesideAndReloaded) {
  auto dir = test::scratchDir("io_tex");
  TriangleMesh m = quadMesh();
  auto img = std::make_shared<Image>(4, 2, Color(1, 0, 0, 1));
  img->at(3, 1) = Color(0, 0, 1, 1);
  m.texture = img;
  for (const char* name : {"t.ply", "t.obj"}) {
    writeMesh(dir / name, m);
    EXPECT_TRUE(fs::exists(dir / (fs::path(name).stem().string() + "_texture.png")));
    TriangleMesh r = readMesh(dir / name);
    ASSERT_TRUE(r.texture) << name;
    EXPECT_EQ(r.texture->width, 4);
    EXPECT_EQ(r.texture->at(3, 1), Color(0, 0, 1, 1));
    EXPECT_EQ(r.cornerUVs, m.cornerUVs) << name;
    EXPECT_EQ(r.faces, m.faces) << name;
    EXPECT_EQ(r.positions, m.positions) << name;
  }
  EXPECT_NE(slurp(dir / "t.ply").find("comment TextureFile t_texture.png\n"), std::string::npos);
  EXPECT_EQ(readMesh(dir / "t.ply").comments, m.comments);  // TextureFile is not a plain comment
}

TEST(ModelIo, ObjRoundTripNormals) {
  auto dir = test::scratchDir("io_obj");
  TriangleMesh m = quadMesh();
  m.cornerUVs.clear();
  writeMesh(dir / "q.obj", m);
  TriangleMesh r = readMesh(dir / "q.obj");
  EXPECT_EQ(r.positions, m.positions);
  EXPECT_EQ(r.faces, m.faces);
  EXPECT_EQ(r.normals, m.normals);
  EXPECT_TRUE(r.cornerUVs.empty());
  EXPECT_TRUE(fileHoldsMesh(dir / "q.obj"));
  EXPECT_EQ(readModel(dir / "q.obj").points.size(), 4u);
}

TEST(ModelIo, XyzRoundTrip) {
  auto dir = test::scratchDir("io_xyz");
  HybridModel m = randomModel(50, 0, 3);
  m.pointProperties.clear();
  m.attributes = {true, false, false, false};
  writeModel(dir / "p.xyz", m);
  HybridModel r = readModel(dir / "p.xyz");
  ASSERT_EQ(r.points.size(), 50u);
  for (size_t i = 0; i < 50; ++i) {
    EXPECT_EQ(r.points[i].position, m.points[i].position);
    EXPECT_EQ(r.points[i].normal, m.points[i].normal);
  }
  EXPECT_TRUE(r.attributes.normals);
  EXPECT_EQ(r.comments, m.comments);
  EXPECT_FALSE(fileHoldsMesh(dir / "p.xyz"));
}

TEST(ModelIo, WriterLeavesNothingOnFailure) {
  auto dir = test::scratchDir("io_fail");
  HybridModel m = randomModel(3, 0, 1);
  EXPECT_THROW(writeModel(dir / "missing" / "m.ply", m), Error);
  EXPECT_FALSE(fs::exists(dir / "missing"));
  m.pointProperties["bad"] = {1.0f};  // wrong length
  try {
    writeModel(dir / "m.ply", m);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::Io);
  }
  EXPECT_TRUE(fs::is_empty(dir));
  m.pointProperties.erase("bad");
  writeModel(dir / "m.ply", m);
  size_t files = 0;
  for (auto& entry : fs::directory_iterator(dir)) {
    ++files;
    EXPECT_EQ(entry.path().filename(), "m.ply");  // no temporary left behind
  }
  EXPECT_EQ(files, 1u);
}

TEST(ModelIo, PolygonsAreFanTriangulatedAndListTypesAccepted) {
  const std::string ply =
      "ply\nformat ascii 1.0\ncomment hello  world\nelement vertex 5\nproperty double x\nproperty int16 y\n"
      "property uint8 z\nproperty list int32 float64 junk\nelement face 1\nproperty list ushort uint vertex_index\n"
      "property list uchar float texcoord\nelement extra 2\nproperty list uchar int stuff\nproperty float w\n"
      "end_header\n0 0 0 2 1 2\n1 0 0 0\n1 1 0 1 -3\n0 1 0 0\n0.5 2 0 0\n"
      "5 0 1 2 3 4 10 0 0 1 0 1 1 0 1 0.5 2\n3 1 2 3 4.5\n0 1\n";
  TriangleMesh m = readPlyMeshFromMemory(ply, "mem.ply");
  ASSERT_EQ(m.faces.size(), 3u);
  EXPECT_EQ(m.faces[0], (std::array<uint32_t, 3>{0, 1, 2}));
  EXPECT_EQ(m.faces[2], (std::array<uint32_t, 3>{0, 3, 4}));
  EXPECT_EQ(m.cornerUVs[2][2], Vec2f(0.5f, 2));
  EXPECT_EQ(m.positions[4], Vec3f(0.5f, 2, 0));
  EXPECT_EQ(m.comments, std::vector<std::string>{"hello  world"});
  HybridModel p = readPlyModelFromMemory(ply, "mem.ply");
  EXPECT_EQ(p.points.size(), 5u);
  EXPECT_TRUE(p.pointProperties.empty());  // list properties on vertices are skipped
}

TEST(ModelIo, BigEndianAndFloatColours) {
  std::string ply = "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                    "property float z\nproperty float red\nproperty float green\nproperty float blue\n"
                    "property short curvature\nend_header\n";
  auto be = [&](float f) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    for (int s = 24; s >= 0; s -= 8) ply += char((u >> s) & 0xff);
  };
  for (float f : {1.5f, -2.0f, 3.0f, 0.25f, 0.5f, 1.0f}) be(f);
  ply += char(0xff), ply += char(0xfe);  // -2 as big-endian int16
  HybridModel m = readPlyModelFromMemory(ply, "be.ply");
  ASSERT_EQ(m.points.size(), 1u);
  EXPECT_EQ(m.points[0].position, Vec3f(1.5f, -2, 3));
  EXPECT_EQ(m.points[0].color, Color(0.25f, 0.5f, 1, 1));
  EXPECT_TRUE(m.attributes.colors);
  EXPECT_EQ(m.pointProperties.at("curvature"), std::vector<float>{-2.0f});
}

TEST(SharedModelIo, ReadsEveryBundledModel) {
  LINESURF_REQUIRE_SHARED_DATA();
  TriangleMesh buddha = readMesh(test::sharedData() / "buddha_mesh.ply");
  EXPECT_EQ(buddha.positions.size(), 25697u);
  EXPECT_EQ(buddha.faces.size(), 51414u);
  EXPECT_EQ(buddha.cornerUVs.size(), 51414u);
  ASSERT_FALSE(buddha.comments.empty());
  EXPECT_EQ(buddha.comments[0].rfind("source:", 0), 0u);
  TriangleMesh horse = readMesh(test::sharedData() / "horse_mesh.ply");
  EXPECT_EQ(horse.normals.size(), 48485u);
  HybridModel igea = readModel(test::sharedData() / "igea_points.ply");
  EXPECT_EQ(igea.points.size(), 134345u);
  EXPECT_FALSE(fileHoldsMesh(test::sharedData() / "igea_points.ply"));
  EXPECT_TRUE(fileHoldsMesh(test::sharedData() / "dragon_mesh.ply"));
  for (auto& entry : fs::directory_iterator(test::sharedData())) {
    if (entry.path().extension() != ".ply") continue;
    HybridModel m = readModel(entry.path());  // every file reads as points
    EXPECT_FALSE(m.points.empty()) << entry.path();
    if (fileHoldsMesh(entry.path())) { EXPECT_FALSE(readMesh(entry.path()).faces.empty()) << entry.path(); }
  }
}

TEST(ModelIo, FailedOverwriteKeepsTheOldFile) {
  auto dir = test::scratchDir("io_keep");
  HybridModel m = randomModel(4, 1, 5);
  writeModel(dir / "m.ply", m);
  const std::string before = slurp(dir / "m.ply");
  HybridModel bad = m;
  bad.provenance = {{1}, {2}};  // two lists for one segment
  EXPECT_THROW(writeModel(dir / "m.ply", bad), Error);
  EXPECT_EQ(slurp(dir / "m.ply"), before);
}

TEST(ModelIo, AsciiWithWindowsLineEndings) {
  const std::string ply = "ply\r\nformat ascii 1.0\r\ncomment crlf\r\nelement vertex 2\r\nproperty float x\r\n"
                          "property float y\r\nproperty float z\r\nend_header\r\n1 2 3\r\n4 5 6\r\n";
  HybridModel m = readPlyModelFromMemory(ply, "crlf.ply");
  ASSERT_EQ(m.points.size(), 2u);
  EXPECT_EQ(m.points[1].position, Vec3f(4, 5, 6));
  EXPECT_EQ(m.comments, std::vector<std::string>{"crlf"});
}

TEST(ModelIo, FileHoldsMeshWithAHeaderLongerThan64KiB) {
  auto dir = test::scratchDir("io_longheader");
  TriangleMesh m = quadMesh();
  m.comments.assign(3000, std::string(40, 'c'));  // ~140 KB of comments
  writeMesh(dir / "long.ply", m);
  EXPECT_TRUE(fileHoldsMesh(dir / "long.ply"));
  EXPECT_EQ(readMesh(dir / "long.ply").comments.size(), 3000u);
}
