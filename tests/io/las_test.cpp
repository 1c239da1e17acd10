// LAS reading and writing (io/las_io.h): every point format bit-exact, far-from-origin tiles,
// the colour rule, extra bytes, and every refused input with its message.
#include <gtest/gtest.h>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <tuple>

#include "linesurf/core/error.h"
#include "linesurf/io/las_io.h"
#include "linesurf/io/model_io.h"
#include "test_util.h"

namespace fs = std::filesystem;

namespace linesurf {
namespace {

constexpr std::array<int, 11> kRecordSize = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};
constexpr std::array<int, 11> kRgbAt = {-1, -1, 20, 28, -1, 28, -1, 30, 30, -1, 30};

template <class T>
void put(std::string& b, size_t at, T v) {
  std::memcpy(b.data() + at, &v, sizeof(T));
}
template <class T>
T get(const std::string& b, size_t at) {
  T v;
  std::memcpy(&v, b.data() + at, sizeof(T));
  return v;
}

struct LasPoint {
  std::array<int32_t, 3> xyz{};
  uint16_t intensity = 0;
  uint8_t cls = 0;
  std::array<uint16_t, 3> rgb{};
};

/// An extra-bytes descriptor: name, LAS data type, options bits, scale, offset.
struct Extra {
  std::string name;
  uint8_t type = 9;
  uint8_t options = 0;
  double scale = 1, offset = 0;
};

/// A LAS file built field by field, independently of the writer under test.
struct LasBuilder {
  int minor = 2, format = 0;
  int recordLength = -1;  ///< -1: the format's size + the extras'
  size_t headerPadding = 0, pointPadding = 0;  ///< bytes after the header and before the points
  std::array<double, 3> scale{0.001, 0.001, 0.001}, offset{0, 0, 0};
  std::vector<LasPoint> points;
  std::vector<Extra> extras;
  std::vector<std::vector<uint8_t>> extraValues;  ///< per point, the extra bytes
  std::vector<std::tuple<std::string, uint16_t, std::string>> vlrs, evlrs;  ///< user id, record id, payload

  std::string bytes() const {
    const size_t hs = (minor < 3 ? 227 : minor == 3 ? 235 : 375) + headerPadding;
    std::string vl;
    auto addVlr = [&](const std::string& user, uint16_t id, const std::string& payload) {
      std::string v(54, '\0');
      std::memcpy(v.data() + 2, user.data(), std::min<size_t>(16, user.size()));
      put<uint16_t>(v, 18, id);
      put<uint16_t>(v, 20, uint16_t(payload.size()));
      vl += v + payload;
    };
    size_t extraSize = 0;
    if (!extras.empty()) {
      std::string d(192 * extras.size(), '\0');
      for (size_t e = 0; e < extras.size(); ++e) {
        put<uint8_t>(d, 192 * e + 2, extras[e].type);
        put<uint8_t>(d, 192 * e + 3, extras[e].options);
        std::memcpy(d.data() + 192 * e + 4, extras[e].name.data(), std::min<size_t>(32, extras[e].name.size()));
        put<double>(d, 192 * e + 112, extras[e].scale);
        put<double>(d, 192 * e + 136, extras[e].offset);
        static constexpr int sizes[11] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 4, 8};
        const uint8_t t = extras[e].type;
        extraSize += t == 0 ? extras[e].options : t <= 10 ? size_t(sizes[t]) : 0;
      }
      addVlr("LASF_Spec", 4, d);
    }
    for (const auto& [user, id, payload] : vlrs) addVlr(user, id, payload);
    vl += std::string(pointPadding, '\xdd');
    const size_t len = recordLength >= 0 ? size_t(recordLength) : size_t(kRecordSize[size_t(format)]) + extraSize;
    std::string b(hs, '\0');
    std::memcpy(b.data(), "LASF", 4);
    b[24] = 1, b[25] = char(minor);
    put<uint16_t>(b, 94, uint16_t(hs));
    put<uint32_t>(b, 96, uint32_t(hs + vl.size()));
    put<uint32_t>(b, 100, uint32_t(vlrs.size() + (extras.empty() ? 0 : 1)));
    put<uint8_t>(b, 104, uint8_t(format));
    put<uint16_t>(b, 105, uint16_t(len));
    if (format <= 5) put<uint32_t>(b, 107, uint32_t(points.size()));
    for (int a = 0; a < 3; ++a) put<double>(b, 131 + 8 * size_t(a), scale[size_t(a)]), put<double>(b, 155 + 8 * size_t(a), offset[size_t(a)]);
    if (minor >= 4) put<uint64_t>(b, 247, points.size());
    b += vl;
    for (size_t i = 0; i < points.size(); ++i) {
      // Filled at full size, then cut to the record length (a record may be made too short).
      std::string r(std::max(len, size_t(kRecordSize[size_t(format)]) + extraSize), '\0');
      const LasPoint& p = points[i];
      for (int a = 0; a < 3; ++a) put<int32_t>(r, 4 * size_t(a), p.xyz[size_t(a)]);
      put<uint16_t>(r, 12, p.intensity);
      if (format >= 6) put<uint8_t>(r, 16, p.cls);
      else put<uint8_t>(r, 15, p.cls);
      if (kRgbAt[size_t(format)] >= 0)
        for (int c = 0; c < 3; ++c) put<uint16_t>(r, size_t(kRgbAt[size_t(format)] + 2 * c), p.rgb[size_t(c)]);
      if (i < extraValues.size())
        std::memcpy(r.data() + kRecordSize[size_t(format)], extraValues[i].data(),
                    std::min(extraValues[i].size(), r.size() - size_t(kRecordSize[size_t(format)])));
      r.resize(len);
      b += r;
    }
    if (!evlrs.empty()) {
      put<uint64_t>(b, 235, b.size());
      put<uint32_t>(b, 243, uint32_t(evlrs.size()));
    }
    for (const auto& [user, id, payload] : evlrs) {
      std::string v(60, '\0');
      std::memcpy(v.data() + 2, user.data(), std::min<size_t>(16, user.size()));
      put<uint16_t>(v, 18, id);
      put<uint64_t>(v, 20, payload.size());
      b += v + payload;
    }
    return b;
  }
};

/// The point records' offset and length of a LAS file's bytes.
std::pair<size_t, size_t> recordsOf(const std::string& b) { return {get<uint32_t>(b, 96), get<uint16_t>(b, 105)}; }

std::vector<LasPoint> randomPoints(size_t n, int format, uint32_t seed, int32_t lo, int32_t hi) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int32_t> coord(lo, hi);
  std::vector<LasPoint> pts(n);
  for (LasPoint& p : pts) {
    for (int32_t& v : p.xyz) v = coord(rng);
    p.intensity = uint16_t(rng() % 65536);
    p.cls = uint8_t(rng() % (format >= 6 ? 256 : 32));
    if (kRgbAt[size_t(format)] >= 0)
      for (uint16_t& c : p.rgb) c = uint16_t(rng() % 65536);
  }
  return pts;
}

std::string errorOf(const std::string& bytes, const std::string& name = "t.las") {
  try {
    readLasModelFromMemory(bytes, name);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadInput) << e.what();
    return e.what();
  }
  return "(no error)";
}

void writeBytes(const fs::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

std::string readBytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(f), {});
}

// ---------------------------------------------------------------------------------------------

TEST(LasRoundTrip, EveryPointFormatIsBitExact) {
  for (int format = 0; format <= 10; ++format) {
    SCOPED_TRACE("point format " + std::to_string(format));
    LasBuilder in;
    in.minor = format <= 5 ? 2 : 4;
    in.format = format;
    in.points = randomPoints(500, format, uint32_t(format), -200000, 200000);
    const std::string src = in.bytes();
    const HybridModel m = readLasModelFromMemory(src, "in.las");
    ASSERT_EQ(m.points.size(), 500u);
    EXPECT_EQ(m.attributes.colors, kRgbAt[size_t(format)] >= 0);
    const std::string out = lasBytes(m, {.pointFormat = format}, "out.las");
    const auto [so, sl] = recordsOf(src);
    const auto [oo, ol] = recordsOf(out);
    ASSERT_EQ(sl, ol);
    ASSERT_EQ(get<double>(out, 131), 0.001);
    for (size_t i = 0; i < 500; ++i) {
      const size_t a = so + i * sl, b = oo + i * ol;
      EXPECT_EQ(src.substr(a, 14), out.substr(b, 14)) << "X Y Z intensity of point " << i;
      const size_t c = format >= 6 ? 16 : 15;
      EXPECT_EQ(uint8_t(src[a + c]) & (format >= 6 ? 0xFF : 0x1F), uint8_t(out[b + c])) << "class of point " << i;
      if (const int rgb = kRgbAt[size_t(format)]; rgb >= 0) {
        EXPECT_EQ(src.substr(a + size_t(rgb), 6), out.substr(b + size_t(rgb), 6)) << "RGB of point " << i;
      }
    }
    // Written by the writer and read again: the same bytes.
    EXPECT_EQ(lasBytes(readLasModelFromMemory(out, "out.las"), {.pointFormat = format}, "again.las"), out);
  }
}

TEST(LasRoundTrip, NormalsRadiusAndPropertiesAsExtraBytes) {
  HybridModel m;
  for (int i = 0; i < 40; ++i) {
    Point p;
    p.position = Vec3f(0.25f * float(i), 1.5f, -0.125f * float(i));
    p.normal = Vec3f(0.6f, 0, 0.8f);
    p.radius = 0.01f * float(i + 1);
    p.color = Color(float(i) / 40.0f, 0.5f, 1, 1);
    m.points.push_back(p);
  }
  m.attributes.normals = m.attributes.radii = m.attributes.colors = true;
  m.pointProperties["k_min"].assign(40, -0.75f);
  m.pointProperties["intensity"].assign(40, 0.5f);  // not a uint16: kept as extra bytes
  m.comments = {"source: a test", "second comment"};
  const std::string b = lasBytes(m, {}, "m.las");
  EXPECT_EQ(int(uint8_t(b[104])), 7);  // colour: format 7
  const HybridModel r = readLasModelFromMemory(b, "m.las");
  ASSERT_EQ(r.points.size(), 40u);
  EXPECT_TRUE(r.attributes.normals && r.attributes.radii && r.attributes.colors);
  for (size_t i = 0; i < 40; ++i) {
    EXPECT_LT((r.points[i].position - m.points[i].position).norm(), 1e-6f);
    EXPECT_EQ(r.points[i].normal, m.points[i].normal);
    EXPECT_EQ(r.points[i].radius, m.points[i].radius);
    EXPECT_NEAR(r.points[i].color[0], m.points[i].color[0], 1.0 / 65535);
  }
  EXPECT_EQ(r.pointProperties.at("k_min"), m.pointProperties.at("k_min"));
  EXPECT_EQ(r.pointProperties.at("intensity"), m.pointProperties.at("intensity"));
  ASSERT_GE(r.comments.size(), 2u);
  EXPECT_EQ(r.comments[0], "source: a test");
  EXPECT_EQ(r.comments[1], "second comment");
  EXPECT_NE(std::find(r.comments.begin(), r.comments.end(), "linesurf_up_axis z"), r.comments.end());
}

TEST(LasRoundTrip, UtmTileIsBitExactAndPrecise) {
  // A 1 km tile at (5e5, 5e6) m, scale 1 mm: float32 absolute coordinates would step by 0.5 m.
  LasBuilder in;
  in.minor = 4, in.format = 6;
  in.offset = {500000, 5000000, 0};
  in.points = randomPoints(2000, 6, 7, 0, 1000000);
  for (LasPoint& p : in.points) p.xyz[2] /= 5;  // 0-200 m high
  const std::string src = in.bytes();
  const HybridModel m = readLasModelFromMemory(src, "utm.las");
  const Vec3d origin = modelOrigin(m);
  EXPECT_NEAR(origin.x(), 500500, 1);
  EXPECT_NEAR(origin.y(), 5000500, 1);
  for (size_t i = 0; i < m.points.size(); ++i) {
    const LasPoint& p = in.points[i];
    const Vec3d truth(500000 + p.xyz[0] * 0.001, 5000000 + p.xyz[1] * 0.001, p.xyz[2] * 0.001);
    ASSERT_LT((origin + m.points[i].position.cast<double>() - truth).cwiseAbs().maxCoeff(), 1e-4) << "point " << i;
  }
  auto sameRecords = [&](const std::string& out) {
    const auto [so, sl] = recordsOf(src);
    const auto [oo, ol] = recordsOf(out);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(get<double>(out, 131 + 8 * size_t(a)), in.scale[size_t(a)]);
    for (int a = 0; a < 3; ++a) EXPECT_EQ(get<double>(out, 155 + 8 * size_t(a)), in.offset[size_t(a)]);
    size_t differ = 0;
    for (size_t i = 0; i < in.points.size(); ++i) differ += src.substr(so + i * sl, 12) != out.substr(oo + i * ol, 12);
    EXPECT_EQ(differ, 0u);
  };
  sameRecords(lasBytes(m, {}, "utm2.las"));
  // Through a PLY file (float positions and the comments) and back.
  const fs::path dir = test::scratchDir("las_utm");
  writeModel(dir / "utm.ply", m);
  sameRecords(lasBytes(readModel(dir / "utm.ply"), {}, "utm3.las"));
}

TEST(LasRoundTrip, ModelNotFromLasGetsAFittingScale) {
  HybridModel m;
  for (int i = 0; i < 100; ++i) {
    Point p;
    p.position = Vec3f(0.001f * float(i), 0.1f + 0.0003f * float(i), -0.05f);
    m.points.push_back(p);
  }
  const HybridModel r = readLasModelFromMemory(lasBytes(m, {}, "s.las"), "s.las");
  // 10^ceil(log10(0.13 / 2^22)) = 1e-7: within half a step.
  for (size_t i = 0; i < 100; ++i) EXPECT_LT((r.points[i].position - m.points[i].position).cwiseAbs().maxCoeff(), 6e-8f);
}

TEST(LasRoundTrip, HeaderSizeOffsetAndUnknownVlrsHonoured) {
  LasBuilder in;
  in.minor = 3, in.format = 1;
  in.headerPadding = 20, in.pointPadding = 2;  // a longer header, and the pad bytes of old writers
  in.vlrs = {{"some tool", 42, std::string(300, 'v')}};
  in.points = randomPoints(5, 1, 9, -50, 50);
  const HybridModel m = readLasModelFromMemory(in.bytes(), "pad.las");
  ASSERT_EQ(m.points.size(), 5u);
  EXPECT_EQ(m.points[4].position.x(), float(in.points[4].xyz[0] * 0.001));
}

TEST(LasRoundTrip, CoordinateSystemRecordsKept) {
  LasBuilder in;
  in.minor = 4, in.format = 6;
  in.points = randomPoints(10, 6, 3, -100, 100);
  const std::string keys("\x01\x00\x01\x00\x00\x00\x01\x00\xff\x00", 10);
  const std::string wkt = "PROJCS[\"ETRS89 / UTM zone 32N\"]";
  in.vlrs = {{"LASF_Projection", 34735, keys}, {"other tool", 7, "dropped"}};
  in.evlrs = {{"LASF_Projection", 2112, wkt}};
  const HybridModel m = readLasModelFromMemory(in.bytes(), "crs.las");
  const fs::path dir = test::scratchDir("las_crs");
  writeModel(dir / "crs.ply", m);  // and through a PLY file
  writeModel(dir / "crs.las", readModel(dir / "crs.ply"));
  const std::string out = readBytes(dir / "crs.las");
  EXPECT_EQ(get<uint16_t>(out, 6) & 0x10, 0x10);  // WKT
  const HybridModel r = readModel(dir / "crs.las");
  std::vector<std::string> crs;
  for (const std::string& c : r.comments)
    if (c.rfind("linesurf_las_crs ", 0) == 0) crs.push_back(c);
  ASSERT_EQ(crs.size(), 2u);
  EXPECT_EQ(crs[0], "linesurf_las_crs 34735 0100010000000100ff00");
  EXPECT_NE(out.find(wkt), std::string::npos);
  EXPECT_EQ(out.find("dropped"), std::string::npos);
}

TEST(LasRoundTrip, FuzzCorpusFilesRead) {
  // Written by a separate encoder (a Python script): formats 0, 1, 3, 7, 10 of LAS 1.2-1.4.
  const fs::path dir = fs::path(LINESURF_SOURCE_DIR) / "tests" / "fuzz" / "corpus_las";
  EXPECT_EQ(readModel(dir / "format0_v12.las").pointProperties.at("classification"), (std::vector<float>{2, 2, 6}));
  EXPECT_EQ(readModel(dir / "format1_v13.las").points[1].position, Vec3f(0.04f, 0.05f, 0.06f));
  const HybridModel c = readModel(dir / "format3_rgb16.las");
  EXPECT_EQ(c.points[0].color[0], 1.0f);
  EXPECT_EQ(c.points[3].color[0], 9.0f / 65535.0f);
  const HybridModel e = readModel(dir / "format7_extra_bytes.las");
  ASSERT_EQ(e.points.size(), 3u);
  EXPECT_TRUE(e.attributes.normals && e.attributes.radii);
  EXPECT_EQ(e.points[1].normal, Vec3f(0, 1, 0));
  EXPECT_EQ(e.points[2].radius, 1.0f);
  EXPECT_EQ(e.comments.at(0), "source: corpus");
  EXPECT_EQ(e.comments.at(1), "second");
  // The centre of the records, (25, 25, 0) steps of 1 mm.
  EXPECT_LT((modelOrigin(e) - Vec3d(500000.025, 5000000.025, 0)).cwiseAbs().maxCoeff(), 1e-6);
  const HybridModel t = readModel(dir / "format10_v14.las");
  EXPECT_EQ(t.pointProperties.at("classification"), (std::vector<float>{200, 201}));
  EXPECT_EQ(t.points[1].color[2], 6.0f / 255.0f);
}

TEST(LasColour, EightBitValuesInSixteenBitFields) {
  LasBuilder in;
  in.format = 2;
  in.points.resize(3);
  in.points[0].rgb = {255, 0, 128};
  in.points[1].rgb = {10, 20, 30};
  const HybridModel m = readLasModelFromMemory(in.bytes(), "c8.las");
  ASSERT_TRUE(m.attributes.colors);
  EXPECT_EQ(m.points[0].color[0], 1.0f);
  EXPECT_EQ(m.points[0].color[2], 128.0f / 255.0f);
  EXPECT_EQ(m.points[1].color[1], 20.0f / 255.0f);
}

TEST(LasColour, SixteenBitValuesKeptWhole) {
  LasBuilder in;
  in.format = 3;
  in.points.resize(2);
  in.points[0].rgb = {65535, 256, 0};
  in.points[1].rgb = {255, 12345, 40000};
  const HybridModel m = readLasModelFromMemory(in.bytes(), "c16.las");
  EXPECT_EQ(m.points[0].color[0], 1.0f);
  EXPECT_EQ(m.points[0].color[1], 256.0f / 65535.0f);
  EXPECT_EQ(m.points[1].color[0], 255.0f / 65535.0f);  // not 1: the file has 16-bit values
}

TEST(LasColour, AllZeroFieldsAreNoColour) {
  LasBuilder in;
  in.format = 7, in.minor = 4;
  in.points.resize(4);
  EXPECT_FALSE(readLasModelFromMemory(in.bytes(), "z.las").attributes.colors);
}

TEST(LasExtraBytes, NormalsRadiusScaledAndUndocumentedFields) {
  LasBuilder in;
  in.minor = 4, in.format = 6;
  in.extras = {{"NormalX", 9}, {"NormalY", 9}, {"NormalZ", 9}, {"radius", 3, 0x08, 0.001, 0}, {"", 0, 3},
               {"Reflectance db", 4, 0x18, 0.5, 10}};
  in.points.resize(2);
  for (int i = 0; i < 2; ++i) {
    std::vector<uint8_t> e(12 + 2 + 3 + 2);
    const float n[3] = {0, 0, i == 0 ? 1.0f : -1.0f};
    std::memcpy(e.data(), n, 12);
    const uint16_t r = uint16_t(25 * (i + 1));
    std::memcpy(e.data() + 12, &r, 2);
    const int16_t refl = int16_t(-4 + i);
    std::memcpy(e.data() + 17, &refl, 2);
    in.extraValues.push_back(e);
  }
  const HybridModel m = readLasModelFromMemory(in.bytes(), "e.las");
  ASSERT_TRUE(m.attributes.normals);
  EXPECT_EQ(m.points[1].normal, Vec3f(0, 0, -1));
  ASSERT_TRUE(m.attributes.radii);
  EXPECT_FLOAT_EQ(m.points[1].radius, 0.05f);
  ASSERT_EQ(m.pointProperties.count("Reflectance_db"), 1u);
  EXPECT_EQ(m.pointProperties.at("Reflectance_db")[0], 8.0f);  // -4 * 0.5 + 10
  EXPECT_EQ(m.pointProperties.size(), 1u);
}

TEST(LasWrite, HybridModelRefusedInOneLine) {
  HybridModel m = test::squareStrips();
  try {
    lasBytes(m, {}, "h.las");
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadParameter);
    EXPECT_EQ(std::string(e.what()), "h.las: a LAS file holds points only, and the model has 41 line segments (write .ply)");
  }
}

// ---------------------------------------------------------------------------------------------
// Bad input: one line naming the file and what is wrong.

LasBuilder smallFile(int format = 1) {
  LasBuilder b;
  b.format = format;
  b.points = randomPoints(3, format, 1, -1000, 1000);
  return b;
}

TEST(LasBadInput, NotLas) { EXPECT_EQ(errorOf("PLY!" + std::string(300, 'x')), "t.las: header: no 'LASF' signature at the start (not a LAS file)"); }

TEST(LasBadInput, TruncatedHeader) {
  EXPECT_EQ(errorOf(smallFile().bytes().substr(0, 100)),
            "t.las: header: the file has 100 bytes, fewer than the 227 of a LAS header (truncated)");
}

TEST(LasBadInput, TruncatedPoints) {
  const std::string b = smallFile().bytes();
  EXPECT_EQ(errorOf(b.substr(0, b.size() - 5)),
            "t.las: header: 3 points of 28 bytes from byte 227 do not fit the file's 306 bytes (truncated, or the point count "
            "is wrong)");
}

TEST(LasBadInput, PointCountLies) {
  std::string b = smallFile().bytes();
  put<uint32_t>(b, 107, 4000000000u);  // never allocated: checked against the file's size first
  EXPECT_NE(errorOf(b).find("t.las: header: 4000000000 points of 28 bytes from byte 227 do not fit"), std::string::npos);
  LasBuilder wide = smallFile(6);
  wide.minor = 4;
  b = wide.bytes();
  put<uint64_t>(b, 247, ~uint64_t(0));
  // oneLine shortens a 20-digit number.
  EXPECT_EQ(errorOf(b), "t.las: header: 1.84467e+19 points of 30 bytes from byte 375 do not fit the file's 465 bytes "
                        "(truncated, or the point count is wrong)");
}

TEST(LasBadInput, OffsetsLie) {
  std::string b = smallFile().bytes();
  put<uint32_t>(b, 96, 100);
  EXPECT_EQ(errorOf(b), "t.las: header: offset to point data 100 lies inside the 227-byte header");
  put<uint32_t>(b, 96, 1u << 30);
  EXPECT_EQ(errorOf(b), "t.las: header: offset to point data 1073741824 lies past the end of the file (311 bytes; truncated)");
  b = smallFile().bytes();
  put<uint16_t>(b, 94, 200);
  EXPECT_EQ(errorOf(b), "t.las: header: header size 200 is less than the 227 bytes of LAS 1.2");
  b = smallFile().bytes();
  put<uint32_t>(b, 100, 7);  // VLRs that are not there
  EXPECT_EQ(errorOf(b), "t.las: VLR 0: its header at byte 227 runs past the offset to point data (227): the header's count "
                        "of 7 VLRs is wrong");
}

TEST(LasBadInput, ExtendedVlrsLie) {
  LasBuilder s = smallFile(6);
  s.minor = 4;
  s.evlrs = {{"LASF_Projection", 2112, "PROJCS[]"}};
  std::string b = s.bytes();
  put<uint64_t>(b, 235, b.size() - 10);
  EXPECT_EQ(errorOf(b), "t.las: EVLR 0: its header at byte 523 runs past the end of the file (533 bytes): the header's start or "
                        "count of extended VLRs is wrong");
  b = s.bytes();
  put<uint64_t>(b, 20 + get<uint64_t>(b, 235), 1000);
  EXPECT_EQ(errorOf(b), "t.las: EVLR 0: its 1000 bytes at byte 525 run past the end of the file (533 bytes)");
}

TEST(LasBadInput, UnknownPointFormat) {
  std::string b = smallFile().bytes();
  put<uint8_t>(b, 104, 11);
  EXPECT_EQ(errorOf(b), "t.las: header: unknown point data format 11 (LAS defines 0-10)");
}

TEST(LasBadInput, RecordShorterThanItsFormat) {
  LasBuilder s = smallFile(3);
  s.recordLength = 30;
  EXPECT_EQ(errorOf(s.bytes()), "t.las: header: point record length 30 is shorter than the 34 bytes of point data format 3");
}

TEST(LasBadInput, ExtraBytesThatDoNotFitTheRecord) {
  LasBuilder s = smallFile(6);
  s.minor = 4;
  s.extras = {{"nx", 9}, {"ny", 9}, {"nz", 10}};
  s.recordLength = 30 + 12;
  EXPECT_EQ(errorOf(s.bytes()), "t.las: VLR 0: extra-bytes descriptors 0-2 need 46 bytes a point, the point record has 42 "
                                "(format 6: 30 standard bytes)");
  s.extras = {{"odd", 42}};
  s.recordLength = -1;
  EXPECT_EQ(errorOf(s.bytes()), "t.las: VLR 0: extra-bytes descriptor 0 ('odd') has unknown data type 42");
}

TEST(LasBadInput, CompressedLaz) {
  std::string b = smallFile().bytes();
  put<uint8_t>(b, 104, uint8_t(0x80 | 3));
  EXPECT_EQ(errorOf(b), "t.las: header: the points are compressed (LAZ); decompress it first, e.g. with laszip/PDAL, to .las");
  LasBuilder v = smallFile();
  v.vlrs = {{"laszip encoded", 22204, "x"}};
  EXPECT_EQ(errorOf(v.bytes()), "t.las: VLR 0: the points are compressed (LAZ); decompress it first, e.g. with laszip/PDAL, to .las");
}

TEST(LasBadInput, CliNamesTheFileAndWritesNothing) {
  const fs::path dir = test::scratchDir("las_bad_cli");
  std::string trunc = smallFile().bytes();
  trunc.resize(trunc.size() - 1);
  writeBytes(dir / "trunc.las", trunc);
  writeBytes(dir / "scan.laz", smallFile().bytes());
  const std::string out = (dir / "out.ply").string();
  test::CliResult r = test::runCli("convert '" + (dir / "trunc.las").string() + "' '" + out + "'");
  EXPECT_EQ(r.exitCode, 2) << r.out;
  EXPECT_EQ(r.out, (dir / "trunc.las").string() +
                       ": header: 3 points of 28 bytes from byte 227 do not fit the file's 310 bytes (truncated, or the point "
                       "count is wrong)\n");
  r = test::runCli("normals '" + (dir / "scan.laz").string() + "' -o '" + out + "'");
  EXPECT_EQ(r.exitCode, 2) << r.out;
  EXPECT_EQ(r.out, (dir / "scan.laz").string() + ": LAZ is compressed LAS; decompress it first, e.g. with laszip/PDAL, to .las\n");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 2);  // no temporary left
}

TEST(LasCli, InfoConvertAndNormals) {
  const fs::path dir = test::scratchDir("las_cli");
  LasBuilder in;
  in.format = 3;
  in.offset = {600000, 4000000, 0};
  // A gently curved 30 x 30 patch, 0.1 m apart.
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) {
      LasPoint p;
      p.xyz = {100 * i, 100 * j, (i - 15) * (i - 15) + (j - 15) * (j - 15)};
      p.rgb = {uint16_t(2000 * i), 300, uint16_t(1000 * j)};
      in.points.push_back(p);
    }
  writeBytes(dir / "tile.las", in.bytes());
  auto q = [](const fs::path& p) { return "'" + p.string() + "'"; };
  test::CliResult r = test::runCli("info " + q(dir / "tile.las"));
  EXPECT_EQ(r.exitCode, 0) << r.out;
  EXPECT_NE(r.out.find("900"), std::string::npos) << r.out;
  r = test::runCli("-q normals " + q(dir / "tile.las") + " -o " + q(dir / "n.ply"));
  ASSERT_EQ(r.exitCode, 0) << r.out;
  r = test::runCli("-q convert " + q(dir / "n.ply") + " " + q(dir / "n.las"));
  ASSERT_EQ(r.exitCode, 0) << r.out;
  const std::string src = in.bytes(), out = readBytes(dir / "n.las");
  const HybridModel n = readModel(dir / "n.las");
  EXPECT_TRUE(n.attributes.normals);
  EXPECT_TRUE(n.attributes.colors);
  // normals keeps the point order: the records come back as they were.
  const auto [so, sl] = recordsOf(src);
  const auto [oo, ol] = recordsOf(out);
  size_t differ = 0;
  for (size_t i = 0; i < in.points.size(); ++i) differ += src.substr(so + i * sl, 12) != out.substr(oo + i * ol, 12);
  EXPECT_EQ(differ, 0u);
}

TEST(LasCli, NormalsCleanAndSmoothWriteLasBitExact) {
  const fs::path dir = test::scratchDir("las_cli_out");
  LasBuilder in;
  in.format = 3;
  in.offset = {500000, 5000000, 100};  // a UTM-like tile far from the origin
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) {
      LasPoint p;
      p.xyz = {100 * i, 100 * j, (i - 15) * (i - 15) + (j - 15) * (j - 15)};
      p.rgb = {uint16_t(2000 * i), 300, uint16_t(1000 * j)};
      in.points.push_back(p);
    }
  writeBytes(dir / "tile.las", in.bytes());
  auto q = [](const fs::path& p) { return "'" + p.string() + "'"; };
  const std::string src = in.bytes();
  const auto [so, sl] = recordsOf(src);
  test::CliResult r = test::runCli("-q normals " + q(dir / "tile.las") + " -o " + q(dir / "n.las"));
  ASSERT_EQ(r.exitCode, 0) << r.out;
  // The same normals and radii as the PLY output, through LAS 1.4 extra bytes.
  r = test::runCli("-q normals " + q(dir / "tile.las") + " -o " + q(dir / "n.ply"));
  ASSERT_EQ(r.exitCode, 0) << r.out;
  const HybridModel nl = readModel(dir / "n.las"), np = readModel(dir / "n.ply");
  ASSERT_TRUE(nl.attributes.normals);
  ASSERT_TRUE(nl.attributes.radii);
  ASSERT_EQ(nl.points.size(), np.points.size());
  EXPECT_EQ(modelOrigin(nl), modelOrigin(np));
  size_t differ = 0;
  for (size_t i = 0; i < np.points.size(); ++i)
    differ += nl.points[i].normal != np.points[i].normal || nl.points[i].radius != np.points[i].radius ||
              nl.points[i].position != np.points[i].position;
  EXPECT_EQ(differ, 0u);
  // Point order kept: the integer X Y Z records come back bit-exact.
  const std::string out = readBytes(dir / "n.las");
  const auto [oo, ol] = recordsOf(out);
  differ = 0;
  for (size_t i = 0; i < in.points.size(); ++i) differ += src.substr(so + i * sl, 12) != out.substr(oo + i * ol, 12);
  EXPECT_EQ(differ, 0u);
  r = test::runCli("-q clean " + q(dir / "tile.las") + " -o " + q(dir / "c.las"));
  ASSERT_EQ(r.exitCode, 0) << r.out;
  EXPECT_EQ(modelOrigin(readModel(dir / "c.las")), modelOrigin(np));
  r = test::runCli("-q smooth " + q(dir / "tile.las") + " -o " + q(dir / "s.las"));
  ASSERT_EQ(r.exitCode, 0) << r.out;
  const HybridModel s = readModel(dir / "s.las");
  EXPECT_EQ(s.points.size(), in.points.size());
  // Smoothing moves the points, so the origin (the centre of the records' range) moves with
  // them; it stays far from zero, and object-space points stay within 1 m of the input's.
  EXPECT_LT((modelOrigin(s) - modelOrigin(np)).norm(), 1.0);
}

TEST(LasCli, NormalsOfAHybridRefusesLasInOneLine) {
  const fs::path dir = test::scratchDir("las_cli_hybrid");
  HybridModel m;
  for (int i = 0; i < 40; ++i) {
    Point p;
    p.position = Vec3f(float(i % 7), float(i / 7), 0.1f * float(i % 3));
    m.points.push_back(p);
  }
  Segment s;
  s.p0 = Vec3f(0, 0, 0), s.p1 = Vec3f(1, 0, 0), s.normal = Vec3f(0, 0, 1);
  m.segments.push_back(s);
  writeModel(dir / "h.ply", m);
  const fs::path out = dir / "h.las";
  test::CliResult r = test::runCli("-q normals '" + (dir / "h.ply").string() + "' -k 8 -o '" + out.string() + "'");
  EXPECT_EQ(r.exitCode, 1) << r.out;
  EXPECT_EQ(r.out, out.string() + ": a LAS file holds points only, and the model has 1 line segments (write .ply)\n");
  EXPECT_FALSE(fs::exists(out));
}

TEST(LasBadInput, OutOfCoreRefusesLasInOneLine) {
  const fs::path dir = test::scratchDir("las_bad_ooc");
  writeBytes(dir / "tile.las", smallFile().bytes());
  const fs::path out = dir / "n.ply";
  test::CliResult r = test::runCli("-q normals '" + (dir / "tile.las").string() + "' --out-of-core -o '" + out.string() + "'");
  EXPECT_EQ(r.exitCode, 2) << r.out;
  EXPECT_EQ(r.out, (dir / "tile.las").string() +
                       ": the out-of-core path does not stream LAS yet: raise --max-mb to read it in memory, or 'linesurf "
                       "convert' it to binary .ply first\n");
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir), fs::directory_iterator()), 1);  // no tile folder, no temporary
}

TEST(LasShared, LionReadsDirectly) {
  LINESURF_REQUIRE_SHARED_DATA();
  const fs::path lion = test::sharedData() / "lion_takanawa.las";
  if (!fs::exists(lion)) GTEST_SKIP() << "lion_takanawa.las not in the shared data";
  const HybridModel m = readModel(lion);
  EXPECT_EQ(m.points.size(), 341989u);
  EXPECT_TRUE(m.attributes.colors);
  EXPECT_EQ(modelOrigin(m), Vec3d::Zero());  // a statue near the origin needs none
  // Written back in its own format: X Y Z and RGB of every record bit-exact.
  const std::string src = readBytes(lion);
  const std::string out = lasBytes(m, {.pointFormat = 2}, "lion.las");
  const auto [so, sl] = recordsOf(src);
  const auto [oo, ol] = recordsOf(out);
  size_t differ = 0;
  for (size_t i = 0; i < m.points.size(); ++i)
    differ += src.substr(so + i * sl, 12) != out.substr(oo + i * ol, 12) || src.substr(so + i * sl + 20, 6) != out.substr(oo + i * ol + 20, 6);
  EXPECT_EQ(differ, 0u);
}

}  // namespace
}  // namespace linesurf
