// The level-of-detail hierarchy (include/linesurf/lod/lod.h): every original in exactly one leaf,
// merged splats that cover their children, budgets respected, a full budget giving today's
// picture, half of it close to it, failed and foreign nodes reported, any thread count alike.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <set>

#include "../test_util.h"
#include "linesurf/core/error.h"
#include "linesurf/core/parallel.h"
#include "linesurf/eval/image_metrics.h"
#include "linesurf/io/image_io.h"
#include "linesurf/io/model_io.h"
#include "linesurf/lod/lod.h"
#include "linesurf/render/renderer.h"

namespace linesurf {
namespace {

// A unit sphere: points (Fibonacci lattice) on its upper half, rings of segments along the
// latitudes of its lower half, the hybrid models the extractors make.
HybridModel sphereHybrid(int n = 12000) {
  HybridModel m;
  const float h = std::sqrt(4 * std::numbers::pi_v<float> / float(n));  // sample spacing
  const float golden = std::numbers::pi_v<float> * (3 - std::sqrt(5.0f));
  for (int i = 0; i < n; ++i) {
    const float y = 1 - 2 * (float(i) + 0.5f) / float(n);
    if (y < 0) continue;
    const float r = std::sqrt(1 - y * y), t = golden * float(i);
    Point p;
    p.position = Vec3f(r * std::cos(t), y, r * std::sin(t));
    p.normal = p.position.normalized();
    p.radius = h;
    p.color = Color(0.9f, 0.5f + 0.4f * y, 0.3f, 1);
    m.points.push_back(p);
  }
  for (float lat = -h / 2; lat > -std::numbers::pi_v<float> / 2 + h; lat -= h) {
    const float y = std::sin(lat), r = std::cos(lat);
    const int pieces = std::max(3, int(2 * std::numbers::pi_v<float> * r / (4 * h)));
    for (int k = 0; k < pieces; ++k) {
      const float a0 = 2 * std::numbers::pi_v<float> * float(k) / float(pieces);
      const float a1 = 2 * std::numbers::pi_v<float> * float(k + 1) / float(pieces);
      Segment s;
      s.p0 = Vec3f(r * std::cos(a0), y, r * std::sin(a0));
      s.p1 = Vec3f(r * std::cos(a1), y, r * std::sin(a1));
      const Vec3f mid = 0.5f * (s.p0 + s.p1), d = (s.p1 - s.p0).normalized();
      s.normal = (mid - mid.dot(d) * d).normalized();
      s.radius = h;
      s.color = Color(0.3f, 0.6f, 0.9f, 1);
      m.segments.push_back(s);
    }
  }
  m.attributes.normals = m.attributes.radii = m.attributes.colors = true;
  return m;
}

std::filesystem::path writeLod(const HybridModel& m, const std::string& name, lod::BuildOptions o = {},
                               std::string* bytesOut = nullptr) {
  const std::string bytes = lod::buildLod(m, ModelFrame{}, o);
  const auto path = test::scratchDir("lod_" + name) / (name + ".lod");
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  if (bytesOut) *bytesOut = bytes;
  return path;
}

lod::BuildOptions small() {
  lod::BuildOptions o;
  o.leafSize = 256;
  o.grid = 16;
  return o;
}

Camera viewOf(const BoundingSphere& s, int size = 256) { return Camera::orbit(s, 30, 20, 0, size, size); }

TEST(Lod, EveryOriginalInExactlyOneLeafUnchanged) {
  const HybridModel m = sphereHybrid();
  lod::LodFile f(writeLod(m, "once", small()));
  ASSERT_GT(f.nodes().size(), 8u);
  std::vector<int> seenP(m.points.size()), seenS(m.segments.size());
  for (uint32_t i = 0; i < f.nodes().size(); ++i) {
    if (!f.nodes()[i].leaf) continue;
    const lod::NodeData d = f.readNode(i);
    for (size_t k = 0; k < d.points.size(); ++k) {
      ASSERT_LT(d.pointIndex[k], m.points.size());
      ++seenP[d.pointIndex[k]];
      EXPECT_EQ(d.points[k].position, m.points[d.pointIndex[k]].position);
      EXPECT_EQ(d.points[k].radius, m.points[d.pointIndex[k]].radius);
    }
    for (size_t k = 0; k < d.segments.size(); ++k) {
      ASSERT_LT(d.segmentIndex[k], m.segments.size());
      ++seenS[d.segmentIndex[k]];
      EXPECT_EQ(d.segments[k].p0, m.segments[d.segmentIndex[k]].p0);
      EXPECT_EQ(d.segments[k].p1, m.segments[d.segmentIndex[k]].p1);
    }
  }
  for (int c : seenP) ASSERT_EQ(c, 1);
  for (int c : seenS) ASSERT_EQ(c, 1);
}

TEST(Lod, MergedSplatsCoverTheirChildren) {
  const HybridModel m = sphereHybrid(4000);
  lod::BuildOptions o = small();
  o.leafSize = 64;
  lod::LodFile f(writeLod(m, "cover", o));
  int checked = 0;
  for (uint32_t i = 0; i < f.nodes().size(); ++i) {
    const lod::NodeInfo& n = f.nodes()[i];
    if (n.leaf) continue;
    const lod::NodeData parent = f.readNode(i);
    EXPECT_LE(parent.points.size() + parent.segments.size(), [&] {
      uint64_t c = 0;
      for (uint32_t k = n.firstChild; k < n.firstChild + n.childCount; ++k) c += f.nodes()[k].count();
      return c;
    }()) << "node " << i << " holds more than its children";
    const float h = n.side / float(o.grid);
    for (uint32_t k = n.firstChild; k < n.firstChild + n.childCount; ++k) {
      const lod::NodeData child = f.readNode(k);
      for (const Point& p : child.points) {
        bool covered = false;
        for (const Point& q : parent.points)
          covered |= (p.position - q.position).norm() + p.radius <= q.radius * (1 + 1e-5f) + 1e-6f;
        ASSERT_TRUE(covered) << "a point of node " << k << " is outside every splat of its parent " << i;
        ++checked;
      }
      for (const Segment& s : child.segments) {
        if (s.length() >= h) continue;  // kept whole in the parent
        bool covered = false;
        for (const Point& q : parent.points)
          covered |= (0.5f * (s.p0 + s.p1) - q.position).norm() + 0.5f * s.length() + s.radius <= q.radius * (1 + 1e-5f) + 1e-6f;
        ASSERT_TRUE(covered) << "a short segment of node " << k << " is outside every splat of its parent " << i;
      }
    }
  }
  EXPECT_GT(checked, 1000);
}

TEST(Lod, FullBudgetIsTodaysRender) {
  const HybridModel m = sphereHybrid();
  lod::LodFile f(writeLod(m, "full", small()));
  const RenderOptions o;
  Renderer today(m, o);
  lod::LodRenderer lr(f, o, m.points.size() + m.segments.size());
  EXPECT_EQ(lr.sphere().center, today.sphere().center);
  EXPECT_EQ(lr.sphere().radius, today.sphere().radius);
  const Camera cam = viewOf(lr.sphere());
  const lod::LodFrameResult r = lr.render(cam);
  EXPECT_TRUE(r.failures.empty());
  EXPECT_EQ(r.selection.primitives, m.points.size() + m.segments.size());
  EXPECT_EQ(test::maxAbsDiff(r.render.color, today.render(cam).color), 0.0f);
}

TEST(Lod, HalfBudgetIsCloseAndSmaller) {
  const HybridModel m = sphereHybrid(40000);
  lod::LodFile f(writeLod(m, "half", small()));
  const RenderOptions o;
  const uint64_t total = m.points.size() + m.segments.size();
  const Camera cam = viewOf(f.header().sphere);
  const Image full = Renderer(m, o).render(cam).color;
  const lod::LodFrameResult half = lod::LodRenderer(f, o, total / 2).render(cam);
  EXPECT_LE(half.selection.primitives, total / 2);
  EXPECT_GT(half.selection.primitives, total / 4);  // the budget is used, not left idle
  const double ssim = compareImages(full, half.render.color).ssim;
  EXPECT_GE(ssim, 0.97);
  // A tiny budget still draws the surface, coarser: worse than half, better than nothing.
  const lod::LodFrameResult tiny = lod::LodRenderer(f, o, total / 50).render(cam);
  const double tinySsim = compareImages(full, tiny.render.color).ssim;
  EXPECT_LT(tinySsim, ssim);
  EXPECT_GT(tinySsim, compareImages(full, Image(full.width, full.height, o.background)).ssim);
}

TEST(Lod, SelectionRespectsTheBudgetAndIsACut) {
  const HybridModel m = sphereHybrid(20000);
  lod::LodFile f(writeLod(m, "cut", small()));
  const auto& nodes = f.nodes();
  std::vector<uint32_t> parent(nodes.size(), lod::kNoIndex);
  for (uint32_t i = 0; i < nodes.size(); ++i)
    for (uint32_t c = nodes[i].firstChild; c < nodes[i].firstChild + nodes[i].childCount; ++c) parent[c] = i;
  const Camera cam = viewOf(f.header().sphere);
  const uint64_t total = m.points.size() + m.segments.size();
  for (uint64_t budget : {nodes[0].count(), total / 10, total / 3, total / 2, total - 1, total}) {
    const lod::Selection s = lod::selectNodes(f, cam, budget);
    uint64_t sum = 0;
    std::set<uint32_t> chosen(s.nodes.begin(), s.nodes.end());
    for (uint32_t i : s.nodes) sum += nodes[i].count();
    EXPECT_EQ(sum, s.primitives);
    EXPECT_LE(s.primitives, budget) << "budget " << budget;
    // The whole sphere is in view: every leaf stands for itself or through one chosen ancestor.
    for (uint32_t i = 0; i < nodes.size(); ++i) {
      if (!nodes[i].leaf) continue;
      int hits = 0;
      for (uint32_t a = i; a != lod::kNoIndex; a = parent[a]) hits += int(chosen.count(a));
      ASSERT_EQ(hits, 1) << "leaf " << i << " at budget " << budget;
    }
  }
  // Nearer parts get finer nodes: from the front, the chosen nodes facing the camera are deeper.
  const lod::Selection s = lod::selectNodes(f, cam, total / 2);
  double nearLevel = 0, farLevel = 0;
  int nearCount = 0, farCount = 0;
  for (uint32_t i : s.nodes) {
    const Vec3f c = 0.5f * (nodes[i].boundsMin + nodes[i].boundsMax);
    const bool near = (c - cam.eye()).norm() < (f.header().sphere.center - cam.eye()).norm();
    (near ? nearLevel : farLevel) += nodes[i].level;
    ++(near ? nearCount : farCount);
  }
  ASSERT_GT(nearCount, 0);
  ASSERT_GT(farCount, 0);
  EXPECT_GT(nearLevel / nearCount, farLevel / farCount);
}

TEST(Lod, TruncatedNodeIsReportedAndTheRestDrawn) {
  const HybridModel m = sphereHybrid();
  std::string bytes;
  const auto path = writeLod(m, "trunc", small(), &bytes);
  uint32_t lastLeaf = 0;  // the leaf whose block lies last (inner nodes' blocks follow the leaves')
  uint64_t firstBlock = UINT64_MAX;
  {
    lod::LodFile f(path);
    for (uint32_t i = 0; i < f.nodes().size(); ++i) {
      firstBlock = std::min(firstBlock, f.nodes()[i].offset);
      if (f.nodes()[i].leaf && (!f.nodes()[lastLeaf].leaf || f.nodes()[i].offset > f.nodes()[lastLeaf].offset)) lastLeaf = i;
    }
    std::filesystem::resize_file(path, f.nodes()[lastLeaf].offset + f.nodes()[lastLeaf].size / 2);
  }
  lod::LodFile f(path);
  const uint64_t total = m.points.size() + m.segments.size();
  const lod::Assembled a = lod::assemble(f, lod::selectNodes(f, viewOf(f.header().sphere), total));
  ASSERT_EQ(a.failures.size(), 1u);
  EXPECT_NE(a.failures[0].find("node " + std::to_string(lastLeaf) + ":"), std::string::npos) << a.failures[0];
  EXPECT_NE(a.failures[0].find("truncated"), std::string::npos) << a.failures[0];
  EXPECT_EQ(a.model.points.size() + a.model.segments.size(), total - f.nodes()[lastLeaf].count());
  // The file cut inside its node table is refused as a whole.
  std::filesystem::resize_file(path, firstBlock - 10);
  EXPECT_THROW(lod::LodFile{path}, Error);
}

TEST(Lod, NodeOfAnotherHierarchyIsRefused) {
  const HybridModel m = sphereHybrid(), other = sphereHybrid(9000);
  std::string bytes, otherBytes;
  const auto path = writeLod(m, "foreign", small(), &bytes);
  writeLod(other, "foreign_other", small(), &otherBytes);
  lod::LodFile f(path);
  lod::LodFile g(test::scratchRoot() / "lod_foreign_other" / "foreign_other.lod");
  ASSERT_NE(f.header().hierarchyId, g.header().hierarchyId);
  // Node 1's block, stamped with the other hierarchy's id (as if copied from its file).
  const uint64_t otherId = g.header().hierarchyId;
  std::memcpy(bytes.data() + f.nodes()[1].offset + 8, &otherId, 8);
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  lod::LodFile h(path);
  try {
    h.readNode(1);
    FAIL() << "a foreign node was read";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("another hierarchy"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("node 1"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(h.readNode(2));
  // A flipped byte inside a block fails its checksum.
  bytes[f.nodes()[2].offset + 40] ^= 0x10;
  std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
  lod::LodFile k(path);
  EXPECT_THROW(k.readNode(2), Error);
}

TEST(Lod, SameBytesForAnyThreadCount) {
  const HybridModel m = sphereHybrid();
  std::string one, two;
  {
    ThreadLimit t(1);
    one = lod::buildLod(m, ModelFrame{}, small());
  }
  {
    ThreadLimit t(2);
    two = lod::buildLod(m, ModelFrame{}, small());
  }
  EXPECT_EQ(one, two);
}

TEST(Lod, CliRendersAHierarchyWithABudget) {
  const auto dir = test::scratchDir("lod_cli");
  const HybridModel m = sphereHybrid(6000);
  writeModel(dir / "s.ply", m);
  const std::string q = "'" + dir.string() + "/";
  auto r = test::runCli("-q lod build " + q + "s.ply' -o " + q + "s.lod' --leaf-size 256");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  r = test::runCli("-q render " + q + "s.ply' -o " + q + "a.png' --size 96x96");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  r = test::runCli("-q render " + q + "s.lod' -o " + q + "b.png' --size 96x96");
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_EQ(test::maxAbsDiff(readImage(dir / "a.png"), readImage(dir / "b.png")), 0.0f);
  r = test::runCli("-q render " + q + "s.lod' -o " + q + "c.png' --size 96x96 --budget 1000");
  EXPECT_EQ(r.exitCode, 0) << r.out;
  r = test::runCli("-q render " + q + "s.ply' -o " + q + "d.png' --budget 1000");
  EXPECT_EQ(r.exitCode, 1) << r.out;  // a budget needs a hierarchy
  EXPECT_FALSE(std::filesystem::exists(dir / "d.png"));
  // A budget is a decimal count: no sign, no hex, no empty text, nothing past 1e15.
  for (const char* bad : {"-1", "18446744073709551616", "''", "0x10", "1e3", "2000000000000000"}) {
    r = test::runCli("-q render " + q + "s.lod' -o " + q + "e.png' --size 64x64 --budget " + bad);
    EXPECT_EQ(r.exitCode, 1) << bad << ": " << r.out;
    EXPECT_NE(r.out.find("budget"), std::string::npos) << bad << ": " << r.out;
    EXPECT_FALSE(std::filesystem::exists(dir / "e.png")) << bad;
  }
  // info describes what render reads: the hierarchy's counts and table.
  r = test::runCli("info " + q + "s.lod'");
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("level-of-detail hierarchy"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("points:     " + std::to_string(m.points.size())), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("segments:   " + std::to_string(m.segments.size())), std::string::npos) << r.out;
  // A working folder that does not exist is refused before the build, not after it.
  r = test::runCli("-q lod build " + q + "s.ply' -o " + q + "w.lod' --work-dir " + q + "missing'");
  EXPECT_EQ(r.exitCode, 1) << r.out;
  EXPECT_NE(r.out.find("--work-dir"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "w.lod"));
}

// A hierarchy larger than --max-mb renders with a budget that fits (only the view's nodes are
// read); without a budget every leaf would be held, which the budget refuses up front.
TEST(Lod, CliBudgetBoundsWhatAViewHolds) {
  const auto dir = test::scratchDir("lod_cli_maxmb");
  writeModel(dir / "s.ply", sphereHybrid(60000));  // ~45 k primitives: 4.5 MB of splats
  const std::string q = "'" + dir.string() + "/";
  ASSERT_EQ(test::runCli("-q lod build " + q + "s.ply' -o " + q + "s.lod' --leaf-size 256").exitCode, 0);
  const double mb = double(std::filesystem::file_size(dir / "s.lod")) / (1024.0 * 1024.0);
  ASSERT_GT(mb, 2.0);  // and every leaf, 100 bytes a splat, over 1 MiB
  const std::string maxMb = fmt::format(" --max-mb {:.2f}", 0.9 * mb);  // under the file, over 2000 splats
  auto r = test::runCli("-q render " + q + "s.lod' -o " + q + "a.png' --size 64x64 --budget 2000" + maxMb);
  EXPECT_EQ(r.exitCode, 0) << r.out;
  r = test::runCli("-q render " + q + "s.lod' -o " + q + "b.png' --size 64x64 --max-mb 1");
  EXPECT_EQ(r.exitCode, 1) << r.out;
  EXPECT_NE(r.out.find("set --budget"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir / "b.png"));
}

// A model far from unit size is drawn in its normalising frame: the hierarchy keeps that frame.
TEST(Lod, CliFarFromUnitSizeIsTodaysRender) {
  const auto dir = test::scratchDir("lod_cli_far");
  HybridModel m = sphereHybrid(6000);
  for (Point& p : m.points) p.position = 1e7f * p.position + Vec3f(3e8f, 0, 0), p.radius *= 1e7f;
  for (Segment& s : m.segments)
    s.p0 = 1e7f * s.p0 + Vec3f(3e8f, 0, 0), s.p1 = 1e7f * s.p1 + Vec3f(3e8f, 0, 0), s.radius *= 1e7f;
  writeModel(dir / "far.ply", m);
  const std::string q = "'" + dir.string() + "/";
  ASSERT_EQ(test::runCli("-q lod build " + q + "far.ply' -o " + q + "far.lod'").exitCode, 0);
  ASSERT_EQ(test::runCli("-q render " + q + "far.ply' -o " + q + "a.png' --size 96x96 --azimuth 70").exitCode, 0);
  ASSERT_EQ(test::runCli("-q render " + q + "far.lod' -o " + q + "b.png' --size 96x96 --azimuth 70").exitCode, 0);
  EXPECT_EQ(test::maxAbsDiff(readImage(dir / "a.png"), readImage(dir / "b.png")), 0.0f);
}

// The bundled igea scan made a hybrid as users make one (normals, then eps-delta): every leaf gives
// today's picture, half the budget SSIM >= 0.97.
TEST(Lod, CliIgeaHybridFullAndHalfBudget) {
  const auto dir = test::scratchDir("lod_cli_igea");
  const std::string q = "'" + dir.string() + "/";
  const std::string in = "'" + (test::bundledData() / "igea_points.ply").string() + "'";
  ASSERT_EQ(test::runCli("-q normals " + in + " -o " + q + "n.ply'").exitCode, 0);
  ASSERT_EQ(test::runCli("-q extract eps-delta " + q + "n.ply' -o " + q + "h.ply'").exitCode, 0);
  ASSERT_EQ(test::runCli("-q lod build " + q + "h.ply' -o " + q + "h.lod'").exitCode, 0);
  const HybridModel h = readModel(dir / "h.ply");
  const size_t total = h.points.size() + h.segments.size();
  ASSERT_EQ(test::runCli("-q render " + q + "h.ply' -o " + q + "a.png'").exitCode, 0);
  ASSERT_EQ(test::runCli("-q render " + q + "h.lod' -o " + q + "b.png' --budget " + std::to_string(total)).exitCode, 0);
  ASSERT_EQ(test::runCli("-q render " + q + "h.lod' -o " + q + "c.png' --budget " + std::to_string(total / 2)).exitCode, 0);
  const Image a = readImage(dir / "a.png");
  EXPECT_EQ(test::maxAbsDiff(a, readImage(dir / "b.png")), 0.0f);
  EXPECT_GE(compareImages(a, readImage(dir / "c.png")).ssim, 0.97);
}

}  // namespace
}  // namespace linesurf
