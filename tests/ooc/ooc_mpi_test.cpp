// `mpirun -n 3 linesurf normals` (and the extractions) against one process: the same bytes.
// Skipped where mpirun is missing or the CLI was built without MPI (an optional dependency).
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "linesurf/ooc/synthetic_scan.h"
#include "test_util.h"

namespace linesurf {
namespace {

namespace fs = std::filesystem;

test::CliResult shell(const std::string& cmd) {
  test::CliResult r;
  FILE* pipe = popen((cmd + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  size_t n;
  while ((n = fread(buf.data(), 1, buf.size(), pipe)) > 0) r.out.append(buf.data(), n);
  const int status = pclose(pipe);
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

TEST(OocMpi, ThreeRanksWriteWhatOneProcessWrites) {
  if (shell("command -v mpirun").exitCode != 0) GTEST_SKIP() << "mpirun not found (Debian openmpi-bin)";
  const fs::path d = test::scratchDir("ooc_mpi");
  ooc::SyntheticScanOptions s;
  s.count = 200000;
  s.seed = 9;
  ooc::writeSyntheticScan(d / "scan.ply", s);
  const std::string in = "'" + (d / "scan.ply").string() + "'";
  const auto one = test::runCli("normals " + in + " -o '" + (d / "one.ply").string() + "' --tiles 16");
  ASSERT_EQ(one.exitCode, 0) << one.out;
  // root in containers: Open MPI refuses root without these; 3 ranks on 2 cores: oversubscribe.
  const std::string mpirun = "mpirun --allow-run-as-root --oversubscribe -n 3 ";
  const auto three = shell(mpirun + LINESURF_CLI + " normals " + in + " -o '" + (d / "three.ply").string() + "' --tiles 16 -j 1");
  if (three.out.find("built without MPI") != std::string::npos) GTEST_SKIP() << "linesurf built without MPI";
  ASSERT_EQ(three.exitCode, 0) << three.out;
  EXPECT_NE(three.out.find("3 MPI ranks"), std::string::npos) << three.out;
  EXPECT_TRUE(slurp(d / "three.ply") == slurp(d / "one.ply"));
  EXPECT_FALSE(fs::exists(d / "three.ply.tiles"));

  // The (ε,δ) extraction too.
  const auto eOne = test::runCli("extract eps-delta " + in + " -o '" + (d / "e1.ply").string() + "' --provenance --tiles 16");
  ASSERT_EQ(eOne.exitCode, 0) << eOne.out;
  const auto eThree = shell(mpirun + LINESURF_CLI + " extract eps-delta " + in + " -o '" + (d / "e3.ply").string() +
                            "' --provenance --tiles 16 -j 1");
  ASSERT_EQ(eThree.exitCode, 0) << eThree.out;
  EXPECT_TRUE(slurp(d / "e3.ply") == slurp(d / "e1.ply"));

  // And the shape approximation, with the clustering that draws random seeds.
  const std::string sa = " --clustering hierarchical --provenance --tiles 16";
  const auto sOne = test::runCli("extract shape-approx " + in + " -o '" + (d / "s1.ply").string() + "'" + sa);
  ASSERT_EQ(sOne.exitCode, 0) << sOne.out;
  const auto sThree =
      shell(mpirun + LINESURF_CLI + " extract shape-approx " + in + " -o '" + (d / "s3.ply").string() + "'" + sa + " -j 1");
  ASSERT_EQ(sThree.exitCode, 0) << sThree.out;
  EXPECT_TRUE(slurp(d / "s3.ply") == slurp(d / "s1.ply"));

  // A bad input stops every rank with the reader's exit code and leaves no output.
  const std::string bytes = slurp(d / "scan.ply");
  std::ofstream(d / "cut.ply", std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  const auto bad = shell(mpirun + LINESURF_CLI + " normals '" + (d / "cut.ply").string() + "' -o '" + (d / "bad.ply").string() + "'");
  EXPECT_EQ(bad.exitCode, 2) << bad.out;
  EXPECT_NE(bad.out.find("truncated binary body"), std::string::npos) << bad.out;
  EXPECT_FALSE(fs::exists(d / "bad.ply"));
  // ...said once, by one rank, not once a rank.
  auto count = [](const std::string& text, const std::string& what) {
    size_t n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_EQ(count(bad.out, "truncated binary body"), 1u) << bad.out;
  const auto missing = shell(mpirun + LINESURF_CLI + " normals '" + (d / "none.ply").string() + "' -o '" +
                             (d / "bad.ply").string() + "' --tiles 4");
  EXPECT_EQ(missing.exitCode, 2) << missing.out;
  EXPECT_EQ(count(missing.out, "none.ply: no such file"), 1u) << missing.out;
}

}  // namespace
}  // namespace linesurf
