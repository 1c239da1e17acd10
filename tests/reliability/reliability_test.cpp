// Reliability suite (docs/decisions.md "CLI and reliability"): malformed and hostile files, absurd
// parameters and outputs that cannot be written, across every command. Each case runs the CLI in a
// fresh folder holding good fixtures, hostile files and sentinel files at every output path, and
// asserts
//   - the exit code (1 usage/bad parameter, 2 bad input file, 3 failure to write / other),
//   - exactly one line of output (-q), naming the file or option at fault,
//   - every file that existed before is unchanged byte for byte, and no file was added (no
//     half-written output, no temporary left behind).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "linesurf/io/image_io.h"
#include "linesurf/io/model_io.h"
#include "sphere_fixture.h"
#include "test_util.h"

using namespace linesurf;
namespace fs = std::filesystem;

namespace {

void put(const fs::path& p, const std::string& bytes) {
  std::ofstream f(p, std::ios::binary);
  f << bytes;
}

std::string plyHead(const std::string& format, int vertices, const std::string& vertexProps, int faces = -1,
                    const std::string& faceProps = "property list uchar int vertex_indices\n") {
  std::string h = "ply\nformat " + format + " 1.0\nelement vertex " + std::to_string(vertices) + "\n" + vertexProps;
  if (faces >= 0) h += "element face " + std::to_string(faces) + "\n" + faceProps;
  return h + "end_header\n";
}
const std::string kXYZ = "property float x\nproperty float y\nproperty float z\n";

uint32_t crc32(const std::string& s) {
  uint32_t c = 0xFFFFFFFFu;
  for (unsigned char b : s) {
    c ^= b;
    for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1u)));
  }
  return ~c;
}
std::string be32(uint32_t v) {
  return {char(v >> 24), char((v >> 16) & 0xFF), char((v >> 8) & 0xFF), char(v & 0xFF)};
}
/// A tiny PNG file whose header declares w x h pixels (its data is far too short).
std::string pngDeclaring(uint32_t w, uint32_t h) {
  std::string ihdr = "IHDR" + be32(w) + be32(h) + std::string("\x08\x06\x00\x00\x00", 5);
  std::string idat = "IDAT" + std::string("\x78\x9c\x03\x00\x00\x00\x00\x01", 8);
  return std::string("\x89PNG\r\n\x1a\n", 8) + be32(13) + ihdr + be32(crc32(ihdr)) + be32(8) + idat + be32(crc32(idat)) +
         be32(0) + "IEND" + be32(crc32("IEND"));
}

/// A 2 x 1 indexed PNG (8-bit) with a one-colour palette whose second pixel uses `index`; every
/// chunk's CRC is right, so only the index is wrong when it is past 0.
std::string palettePngWithIndex(unsigned char index) {
  std::string ihdr = "IHDR" + be32(2) + be32(1) + std::string("\x08\x03\x00\x00\x00", 5);
  std::string plte = "PLTE" + std::string("\xff\x00\x00", 3);
  // zlib stream, one stored block: filter 0, indices 0 and `index`.
  const std::string raw = std::string("\x00\x00", 2) + char(index);
  uint32_t a = 1, b = 0;
  for (unsigned char c : raw) a = (a + c) % 65521, b = (b + a) % 65521;
  std::string z = std::string("\x78\x01\x01", 3) + char(raw.size()) + '\0' + char(~raw.size()) + '\xff' + raw + be32(b << 16 | a);
  std::string idat = "IDAT" + z;
  return std::string("\x89PNG\r\n\x1a\n", 8) + be32(13) + ihdr + be32(crc32(ihdr)) + be32(3) + plte + be32(crc32(plte)) +
         be32(uint32_t(z.size())) + idat + be32(crc32(idat)) + be32(0) + "IEND" + be32(crc32("IEND"));
}

/// Good fixtures, hostile files and sentinels, written once; every case gets a copy.
const fs::path& templateDir() {
  static const fs::path dir = [] {
    // One template per process (ctest runs the cases in parallel processes); removed at exit.
    fs::path d = test::scratchDir("reliability_template_" + std::to_string(::getpid()));
    static struct Cleanup {
      fs::path p;
      ~Cleanup() {
        std::error_code ec;
        fs::remove_all(p, ec);
      }
    } cleanup{d};
    // A sphere of 300 points: with normals and radii, and raw.
    HybridModel pts = test::randomSphere(300, 1.0f, true, 7);
    for (Point& p : pts.points) p.radius = 0.15f;
    writeModel(d / "pts.ply", pts, WriteOptions{PlyEncoding::Ascii});
    writeModel(d / "pts.xyz", pts);
    HybridModel raw = pts;
    raw.attributes = {};
    writeModel(d / "raw.ply", raw);
    // A 6 x 6 grid mesh.
    TriangleMesh mesh;
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 6; ++i) mesh.positions.emplace_back(float(i), float(j), 0.0f);
    for (int j = 0; j < 5; ++j)
      for (int i = 0; i < 5; ++i) {
        uint32_t a = uint32_t(j * 6 + i);
        mesh.faces.push_back({a, a + 1, a + 6});
        mesh.faces.push_back({a + 1, a + 7, a + 6});
      }
    writeMesh(d / "mesh.ply", mesh);
    for (const char* f : {"quad.obj", "quad.mtl", "texture.png"}) fs::copy_file(test::testData() / "ok" / f, d / f);
    Image a(16, 16), c(8, 8);
    for (auto& px : a.pixels) px = Color(0.5f, 0.25f, 1.0f, 1.0f);
    writePng(d / "a.png", a);
    writePng(d / "b.png", a);
    writePng(d / "c.png", c);
    put(d / "huge.png", pngDeclaring(16384, 16384));
    put(d / "huge2.png", pngDeclaring(16384, 16384));
    put(d / "notpng.png", "this is not an image\n");
    fs::create_directories(d / "expdata");
    fs::copy_file(d / "pts.ply", d / "expdata" / "pts.ply");

    // Hostile model files.
    const std::string tri = "0 0 0\n1 0 0\n0 1 0\n";
    put(d / "face_oob.ply", plyHead("ascii", 3, kXYZ, 1) + tri + "3 0 1 7\n");
    put(d / "face_neg.ply", plyHead("ascii", 3, kXYZ, 1) + tri + "3 0 -1 2\n");
    put(d / "face_two.ply", plyHead("ascii", 3, kXYZ, 1) + tri + "2 0 1\n");
    put(d / "face_scalar.ply", plyHead("ascii", 3, kXYZ, 1, "property int vertex_indices\n") + tri + "1\n");
    put(d / "big_double.ply", plyHead("ascii", 1, "property double x\nproperty double y\nproperty double z\n") + "1e300 0 0\n");
    put(d / "neg_radius.ply", plyHead("ascii", 3, kXYZ + "property float radius\n") + "0 0 0 0.1\n1 0 0 -0.1\n0 1 0 0.1\n");
    put(d / "huge_radius.ply", plyHead("ascii", 3, kXYZ + "property float radius\n") + "0 0 0 0.1\n1 0 0 1e30\n0 1 0 0.1\n");
    put(d / "neg_alpha.ply", plyHead("ascii", 2, kXYZ + "property float red\nproperty float green\nproperty float blue\nproperty float alpha\n") +
                                 "0 0 0 1 1 1 1\n1 0 0 1 1 1 -0.5\n");
    put(d / "red2.ply", plyHead("ascii", 2, kXYZ + "property float red\nproperty float green\nproperty float blue\n") +
                            "0 0 0 2 1 1\n1 0 0 1 1 1\n");
    put(d / "seg_inf.ply", "ply\nformat ascii 1.0\nelement segment 1\nproperty float x0\nproperty float y0\nproperty float z0\n"
                           "property float x1\nproperty float y1\nproperty float z1\nend_header\n0 0 0 inf 0 0\n");
    {
      std::string u16 = "\xFF\xFE";  // UTF-16LE with BOM: "ply\n..." with NUL after every byte
      for (char ch : std::string("ply\nformat ascii 1.0\nelement vertex 1\n")) u16 += std::string(1, ch) + '\0';
      put(d / "utf16.ply", u16);
    }
    put(d / "junk_header.ply", std::string("ply\nformat ascii 1.0\nel\xE9ment\x01\x02 vertex 1\n") + kXYZ + "end_header\n0 0 0\n");
    put(d / "truncated.ply", plyHead("binary_little_endian", 5, kXYZ) + std::string(20, '\0'));
    put(d / "obj_abc.obj", "v 5 abc 7\nv 0 1 0\nv 1 0 0\nf 1 2 3\n");
    put(d / "obj_short.obj", "v 0.5\n");
    put(d / "obj_vnnan.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn nan 0 1\nf 1//1 2//1 3//1\n");
    put(d / "obj_f2.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n");
    put(d / "obj_five.obj", "v 0 0 0 1 2\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    put(d / "obj_inf.obj", "v 1e39 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    put(d / "obj_oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    put(d / "obj_corner.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n");
    put(d / "bad_inf.xyz", "0 0 0\n1e39 0 0\n");
    put(d / "bad_text.xyz", "0 0 0\n1 2 three\n");
    put(d / "bad_cols.xyz", "0 0 0\n1 2 3 4\n");
    put(d / "empty.xyz", "");
    put(d / "empty_cloud.ply", plyHead("ascii", 0, kXYZ));
    put(d / "model.stl", "solid x\nendsolid x\n");
    put(d / "new\nline\x01.xyz", "0 0 0\nnot a point\n");  // a name to print on one line
    fs::create_directories(d / "folder.ply");
    ::mkfifo((d / "fifo.ply").c_str(), 0644);
    fs::create_symlink("/dev/zero", d / "zero.ply");
    fs::create_symlink("pts.ply", d / "link.png");  // an output name that is the input

    // Hostile inputs of the second round: experiment runs, budgets, unbounded work, acceptance rules.
    {
      // Corrupt models beside no good one: an experiment has nothing to report.
      fs::create_directories(d / "baddata");
      put(d / "baddata" / "a_bad.ply", plyHead("ascii", 2, "property float x\n") + "0\n1\n");
      put(d / "baddata" / "b_bad.xyz", "0 0 zero\n");
      // A mesh whose texture coordinates do not match its faces (4 values for 3 corners).
      put(d / "tcmis.ply", plyHead("ascii", 3, kXYZ, 1,
                                   "property list uchar int vertex_indices\nproperty list uchar float texcoord\n") +
                               tri + "3 0 1 2 4 0 0 1 0\n");
      // An extra vertex property whose name the writer cannot write back.
      put(d / "badprop.ply", plyHead("ascii", 1, kXYZ + "property float we?ird\n") + "0 0 0 1\n");
      // OBJ material libraries: missing, a device, outside the folder, absolute; a texture outside.
      const std::string objTri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
      put(d / "mtl_missing.obj", "mtllib nothere.mtl\n" + objTri);
      fs::create_symlink("/dev/zero", d / "zero.mtl");
      put(d / "mtl_zero.obj", "mtllib zero.mtl\n" + objTri);
      put(d / "mtl_outside.obj", "mtllib ../outside.mtl\n" + objTri);
      put(d / "mtl_absolute.obj", "mtllib /etc/passwd\n" + objTri);
      put(d / "tex_outside.mtl", "newmtl m\nmap_Kd ../texture.png\n");
      put(d / "tex_outside.obj", "mtllib tex_outside.mtl\nusemtl m\n" + objTri);
      put(d / "points_only.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n");
      // PNGs: a flipped byte under a valid-looking chunk (bad CRC), a palette index past the
      // palette's end, a file cut inside a chunk; and a textured OBJ whose texture is corrupt.
      {
        std::ifstream f(d / "a.png", std::ios::binary);
        std::stringstream ss;
        ss << f.rdbuf();
        std::string png = ss.str();
        png[png.size() - 20] ^= 0x01;  // inside IDAT's data
        put(d / "badcrc.png", png);
        put(d / "trunc.png", ss.str().substr(0, ss.str().size() - 30));
        put(d / "crc_texture.mtl", "newmtl m\nmap_Kd badcrc.png\n");
        put(d / "crc_texture.obj", "mtllib crc_texture.mtl\nusemtl m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n"
                                   "f 1/1 2/2 3/3\n");
      }
      put(d / "palette.png", palettePngWithIndex(5));
      put(d / "palette_ok.png", palettePngWithIndex(0));
      // Headers of 100,000 properties / elements ending in a duplicate: refused, in linear time.
      {
        std::string h = "ply\nformat ascii 1.0\nelement vertex 1\n" + kXYZ;
        for (int i = 0; i < 100000; ++i) h += "property uchar p" + std::to_string(i) + "\n";
        put(d / "manyprops_dup.ply", h + "property uchar p7\nend_header\n");
        std::string e = "ply\nformat ascii 1.0\nelement vertex 0\n" + kXYZ;
        for (int i = 0; i < 100000; ++i) e += "element e" + std::to_string(i) + " 0\n";
        put(d / "manyelements_dup.ply", e + "element e5 0\nend_header\n");
      }
      // A file name that is not UTF-8, holding a broken model.
      put(d / "bad\xff\xfename.ply", plyHead("ascii", 1, kXYZ) + "0 0\n");
      // A cloud big enough for --max-mb 1 to refuse its geometry and outputs, small enough to read.
      HybridModel big = test::randomSphere(40000, 1.0f, false, 11);
      big.attributes = {};
      writeModel(d / "big.ply", big);
    }

    // Sentinels at every output path the cases name.
    for (const char* s : {"out.png", "d.png", "n.png", "al.png", "diff.png", "out.ply", "c.ply", "out.xyz", "out.obj",
                          "out_000.png", "conv_texture.png", "conv2.mtl", "exp/results.json", "exp/pts/view_000_points.png",
                          "out.html"}) {
      fs::create_directories((d / s).parent_path());
      put(d / s, std::string("sentinel ") + s + "\n");
    }
    // Outputs that can be staged but not written: they fail after other outputs were written.
    fs::create_directories(d / "out_001.png");
    fs::create_directories(d / "conv.mtl");
    fs::create_directories(d / "conv2_texture.png");
    fs::create_directories(d / "outdir.png");
    return d;
  }();
  return dir;
}

struct Entry {
  std::string type;  ///< "file", "dir", "link", "other"
  std::string bytes;
};
std::map<std::string, Entry> snapshot(const fs::path& root) {
  std::map<std::string, Entry> s;
  for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
    const fs::path rel = it->path().lexically_relative(root);
    const auto st = fs::symlink_status(it->path());
    Entry e;
    if (fs::is_symlink(st)) {
      e = {"link", fs::read_symlink(it->path()).string()};
    } else if (fs::is_regular_file(st)) {
      std::ifstream f(it->path(), std::ios::binary);
      std::stringstream ss;
      ss << f.rdbuf();
      e = {"file", ss.str()};
    } else if (fs::is_directory(st)) {
      e = {"dir", ""};
    } else {
      e = {"other", ""};
    }
    s[rel.string()] = e;
  }
  return s;
}

void copyTree(const fs::path& from, const fs::path& to) {
  fs::create_directories(to);
  for (auto it = fs::recursive_directory_iterator(from); it != fs::recursive_directory_iterator(); ++it) {
    const fs::path rel = it->path().lexically_relative(from), dst = to / rel;
    const auto st = fs::symlink_status(it->path());
    if (fs::is_symlink(st)) fs::copy_symlink(it->path(), dst);
    else if (fs::is_directory(st)) fs::create_directories(dst);
    else if (fs::is_regular_file(st)) fs::copy_file(it->path(), dst);
    else ::mkfifo(dst.c_str(), 0644);
  }
}

test::CliResult runIn(const fs::path& dir, const std::string& args, const std::string& limits = "") {
  test::CliResult r;
  const std::string cmd = "cd '" + dir.string() + "' && " + (limits.empty() ? "" : limits + "; ") + "timeout 60 " +
                          std::string(LINESURF_CLI) + " " + args + " 2>&1";
  FILE* pipe = popen(cmd.c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

struct Case {
  std::string name, args;
  int code;
  std::vector<std::string> needles;  ///< each appears in the one-line message
  std::string limits;                ///< shell commands before the CLI (e.g. "ulimit -f 8")
};

std::ostream& operator<<(std::ostream& os, const Case& c) { return os << c.name; }

// clang-format off
const std::vector<Case> kCases = {
  // --- Outputs: the transaction, refused paths, unwritable outputs ---------------------------
  {"RenderDepthOutMissingFolder", "render pts.ply -o out.png --depth-out nodir/d.png", 3, {"nodir/d.png", "output folder does not exist"}},
  {"RenderNormalOutMissingFolder", "render pts.ply -o out.png --normal-out nodir/n.png", 3, {"nodir/n.png"}},
  {"RenderAlphaOutIsFolder", "render pts.ply -o out.png --alpha-out outdir.png", 3, {"outdir.png", "is a directory"}},
  {"RenderOutputIsFolder", "render pts.ply -o outdir.png", 3, {"outdir.png", "is a directory"}},
  {"RenderOutputOntoInput", "render pts.ply -o pts.ply", 1, {"--output", "pts.ply", "also the input"}},
  {"RenderOutputLinkToInput", "render pts.ply -o link.png", 1, {"--output", "link.png", "also the input"}},
  {"RenderDepthOntoInput", "render pts.ply -o out.png --depth-out ./pts.ply", 1, {"--depth-out", "also the input"}},
  {"RenderEmptyOutput", "render pts.ply -o ''", 1, {"--output", "empty path"}},
  {"ConvertEmptyOutput", "convert pts.ply ''", 1, {"output", "empty path"}},
  {"RenderJpegName", "render pts.ply -o r.jpg", 1, {"--output", "r.jpg", ".png"}},
  {"RenderTwoOutputsOnePath", "render pts.ply -o out.png --depth-out out.png", 1, {"--depth-out", "--output"}},
  {"RenderTwoOutputsOnePathSpelledApart", "render pts.ply -o out.png --normal-out ./sub/../out.png", 1, {"--normal-out"}},
  {"RenderViewFailsAfterFirstView", "render pts.ply -o out.png --views 2 --size 32x32", 3, {"out_001.png", "is a directory"}},
  {"RenderViewsDepthMissingFolder", "render pts.ply -o out.png --views 2 --size 32x32 --depth-out nodir/d.png", 3, {"nodir/d.png"}},
  {"ConvertObjMtlIsFolder", "convert quad.obj conv.obj", 3, {"conv.mtl", "is a directory"}},
  {"ConvertObjTextureIsFolder", "convert quad.obj conv2.obj", 3, {"conv2_texture.png", "is a directory"}},
  {"ConvertOntoInput", "convert quad.obj quad.obj", 1, {"quad.obj", "also the input"}},
  {"ConvertUnknownOutputFormat", "convert pts.ply out.stl", 1, {"out.stl", ".ply"}},
  {"ConvertPointsToObj", "convert pts.ply out.obj", 1, {"out.obj"}},
  {"ConvertEmptyCloudToXyzRefused", "convert empty_cloud.ply out.xyz", 3, {"out.xyz", "at least one point"}},
  {"NormalsOntoInput", "normals raw.ply -o raw.ply", 1, {"--output", "raw.ply"}},
  {"NormalsMissingFolder", "normals raw.ply -o nodir/x.ply", 3, {"nodir/x.ply"}},
  {"EpsDeltaOntoInput", "extract eps-delta pts.ply -o pts.ply", 1, {"--output", "pts.ply"}},
  {"EpsDeltaXyzOutput", "extract eps-delta pts.ply -o out.xyz", 1, {"--output", "out.xyz", ".ply"}},
  {"ShapeApproxClustersMissingFolder", "extract shape-approx pts.ply -o out.ply --clusters-out nodir/c.ply", 3, {"nodir/c.ply"}},
  {"ShapeApproxClustersOntoOutput", "extract shape-approx pts.ply -o out.ply --clusters-out out.ply", 1, {"--clusters-out", "--output"}},
  {"ContourOntoInput", "extract contour mesh.ply -o mesh.ply", 1, {"--output", "mesh.ply"}},
  {"CompareDiffOntoInput", "compare a.png b.png --diff a.png", 1, {"--diff", "a.png"}},
  {"CompareDiffJpeg", "compare a.png b.png --diff out.jpg", 1, {"--diff", "out.jpg"}},
  {"CompareDiffMissingFolder", "compare a.png b.png --diff nodir/diff.png", 3, {"nodir/diff.png"}},
  // --- Resources ---------------------------------------------------------------------------
  {"RenderHugeSize", "render pts.ply -o out.png --size 16384x16384", 1, {"--size", "--max-mb"}},
  {"RenderSizeOverLoweredLimit", "render pts.ply -o out.png --size 512x512 --max-mb 1", 1, {"--size", "--max-mb"}},
  {"ContourTinySpacing", "extract contour mesh.ply -o out.ply --spacing 1e-6", 1, {"--spacing", "--max-mb"}},
  {"ContourTinySpacingAllPoints", "extract contour mesh.ply -o out.ply --spacing 1e-4 --all-points", 1, {"--spacing", "--max-mb"}},
  {"ContourTinySpacingScale", "extract contour mesh.ply -o out.ply --spacing-scale 1e-6", 1, {"--spacing-scale"}},
  {"ContourNegativeDiagonalDivisions", "extract contour mesh.ply -o out.ply --diagonal-divisions -1", 1, {"--diagonal-divisions"}},
  {"ContourHugeDiagonalDivisions", "extract contour mesh.ply -o out.ply --diagonal-divisions 1e6 --max-mb 64", 1, {"--diagonal-divisions"}},
  {"CompareHugeHeaderSizeMismatch", "compare a.png huge.png", 2, {"huge.png", "16384x16384"}},
  {"CompareHugeHeaders", "compare huge.png huge2.png --diff diff.png", 1, {"huge.png", "--max-mb"}},
  {"InfoFifo", "info fifo.ply", 2, {"fifo.ply", "not a regular file"}},
  {"RenderFifo", "render fifo.ply -o out.png", 2, {"fifo.ply", "not a regular file"}},
  {"InfoDevZero", "info zero.ply", 2, {"zero.ply", "not a regular file"}},
  {"ConvertDevZero", "convert zero.ply out.ply", 2, {"zero.ply"}},
  {"InfoFolder", "info folder.ply", 2, {"folder.ply", "directory"}},
  // --- Bad input files: every command applies the same checks --------------------------------
  {"RenderMissingFile", "render missing.ply -o out.png", 2, {"missing.ply", "no such file"}},
  {"NormalsMissingFile", "normals missing.xyz -o out.ply", 2, {"missing.xyz", "no such file"}},
  {"InfoFaceOutOfRange", "info face_oob.ply", 2, {"face_oob.ply", "out of range"}},
  {"NormalsFaceOutOfRange", "normals face_oob.ply -o out.ply", 2, {"face_oob.ply", "out of range"}},
  {"EpsDeltaFaceNegative", "extract eps-delta face_neg.ply -o out.ply", 2, {"face_neg.ply", "out of range"}},
  {"ShapeApproxFaceTwoCorners", "extract shape-approx face_two.ply -o out.ply", 2, {"face_two.ply", "at least 3"}},
  {"ConvertFaceOutOfRange", "convert face_oob.ply out.ply", 2, {"face_oob.ply", "out of range"}},
  {"ConvertFaceNotAList", "convert face_scalar.ply out.ply", 2, {"face_scalar.ply", "list"}},
  {"RenderFaceNotAList", "render face_scalar.ply -o out.png", 2, {"face_scalar.ply", "list"}},
  {"ConvertDoubleOverflowsFloat", "convert big_double.ply out.ply", 2, {"big_double.ply", "too large"}},
  {"RenderNegativeRadius", "render neg_radius.ply -o out.png", 2, {"neg_radius.ply", "negative"}},
  {"RenderHugeRadius", "render huge_radius.ply -o out.png", 2, {"huge_radius.ply", "radius"}},
  {"RenderNegativeAlpha", "render neg_alpha.ply -o out.png", 2, {"neg_alpha.ply", "alpha"}},
  {"ConvertColourAboveOne", "convert red2.ply out.ply", 2, {"red2.ply", "red"}},
  {"RenderInfiniteSegment", "render seg_inf.ply -o out.png", 2, {"seg_inf.ply", "line 11", "x1"}},
  {"InfoUtf16", "info utf16.ply", 2, {"utf16.ply"}},
  {"InfoNonUtf8Header", "info junk_header.ply", 2, {"junk_header.ply", "line 3", "unknown header keyword"}},
  {"RenderTruncatedBinary", "render truncated.ply -o out.png", 2, {"truncated.ply", "truncated"}},
  {"InfoObjNotANumber", "info obj_abc.obj", 2, {"obj_abc.obj", "line 1", "abc"}},
  {"ConvertObjTooFewCoordinates", "convert obj_short.obj out.ply", 2, {"obj_short.obj", "line 1"}},
  {"RenderObjNanNormal", "render obj_vnnan.obj -o out.png", 2, {"obj_vnnan.obj", "line 4"}},
  {"ContourObjTwoCornerFace", "extract contour obj_f2.obj -o out.ply", 2, {"obj_f2.obj", "line 4", "3 corners"}},
  {"NormalsObjFiveCoordinates", "normals obj_five.obj -o out.ply", 2, {"obj_five.obj", "line 1"}},
  {"ConvertObjOverflow", "convert obj_inf.obj out.ply", 2, {"obj_inf.obj", "line 1"}},
  {"ConvertObjFaceOutOfRange", "convert obj_oob.obj out.obj", 2, {"obj_oob.obj", "out of range"}},
  {"InfoObjBadCorner", "info obj_corner.obj", 2, {"obj_corner.obj", "line 4"}},
  {"NormalsXyzOverflow", "normals bad_inf.xyz -o out.ply", 2, {"bad_inf.xyz", "line 2"}},
  {"EpsDeltaXyzText", "extract eps-delta bad_text.xyz -o out.ply", 2, {"bad_text.xyz", "line 2"}},
  {"ConvertXyzColumns", "convert bad_cols.xyz out.ply", 2, {"bad_cols.xyz", "line 2"}},
  {"RenderEmptyXyz", "render empty.xyz -o out.png", 2, {"empty.xyz"}},
  {"RenderUnknownExtension", "render model.stl -o out.png", 2, {"model.stl", "extension"}},
  {"ContourOnPointCloud", "extract contour pts.ply -o out.ply", 2, {"pts.ply"}},
  {"CompareNotAnImage", "compare notpng.png a.png", 2, {"notpng.png"}},
  {"CompareMissingImage", "compare missing.png a.png", 2, {"missing.png"}},
  {"CompareSizeMismatch", "compare a.png c.png --diff diff.png", 2, {"c.png", "differs"}},
  {"VerifyMissingInput", "verify-extraction missing.ply pts.ply", 2, {"missing.ply"}},
  // --- Parameters: refused at once with 1, naming the option -----------------------------------
  {"RenderBadSize", "render pts.ply -o out.png --size 0x5", 1, {"--size"}},
  {"RenderSizeJunk", "render pts.ply -o out.png --size 64x64x", 1, {"--size"}},
  {"RenderNegativeViews", "render pts.ply -o out.png --views -1", 1, {"--views"}},  // 0: the one orbit view
  {"RenderFov", "render pts.ply -o out.png --fov 500", 1, {"--fov"}},
  {"RenderUpAxis", "render pts.ply -o out.png --up-axis w", 1, {"--up-axis"}},
  {"RenderSegmentMethod", "render pts.ply -o out.png --segment-method foo", 1, {"--segment-method"}},
  {"RenderBackground", "render pts.ply -o out.png --background purple", 1, {"--background"}},
  {"RenderNegativeThreads", "render pts.ply -o out.png -j -1", 1, {"--threads"}},
  {"RenderNoModel", "render -o out.png", 1, {"MODEL"}},
  {"ShapeApproxDeltaN", "extract shape-approx pts.ply -o out.ply --delta-n 5", 1, {"delta-n"}},
  {"NormalsTinyK", "normals raw.ply -o out.ply --k 1", 1, {"--k"}},
  {"CompareSaturateZero", "compare a.png b.png --diff diff.png --saturate 0", 1, {"--saturate"}},
  {"UnknownCommand", "frobnicate pts.ply", 1, {"frobnicate", "unknown command"}},
  {"MaxMbZero", "info pts.ply --max-mb 0", 1, {"--max-mb"}},
  {"ExperimentZeroViews", "experiment expdata -o exp --views 0", 1, {"--views"}},
  {"ExperimentUnknownMethod", "experiment expdata -o exp --methods foo", 1, {"foo"}},
  {"RenderEyeIsTarget", "render pts.ply -o out.png --eye 0 0 0 --target 0 0 0", 1, {"--eye", "--target"}},
  {"RenderUpAlongView", "render pts.ply -o out.png --eye 0 0 5 --target 0 0 0 --up 0 0 0", 1, {"--up"}},
  {"ExperimentHugeBoundPrintedBriefly", "experiment expdata -o exp --contour-spacing -1", 1, {"--contour-spacing", "1e+30"}},
  {"ViewOntoInput", "view pts.ply -o pts.ply", 1, {"--output", "pts.ply"}},
  {"ViewMissingFolder", "view pts.ply -o nodir/v.html", 3, {"nodir/v.html"}},
  {"ViewMissingModel", "view missing.ply -o out.html", 2, {"missing.ply: no such file"}},
  {"ExperimentMissingFolder", "experiment nodata -o exp", 2, {"nodata: no such folder"}},
  {"InfoControlBytesInName", "info new*line*.xyz", 2, {"new\\nline\\x01.xyz: line 2"}},
  {"VerifyWithoutTolerances", "verify-extraction pts.ply raw.ply", 1, {"epsilon"}},
  // --- experiment: parameters refused before any work, naming the flag typed; corrupt models
  //     and failed writes leave the earlier run (exp/) as it was --------------------------------
  {"ExperimentEpsilonNan", "experiment expdata -o exp --epsilon nan", 1, {"--epsilon:", "nan"}},
  {"ExperimentEpsilonNanNewFolder", "experiment expdata -o newexp --epsilon nan", 1, {"--epsilon:"}},
  {"ExperimentDeltaNNegative", "experiment expdata -o exp --delta-n -1", 1, {"--delta-n:"}},
  {"ExperimentDeltaTooLarge", "experiment expdata -o exp --delta 3", 1, {"--delta:"}},
  {"ExperimentContourScaleNan", "experiment expdata -o exp --contour-scale nan", 1, {"--contour-scale:"}},
  {"ExperimentMergeAngleNan", "experiment expdata -o exp --contour-merge-angle nan", 1, {"--contour-merge-angle:"}},
  {"ExperimentKTooLarge", "experiment expdata -o exp --k 5000", 1, {"--k"}},
  {"ExperimentAllModelsCorrupt", "experiment baddata -o exp --views 2", 2, {"baddata", "all 2 models failed", "a_bad.ply"}},
  {"ExperimentOutputIsAFile", "experiment expdata -o out.png --views 2", 3, {"out.png", "not a folder"}},
  {"ExperimentDiskFull", "experiment expdata -o exp --views 2 --image-views 1", 3, {"File too large"}, "ulimit -f 4"},
  {"ExperimentDiskFullNewFolder", "experiment expdata -o newexp --views 2 --image-views 1", 3, {"File too large"}, "ulimit -f 4"},
  // --- --max-mb bounds every output and the working memory, before the work -------------------
  {"RenderViewsOutputOverBudget", "render pts.ply -o out.png --views 10000 --size 2048x2048", 1, {"--views", "--max-mb"}},
  {"RenderViewsBuffersOverBudget", "render pts.ply -o out.png --views 1000 --size 1024x1024 --depth-out d.png", 1, {"--views", "2000 images"}},
  {"RenderOneViewOverLoweredBudget", "render pts.ply -o out.png --size 400x400 --max-mb 1", 1, {"--size", "--max-mb 1"}},
  {"ExperimentHugeViewsAndSize", "experiment expdata -o exp --views 100000 --size 8192", 1, {"--size", "--max-mb"}},
  {"ExperimentViewsOverBudget", "experiment expdata -o exp --views 100000 --size 16 --max-mb 64", 1, {"--views", "--max-mb 64"}},
  {"ExperimentMeshViewsOverBudget", "experiment expdata -o exp --mesh-views 100000 --size 16 --max-mb 64", 1, {"--mesh-views"}},
  // Over the in-memory estimate the commands go out of core by themselves; below that path's floor
  // they refuse.
  {"NormalsOverBudget", "normals big.ply -o out.ply --max-mb 1", 1, {"--max-mb", "out-of-core", "--max-mb 1"}},
  {"NormalsXyzOverBudget", "normals big.ply -o out.xyz --max-mb 1", 1, {"--output", "out-of-core"}},
  {"ViewOverBudget", "view big.ply -o out.html --max-mb 1", 1, {"--output", "page", "--max-mb 1"}},
  {"ConvertXyzOverBudget", "convert big.ply out.xyz --max-mb 1", 1, {"output", "40000 points", "--max-mb 1"}},
  {"EpsDeltaOverBudget", "extract eps-delta big.ply -o out.ply --max-mb 1", 1, {"--max-mb", "out-of-core", "--max-mb 1"}},
  {"ShapeApproxOverBudget", "extract shape-approx big.ply -o out.ply --max-mb 1", 1, {"--max-mb", "out-of-core", "--max-mb 1"}},
  // Out of core, a budget below what the process, the stages' buffers and two smallest tiles need
  // (the budget is the peak resident set): one line with the figure, before any file.
  {"NormalsOutOfCoreBelowItsFloor", "normals big.ply -o out.ply --out-of-core --max-mb 16", 1, {"--max-mb", "needs at least", "--max-mb 16"}},
  {"EpsDeltaTilesBelowTheirFloor", "extract eps-delta big.ply -o out.ply --tiles 4 --max-mb 16", 1, {"--max-mb", "needs at least"}},
  {"ShapeApproxOutOfCoreBelowItsFloor", "extract shape-approx big.ply -o out.ply --out-of-core --max-mb 24", 1, {"--max-mb 24"}},
  {"ShapeApproxClustersOutOfCore", "extract shape-approx pts.ply -o out.ply --clusters-out c.ply --tiles 2", 1,
   {"--clusters-out", "out of core"}},
  {"RenderGeometryOverBudget", "render big.ply -o out.png --size 16x16 --max-mb 1", 1, {"big.ply", "geometry"}},
  {"MaxMbNan", "normals raw.ply -o out.ply --max-mb nan", 1, {"--max-mb", "nan"}},
  // --- One parameter cannot make unbounded work --------------------------------------------------
  {"ShapeApproxMaxIterationsHuge", "extract shape-approx pts.ply -o out.ply --clustering hierarchical --max-iterations 2147483647", 1,
   {"--max-iterations", "[1, 1000]"}},
  {"ShapeApproxMaxIterationsOverBound", "extract shape-approx pts.ply -o out.ply --max-iterations 1001", 1, {"--max-iterations: must be in [1, 1000] (got 1001)"}},
  {"HeaderOf100000PropertiesDuplicate", "info manyprops_dup.ply", 2, {"manyprops_dup.ply", "line 100007", "'p7' declared twice"}},
  {"HeaderOf100000ElementsDuplicate", "info manyelements_dup.ply", 2, {"manyelements_dup.ply", "line 100007", "'e5' declared twice"}},
  // --- One acceptance rule and one message for every command ---------------------------------------
  {"InfoTexcoordMismatch", "info tcmis.ply", 2, {"tcmis.ply: line 14", "texcoord"}},
  {"NormalsTexcoordMismatch", "normals tcmis.ply -o out.ply", 2, {"tcmis.ply: line 14", "texcoord"}},
  {"EpsDeltaTexcoordMismatch", "extract eps-delta tcmis.ply -o out.ply", 2, {"tcmis.ply: line 14", "texcoord"}},
  {"ShapeApproxTexcoordMismatch", "extract shape-approx tcmis.ply -o out.ply", 2, {"tcmis.ply: line 14", "texcoord"}},
  {"ConvertXyzTexcoordMismatch", "convert tcmis.ply out.xyz", 2, {"tcmis.ply: line 14", "texcoord"}},
  {"ViewTexcoordMismatch", "view tcmis.ply -o out.html", 2, {"tcmis.ply: line 14", "texcoord"}},
  {"RenderPointsTexcoordMismatch", "render tcmis.ply -o out.png --primitive points", 2, {"tcmis.ply: line 14"}},
  {"InfoObjMtlMissing", "info mtl_missing.obj", 2, {"mtl_missing.obj: line 1", "nothere.mtl", "not found"}},
  {"NormalsObjMtlMissing", "normals mtl_missing.obj -o out.ply", 2, {"mtl_missing.obj: line 1", "not found"}},
  {"RenderObjMtlDevZero", "render mtl_zero.obj -o out.png", 2, {"mtl_zero.obj: line 1", "not a regular file"}},
  {"ConvertObjMtlOutsideFolder", "convert mtl_outside.obj out.ply", 2, {"mtl_outside.obj: line 1", "outside"}},
  {"InfoObjMtlAbsolute", "info mtl_absolute.obj", 2, {"mtl_absolute.obj: line 1", "outside"}},
  {"RenderObjTextureOutsideFolder", "render tex_outside.obj -o out.png", 2, {"tex_outside.obj", "outside"}},
  {"RenderPointsOnlyObjAsMesh", "render points_only.obj -o out.png --primitive mesh", 1, {"--primitive", "holds none"}},
  {"InfoJsonNonUtf8Name", "info --json bad*name.ply", 2, {"bad\\xFF\\xFEname.ply: line 8"}},
  {"ViewNonUtf8Name", "view bad*name.ply -o out.html", 2, {"bad\\xFF\\xFEname.ply: line 8"}},
  {"ConvertInvalidPropertyName", "convert badprop.ply out.ply", 2, {"badprop.ply: line 7", "property name 'we?ird'"}},
  {"NormalsInvalidPropertyName", "normals badprop.ply -o out.ply", 2, {"badprop.ply: line 7"}},
  {"CompareBadCrc", "compare badcrc.png a.png", 2, {"badcrc.png", "bad CRC"}},
  {"CompareTruncatedPng", "compare trunc.png a.png", 2, {"trunc.png", "truncated"}},
  {"ComparePaletteIndexPastEnd", "compare palette.png palette_ok.png", 2, {"palette.png", "palette"}},
  {"RenderTextureBadCrc", "render crc_texture.obj -o out.png", 2, {"badcrc.png", "bad CRC"}},
  {"RenderDiskFull", "render pts.ply -o out.png --size 256x256", 3, {"out.png", "File too large"}, "ulimit -f 2"},
  {"ConvertDiskFull", "convert big.ply out.ply", 3, {"out.ply", "File too large"}, "ulimit -f 16"},
};
// clang-format on

class Reliability : public ::testing::TestWithParam<Case> {};

TEST_P(Reliability, RefusedInOneLineLeavingEveryFileAsItWas) {
  const Case& c = GetParam();
  const fs::path dir = fs::temp_directory_path() / ("linesurf_reliability_" + c.name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  copyTree(templateDir(), dir);
  const auto before = snapshot(dir);
  const test::CliResult r = runIn(dir, c.args + " -q", c.limits);
  EXPECT_EQ(r.exitCode, c.code) << c.args << "\n" << r.out;
  ASSERT_FALSE(r.out.empty()) << c.args;
  EXPECT_EQ(r.out.back(), '\n') << r.out;
  EXPECT_EQ(r.out.find('\n'), r.out.size() - 1) << "not one line: " << r.out;
  EXPECT_EQ(r.out.find('\0'), std::string::npos) << r.out;
  for (const std::string& n : c.needles) EXPECT_NE(r.out.find(n), std::string::npos) << "'" << n << "' not in: " << r.out;
  const auto after = snapshot(dir);
  for (const auto& [path, e] : before) {
    auto it = after.find(path);
    ASSERT_NE(it, after.end()) << path << " was removed";
    EXPECT_EQ(it->second.type, e.type) << path;
    EXPECT_TRUE(it->second.bytes == e.bytes) << path << " changed";
  }
  for (const auto& [path, e] : after) EXPECT_TRUE(before.count(path)) << path << " was added (" << e.type << ")";
  fs::remove_all(dir);
}

INSTANTIATE_TEST_SUITE_P(Cases, Reliability, ::testing::ValuesIn(kCases),
                         [](const ::testing::TestParamInfo<Case>& i) { return i.param.name; });

// --- Interrupted commands ---------------------------------------------------------------------

/// Whether a temporary output (the short hidden ".ls-" names of io/atomic_file.h) lies under `dir`.
bool hasTemporary(const fs::path& dir) {
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it)
    if (it->path().filename().string().rfind(".ls-", 0) == 0) return true;
  return false;
}

/// Runs the CLI in `dir` with the signals at their default actions (as from a terminal), sends
/// `sig` once a temporary output exists (the command is mid-way), and returns the wait status.
int interruptMidway(const fs::path& dir, const std::vector<std::string>& args, int sig) {
  std::vector<std::string> all = {LINESURF_CLI};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string where = dir.string();
  const pid_t pid = ::fork();
  if (pid == 0) {  // only async-signal-safe calls until exec
    for (int s : {SIGINT, SIGTERM, SIGHUP}) ::signal(s, SIG_DFL);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    if (::chdir(where.c_str()) != 0) ::_exit(126);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1);
    ::dup2(null, 2);
    ::execv(argv[0], argv.data());
    ::_exit(127);
  }
  int status = 0;
  const auto start = std::chrono::steady_clock::now();
  while (!hasTemporary(dir) && std::chrono::steady_clock::now() - start < std::chrono::seconds(60)) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return status;  // ended before it could be interrupted
    ::usleep(2000);
  }
  ::kill(pid, sig);
  ::waitpid(pid, &status, 0);
  return status;
}

struct Interruption {
  std::string name;
  std::vector<std::string> args;
  int signal;
};

class Interrupted : public ::testing::TestWithParam<Interruption> {};

TEST_P(Interrupted, LeavesTheFolderAsItWasAndDiesByTheSignal) {
  const Interruption& c = GetParam();
  const fs::path dir = fs::temp_directory_path() / ("linesurf_interrupted_" + c.name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  copyTree(templateDir(), dir);
  const auto before = snapshot(dir);
  const int status = interruptMidway(dir, c.args, c.signal);
  ASSERT_TRUE(WIFSIGNALED(status)) << "not interrupted: exit " << (WIFEXITED(status) ? WEXITSTATUS(status) : -1);
  EXPECT_EQ(WTERMSIG(status), c.signal);
  EXPECT_FALSE(hasTemporary(dir));
  const auto after = snapshot(dir);
  for (const auto& [path, e] : before) {
    auto it = after.find(path);
    ASSERT_NE(it, after.end()) << path << " was removed";
    EXPECT_TRUE(it->second.bytes == e.bytes) << path << " changed";
  }
  for (const auto& [path, e] : after) EXPECT_TRUE(before.count(path)) << path << " was added (" << e.type << ")";
  fs::remove_all(dir);
}

const std::vector<std::string> kManyViews = {"render", "pts.ply", "-o", "v.png", "--views", "5000", "--size", "128x128"};
const std::vector<std::string> kLongExperiment = {"experiment", "expdata", "-o", "exp", "--views", "3000", "--size", "64"};
const std::vector<std::string> kLongExperimentNewFolder = {"experiment", "expdata", "-o", "new/run", "--views", "3000", "--size", "64"};

INSTANTIATE_TEST_SUITE_P(Signals, Interrupted,
                         ::testing::Values(Interruption{"RenderSigint", kManyViews, SIGINT},
                                           Interruption{"RenderSigterm", kManyViews, SIGTERM},
                                           Interruption{"RenderSighup", kManyViews, SIGHUP},
                                           Interruption{"ExperimentSigint", kLongExperiment, SIGINT},
                                           Interruption{"ExperimentSigterm", kLongExperiment, SIGTERM},
                                           Interruption{"ExperimentNewFolderSigint", kLongExperimentNewFolder, SIGINT}),
                         [](const ::testing::TestParamInfo<Interruption>& i) { return i.param.name; });

// --- Commands that succeed where they used to fail or to be partial --------------------------------

fs::path freshCopy(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("linesurf_reliability_ok_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  copyTree(templateDir(), dir);
  return dir;
}

std::string readAll(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

TEST(Reliability, ExperimentWithCorruptModelsReplacesTheEarlierRunWhole) {
  const fs::path dir = freshCopy("experiment_mixed");
  fs::create_directories(dir / "mixed");
  fs::copy_file(dir / "pts.ply", dir / "mixed" / "pts.ply");
  fs::copy_file(dir / "baddata" / "a_bad.ply", dir / "mixed" / "a_bad.ply");
  put(dir / "exp" / "pts" / "stale.png", "from an earlier run");
  const std::string earlier = readAll(dir / "exp" / "results.json");
  const test::CliResult r = runIn(dir, "experiment mixed -o exp --views 2 --image-views 1 -q");
  EXPECT_EQ(r.exitCode, 2) << r.out;
  EXPECT_NE(r.out.find("mixed: 1 of 2 models failed"), std::string::npos) << r.out;
  // The good model's results form a fresh run: new reports, and the model's folder replaced whole.
  const std::string results = readAll(dir / "exp" / "results.json");
  EXPECT_NE(results, earlier);
  const nlohmann::json j = nlohmann::json::parse(results);
  EXPECT_EQ(j.dump().find("a_bad.ply") != std::string::npos, true);
  EXPECT_FALSE(fs::exists(dir / "exp" / "pts" / "stale.png"));
  EXPECT_EQ(readImage(dir / "exp" / "pts" / "view_000_points.png").width, 512);
  EXPECT_FALSE(hasTemporary(dir));
  EXPECT_FALSE(fs::exists(dir / "exp" / "a_bad"));
  fs::remove_all(dir);
}

TEST(Reliability, FacelessObjRendersAsPoints) {
  const fs::path dir = freshCopy("faceless_obj");
  const test::CliResult r = runIn(dir, "render points_only.obj -o p.png --size 32x32");
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("points: 4 drawn"), std::string::npos) << r.out;  // a cloud of its vertices
  EXPECT_EQ(readImage(dir / "p.png").width, 32);
  fs::remove_all(dir);
}

TEST(Reliability, NonUtf8FileNameIsReportedAndViewed) {
  const fs::path dir = freshCopy("non_utf8");
  fs::copy_file(dir / "pts.ply", dir / "ok\xff\xfe.ply");
  const test::CliResult info = runIn(dir, "info --json ok*.ply");
  ASSERT_EQ(info.exitCode, 0) << info.out;
  const nlohmann::json j = nlohmann::json::parse(info.out);  // valid JSON (UTF-8) whatever the name's bytes
  EXPECT_EQ(j["points"], 300);
  const test::CliResult view = runIn(dir, "view ok*.ply -o page.html -q");
  EXPECT_EQ(view.exitCode, 0) << view.out;
  EXPECT_TRUE(fs::exists(dir / "page.html"));
  fs::remove_all(dir);
}

TEST(Reliability, LongestLegalOutputNameIsWritten) {
  const fs::path dir = freshCopy("long_name");
  const std::string name = std::string(251, 'n') + ".ply";  // 255 bytes: the longest name a folder holds
  const test::CliResult r = runIn(dir, "convert pts.ply " + name + " -q");
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_EQ(readModel(dir / name).points.size(), 300u);
  EXPECT_FALSE(hasTemporary(dir));
  fs::remove_all(dir);
}

TEST(Reliability, AtLeastOneHundredFiftyCases) { EXPECT_GE(kCases.size(), 150u); }

}  // namespace
