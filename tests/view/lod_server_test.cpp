// `linesurf view MODEL.lod`'s server against clients that make it work for nothing: many ranges,
// headers that never end, more connections than it has threads, stop signals in a row, and an
// address other machines could reach. Plain POSIX sockets against the CLI; each test a few
// seconds at most (the header timeout is set to 1 s).
#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "linesurf/lod/lod.h"
#include "test_util.h"

namespace linesurf {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A hierarchy of a few hundred points (small enough that a whole-file answer is quick, with room
// for 40 disjoint ranges).
fs::path smallLod() {
  static const fs::path path = [] {
    HybridModel m;
    for (int i = 0; i < 300; ++i) {
      Point p;
      p.position = Vec3f(float(i % 20), float(i / 20), 0.0f);
      p.normal = Vec3f(0, 0, 1);
      p.radius = 0.5f;
      m.points.push_back(p);
    }
    m.attributes.normals = m.attributes.radii = true;
    const std::string bytes = lod::buildLod(m, ModelFrame{}, {.leafSize = 16, .grid = 4});
    const fs::path p = test::scratchDir("lod_server") / "small.lod";
    std::ofstream(p, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    return p;
  }();
  return path;
}

// `linesurf view FILE --port 0 -q ARGS...` in a child process with the signals at their default
// actions (as from a terminal); the port read from its "serving ... at http://HOST:PORT/" line.
class Served {
 public:
  explicit Served(const std::vector<std::string>& extra = {"--header-timeout", "1"}) {
    std::vector<std::string> all = {LINESURF_CLI, "view", smallLod().string(), "--port", "0", "-q"};
    all.insert(all.end(), extra.begin(), extra.end());
    std::vector<char*> argv;
    for (std::string& a : all) argv.push_back(a.data());
    argv.push_back(nullptr);
    int out[2];
    if (::pipe2(out, O_CLOEXEC) != 0) return;
    pid_ = ::fork();
    if (pid_ == 0) {  // only async-signal-safe calls until exec
      for (int s : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) ::signal(s, SIG_DFL);
      sigset_t none;
      sigemptyset(&none);
      ::sigprocmask(SIG_SETMASK, &none, nullptr);
      ::dup2(out[1], 1);
      ::dup2(out[1], 2);
      ::execv(argv[0], argv.data());
      ::_exit(127);
    }
    ::close(out[1]);
    out_ = out[0];
    std::string text;
    const auto start = Clock::now();
    while (secondsSince(start) < 20) {
      pollfd p{out_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char buf[512];
      const ssize_t n = ::read(out_, buf, sizeof buf);
      if (n <= 0) break;
      text.append(buf, size_t(n));
      const size_t at = text.find("serving ");
      const size_t colon = at == std::string::npos ? at : text.find(":", text.find("http://", at) + 7);
      const size_t slash = colon == std::string::npos ? colon : text.find("/ ", colon);
      if (slash != std::string::npos) {
        port_ = std::stoi(text.substr(colon + 1, slash - colon - 1));
        break;
      }
    }
    output_ = text;
  }
  ~Served() {
    if (pid_ > 0 && status_ < 0) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
    if (out_ >= 0) ::close(out_);
  }
  int port() const { return port_; }
  const std::string& output() const { return output_; }
  void signal(int sig) const { ::kill(pid_, sig); }
  /// The wait status once it ended, or -1 after `seconds`.
  int wait(double seconds) {
    const auto start = Clock::now();
    while (status_ < 0 && secondsSince(start) < seconds) {
      int st = 0;
      if (::waitpid(pid_, &st, WNOHANG) == pid_) status_ = st;
      else std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return status_;
  }

 private:
  pid_t pid_ = -1;
  int out_ = -1;
  int port_ = 0;
  int status_ = -1;
  std::string output_;
};

int connectTo(int port) {
  const int s = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(uint16_t(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(s, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(s);
    return -1;
  }
  return s;
}

void sendAll(int s, const std::string& data) {
  for (size_t at = 0; at < data.size();) {
    const ssize_t n = ::send(s, data.data() + at, data.size() - at, MSG_NOSIGNAL);
    if (n <= 0) return;
    at += size_t(n);
  }
}

// Everything the server sends on `s` until it closes the connection (or `seconds` pass).
std::string readUntilClosed(int s, double seconds) {
  std::string got;
  const auto start = Clock::now();
  while (secondsSince(start) < seconds) {
    pollfd p{s, POLLIN, 0};
    if (::poll(&p, 1, 20) <= 0) continue;
    char buf[65536];
    const ssize_t n = ::recv(s, buf, sizeof buf, 0);
    if (n <= 0) break;
    got.append(buf, size_t(n));
  }
  return got;
}

struct Response {
  int status = 0;
  std::string head, body;
};

Response parse(const std::string& raw) {
  Response r;
  const size_t end = raw.find("\r\n\r\n");
  if (raw.size() < 12 || end == std::string::npos) return r;
  r.status = std::atoi(raw.c_str() + 9);
  r.head = raw.substr(0, end);
  r.body = raw.substr(end + 4);
  return r;
}

// One GET of /model.lod with `range` (none when empty) on a fresh connection.
Response get(int port, const std::string& range, double seconds = 2.5) {
  const int s = connectTo(port);
  if (s < 0) return {};
  sendAll(s, "GET /model.lod HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n" +
                 (range.empty() ? "" : "Range: bytes=" + range + "\r\n") + "\r\n");
  Response r = parse(readUntilClosed(s, seconds));
  ::close(s);
  return r;
}

std::string headerValue(const Response& r, const std::string& key) {
  const size_t at = r.head.find("\r\n" + key + ": ");
  if (at == std::string::npos) return "";
  const size_t from = at + key.size() + 4;
  return r.head.substr(from, r.head.find("\r\n", from) - from);
}

// 2,000 copies of `0-` in a 6 KB request are one range: the file once, not 2,000 times. Overlapping
// and adjacent ranges merge; more than 16 disjoint ones are refused (416), as are ranges outside
// the file; a suffix range longer than the file is the whole file.
TEST(LodServer, RangesAreMergedAndBoundedByTheFile) {
  const uint64_t size = fs::file_size(smallLod());
  ASSERT_GT(size, 200u);
  Served server;
  ASSERT_GT(server.port(), 0) << server.output();

  std::string many = "0-";
  for (int i = 1; i < 2000; ++i) many += ",0-";
  const Response all = get(server.port(), many);
  EXPECT_EQ(all.status, 206) << all.head;
  EXPECT_EQ(headerValue(all, "Content-Length"), std::to_string(size)) << all.head;
  EXPECT_EQ(headerValue(all, "Content-Range"), "bytes 0-" + std::to_string(size - 1) + "/" + std::to_string(size));
  EXPECT_EQ(all.body.size(), size);

  const Response merged = get(server.port(), "10-19,0-9,15-40,41-41");
  EXPECT_EQ(merged.status, 206) << merged.head;
  EXPECT_EQ(headerValue(merged, "Content-Range"), "bytes 0-41/" + std::to_string(size));
  EXPECT_EQ(merged.body.size(), 42u);

  const Response two = get(server.port(), "100-109,0-9");  // two parts of a multipart answer, in file order
  EXPECT_EQ(two.status, 206) << two.head;
  EXPECT_NE(headerValue(two, "Content-Type").find("multipart/byteranges"), std::string::npos) << two.head;
  EXPECT_LT(two.body.size(), 1000u);
  EXPECT_EQ(headerValue(two, "Content-Length"), std::to_string(two.body.size()));
  std::ifstream in(smallLod(), std::ios::binary);
  std::string bytes(110, '\0');
  in.read(bytes.data(), 110);
  for (const auto& [first, part] : {std::pair{0, std::string("0-9")}, std::pair{100, std::string("100-109")}}) {
    const std::string label = "Content-Range: bytes " + part + "/" + std::to_string(size) + "\r\n\r\n";
    const size_t at = two.body.find(label);
    ASSERT_NE(at, std::string::npos) << two.body;
    EXPECT_EQ(two.body.substr(at + label.size(), 12), bytes.substr(size_t(first), 10) + "\r\n");
  }
  const std::string boundary = headerValue(two, "Content-Type").substr(headerValue(two, "Content-Type").find("boundary=") + 9);
  EXPECT_EQ(two.body.substr(two.body.size() - boundary.size() - 6), "--" + boundary + "--\r\n");

  std::string sixteen, seventeen;
  for (int i = 0; i < 17; ++i) (i < 16 ? sixteen : seventeen) += (i ? "," : "") + std::to_string(2 * i) + "-" + std::to_string(2 * i);
  seventeen = sixteen + seventeen;
  EXPECT_EQ(get(server.port(), sixteen).status, 206);
  const Response tooMany = get(server.port(), seventeen);
  EXPECT_EQ(tooMany.status, 416) << tooMany.head;
  EXPECT_EQ(headerValue(tooMany, "Content-Range"), "bytes */" + std::to_string(size));
  EXPECT_TRUE(tooMany.body.empty());

  EXPECT_EQ(get(server.port(), std::to_string(size) + "-").status, 416);
  EXPECT_EQ(get(server.port(), "-0").status, 416);
  const Response suffix = get(server.port(), "-" + std::to_string(10 * size));
  EXPECT_EQ(suffix.status, 206);
  EXPECT_EQ(suffix.body.size(), size);
  const Response past = get(server.port(), "0-" + std::to_string(100 * size));
  EXPECT_EQ(past.status, 206);
  EXPECT_EQ(past.body.size(), size);
  const Response whole = get(server.port(), "");
  EXPECT_EQ(whole.status, 200);
  EXPECT_EQ(whole.body.size(), size);
}

// A client that sends half a header and waits, and one that sends a header a byte every 0.2 s
// (never idle for a second), are both closed about a header timeout (1 s) after they connected.
TEST(LodServer, SlowHeadersAreDroppedAfterTheHeaderTimeout) {
  Served server;
  ASSERT_GT(server.port(), 0) << server.output();
  const auto start = Clock::now();
  const int half = connectTo(server.port());
  const int trickle = connectTo(server.port());
  ASSERT_GE(half, 0);
  ASSERT_GE(trickle, 0);
  sendAll(half, "GET /model.lod HTTP/1.1\r\nHost: 127.0.0.1\r\n");
  double halfClosed = -1, trickleClosed = -1;
  const std::string header = "GET /model.lod HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\r\n\r\n";
  size_t sent = 0;
  while (secondsSince(start) < 2.5 && (halfClosed < 0 || trickleClosed < 0)) {
    if (trickleClosed < 0 && sent < header.size() && secondsSince(start) >= 0.2 * double(sent)) sendAll(trickle, header.substr(sent++, 1));
    for (auto [s, when] : {std::pair{half, &halfClosed}, std::pair{trickle, &trickleClosed}}) {
      if (*when >= 0) continue;
      pollfd p{s, POLLIN, 0};
      if (::poll(&p, 1, 5) > 0 && readUntilClosed(s, 0.2).find("200 OK") == std::string::npos) *when = secondsSince(start);
    }
  }
  ::close(half);
  ::close(trickle);
  EXPECT_GE(halfClosed, 0.8);
  EXPECT_LE(halfClosed, 1.6) << "a half header was held past the timeout";
  EXPECT_GE(trickleClosed, 0.8);
  EXPECT_LE(trickleClosed, 1.6) << "a trickled header was held past the timeout";
}

// 40 connections of half a header (five times the server's 8 threads) delay a 32-byte range
// request behind them by one header timeout, not by five.
TEST(LodServer, AFloodOfHalfHeadersDoesNotStarveARequest) {
  Served server;
  ASSERT_GT(server.port(), 0) << server.output();
  std::vector<int> flood;
  const auto connecting = Clock::now();
  for (int i = 0; i < 40; ++i) {
    const int s = connectTo(server.port());
    ASSERT_GE(s, 0);
    sendAll(s, "GET /model.lod HTTP/1.1\r\nHost: 127.0.0.1\r\nRange: by");
    flood.push_back(s);
  }
  const double connected = secondsSince(connecting);
  const auto start = Clock::now();
  const Response r = get(server.port(), "0-31", 2.8);
  const double took = secondsSince(start);
  for (int s : flood) ::close(s);
  EXPECT_EQ(r.status, 206) << "no answer in " << took << " s";
  EXPECT_EQ(r.body.size(), 32u);
  EXPECT_LE(took, 1.8);
  EXPECT_LE(connected, 0.5) << "the 40 connections took that long to be accepted";
}

// Stop signals in any order and number, back to back or while the server stops (a client holds
// a connection open), end `view` with exit 0; a later signal never kills it.
TEST(LodServer, AnySequenceOfStopSignalsExitsZero) {
  const std::vector<std::vector<int>> sequences = {
      {SIGTERM, SIGTERM}, {SIGINT, SIGTERM}, {SIGHUP, SIGINT, SIGTERM}, {SIGTERM, SIGTERM, SIGTERM, SIGTERM}};
  for (const auto& seq : sequences)
    for (int pause : {0, 2}) {
      Served server;
      ASSERT_GT(server.port(), 0) << server.output();
      const int client = connectTo(server.port());
      sendAll(client, "GET /model.lod HTTP/1.1\r\n");
      for (int sig : seq) {
        server.signal(sig);
        if (pause) std::this_thread::sleep_for(std::chrono::milliseconds(pause));
      }
      const auto start = Clock::now();
      const int status = server.wait(2);
      ::close(client);
      ASSERT_GE(status, 0) << "still serving 2 s after the signals";
      EXPECT_TRUE(WIFEXITED(status)) << "killed by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0)
                                     << " (sequence of " << seq.size() << ", pause " << pause << " ms)";
      EXPECT_EQ(WIFEXITED(status) ? WEXITSTATUS(status) : -1, 0);
      EXPECT_LE(secondsSince(start), 0.5) << "stopping waited on the client";
    }
}

// The server listens on loopback unless told otherwise in two flags: --host with an address other
// machines can reach is refused in one line (exit 1) without --allow-remote.
TEST(LodServer, ARemoteHostNeedsAllowRemote) {
  const std::string lod = smallLod().string();
  for (const char* host : {"0.0.0.0", "::", "192.0.2.1", "example.org"}) {
    const auto r = test::runCli("view " + lod + " --port 0 --host " + host);
    EXPECT_EQ(r.exitCode, 1) << host << ": " << r.out;
    EXPECT_NE(r.out.find("--host"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("--allow-remote"), std::string::npos) << r.out;
    EXPECT_EQ(std::count(r.out.begin(), r.out.end(), '\n'), 1) << r.out;
  }
  for (const char* timeout : {"0", "-1", "nan", "inf"}) {
    const auto r = test::runCli("view " + lod + " --port 0 --header-timeout " + timeout);
    EXPECT_EQ(r.exitCode, 1) << timeout << ": " << r.out;
    EXPECT_NE(r.out.find("--header-timeout"), std::string::npos) << r.out;
  }
  {
    Served loopback({"--host", "127.0.0.2"});  // all of 127/8 is loopback
    EXPECT_GT(loopback.port(), 0) << loopback.output();
  }
  Served remote({"--host", "0.0.0.0", "--allow-remote", "--header-timeout", "1"});
  ASSERT_GT(remote.port(), 0) << remote.output();
  EXPECT_EQ(get(remote.port(), "0-31").body.size(), 32u);
  remote.signal(SIGTERM);
  const int status = remote.wait(2);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
}

}  // namespace
}  // namespace linesurf
