// Colour and further point properties (intensity, class, any scalar) through the out-of-core
// path: the streamed records carry them, `normals` writes the in-memory bytes, the extractions
// give kept points and segments the in-memory attributes, and the synthetic scan's colour.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>

#include "extract/detail/segment_attributes.h"
#include "extract/detail/segment_width.h"
#include "linesurf/core/error.h"
#include "linesurf/extract/eps_delta.h"
#include "linesurf/geometry/point_geometry.h"
#include "linesurf/io/model_io.h"
#include "linesurf/ooc/ooc_extract.h"
#include "linesurf/ooc/ooc_normals.h"
#include "linesurf/ooc/point_stream.h"
#include "linesurf/ooc/synthetic_scan.h"
#include "test_util.h"

namespace linesurf {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>());
}

/// The coloured synthetic scan of `count` points.
ooc::SyntheticScanOptions colouredScan(uint64_t count, uint64_t seed) {
  ooc::SyntheticScanOptions s;
  s.count = count;
  s.seed = seed;
  s.color = true;
  return s;
}

/// A coloured synthetic scan with an intensity (a smooth field) and a class (0..4 by height),
/// written by writeModel (uchar colour, float properties).
HybridModel writeAttributedScan(const fs::path& path, uint64_t count, uint64_t seed) {
  ooc::writeSyntheticScan(path, colouredScan(count, seed));
  HybridModel m = readModel(path);
  std::vector<float>& intensity = m.pointProperties["intensity"];
  std::vector<float>& cls = m.pointProperties["classification"];
  for (const Point& p : m.points) {
    intensity.push_back(std::round(1000 * (1 + p.position.x())));
    cls.push_back(std::floor(2.5f * (p.position.z() + 1)));
  }
  writeModel(path, m);
  return m;
}

/// What `linesurf normals IN -o OUT` writes in memory.
void inMemoryNormals(const fs::path& in, const fs::path& out, bool curvature) {
  HybridModel m = readModel(in);
  GeometryOptions o;
  o.delaunayNeighbours = o.curvature = curvature;
  const PointGeometry g = computePointGeometry(m, o);
  applyGeometry(m, g);
  if (curvature) addCurvatureProperties(m, g);
  writeModel(out, m);
}

ooc::OocNormalsOptions tiled(const fs::path& dir, int tiles, bool curvature = false) {
  ooc::OocNormalsOptions o;
  o.geometry.delaunayNeighbours = o.geometry.curvature = curvature;
  o.workDir = dir;
  o.minTiles = tiles;
  return o;
}

// A coloured cloud with intensity and class in 16+ tiles: the in-memory file byte for byte, with
// and without curvature (whose properties sort among the input's: classification, dmin_*,
// intensity, k_max, k_min).
TEST(OocAttributes, NormalsInTilesWriteTheInMemoryBytes) {
  const fs::path d = test::scratchDir("ooc_attr_normals");
  const HybridModel in = writeAttributedScan(d / "scan.ply", 80000, 7);
  ASSERT_TRUE(in.attributes.colors);
  for (bool curvature : {false, true}) {
    inMemoryNormals(d / "scan.ply", d / "mem.ply", curvature);
    const ooc::OocNormalsReport r = ooc::computeNormalsOutOfCore(d / "scan.ply", d / "ooc.ply", tiled(d / "tiles", 16, curvature));
    EXPECT_GE(r.tiles, 16u);
    EXPECT_TRUE(slurp(d / "ooc.ply") == slurp(d / "mem.ply")) << "curvature " << curvature;
  }
  const HybridModel out = readModel(d / "ooc.ply");
  ASSERT_TRUE(out.attributes.colors);
  ASSERT_EQ(out.points.size(), in.points.size());
  for (size_t i = 0; i < in.points.size(); i += 97) {
    EXPECT_EQ(out.points[i].color, in.points[i].color) << i;
    EXPECT_EQ(out.pointProperties.at("intensity")[i], in.pointProperties.at("intensity")[i]);
    EXPECT_EQ(out.pointProperties.at("classification")[i], in.pointProperties.at("classification")[i]);
  }
}

/// Writes `m`'s points as binary PLY with 16-bit colour (ushort red green blue, no alpha) and a
/// ushort intensity: what a LiDAR converter writes, which writeModel does not.
void writeSixteenBit(const fs::path& path, const HybridModel& m) {
  std::string b = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(m.points.size()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nproperty ushort intensity\n"
                  "property ushort red\nproperty ushort green\nproperty ushort blue\nend_header\n";
  for (size_t i = 0; i < m.points.size(); ++i) {
    b.append(reinterpret_cast<const char*>(m.points[i].position.data()), 12);
    uint16_t v[4] = {uint16_t(i % 65536), 0, 0, 0};
    for (int c = 0; c < 3; ++c) v[c + 1] = uint16_t(std::lround(m.points[i].color[c] * 65535.0f) ^ (i & 0xff));
    b.append(reinterpret_cast<const char*>(v), 8);
  }
  std::ofstream(path, std::ios::binary) << b;
}

// 16-bit colour is kept as the in-memory reader keeps it (channel / 65535, written as uchar), an
// integer property as its float: the same bytes in tiles; and the reader's chunks are readModel's.
TEST(OocAttributes, SixteenBitColourAndIntegerPropertiesAsInMemory) {
  const fs::path d = test::scratchDir("ooc_attr_16bit");
  ooc::writeSyntheticScan(d / "c8.ply", colouredScan(40000, 9));
  writeSixteenBit(d / "scan.ply", readModel(d / "c8.ply"));
  const HybridModel whole = readModel(d / "scan.ply");
  ooc::PointReader reader(d / "scan.ply");
  ASSERT_TRUE(reader.info().colors);
  ASSERT_EQ(reader.info().properties, std::vector<std::string>{"intensity"});
  std::vector<Vec3f> pos, nrm;
  std::vector<float> att;
  size_t i = 0;
  while (reader.read(pos, nrm, 7777, nullptr, &att) > 0) {
    ASSERT_EQ(att.size(), pos.size() * 5);
    for (size_t k = 0; k < pos.size(); ++k, ++i) {
      for (int c = 0; c < 4; ++c) ASSERT_EQ(att[k * 5 + size_t(c)], whole.points[i].color[c]) << i;
      ASSERT_EQ(att[k * 5 + 4], whole.pointProperties.at("intensity")[i]);
    }
  }
  EXPECT_EQ(i, whole.points.size());
  inMemoryNormals(d / "scan.ply", d / "mem.ply", false);
  ooc::computeNormalsOutOfCore(d / "scan.ply", d / "ooc.ply", tiled(d / "tiles", 8));
  EXPECT_TRUE(slurp(d / "ooc.ply") == slurp(d / "mem.ply"));
}

// With one tile the extractions are the in-memory ones: the same bytes, colours and properties
// included (kept points keep theirs, a segment's colour is its points' mean).
TEST(OocAttributes, OneTileExtractionsWriteTheInMemoryBytes) {
  const fs::path d = test::scratchDir("ooc_attr_one_tile");
  writeAttributedScan(d / "scan.ply", 30000, 3);
  const std::string q = "'" + d.string() + "/";
  for (const std::string what : {"eps-delta", "shape-approx"}) {
    ASSERT_EQ(test::runCli("-q extract " + what + " " + q + "scan.ply' -o " + q + "mem.ply' --provenance").exitCode, 0);
    const auto r = test::runCli("extract " + what + " " + q + "scan.ply' -o " + q + "ooc.ply' --provenance --tiles 1");
    ASSERT_EQ(r.exitCode, 0) << r.out;
    EXPECT_NE(r.out.find("out of core"), std::string::npos) << r.out;
    EXPECT_TRUE(slurp(d / "ooc.ply") == slurp(d / "mem.ply")) << what;
    const HybridModel m = readModel(d / "ooc.ply");
    EXPECT_TRUE(m.attributes.colors) << what;
    EXPECT_GT(m.segments.size(), 0u) << what;
    EXPECT_EQ(m.pointProperties.at("intensity").size(), m.points.size()) << what;
  }
}

// In tiles: every kept point keeps its own colour and properties, every segment's colour is the
// mean of the colours of the points it replaced (to the byte it is written as), its intensity
// their mean and its class their mode.
TEST(OocAttributes, TiledEpsDeltaKeepsEachPointsAttributesAndMeanSegmentColour) {
  const fs::path d = test::scratchDir("ooc_attr_tiles");
  const HybridModel in = writeAttributedScan(d / "scan.ply", 60000, 5);
  EpsDeltaOptions e;
  e.provenance = true;
  ooc::OocNormalsOptions o = tiled(d / "tiles", 12);
  const ooc::OocEpsDeltaReport r = ooc::extractEpsDeltaOutOfCore(d / "scan.ply", d / "ooc.ply", o, e);
  EXPECT_GE(r.geometry.tiles, 12u);
  const HybridModel out = readModel(d / "ooc.ply");
  ASSERT_TRUE(out.attributes.colors);
  ASSERT_GT(out.segments.size(), 100u);
  std::map<std::array<float, 3>, size_t> at;
  for (size_t i = 0; i < in.points.size(); ++i) at[{in.points[i].position.x(), in.points[i].position.y(), in.points[i].position.z()}] = i;
  for (size_t k = 0; k < out.points.size(); ++k) {
    const Vec3f& p = out.points[k].position;
    const size_t i = at.at({p.x(), p.y(), p.z()});
    ASSERT_EQ(out.points[k].color, in.points[i].color) << k;
    ASSERT_EQ(out.pointProperties.at("intensity")[k], in.pointProperties.at("intensity")[i]);
    ASSERT_EQ(out.pointProperties.at("classification")[k], in.pointProperties.at("classification")[i]);
  }
  for (size_t s = 0; s < out.segments.size(); ++s) {
    Eigen::Vector4d mean = Eigen::Vector4d::Zero();
    for (uint32_t j : out.provenance[s]) mean += in.points[j].color.cast<double>();
    mean /= double(out.provenance[s].size());
    const Eigen::Vector4d got = out.segments[s].color.cast<double>();
    ASSERT_LE((got - mean).cwiseAbs().maxCoeff(), 0.5 / 255 + 1e-6) << s;
  }
  // The segments' intensity (mean) and class (mode) are the in-memory rule over their members.
  std::vector<uint32_t> owner(in.points.size(), detail::kKeptPoint);
  for (size_t s = 0; s < out.provenance.size(); ++s)
    for (uint32_t j : out.provenance[s]) owner[j] = uint32_t(s);
  HybridModel rule;
  rule.segments = out.segments;
  detail::setSegmentProperties(rule, in, owner);
  ASSERT_EQ(out.segmentProperties.size(), 2u);
  EXPECT_EQ(out.segmentProperties, rule.segmentProperties);
}

// The chain a coloured scan larger than memory takes, every stage out of core: normals, (ε,δ) and
// the hierarchy keep the colour, and each writes what the in-memory stage writes from the same input.
TEST(OocAttributes, ColouredChainOutOfCoreAsInMemory) {
  const fs::path d = test::scratchDir("ooc_attr_chain");
  ooc::writeSyntheticScan(d / "scan.ply", colouredScan(40000, 8));
  const std::string q = "'" + d.string() + "/";
  ASSERT_EQ(test::runCli("-q normals " + q + "scan.ply' -o " + q + "n_mem.ply'").exitCode, 0);
  ASSERT_EQ(test::runCli("-q normals " + q + "scan.ply' -o " + q + "n.ply' --tiles 6").exitCode, 0);
  EXPECT_TRUE(slurp(d / "n.ply") == slurp(d / "n_mem.ply"));
  ASSERT_EQ(test::runCli("-q extract eps-delta " + q + "n.ply' -o " + q + "e.ply' --tiles 6").exitCode, 0);
  ASSERT_EQ(test::runCli("-q lod build " + q + "e.ply' -o " + q + "mem.lod'").exitCode, 0);
  ASSERT_EQ(test::runCli("-q lod build " + q + "e.ply' -o " + q + "ooc.lod' --out-of-core").exitCode, 0);
  EXPECT_TRUE(slurp(d / "ooc.lod") == slurp(d / "mem.lod"));
  const HybridModel e = readModel(d / "e.ply");
  EXPECT_TRUE(e.attributes.colors);
  EXPECT_GT(e.segments.size(), 0u);
  const auto info = test::runCli("info " + q + "ooc.lod'");
  EXPECT_NE(info.out.find("colors"), std::string::npos) << info.out;
}

// The synthetic scan's colour: deterministic, the same for any chunking, smooth (neighbouring
// points within the dither and a little of the field), spread over the range, and the points are
// those of the colourless scan.
TEST(SyntheticScan, ColourIsDeterministicSmoothAndLeavesThePoints) {
  ooc::SyntheticScanOptions s = colouredScan(20000, 4);
  std::vector<uint8_t> all, part;
  ooc::syntheticScanColors(s, 0, s.count, all);
  ooc::syntheticScanColors(s, 12345, 100, part);
  ASSERT_EQ(part.size(), 300u);
  EXPECT_EQ(0, std::memcmp(part.data(), all.data() + 3 * 12345, 300));
  int lo = 255, hi = 0;
  for (uint8_t v : all) lo = std::min<int>(lo, v), hi = std::max<int>(hi, v);
  EXPECT_LE(lo, 10);
  EXPECT_GE(hi, 245);
  const fs::path d = test::scratchDir("synthetic_colour");
  ooc::writeSyntheticScan(d / "c.ply", s);
  s.color = false;
  ooc::writeSyntheticScan(d / "p.ply", s);
  const HybridModel c = readModel(d / "c.ply"), p = readModel(d / "p.ply");
  ASSERT_TRUE(c.attributes.colors);
  ASSERT_FALSE(p.attributes.colors);
  ASSERT_EQ(c.points.size(), p.points.size());
  double far = 0;
  size_t nearPairs = 0;
  for (size_t i = 0; i < c.points.size(); ++i) {
    ASSERT_EQ(c.points[i].position, p.points[i].position);
    for (int k = 0; k < 3; ++k) ASSERT_EQ(c.points[i].color[k], float(all[3 * i + size_t(k)]) / 255.0f);
    ASSERT_EQ(c.points[i].color[3], 1.0f);
  }
  // Smooth: points closer than 0.02 differ by at most the dither (16 levels) and 0.02 x 4 of the field.
  for (size_t i = 0; i + 1 < c.points.size(); ++i)
    for (size_t j = i + 1; j < std::min(c.points.size(), i + 400); ++j)
      if ((c.points[i].position - c.points[j].position).norm() < 0.02f) {
        ++nearPairs;
        far = std::max(far, double((c.points[i].color - c.points[j].color).cwiseAbs().maxCoeff()));
      }
  EXPECT_GT(nearPairs, 100u);
  EXPECT_LE(far, (16.0 + 255 * 0.5 * 4 * 0.03) / 255.0);
}

// A colour group cut short or a shading normal is refused in one line naming the file; a list
// property too.
TEST(OocAttributes, RefusesWhatItCannotCarry) {
  const fs::path d = test::scratchDir("ooc_attr_refuse");
  auto write = [&](const std::string& name, const std::string& props) {
    std::string b = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n" +
                    props + "end_header\n" + std::string(12 + 4 * 3, '\0');
    std::ofstream(d / name, std::ios::binary) << b;
    return d / name;
  };
  auto message = [](const fs::path& p) {
    try {
      ooc::PointReader r(p);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message(write("rg.ply", "property float red\nproperty float green\n")).find("no 'blue'"), std::string::npos);
  EXPECT_NE(message(write("sn.ply", "property float snx\nproperty float sny\nproperty float snz\n")).find("shading normals"),
            std::string::npos);
}

}  // namespace
}  // namespace linesurf
