// OutputTransaction (io/atomic_file.h): staged outputs appear only on commit, a transaction
// dropped without commit leaves every existing file as it was and no temporary file; an output
// onto an input or the same output twice is refused before anything is staged. Also oneLine().
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "linesurf/core/error.h"
#include "linesurf/io/atomic_file.h"
#include "test_util.h"

using namespace linesurf;
namespace fs = std::filesystem;

namespace {
std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}
size_t entries(const fs::path& d) {
  size_t n = 0;
  for ([[maybe_unused]] auto& e : fs::directory_iterator(d)) ++n;
  return n;
}
}  // namespace

TEST(OutputTransaction, RolledBackUnlessCommitted) {
  const fs::path d = test::scratchDir("transaction_rollback");
  writeFileAtomically(d / "a.txt", "old a");
  {
    OutputTransaction t;
    writeFileAtomically(d / "a.txt", "new a");
    writeFileAtomically(d / "b.txt", "new b");
    EXPECT_EQ(t.staged(), 2u);
    EXPECT_EQ(slurp(d / "a.txt"), "old a");  // nothing in place before commit
    EXPECT_FALSE(fs::exists(d / "b.txt"));
  }
  EXPECT_EQ(slurp(d / "a.txt"), "old a");
  EXPECT_EQ(entries(d), 1u);  // no temporary file left
}

TEST(OutputTransaction, CommitRenamesEveryOutput) {
  const fs::path d = test::scratchDir("transaction_commit");
  writeFileAtomically(d / "a.txt", "old a");
  {
    OutputTransaction t;
    writeFileAtomically(d / "a.txt", "new a");
    writeFileAtomically(d / "b.txt", "new b");
    t.commit();
    t.commit();  // idempotent
  }
  EXPECT_EQ(slurp(d / "a.txt"), "new a");
  EXPECT_EQ(slurp(d / "b.txt"), "new b");
  EXPECT_EQ(entries(d), 2u);
  writeFileAtomically(d / "c.txt", "direct");  // no transaction open: written at once
  EXPECT_EQ(slurp(d / "c.txt"), "direct");
}

TEST(OutputTransaction, RefusesAnInputAndTheSameOutputTwice) {
  const fs::path d = test::scratchDir("transaction_refuse");
  writeFileAtomically(d / "in.txt", "input");
  OutputTransaction t;
  noteInput(d / "in.txt");
  try {
    writeFileAtomically(d / "sub" / ".." / "in.txt", "clobber");  // missing folder in the path: Io
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::Io);
  }
  try {
    writeFileAtomically(d / "in.txt", "clobber");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadParameter);
    EXPECT_NE(std::string(e.what()).find("is also an input"), std::string::npos) << e.what();
  }
  writeFileAtomically(d / "out.txt", "one");
  try {
    writeFileAtomically(d / "." / "out.txt", "two");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), Error::Kind::BadParameter);
    EXPECT_NE(std::string(e.what()).find("written twice"), std::string::npos) << e.what();
  }
  EXPECT_EQ(t.staged(), 1u);
  EXPECT_EQ(slurp(d / "in.txt"), "input");
}

TEST(ErrorMessages, OneLinePrintableAndBrief) {
  EXPECT_EQ(oneLine("a\nb\0c"), "a\\nb");  // a C string stops at NUL: pass a view to keep it
  EXPECT_EQ(oneLine(std::string_view("a\nb\0c", 5)), "a\\nb\\0c");
  EXPECT_EQ(oneLine("caf\xC3\xA9 \xFF\x01"), "caf\xC3\xA9 \\xFF\\x01");  // valid UTF-8 kept
  std::string big = "value " + std::string("1") + std::string(308, '0') + ".000000 too large";
  EXPECT_EQ(oneLine(big), "value 1e+308 too large");
  EXPECT_EQ(oneLine("count 12345678901234567 ok"), "count 12345678901234567 ok");  // 17 digits kept
  const Error e(Error::Kind::BadInput, "f\n.ply", "line 1", "bad\tthing");
  EXPECT_STREQ(e.what(), "f\\n.ply: line 1: bad\\tthing");
}

TEST(OutputTransaction, AStagedFolderReplacesTheEarlierOneWholeOnlyAtCommit) {
  const fs::path d = test::scratchDir("txn_folder");
  fs::create_directories(d / "run" / "model");
  writeFileAtomically(d / "run" / "model" / "old.png", "old");
  writeFileAtomically(d / "run" / "results.json", "old results");
  {
    OutputTransaction t;
    makeOutputFolder(d / "run");                // exists: used as it is
    makeOutputFolder(d / "run" / "model", true);  // replaced whole at commit
    makeOutputFolder(d / "run" / "model" / "sub");
    writeFileAtomically(d / "run" / "model" / "sub" / "new.png", "new");
    writeFileAtomically(d / "run" / "results.json", "new results");
    // Nothing visible yet: the earlier run is whole.
    EXPECT_EQ(slurp(d / "run" / "model" / "old.png"), "old");
    EXPECT_FALSE(fs::exists(d / "run" / "model" / "sub"));
    EXPECT_EQ(slurp(d / "run" / "results.json"), "old results");
    EXPECT_EQ(stagedLocation(d / "run" / "model" / "x").parent_path().parent_path(), d / "run");
    t.commit();
  }
  EXPECT_FALSE(fs::exists(d / "run" / "model" / "old.png"));
  EXPECT_EQ(slurp(d / "run" / "model" / "sub" / "new.png"), "new");
  EXPECT_EQ(slurp(d / "run" / "results.json"), "new results");
  EXPECT_EQ(entries(d), 1u);  // no temporary folder left beside it
  EXPECT_EQ(entries(d / "run"), 2u);
}

TEST(OutputTransaction, AStagedFolderIsRemovedUnlessCommitted) {
  const fs::path d = test::scratchDir("txn_folder_rollback");
  fs::create_directories(d / "run" / "model");
  writeFileAtomically(d / "run" / "model" / "old.png", "old");
  {
    OutputTransaction t;
    makeOutputFolder(d / "new" / "deeper");  // neither exists: "new" is staged
    writeFileAtomically(d / "new" / "deeper" / "a.txt", "a");
    makeOutputFolder(d / "run" / "model", true);
    writeFileAtomically(d / "run" / "model" / "b.png", "b");
    EXPECT_FALSE(fs::exists(d / "new"));
  }
  EXPECT_FALSE(fs::exists(d / "new"));
  EXPECT_EQ(entries(d), 1u);
  EXPECT_EQ(entries(d / "run" / "model"), 1u);
  EXPECT_EQ(slurp(d / "run" / "model" / "old.png"), "old");
}

TEST(OutputTransaction, TemporaryNamesAreShortSoAnyLegalNameIsWritable) {
  const fs::path d = test::scratchDir("txn_long_name");
  const std::string name(255, 'x');
  OutputTransaction t;
  writeFileAtomically(d / name, "long");
  t.commit();
  EXPECT_EQ(slurp(d / name), "long");
  EXPECT_EQ(entries(d), 1u);
}

TEST(OutputTransaction, TheCleanupRegistryRemovesWhatIsStaged) {
  // What a signal handler runs: every staged file and folder goes, the earlier outputs stay.
  const fs::path d = test::scratchDir("txn_registry");
  writeFileAtomically(d / "kept.txt", "kept");
  OutputTransaction t;
  writeFileAtomically(d / "a.txt", "a");
  makeOutputFolder(d / "f");
  writeFileAtomically(d / "f" / "b.txt", "b");
  EXPECT_EQ(entries(d), 3u);  // kept.txt and two temporaries
  removeTemporaryOutputs();
  EXPECT_EQ(entries(d), 1u);
  EXPECT_EQ(slurp(d / "kept.txt"), "kept");
}
