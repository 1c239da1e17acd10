// The HTTP side of `linesurf view MODEL.lod` (lod_server.h). cpp-httplib is heavy to compile:
// this is its only translation unit.
#include "lod_server.h"

#include <fmt/format.h>

#include "linesurf/core/error.h"

#ifdef LINESURF_HAVE_HTTPLIB
#include <httplib.h>
#include <pthread.h>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#include "linesurf/core/read_only_file.h"
#endif

namespace linesurf::cli {

#ifdef LINESURF_HAVE_HTTPLIB
namespace {

// Blocks SIGINT and SIGTERM in this thread and every thread it starts (the server's pool), so
// that sigwait() receives them and the server stops cleanly instead of dying mid-response.
struct BlockStopSignals {
  sigset_t set{}, old{};
  BlockStopSignals() {
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set, &old);
  }
  ~BlockStopSignals() { pthread_sigmask(SIG_SETMASK, &old, nullptr); }
};

// cpp-httplib 0.11 applies a request's ranges to a content provider without checking them: a
// range past the end announced an absurd Content-Length and one reaching past it a length never
// sent. Clamps each range to the file (RFC 9110: the last byte at most size - 1; a suffix range of
// more than the file is the whole file); false when one cannot be satisfied (416). The request is
// the server's own non-const object, handed to handlers as const: adjusting it here is what lets
// the provider see valid offsets.
bool satisfiableRanges(httplib::Ranges& ranges, uint64_t size) {
  for (auto& r : ranges) {
    int64_t first = r.first, last = r.second;
    if (first < 0) {  // bytes=-N: the last N bytes
      if (last <= 0) return false;
      first = std::max<int64_t>(0, int64_t(size) - last);
      last = int64_t(size) - 1;
    } else {
      if (uint64_t(first) >= size || (last >= 0 && last < first)) return false;
      if (last < 0 || uint64_t(last) >= size) last = int64_t(size) - 1;
    }
    r = {first, last};
  }
  return true;
}

}  // namespace

void serveLod(const LodServeOptions& o) {
  // Opened once and read by pread from the server's threads (hierarchies are many GB: never read
  // whole; each range is copied through a small buffer as the socket takes it).
  auto file = std::make_shared<ReadOnlyFile>(o.file);
  if (!file->isOpen()) throw Error(Error::Kind::Io, o.file.string(), "", "cannot open the file");
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(o.file, ec);
  if (ec) throw Error(Error::Kind::Io, o.file.string(), "", "cannot read the file size");
  ::signal(SIGPIPE, SIG_IGN);  // a browser that closes a connection mid-range is no error
  BlockStopSignals blocked;

  httplib::Server server;
  server.set_keep_alive_timeout(1);  // stopping waits for idle keep-alive connections
  server.Get("/", [&o](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(o.page, "text/html; charset=utf-8");
  });
  server.Get("/model.lod", [file, size](const httplib::Request& req, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_header("Accept-Ranges", "bytes");
    if (!satisfiableRanges(const_cast<httplib::Request&>(req).ranges, size)) {
      res.status = 416;
      res.set_header("Content-Range", fmt::format("bytes */{}", size));
      return;
    }
    // cpp-httplib applies the request's Range to the provider: it asks for [offset, offset + length).
    res.set_content_provider(size, "application/octet-stream",
                             [file](size_t offset, size_t length, httplib::DataSink& sink) {
                               std::vector<char> buf(std::min<size_t>(length, size_t(1) << 20));
                               const size_t got = file->read(offset, buf.data(), buf.size());
                               if (got == 0) return false;  // the file shrank: the response ends short
                               return sink.write(buf.data(), got);
                             });
  });

  server.Get("/report", [&o](const httplib::Request& req, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    if (!o.report) return;
    // Numbers only (the page's own figures): nothing a page sends reaches the terminal unchecked.
    auto num = [&](const char* key) {
      const std::string v = req.get_param_value(key);
      return !v.empty() && v.size() < 24 && v.find_first_not_of("0123456789.") == std::string::npos ? v : std::string("?");
    };
    o.report(fmt::format("page: first frame {} ms, first complete view {} ms ({} splats in {} nodes, {} bytes fetched)",
                         num("first"), num("complete"), num("splats"), num("nodes"), num("bytes")));
  });

  int port = o.port;
  if (port == 0) port = server.bind_to_any_port(o.host);
  else if (!server.bind_to_port(o.host, port)) port = -1;
  if (port <= 0)
    throw Error(Error::Kind::Io, fmt::format("{}:{}", o.host, o.port), "",
                "cannot listen there (address in use, or not an address of this machine)");
  std::atomic<bool> ended{false};
  std::thread loop([&server, &ended] {
    server.listen_after_bind();
    ended = true;
  });
  while (!server.is_running() && !ended) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  if (ended) {
    loop.join();
    throw Error(Error::Kind::Io, fmt::format("{}:{}", o.host, port), "", "the server stopped at once");
  }
  if (o.listening) o.listening(port);
  int sig = 0;
  sigwait(&blocked.set, &sig);
  server.stop();
  loop.join();
}

#else

void serveLod(const LodServeOptions&) {
  throwBadParameter("view", "this linesurf was built without cpp-httplib, which serves .lod hierarchies; "
                            "install libcpp-httplib-dev and rebuild");
}

#endif

}  // namespace linesurf::cli
