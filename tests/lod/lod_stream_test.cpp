// The streamed hierarchy build (lod::buildLodStreaming): the same bytes as the in-memory build
// for any subtree size, thread count and frame, refusals of models it cannot build, and no working
// or partial file left behind.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <numbers>

#include "../test_util.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/io/model_frame.h"
#include "linesurf/io/model_io.h"
#include "linesurf/io/model_stream.h"
#include "linesurf/lod/lod.h"
#include "linesurf/pipeline/render_job.h"

namespace linesurf {
namespace {

// Points on a sphere's upper half with masses and shading normals, segments with endpoint normals
// on the lower half: every record field the streamed build copies.
HybridModel sphereModel(int n, float scale, const Vec3f& offset) {
  HybridModel m;
  const float h = std::sqrt(4 * std::numbers::pi_v<float> / float(n));
  const float golden = std::numbers::pi_v<float> * (3 - std::sqrt(5.0f));
  std::vector<float> mass;
  for (int i = 0; i < n; ++i) {
    const float y = 1 - 2 * (float(i) + 0.5f) / float(n);
    if (y < 0) continue;
    const float r = std::sqrt(1 - y * y), t = golden * float(i);
    Point p;
    p.position = scale * Vec3f(r * std::cos(t), y, r * std::sin(t)) + offset;
    p.normal = Vec3f(r * std::cos(t), y, r * std::sin(t));
    p.radius = scale * h * (1 + 0.3f * float(i % 3));
    p.color = Color(0.9f, 0.5f + 0.4f * y, 0.3f, 1);
    m.points.push_back(p);
    m.pointShadingNormals.push_back((p.normal + Vec3f(0.1f, 0, 0)).normalized());
    mass.push_back(0.5f + 0.25f * float(i % 4));
  }
  m.pointProperties[kPointMassProperty] = mass;
  for (float lat = -h / 2; lat > -std::numbers::pi_v<float> / 2 + h; lat -= h) {
    const float y = std::sin(lat), r = std::cos(lat);
    const int pieces = std::max(3, int(2 * std::numbers::pi_v<float> * r / (3 * h)));
    for (int k = 0; k < pieces; ++k) {
      const float a0 = 2 * std::numbers::pi_v<float> * float(k) / float(pieces);
      const float a1 = 2 * std::numbers::pi_v<float> * float(k + 1) / float(pieces);
      Segment s;
      const Vec3f q0(r * std::cos(a0), y, r * std::sin(a0)), q1(r * std::cos(a1), y, r * std::sin(a1));
      s.p0 = scale * q0 + offset, s.p1 = scale * q1 + offset;
      const Vec3f mid = 0.5f * (q0 + q1), d = (q1 - q0).normalized();
      s.normal = (mid - mid.dot(d) * d).normalized();
      s.normal0 = q0.normalized(), s.normal1 = q1.normalized();
      s.radius = scale * h;
      s.color = Color(0.3f, 0.6f, 0.9f, 1);
      m.segments.push_back(s);
    }
  }
  m.attributes.normals = m.attributes.radii = m.attributes.colors = true;
  m.attributes.endpointNormals = m.attributes.shadingNormals = true;
  return m;
}

std::string slurp(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// The in-memory build as `linesurf lod build` runs it on the file.
std::string inMemory(const std::filesystem::path& file, const lod::BuildOptions& o) {
  HybridModel m = readModel(file);
  const ModelFrame frame = normalizingFrame(m.bounds());
  toFrame(m, frame);
  prepareForRendering(m, PrepareOptions{});
  return lod::buildLod(m, frame, o);
}

std::string streamed(const std::filesystem::path& file, const std::filesystem::path& out, const lod::BuildOptions& o,
                     double memoryBytes, lod::BuildReport* rep = nullptr) {
  lod::StreamBuildOptions so;
  so.memoryBytes = memoryBytes;
  const lod::BuildReport r = lod::buildLodStreaming(file, out, o, so);
  if (rep) *rep = r;
  return slurp(out);
}

size_t entries(const std::filesystem::path& dir) {
  size_t n = 0;
  for (auto it = std::filesystem::directory_iterator(dir); it != std::filesystem::directory_iterator(); ++it) ++n;
  return n;
}

TEST(LodStream, SameBytesAsInMemoryForAnySubtreeSizeAndThreads) {
  const auto dir = test::scratchDir("lod_stream_same");
  writeModel(dir / "m.ply", sphereModel(30000, 1, Vec3f::Zero()));
  lod::BuildOptions o;
  o.leafSize = 128;
  o.grid = 16;
  const std::string want = inMemory(dir / "m.ply", o);
  // Budgets from one subtree (the whole model) down to subtrees of a few hundred primitives.
  for (double mb : {1000.0, 2.0, 0.3}) {
    for (int threads : {1, 2}) {
      ThreadLimit t(threads);
      lod::BuildReport rep;
      const std::string got = streamed(dir / "m.ply", dir / "s.lod", o, mb * 1024 * 1024, &rep);
      EXPECT_TRUE(got == want) << mb << " MiB, " << threads << " threads: " << got.size() << " vs " << want.size()
                               << " bytes";
      if (mb < 1) {
        EXPECT_GE(rep.chunks, 8u);
      }
      if (mb > 100) {
        EXPECT_EQ(rep.chunks, 1u);
      }
    }
  }
  EXPECT_EQ(entries(dir), 2u) << "a working file was left";  // m.ply, s.lod
}

// Far from the origin at a large scale the model is moved into its frame first, as render does.
TEST(LodStream, SameBytesInANormalisingFrame) {
  const auto dir = test::scratchDir("lod_stream_frame");
  writeModel(dir / "far.ply", sphereModel(8000, 1e4f, Vec3f(3e8f, 1e6f, 0)));
  {
    HybridModel m = readModel(dir / "far.ply");
    ASSERT_FALSE(normalizingFrame(m.bounds()).identity());
  }
  lod::BuildOptions o;
  o.leafSize = 64;
  EXPECT_TRUE(streamed(dir / "far.ply", dir / "s.lod", o, 0.2 * 1024 * 1024) == inMemory(dir / "far.ply", o));
}

// The chunked reader gives readModel's model, chunk by chunk.
TEST(LodStream, ChunkReaderConcatenatesToReadModel) {
  const auto dir = test::scratchDir("lod_stream_reader");
  const HybridModel m = sphereModel(3000, 1, Vec3f::Zero());
  writeModel(dir / "m.ply", m);
  const HybridModel whole = readModel(dir / "m.ply");
  ModelChunkReader r(dir / "m.ply");
  EXPECT_EQ(r.points(), whole.points.size());
  EXPECT_EQ(r.segments(), whole.segments.size());
  HybridModel c;
  size_t p = 0, s = 0, chunks = 0;
  while (r.next(c, 97)) {
    ++chunks;
    EXPECT_LE(c.points.size() + c.segments.size(), 97u);
    for (const Point& q : c.points) {
      ASSERT_LT(p, whole.points.size());
      EXPECT_EQ(q.position, whole.points[p].position);
      EXPECT_EQ(q.radius, whole.points[p].radius);
      ++p;
    }
    for (const Segment& q : c.segments) {
      ASSERT_LT(s, whole.segments.size());
      EXPECT_EQ(q.p1, whole.segments[s].p1);
      EXPECT_EQ(q.normal1, whole.segments[s].normal1);
      ++s;
    }
  }
  EXPECT_EQ(p, whole.points.size());
  EXPECT_EQ(s, whole.segments.size());
  EXPECT_GT(chunks, 10u);
}

void expectRefused(const std::filesystem::path& in, const std::string& what) {
  const auto dir = in.parent_path();
  const size_t before = entries(dir);
  try {
    lod::StreamBuildOptions so;
    so.memoryBytes = 1 << 20;
    lod::buildLodStreaming(in, dir / "out.lod", lod::BuildOptions{}, so);
    ADD_FAILURE() << in << ": accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadInput) << e.what();
    EXPECT_NE(std::string(e.what()).find(in.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
  EXPECT_EQ(entries(dir), before) << "a working or partial file was left";
}

TEST(LodStream, RefusesWhatItCannotBuildAndLeavesNothing) {
  const auto dir = test::scratchDir("lod_stream_bad");
  HybridModel m = sphereModel(3000, 1, Vec3f::Zero());
  writeModel(dir / "good.ply", m);
  {  // a truncated body
    std::string b = slurp(dir / "good.ply");
    b.resize(b.size() - 1000);
    std::ofstream(dir / "cut.ply", std::ios::binary).write(b.data(), std::streamsize(b.size()));
    expectRefused(dir / "cut.ply", "truncated");
  }
  {  // points without radii: the in-memory build estimates them, the streamed one cannot
    HybridModel bare;
    for (const Point& p : m.points) bare.points.push_back({p.position, p.normal, p.color, 0});
    bare.attributes.normals = true;
    writeModel(dir / "bare.ply", bare);
    expectRefused(dir / "bare.ply", "radius");
  }
  {  // ASCII
    WriteOptions w;
    w.encoding = PlyEncoding::Ascii;
    writeModel(dir / "ascii.ply", m, w);
    expectRefused(dir / "ascii.ply", "binary");
    HybridModel pts = m;
    pts.segments.clear();
    writeModel(dir / "points.xyz", pts);
    expectRefused(dir / "points.xyz", "binary");
  }
}

// A z-up model (LAS, or a PLY made from one) records its axis in the hierarchy, in memory and
// streamed alike, so that render and view orbit a .lod about the axis its model had; a model
// without one gives a header without the field.
TEST(LodStream, TheRecordedUpAxisTravelsIntoTheHeader) {
  const auto dir = test::scratchDir("lod_stream_up");
  HybridModel m = sphereModel(5000, 1, Vec3f::Zero());
  writeModel(dir / "plain.ply", m);
  m.comments.push_back("linesurf_up_axis z");
  writeModel(dir / "zup.ply", m);
  lod::BuildOptions o;
  o.leafSize = 256;
  const std::string mem = inMemory(dir / "zup.ply", o);
  const std::string str = streamed(dir / "zup.ply", dir / "zup.lod", o, 1e6);
  EXPECT_TRUE(mem == str);
  EXPECT_EQ(lod::LodFile(dir / "zup.lod").header().upAxis, "z");
  streamed(dir / "plain.ply", dir / "plain.lod", o, 1e6);
  EXPECT_EQ(lod::LodFile(dir / "plain.lod").header().upAxis, "");
  EXPECT_EQ(slurp(dir / "plain.lod").find("upAxis"), std::string::npos);
}

}  // namespace
}  // namespace linesurf
