// Damaged hierarchies against every reader: each lie a .lod can tell (counts, links, header
// values) is refused by the library's one validation (lod::validateHierarchy, through LodFile),
// and by `render`, `info` and `view` with exit 2, one line naming the file, nothing written and
// the file untouched; a truncated file stays what it was (the readable nodes drawn, the rest
// warned about) with nothing sized by the counts of the blocks it lacks.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sys/wait.h>

#include "../test_util.h"
#include "linesurf/core/error.h"
#include "linesurf/lod/lod.h"

namespace linesurf {
namespace {

constexpr size_t kPreamble = 32, kRecord = 88;

template <class T>
T getAt(const std::string& b, size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof v);
  return v;
}
template <class T>
void setAt(std::string& b, size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof v);
}

// A sphere of points with a ring of segments, built small (leaf 16, grid 4): four levels,
// inner nodes with several children.
const std::string& pristine() {
  static const std::string bytes = [] {
    HybridModel m;
    const int n = 700;
    const float golden = std::numbers::pi_v<float> * (3 - std::sqrt(5.0f));
    for (int i = 0; i < n; ++i) {
      const float y = 1 - 2 * (float(i) + 0.5f) / float(n), r = std::sqrt(1 - y * y), t = golden * float(i);
      Point p;
      p.position = Vec3f(r * std::cos(t), y, r * std::sin(t));
      p.normal = p.position;
      p.radius = 0.08f;
      m.points.push_back(p);
    }
    for (int k = 0; k < 40; ++k) {
      const float a0 = 2 * std::numbers::pi_v<float> * float(k) / 40, a1 = 2 * std::numbers::pi_v<float> * float(k + 1) / 40;
      Segment s;
      s.p0 = Vec3f(1.1f * std::cos(a0), 0, 1.1f * std::sin(a0));
      s.p1 = Vec3f(1.1f * std::cos(a1), 0, 1.1f * std::sin(a1));
      s.normal = Vec3f(0, 1, 0);
      s.radius = 0.05f;
      m.segments.push_back(s);
    }
    m.attributes.normals = m.attributes.radii = true;
    return lod::buildLod(m, ModelFrame{}, {.leafSize = 16, .grid = 4});
  }();
  return bytes;
}

size_t tableAt(const std::string& b) { return kPreamble + getAt<uint32_t>(b, 12); }
size_t nodeCount(const std::string& b) { return size_t(getAt<uint64_t>(b, 24)); }
size_t rec(const std::string& b, size_t i) { return tableAt(b) + i * kRecord; }
// Record fields (docs/file-format.md): offset 8, size 16, cube 32, side 44, box 48/60, points 72,
// segments 76, first child 80, child count 84, level 85, leaf 86.
uint64_t blockSize(uint32_t points, uint32_t segments) { return 32 + 64 * uint64_t(points) + 100 * uint64_t(segments); }

struct Node {
  uint32_t firstChild;
  uint8_t childCount, level, leaf;
};
Node node(const std::string& b, size_t i) {
  const size_t r = rec(b, i);
  return {getAt<uint32_t>(b, r + 80), uint8_t(b[r + 84]), uint8_t(b[r + 85]), uint8_t(b[r + 86])};
}
// The first inner node after `from` with at least two children.
size_t innerWithChildren(const std::string& b, size_t from = 0) {
  for (size_t i = from; i < nodeCount(b); ++i)
    if (!node(b, i).leaf && node(b, i).childCount >= 2) return i;
  ADD_FAILURE() << "no inner node with two children";
  return 0;
}
// Two inner nodes of one level (the second's children lie after both).
std::pair<size_t, size_t> twoInnerSiblings(const std::string& b) {
  for (size_t i = 0; i < nodeCount(b); ++i)
    for (size_t k = i + 1; k < nodeCount(b) && !node(b, i).leaf && node(b, k).level == node(b, i).level; ++k)
      if (!node(b, k).leaf) return {i, k};
  ADD_FAILURE() << "no two inner nodes on one level";
  return {0, 0};
}
size_t firstLeaf(const std::string& b) {
  for (size_t i = 0; i < nodeCount(b); ++i)
    if (node(b, i).leaf) return i;
  return 0;
}

// The JSON header edited; the table and blocks move with it (their offsets shifted).
std::string withJson(const std::string& bytes, const std::function<void(nlohmann::json&)>& edit) {
  const uint32_t jb = getAt<uint32_t>(bytes, 12);
  nlohmann::json j = nlohmann::json::parse(bytes.substr(kPreamble, jb));
  edit(j);
  std::string js = j.dump();
  while ((kPreamble + js.size()) % 8) js.push_back(' ');
  const int64_t delta = int64_t(js.size()) - int64_t(jb);
  std::string out = bytes.substr(0, kPreamble) + js + bytes.substr(kPreamble + jb);
  setAt<uint32_t>(out, 12, uint32_t(js.size()));
  for (size_t i = 0; i < nodeCount(out); ++i) {
    const size_t r = rec(out, i) + 8;
    setAt<uint64_t>(out, r, uint64_t(int64_t(getAt<uint64_t>(out, r)) + delta));
  }
  return out;
}

// The header checksum recomputed over the edited header (a hostile writer's lie, which only the
// validation behind the checksum can refuse); bytes too short to hold it are left as they are.
std::string resealed(std::string b) {
  if (b.size() < kPreamble || getAt<uint32_t>(b, 8) < 2) return b;
  const uint64_t end = tableAt(b) + uint64_t(nodeCount(b)) * kRecord;
  if (nodeCount(b) > b.size() / kRecord || end + 8 > b.size()) return b;
  setAt<uint64_t>(b, end, lod::lodChecksum(b.data(), end));
  return b;
}

struct Lie {
  std::string cell;                              // the matrix cell: kind of lie / what
  std::function<std::string(std::string)> make;  // pristine bytes -> damaged bytes
  std::string where;                             // in the library's message: the WHERE named
};

struct Outcome {
  int code = -1;
  std::string out;
};
// A reader run through the shell (with a timeout: `view` would serve a file it accepted).
Outcome shell(const std::string& args) {
  Outcome r;
  FILE* p = popen(("timeout 20 " + std::string(LINESURF_CLI) + " " + args + " 2>&1").c_str(), "r");
  if (!p) return r;
  std::array<char, 4096> buf;
  for (size_t n; (n = fread(buf.data(), 1, buf.size(), p)) > 0;) r.out.append(buf.data(), n);
  const int st = pclose(p);
  r.code = WIFEXITED(st) ? WEXITSTATUS(st) : -1;
  return r;
}
bool oneLineNaming(const std::string& out, const std::string& path) {
  return !out.empty() && out.back() == '\n' && out.find('\n') == out.size() - 1 && out.find(path) != std::string::npos;
}

// Each lie against the library reader (LodFile: what render, view, Python and info construct)
// and the three CLI readers.
void refusedEverywhere(const std::string& dirName, const std::vector<Lie>& lies) {
  const auto dir = test::scratchDir(dirName);
  for (const Lie& lie : lies) {
    SCOPED_TRACE(lie.cell);
    const std::string bytes = resealed(lie.make(pristine()));
    ASSERT_NE(bytes, pristine());
    const std::string path = (dir / (lie.cell + ".lod")).string();
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    try {
      lod::LodFile f(path);
      ADD_FAILURE() << "accepted by the library reader";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), Error::Kind::BadInput);
      EXPECT_EQ(e.path(), path);
      EXPECT_NE(e.where().find(lie.where), std::string::npos) << e.what();
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
    const std::string q = "'" + path + "'", png = (dir / (lie.cell + ".png")).string();
    for (const std::string& args : {"-q render " + q + " -o '" + png + "' --size 32x32 --budget 5000",
                                    "info " + q, "view " + q + " --port 0"}) {
      const Outcome r = shell(args);
      EXPECT_EQ(r.code, 2) << args << ": " << r.out;
      EXPECT_TRUE(oneLineNaming(r.out, path)) << args << ": " << r.out;
    }
    EXPECT_FALSE(std::filesystem::exists(png));
    std::ifstream in(path, std::ios::binary);
    EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), bytes) << "the input changed";
  }
}

TEST(LodDamage, CountsAreCheckedAgainstTheBytesBeforeAnythingIsSized) {
  const std::string& b = pristine();
  ASSERT_GT(nodeCount(b), 8u);
  const size_t leaf = firstLeaf(b);
  std::vector<Lie> lies = {
      {"count_root_points_2e26", [](std::string s) { setAt<uint32_t>(s, rec(s, 0) + 72, 1u << 26); return s; }, "node 0"},
      // The size made to match: the root then claims more than its children hold.
      {"count_root_points_and_size_2e26",
       [](std::string s) {
         setAt<uint32_t>(s, rec(s, 0) + 72, 1u << 26);
         setAt<uint64_t>(s, rec(s, 0) + 16, blockSize(1u << 26, getAt<uint32_t>(s, rec(s, 0) + 76)));
         return s;
       },
       "node 0"},
      // A leaf and the header agreeing on 2^26 more points: its block then overlaps the next one.
      {"count_leaf_and_header_2e26",
       [leaf](std::string s) {
         s = withJson(s, [](nlohmann::json& j) { j["points"] = j["points"].get<uint64_t>() + (1u << 26); });
         const size_t r = rec(s, leaf);
         const uint32_t p = getAt<uint32_t>(s, r + 72) + (1u << 26);
         setAt<uint32_t>(s, r + 72, p);
         setAt<uint64_t>(s, r + 16, blockSize(p, getAt<uint32_t>(s, r + 76)));
         return s;
       },
       "node"},
      {"count_leaves_and_header_differ",
       [](std::string s) { return withJson(s, [](nlohmann::json& j) { j["points"] = j["points"].get<uint64_t>() + 1; }); },
       "node table"},
      {"count_nodes_2e40", [](std::string s) { setAt<uint64_t>(s, 24, uint64_t(1) << 40); return s; }, "header"},
      {"count_json_bytes_2e31", [](std::string s) { setAt<uint32_t>(s, 12, 1u << 31); return s; }, "header"},
      {"count_header_points_negative",
       [](std::string s) { return withJson(s, [](nlohmann::json& j) { j["points"] = -1; }); }, "header"},
      // A block placed over another node's.
      {"layout_block_overlaps",
       [leaf](std::string s) {
         setAt<uint64_t>(s, rec(s, leaf) + 8, getAt<uint64_t>(s, rec(s, leaf + 1) + 8) + 8);
         return s;
       },
       "node"},
  };
  refusedEverywhere("lod_damage_counts", lies);
}

TEST(LodDamage, BrokenLinksAreRefused) {
  const std::string& b = pristine();
  const size_t a = innerWithChildren(b);
  ASSERT_GT(node(b, a).childCount, 1);
  std::vector<Lie> lies = {
      // A later inner node pointing at a's children: two parents (a DAG).
      {"links_dag",
       [](std::string s) {
         const auto [x, y] = twoInnerSiblings(s);
         setAt<uint32_t>(s, rec(s, y) + 80, node(s, x).firstChild);
         s[rec(s, y) + 84] = char(node(s, x).childCount);
         return s;
       },
       "node " + std::to_string(node(b, twoInnerSiblings(b).first).firstChild)},
      {"links_cycle", [a](std::string s) { setAt<uint32_t>(s, rec(s, a) + 80, uint32_t(a)); return s; },
       "node " + std::to_string(a)},
      {"links_orphan",
       [a](std::string s) {
         s[rec(s, a) + 84] = char(node(s, a).childCount - 1);
         return s;
       },
       "node"},
      {"links_level",
       [a](std::string s) {
         const size_t c = node(s, a).firstChild;
         s[rec(s, c) + 85] = char(node(s, c).level + 1);
         return s;
       },
       "node " + std::to_string(node(b, a).firstChild)},
      {"links_cube_not_an_octant",
       [a](std::string s) {
         const size_t r = rec(s, node(s, a).firstChild);
         setAt<float>(s, r + 32, getAt<float>(s, r + 32) + getAt<float>(s, r + 44) / 3);
         return s;
       },
       "node " + std::to_string(node(b, a).firstChild)},
      {"links_box_outside_parent",
       [a](std::string s) {
         const size_t r = rec(s, node(s, a).firstChild);
         setAt<float>(s, r + 60, getAt<float>(s, rec(s, a) + 60) + 1);
         return s;
       },
       "node " + std::to_string(node(b, a).firstChild)},
      {"links_leaf_flag", [a](std::string s) { s[rec(s, a) + 86] = 1; return s; }, "node " + std::to_string(a)},
      {"links_record_of_another_hierarchy", [](std::string s) { s[rec(s, 1)] ^= 0x40; return s; }, "node 1"},
  };
  refusedEverywhere("lod_damage_links", lies);
}

Lie json(std::string cell, std::function<void(nlohmann::json&)> edit) {
  return Lie{cell, [edit](std::string s) { return withJson(s, edit); }, "header"};
}

TEST(LodDamage, SpheresTheCamerasCannotFrameAreRefused) {
  std::vector<Lie> lies = {
      json("header_radius_0", [](nlohmann::json& j) { j["sphere"]["radius"] = 0; }),
      json("header_radius_-1", [](nlohmann::json& j) { j["sphere"]["radius"] = -1; }),
      json("header_radius_1e30", [](nlohmann::json& j) { j["sphere"]["radius"] = 1e30; }),
      json("header_radius_1e39", [](nlohmann::json& j) { j["sphere"]["radius"] = 1e39; }),
      json("header_centre_1e30", [](nlohmann::json& j) { j["sphere"]["center"][0] = 1e30; }),
      json("header_centre_outside_root", [](nlohmann::json& j) { j["sphere"]["center"][1] = 40.0; }),
      json("header_radius_text", [](nlohmann::json& j) { j["sphere"]["radius"] = "1"; }),
  };
  refusedEverywhere("lod_damage_sphere", lies);
}

TEST(LodDamage, FramesAndParametersOutOfRangeAreRefused) {
  std::vector<Lie> lies = {
      json("header_frame_scale_0", [](nlohmann::json& j) { j["frame"]["scale"] = 0; }),
      json("header_frame_scale_3", [](nlohmann::json& j) { j["frame"]["scale"] = 3; }),
      json("header_frame_centre_1e300", [](nlohmann::json& j) { j["frame"]["centre"][2] = 1e300; }),
      json("header_max_radius_1e30", [](nlohmann::json& j) { j["maxRadius"] = 1e30; }),
      json("header_grid_1", [](nlohmann::json& j) { j["grid"] = 1; }),
      {"header_version_3", [](std::string s) { setAt<uint32_t>(s, 8, 3); return s; }, "header"},
      {"header_version_0", [](std::string s) { setAt<uint32_t>(s, 8, 0); return s; }, "header"},
  };
  refusedEverywhere("lod_damage_frame", lies);
}

// A file cut inside its blocks (the last ones: the coarsest nodes, the root last) is what it
// always was: readable nodes drawn, a warning per node not drawn, exit 0; the nodes it lacks
// are sized by nothing (they get no place in the frame's model).
// Edits that every structural check would accept (a bound, a flag, a JSON value within range)
// are refused by the version-2 checksum over the preamble, the JSON and the table.
TEST(LodDamage, EditsBehindTheTableChecksumAreRefused) {
  const std::string& b = pristine();
  ASSERT_EQ(getAt<uint32_t>(b, 8), 2u);
  const size_t leaf = firstLeaf(b);
  std::vector<Lie> lies = {
      {"table_box_grown", [&](std::string s) {
         setAt<float>(s, rec(s, leaf) + 60, getAt<float>(s, rec(s, leaf) + 60) + 1e-3f);
         return s;
       }, "node table"},
      {"table_padding_byte", [&](std::string s) { s[rec(s, leaf) + 87] = 1; return s; }, "node table"},
      {"table_checksum_flipped", [&](std::string s) {
         const size_t end = tableAt(s) + nodeCount(s) * kRecord;
         s[end] = char(s[end] ^ 0x40);
         return s;
       }, "node table"},
      {"json_leaf_size", [&](std::string s) {
         const size_t at = s.find("\"leafSize\":16");
         s[at + 11] = '7';
         return s;
       }, "node table"},
  };
  const auto dir = test::scratchDir("lod_damage_sum");
  for (const Lie& lie : lies) {
    SCOPED_TRACE(lie.cell);
    const std::string bytes = lie.make(b);
    const std::string path = (dir / (lie.cell + ".lod")).string();
    std::ofstream(path, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    try {
      lod::LodFile f(path);
      ADD_FAILURE() << "accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), Error::Kind::BadInput);
      EXPECT_EQ(e.where(), "node table") << e.what();
      EXPECT_NE(std::string(e.what()).find("checksum"), std::string::npos) << e.what();
    }
    for (const std::string& args : {"info '" + path + "'", "-q render '" + path + "' -o '" + path + ".png' --size 16x16"}) {
      const Outcome r = shell(args);
      EXPECT_EQ(r.code, 2) << args << ": " << r.out;
      EXPECT_TRUE(oneLineNaming(r.out, path)) << r.out;
    }
  }
}

// A version-1 file (no table checksum: the same bytes without the trailer, offsets 8 lower) is
// still read, validated as before, and gives the same primitives.
TEST(LodDamage, VersionOneFilesAreStillRead) {
  const std::string& b = pristine();
  const size_t end = tableAt(b) + nodeCount(b) * kRecord;
  std::string v1 = b.substr(0, end) + b.substr(end + 8);
  setAt<uint32_t>(v1, 8, 1);
  for (size_t i = 0; i < nodeCount(v1); ++i) setAt<uint64_t>(v1, rec(v1, i) + 8, getAt<uint64_t>(v1, rec(v1, i) + 8) - 8);
  const auto dir = test::scratchDir("lod_v1");
  const std::string p1 = (dir / "v1.lod").string(), p2 = (dir / "v2.lod").string();
  std::ofstream(p1, std::ios::binary).write(v1.data(), std::streamsize(v1.size()));
  std::ofstream(p2, std::ios::binary).write(b.data(), std::streamsize(b.size()));
  const lod::LodFile f1(p1), f2(p2);
  EXPECT_EQ(f1.header().version, 1u);
  EXPECT_EQ(f2.header().version, 2u);
  ASSERT_EQ(f1.nodes().size(), f2.nodes().size());
  for (uint32_t i = 0; i < f1.nodes().size(); ++i) {
    std::vector<char> a, c;
    f1.readBlock(i, a);
    f2.readBlock(i, c);
    EXPECT_TRUE(std::equal(a.begin(), a.begin() + f1.nodes()[i].size, c.begin())) << "node " << i;
  }
}

TEST(LodDamage, TruncatedBlocksAreSkippedNotSized) {
  const auto dir = test::scratchDir("lod_damage_truncated");
  const std::string& b = pristine();
  const std::string path = (dir / "cut.lod").string();
  std::ofstream(path, std::ios::binary).write(b.data(), std::streamsize(b.size() - 40));
  lod::LodFile f(path);
  EXPECT_FALSE(f.inFile(0));
  EXPECT_TRUE(f.inFile(uint32_t(firstLeaf(b))));
  lod::Selection all;
  for (uint32_t i = 0; i < f.nodes().size(); ++i)
    if (f.nodes()[i].leaf || i == 0) all.nodes.push_back(i);
  const lod::Assembled a = lod::assemble(f, all);
  ASSERT_EQ(a.failures.size(), 1u);
  EXPECT_NE(a.failures[0].find("node 0:"), std::string::npos) << a.failures[0];
  EXPECT_EQ(a.model.points.size() + a.model.segments.size(), f.header().points + f.header().segments);
  const std::string png = (dir / "cut.png").string();
  const Outcome r = shell("-q render '" + path + "' -o '" + png + "' --size 32x32 --budget 50");
  EXPECT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("warning: " + path + ": node 0:"), std::string::npos) << r.out;
  EXPECT_TRUE(std::filesystem::exists(png));
  EXPECT_EQ(shell("info '" + path + "'").code, 0);
}

// A damaged magic is "not a hierarchy", naming the file, for every reader.
TEST(LodDamage, DamagedMagicIsNotAHierarchy) {
  const auto dir = test::scratchDir("lod_damage_magic");
  std::string b = pristine();
  b[3] ^= 0x20;
  const std::string path = (dir / "magic.lod").string();
  std::ofstream(path, std::ios::binary).write(b.data(), std::streamsize(b.size()));
  EXPECT_THROW(lod::LodFile{path}, Error);
  for (const std::string& args : {"-q render '" + path + "' -o '" + (dir / "m.png").string() + "'", "info '" + path + "'",
                                  "view '" + path + "' --port 0"}) {
    const Outcome r = shell(args);
    EXPECT_EQ(r.code, 2) << args << ": " << r.out;
    EXPECT_TRUE(oneLineNaming(r.out, path)) << args << ": " << r.out;
    EXPECT_NE(r.out.find("level-of-detail"), std::string::npos) << args << ": " << r.out;
  }
  EXPECT_FALSE(std::filesystem::exists(dir / "m.png"));
}

// What the writers make passes the readers' validation, and the writer refuses a model that
// would not (its sphere far from its rendering frame) rather than write it.
TEST(LodDamage, WritersRefuseWhatReadersWould) {
  EXPECT_NO_THROW(lod::validateHeader(lod::LodHeader{.sphere = {Vec3f::Zero(), 1.0f}, .points = 1}, "x"));
  HybridModel m;
  Point p;
  p.normal = Vec3f(0, 0, 1);
  p.radius = 1;
  for (int i = 0; i < 20; ++i) p.position = Vec3f(1e8f + float(i), 0, 0), m.points.push_back(p);
  m.attributes.normals = m.attributes.radii = true;
  try {
    lod::buildLod(m, ModelFrame{});  // not in its rendering frame: the centre 1e8 from the origin
    FAIL() << "written";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("sphere centre"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace linesurf
