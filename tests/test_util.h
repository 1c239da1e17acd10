#pragma once
// Helpers shared by the tests: paths to bundled and shared data, running the CLI.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include <unistd.h>

namespace linesurf::test {

/// tests/data inside the repository.
inline std::filesystem::path testData() { return std::filesystem::path(LINESURF_SOURCE_DIR) / "tests" / "data"; }
/// data/ inside the repository (bundled demo models).
inline std::filesystem::path bundledData() { return std::filesystem::path(LINESURF_SOURCE_DIR) / "data"; }

/// ../shared/data beside the repository (or $LINESURF_SHARED_DATA); empty when absent.
inline std::filesystem::path sharedData() {
  if (const char* env = std::getenv("LINESURF_SHARED_DATA")) return env;
  auto p = std::filesystem::path(LINESURF_SOURCE_DIR) / ".." / "shared" / "data";
  std::error_code ec;
  return std::filesystem::is_directory(p, ec) ? std::filesystem::canonical(p) : std::filesystem::path();
}

/// The folder of this test process's scratch folders: private to the process (its pid in the
/// name), so concurrent test runs from several checkouts never share files; removed at exit.
inline const std::filesystem::path& scratchRoot() {
  struct Root {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("linesurf_test_" + std::to_string(::getpid()));
    ~Root() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Root root;
  return root.path;
}

/// A fresh empty folder for one test's outputs.
inline std::filesystem::path scratchDir(const std::string& name) {
  auto p = scratchRoot() / name;
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p;
}

struct CliResult {
  int exitCode = -1;
  std::string out;  ///< stdout and stderr together
};
/// Runs the built CLI with `args` (shell-quoted by the caller), capturing its output.
CliResult runCli(const std::string& args);

}  // namespace linesurf::test

/// Skips the current test when ../shared/data is absent (fresh clone without shared models).
#define LINESURF_REQUIRE_SHARED_DATA()                                                        \
  do {                                                                                        \
    if (::linesurf::test::sharedData().empty())                                               \
      GTEST_SKIP() << "shared models not found (../shared/data absent): large-data test skipped"; \
  } while (0)
