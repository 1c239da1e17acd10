// Every file in tests/data/bad (made by make_bad.py) is rejected with "PATH: WHERE: WHAT", and
// `linesurf info FILE` exits 2 with that one line on stderr.
#include <gtest/gtest.h>

#include <sstream>

#include "linesurf/core/error.h"
#include "linesurf/io/model_io.h"
#include "linesurf/io/model_stats.h"
#include "test_util.h"

using namespace linesurf;

namespace {

/// Loads `name` from tests/data/bad the way `linesurf info` does and returns the error message.
std::string errorOf(const std::string& name) {
  const std::string path = (test::testData() / "bad" / name).string();
  try {
    summarizeFile(path);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadInput) << e.what();
    return e.what();
  }
  return "(no error)";
}

/// The message must be exactly "PATH: " + expected (+ anything after), and the CLI must agree.
void expectBad(const std::string& name, const std::string& expected) {
  const std::string path = (test::testData() / "bad" / name).string();
  const std::string msg = errorOf(name);
  EXPECT_EQ(msg.rfind(path + ": " + expected, 0), 0u) << "message: " << msg << "\nexpected: " << path << ": " << expected;
  test::CliResult r = test::runCli("info '" + path + "'");
  EXPECT_EQ(r.exitCode, 2) << r.out;
  EXPECT_EQ(r.out, msg + "\n");  // one line, nothing else
}

}  // namespace

#define BAD_FILE_TEST(Name, file, expected) \
  TEST(BadFiles, Name) { expectBad(file, expected); }

BAD_FILE_TEST(EmptyFile, "empty.ply", "line 1: empty file")
BAD_FILE_TEST(NotPly, "not_ply.ply", "line 1: not a PLY file (the first line must be 'ply', found 'hello world')")
BAD_FILE_TEST(UnknownFormat, "unknown_format.ply", "line 2: unknown format 'binary_middle_endian'")
BAD_FILE_TEST(MissingEndHeader, "missing_end_header.ply", "line 7: missing end_header")
BAD_FILE_TEST(NegativeCount, "negative_count.ply", "line 3: negative element count '-5'")
BAD_FILE_TEST(NonNumericCount, "non_numeric_count.ply", "line 3: element count 'lots' is not a non-negative integer")
BAD_FILE_TEST(UnsupportedType, "unsupported_type.ply", "line 4: unsupported property type 'int64'")
BAD_FILE_TEST(FloatListCount, "float_list_count.ply", "line 8: list length type must be an integer type, not 'float'")
BAD_FILE_TEST(MissingX, "missing_x.ply", "line 3: element vertex has no property 'x'")
BAD_FILE_TEST(PartialNormals, "partial_normals.ply",
              "line 3: element vertex has some but not all of the properties 'nx ny nz' (no 'nz')")
BAD_FILE_TEST(PropertyBeforeElement, "property_before_element.ply", "line 3: property before any element")
BAD_FILE_TEST(UnknownKeyword, "unknown_keyword.ply", "line 7: unknown header keyword 'vertex'")
BAD_FILE_TEST(DuplicateProperty, "duplicate_property.ply", "line 7: property 'x' declared twice in element 'vertex'")
BAD_FILE_TEST(NoVertexElement, "no_vertex_element.ply", "line 5: no 'vertex' or 'segment' element")
BAD_FILE_TEST(SegmentMissingX1, "segment_missing_x1.ply", "line 7: element segment has no property 'x1'")
BAD_FILE_TEST(TruncatedBinary, "truncated_binary.ply",
              "element vertex 5: truncated binary body: the header declares 10 vertex rows of at least 12 bytes, "
              "but only 66 bytes are left")
BAD_FILE_TEST(AbsurdCount, "absurd_count.ply",
              "element vertex 1: truncated binary body: the header declares 4000000000 vertex rows")
BAD_FILE_TEST(AbsurdCountAscii, "absurd_count_ascii.ply",
              "line 3: element vertex count 999999999999 is larger than the file could hold")
BAD_FILE_TEST(AbsurdListLength, "absurd_list_length.ply",
              "element face 0: truncated binary body: property 'vertex_indices' needs 17179869120 bytes")
BAD_FILE_TEST(NonNumericToken, "non_numeric_token.ply",
              "line 9: element vertex 1: 'abc' is not a number (property 'y')")
BAD_FILE_TEST(NanCoordinate, "nan_coordinate.ply", "line 9: NaN value in property 'x' of element vertex 1")
BAD_FILE_TEST(InfCoordinateBinary, "inf_coordinate_binary.ply",
              "element vertex 2: infinite value in property 'z'")
BAD_FILE_TEST(FaceIndexOutOfRange, "face_index_out_of_range.ply",
              "line 14: face 1 vertex index 7 out of range (the file has 3 vertices)")
BAD_FILE_TEST(NegativeFaceIndex, "negative_face_index.ply", "element face 0: face 0 vertex index -1 out of range")
BAD_FILE_TEST(FaceTwoVertices, "face_two_vertices.ply", "line 13: face 0 has 2 vertices (at least 3 needed)")
BAD_FILE_TEST(TooFewValues, "too_few_values.ply",
              "line 9: element vertex 1: too few values on the line (property 'z' missing)")
BAD_FILE_TEST(TooManyValues, "too_many_values.ply", "line 8: element vertex 0: too many values on the line")
BAD_FILE_TEST(WrongCountExtraData, "wrong_count_extra_data.ply",
              "line 10: unexpected data after the last element (wrong element counts?)")
BAD_FILE_TEST(WrongCountBinaryExtra, "wrong_count_binary_extra.ply",
              "byte 127: 12 bytes of unexpected data after the last element")
BAD_FILE_TEST(FileEndsEarlyAscii, "file_ends_early_ascii.ply",
              "line 10: file ends at element vertex 2 (the header declares 4 rows)")
BAD_FILE_TEST(IntOutOfRange, "int_out_of_range.ply", "line 11: element vertex 0: value '300' out of range for uchar")
BAD_FILE_TEST(NegativeListLength, "negative_list_length.ply", "line 13: element face 0: negative list length -1")
BAD_FILE_TEST(TexcoordCountMismatch, "texcoord_count_mismatch.ply",
              "line 14: face 0 has 4 texcoord values for 3 corners (expected 6)")
BAD_FILE_TEST(MissingTexture, "missing_texture.ply", "line 3: texture file 'nothere.png' not found beside the PLY")
BAD_FILE_TEST(XyzNonNumeric, "non_numeric.xyz", "line 3: 'x' is not a number")
BAD_FILE_TEST(XyzWrongColumns, "wrong_columns.xyz", "line 2: expected 3 (x y z) or 6 (x y z nx ny nz) numbers, found 4")
BAD_FILE_TEST(XyzEmpty, "empty.xyz", "line 2: no points in the file")
BAD_FILE_TEST(ObjFaceOutOfRange, "face_out_of_range.obj", "face 1: vertex index out of range (the file has 3 vertices)")
BAD_FILE_TEST(UnknownExtension, "model.stl", "unknown file extension '.stl' (supported: .ply, .obj, .xyz, .las)")
BAD_FILE_TEST(Directory, "directory.ply", "is a directory, not a file")
BAD_FILE_TEST(NonexistentFile, "no_such_file.ply", "no such file")

TEST(BadFiles, EveryFileInTheFolderHasATest) {
  // Keep this list in step with make_bad.py: a new bad file needs a test above.
  size_t files = 0;
  for (auto& e : std::filesystem::directory_iterator(test::testData() / "bad"))
    if (e.path().filename() != "make_bad.py") ++files;
  EXPECT_EQ(files, 40u);
}

TEST(BadFiles, MemoryReaderGivesTheSameMessages) {
  try {
    readPlyModelFromMemory("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n", "mem");
    FAIL();
  } catch (const Error& e) {
    EXPECT_STREQ(e.what(), "mem: line 3: element vertex has no property 'y'");
  }
}
