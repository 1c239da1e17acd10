// Readers that agree and finish: a header of 200,000 properties is read (the header parser and
// the column lookups are linear: with a quadratic lookup this takes minutes, not a blink), and the
// two text formats read a value below float's range the same way (as 0).
#include <gtest/gtest.h>

#include <string>

#include "linesurf/core/error.h"
#include "linesurf/io/model_io.h"

using namespace linesurf;

TEST(PlyHeader, TwoHundredThousandPropertiesAreRead) {
  const int n = 200000;
  std::string h = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  std::string row = "1 2 3";
  for (int i = 0; i < n; ++i) {
    h += "property uchar p" + std::to_string(i) + "\n";
    row += " " + std::to_string(i % 256);
  }
  const HybridModel m = readPlyModelFromMemory(h + "end_header\n" + row + "\n", "many.ply");
  ASSERT_EQ(m.points.size(), 1u);
  EXPECT_EQ(m.pointProperties.size(), size_t(n));
  EXPECT_EQ(m.pointProperties.at("p199999").at(0), float(199999 % 256));
}

TEST(PlyHeader, ADuplicateAmongManyPropertiesIsFoundOnItsLine) {
  std::string h = "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n";
  for (int i = 0; i < 50000; ++i) h += "property uchar p" + std::to_string(i) + "\n";
  h += "property uchar p49999\nend_header\n";
  try {
    readPlyModelFromMemory(h, "dup.ply");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "dup.ply: line 50007: property 'p49999' declared twice in element 'vertex'");
  }
}

TEST(TextFormats, SubnormalAndUnderflowingValuesReadAsInAsciiPly) {
  for (const char* v : {"1e-320", "-1e-320", "1e-400", "1.4e-46"}) {
    const std::string xyzText = std::string(v) + " 0 0\n1 2 3\n";
    const std::string plyText = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
                                "property float z\nend_header\n" + xyzText;
    const HybridModel x = readXyzModelFromMemory(xyzText, "tiny.xyz");
    const HybridModel p = readPlyModelFromMemory(plyText, "tiny.ply");
    EXPECT_EQ(x.points[0].position.x(), p.points[0].position.x()) << v;
    EXPECT_EQ(x.points[0].position.x(), 0.0f) << v;
  }
  // Overflow stays an error in both.
  EXPECT_THROW(readXyzModelFromMemory("1e400 0 0\n", "big.xyz"), Error);
  EXPECT_THROW(readPlyModelFromMemory("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                                      "property float z\nend_header\n1e400 0 0\n", "big.ply"),
               Error);
}

TEST(PlyHeader, AnExtraPropertyTheWriterCannotNameIsRefusedOnItsLine) {
  try {
    readPlyModelFromMemory("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                           "property float z\nproperty float a/b\nend_header\n0 0 0 1\n", "p.ply");
    FAIL() << "accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadInput);
    EXPECT_STREQ(e.what(), "p.ply: line 7: property name 'a/b' may hold only letters, digits, '_', '-' and '.'");
  }
}
