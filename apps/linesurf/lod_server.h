#pragma once
// Serves the level-of-detail viewer (`linesurf view MODEL.lod`) from localhost: the page and the
// hierarchy file, read by byte ranges. The only place that includes cpp-httplib (lod_server.cpp).
// What a client can make it do is bounded (docs/decisions.md, "Streaming viewer of hierarchies"):
// the ranges of a request, the time its header may take, the connections served and waiting.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>

namespace linesurf::cli {

/// The most ranges one request may ask for once overlapping and adjacent ones are merged; more
/// are refused with 416 (RFC 9110 §15.5.17: "an excessive number of small or overlapping ranges").
inline constexpr size_t kMaxRequestRanges = 16;
/// The default of LodServeOptions::headerSeconds (`view --header-timeout`).
inline constexpr double kDefaultHeaderSeconds = 5;

struct LodServeOptions {
  std::string host = "127.0.0.1";
  int port = 8080;  ///< 0: any free port
  /// A request's line and headers must have arrived this long after its connection was accepted
  /// (a later request on a kept-alive connection: after its first byte), else the connection is
  /// closed; waiting for a free thread counts.
  double headerSeconds = kDefaultHeaderSeconds;
  size_t threads = 8;  ///< connections served at once
  size_t queued = 256;  ///< connections waiting for a thread; one more is closed at once
  std::string page;  ///< the HTML served at /
  std::filesystem::path file;  ///< served at /model.lod with HTTP Range support
  /// Called once the server listens, with the port it took.
  std::function<void(int port)> listening;
  /// Called with what a page reports of its first view (GET /report?first=MS&complete=MS&...):
  /// times measured by the browser's own clock from the page's start.
  std::function<void(const std::string& line)> report;
};

/// Serves until SIGINT, SIGTERM or SIGHUP, then returns (further ones, while it stops or after,
/// are absorbed: the caller exits 0). Throws Error: Io when the address cannot be bound or the file
/// not opened; BadParameter when this linesurf was built without cpp-httplib.
void serveLod(const LodServeOptions& options);

/// Whether `host` names this machine's loopback only: "localhost", 127.0.0.0/8, ::1 (also as
/// ::ffff:127.x.y.z). Anything else (0.0.0.0, ::, a name, another address) may be reachable from
/// other machines.
bool isLoopbackHost(const std::string& host);

}  // namespace linesurf::cli
