#pragma once
// Helpers shared by the tests: paths to bundled and shared data, running the CLI.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <unistd.h>

#include "linesurf/core/image.h"
#include "linesurf/core/model.h"

namespace linesurf::test {

/// The largest difference of any channel (alpha included) between two images of equal size.
inline float maxAbsDiff(const Image& a, const Image& b) {
  float m = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) m = std::max(m, (a.pixels[i] - b.pixels[i]).cwiseAbs().maxCoeff());
  return m;
}

/// A square 2 x 2 in the plane z = 0 as 41 strips along x, spacing h = 0.05 in y, normal +z, grey,
/// radius radiusScale x h.
inline HybridModel squareStrips(float radiusScale = 1) {
  HybridModel m;
  const int n = 41;
  const float h = 2.0f / float(n - 1);
  for (int j = 0; j < n; ++j) {
    Segment s;
    const float y = -1 + float(j) * h;
    s.p0 = Vec3f(-1, y, 0), s.p1 = Vec3f(1, y, 0), s.normal = Vec3f(0, 0, 1), s.radius = radiusScale * h;
    s.color = Color(0.8f, 0.8f, 0.8f, 1);
    m.segments.push_back(s);
  }
  m.attributes = {true, false, true, false};
  return m;
}

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
