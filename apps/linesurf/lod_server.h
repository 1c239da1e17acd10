#pragma once
// Serves the level-of-detail viewer (`linesurf view MODEL.lod`) from localhost: the page and the
// hierarchy file, read by byte ranges. The only place that includes cpp-httplib (lod_server.cpp).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

namespace linesurf::cli {

struct LodServeOptions {
  std::string host = "127.0.0.1";
  int port = 8080;  ///< 0: any free port
  std::string page;  ///< the HTML served at /
  std::filesystem::path file;  ///< served at /model.lod with HTTP Range support
  /// Called once the server listens, with the port it took.
  std::function<void(int port)> listening;
  /// Called with what a page reports of its first view (GET /report?first=MS&complete=MS&...):
  /// times measured by the browser's own clock from the page's start.
  std::function<void(const std::string& line)> report;
};

/// Serves until SIGINT or SIGTERM, then returns. Throws Error: Io when the address cannot be
/// bound or the file not opened; BadParameter when this linesurf was built without cpp-httplib.
void serveLod(const LodServeOptions& options);

}  // namespace linesurf::cli
