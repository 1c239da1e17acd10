// The HTTP side of `linesurf view MODEL.lod` (lod_server.h). cpp-httplib is heavy to compile:
// this is its only translation unit.
#include "lod_server.h"

#include <arpa/inet.h>
#include <fmt/format.h>

#include <algorithm>
#include <cctype>

#include "linesurf/core/error.h"

#ifdef LINESURF_HAVE_HTTPLIB
#include <fcntl.h>
#include <httplib.h>
#include <netdb.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <memory>
#include <mutex>
#include <random>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "linesurf/core/read_only_file.h"
#endif

namespace linesurf::cli {

bool isLoopbackHost(const std::string& host) {
  std::string h = host;
  for (char& c : h) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (h == "localhost") return true;
  in_addr v4{};
  if (::inet_pton(AF_INET, h.c_str(), &v4) == 1) return (ntohl(v4.s_addr) >> 24) == 127;
  in6_addr v6{};
  if (::inet_pton(AF_INET6, h.c_str(), &v6) == 1)
    return IN6_IS_ADDR_LOOPBACK(&v6) || (IN6_IS_ADDR_V4MAPPED(&v6) && v6.s6_addr[12] == 127);
  return false;
}

#ifdef LINESURF_HAVE_HTTPLIB
namespace {

using Clock = std::chrono::steady_clock;

// The most bytes one request (line, headers and any body) may send: a viewer's GET is a few
// hundred. cpp-httplib 0.11 bounds each header line (8 KB) but not their number.
constexpr size_t kMaxRequestBytes = 64 * 1024;

// ---------------------------------------------------------------------------------------------
// Stop signals

// A self-pipe: the handler may run on any thread (also on threads this file did not start, which
// leave the signals unblocked) and only writes a byte. Neither the pipe nor the handlers are ever
// removed: a signal that arrives while the server stops, or after serveLod returned, must find
// them still there (the CLI's own handler would end the process by the signal, exit 128 + N).
int stopPipe[2] = {-1, -1};

extern "C" void onStopSignal(int) {
  const int saved = errno;
  const char byte = 's';
  [[maybe_unused]] const ssize_t n = ::write(stopPipe[1], &byte, 1);  // a full pipe holds a stop already
  errno = saved;
}

void catchStopSignals() {
  static std::once_flag once;
  std::call_once(once, [] {
    if (::pipe2(stopPipe, O_CLOEXEC | O_NONBLOCK) != 0)
      throw Error(Error::Kind::Io, "view", "", fmt::format("cannot create a pipe: {}", std::strerror(errno)));
    for (int sig : {SIGINT, SIGTERM, SIGHUP}) {
      struct sigaction old{};
      if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;  // nohup: keep ignoring
      struct sigaction sa{};
      sa.sa_handler = onStopSignal;
      sigemptyset(&sa.sa_mask);
      sa.sa_flags = SA_RESTART;
      ::sigaction(sig, &sa, nullptr);
    }
  });
}

void waitForStop() {
  pollfd p{stopPipe[0], POLLIN, 0};
  while (::poll(&p, 1, -1) < 0 && errno == EINTR) {
  }
}

// The server's threads never take a stop signal, so that no socket call of theirs is cut short.
void blockStopSignals() {
  sigset_t set;
  sigemptyset(&set);
  for (int sig : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&set, sig);
  pthread_sigmask(SIG_BLOCK, &set, nullptr);
}

// ---------------------------------------------------------------------------------------------
// Connections: a bounded queue, a fixed pool, a deadline for each request's arrival

// When the connection a worker runs was accepted, and whether it is to be closed unread (over the
// queue's bound, or the server stopping). Set by the queue before it runs the connection.
thread_local Clock::time_point tAccepted;
thread_local bool tRefused = false;

// cpp-httplib 0.11's ThreadPool keeps every accepted connection queued however many there are and
// knows nothing of when they came. This one is first come first served with a bound (a connection
// beyond it is closed at once, without a read), and hands each connection its accept time: the
// header deadline counts from then, so connections that never finish a header delay a request
// behind them by one header timeout in all, not by one for every thread-full of them.
class ConnectionQueue final : public httplib::TaskQueue {
 public:
  ConnectionQueue(size_t threads, size_t limit, std::atomic<size_t>& waiting) : limit_(limit), waiting_(waiting) {
    for (size_t i = 0; i < std::max<size_t>(1, threads); ++i) workers_.emplace_back([this] { work(); });
  }
  void enqueue(std::function<void()> fn) override {
    {
      std::lock_guard lock(mutex_);
      if (jobs_.size() < limit_) {
        jobs_.push_back({Clock::now(), std::move(fn)});
        waiting_ = jobs_.size();
        ready_.notify_one();
        return;
      }
    }
    tRefused = true;  // on the accepting thread: the connection is closed before the next accept
    fn();
    tRefused = false;
  }
  void shutdown() override {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    ready_.notify_all();
    for (auto& t : workers_) t.join();  // the queued rest is closed unread (the server has stopped)
  }

 private:
  struct Job {
    Clock::time_point accepted;
    std::function<void()> run;
  };
  void work() {
    for (;;) {
      Job job;
      {
        std::unique_lock lock(mutex_);
        ready_.wait(lock, [&] { return stopping_ || !jobs_.empty(); });
        if (jobs_.empty()) return;
        job = std::move(jobs_.front());
        jobs_.pop_front();
        waiting_ = jobs_.size();
      }
      tAccepted = job.accepted;
      job.run();
    }
  }
  const size_t limit_;
  std::atomic<size_t>& waiting_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<Job> jobs_;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
};

// One connection's socket as cpp-httplib's Stream, with what its SocketStream lacks: a deadline
// for reading the whole request (not only an idle time between reads, which a client sending a
// byte a second never reaches) and a bound on its bytes. Buffered, as the request line and headers
// are read a byte at a time; the buffer lives as long as the connection (pipelined requests).
class ConnectionStream final : public httplib::Stream {
 public:
  ConnectionStream(int sock, int writeMs) : sock_(sock), writeMs_(writeMs) {}
  /// A new request: its bytes must have arrived by `deadline`.
  void startRequest(Clock::time_point deadline) {
    deadline_ = deadline;
    requestBytes_ = 0;
  }
  /// Whether a read was refused (the deadline or the byte bound): the connection is not kept.
  bool cutOff() const { return cutOff_; }
  /// Whether a further request starts within `ms` (a kept-alive connection).
  bool waitRequest(int ms) const { return pos_ < len_ || wait(POLLIN, ms); }

  bool is_readable() const override { return pos_ < len_ || wait(POLLIN, msLeft()); }
  bool is_writable() const override { return wait(POLLOUT, writeMs_); }
  ssize_t read(char* out, size_t n) override {
    if (pos_ == len_) {
      // Past the deadline only bytes already waiting are read: a request that came at once but
      // waited in the queue behind busy threads is still answered (a client streaming header
      // lines as fast as it can is cut off by the byte bound).
      if (requestBytes_ >= kMaxRequestBytes || !wait(POLLIN, msLeft())) {
        cutOff_ = true;
        return -1;
      }
      ssize_t got;
      do got = ::recv(sock_, buf_, sizeof buf_, 0);
      while (got < 0 && errno == EINTR);
      if (got <= 0) return got;
      pos_ = 0, len_ = size_t(got);
    }
    const size_t k = std::min(n, len_ - pos_);
    std::memcpy(out, buf_ + pos_, k);
    pos_ += k;
    requestBytes_ += k;
    return ssize_t(k);
  }
  ssize_t write(const char* data, size_t n) override {
    if (!wait(POLLOUT, writeMs_)) return -1;
    ssize_t put;
    do put = ::send(sock_, data, n, MSG_NOSIGNAL);
    while (put < 0 && errno == EINTR);
    return put;
  }
  void get_remote_ip_and_port(std::string& ip, int& port) const override { address(::getpeername, ip, port); }
  void get_local_ip_and_port(std::string& ip, int& port) const override { address(::getsockname, ip, port); }
  socket_t socket() const override { return sock_; }

 private:
  int msLeft() const {
    const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline_ - Clock::now()).count();
    return int(std::clamp<int64_t>(left, 0, 1 << 30));
  }
  bool wait(short events, int ms) const {
    pollfd p{sock_, events, 0};
    for (;;) {
      const int r = ::poll(&p, 1, ms);
      if (r >= 0 || errno != EINTR) return r > 0;
    }
  }
  void address(int (*get)(int, sockaddr*, socklen_t*), std::string& ip, int& port) const {
    sockaddr_storage a{};
    socklen_t len = sizeof a;
    char host[NI_MAXHOST], serv[NI_MAXSERV];
    if (get(sock_, reinterpret_cast<sockaddr*>(&a), &len) == 0 &&
        ::getnameinfo(reinterpret_cast<sockaddr*>(&a), len, host, sizeof host, serv, sizeof serv,
                      NI_NUMERICHOST | NI_NUMERICSERV) == 0) {
      ip = host;
      port = std::atoi(serv);
    }
  }
  int sock_;
  int writeMs_;
  Clock::time_point deadline_{};
  size_t requestBytes_ = 0;
  bool cutOff_ = false;
  char buf_[4096];
  size_t pos_ = 0, len_ = 0;
};

// cpp-httplib's Server with its per-connection loop replaced (the virtual the library calls for
// each accepted socket): the same keep-alive rules (at most keep_alive_max_count requests, the
// keep-alive timeout between them) around the library's own request parser and router, over the
// stream above. It also knows its open connections, so that stopping need not wait on a client.
class LodHttpServer final : public httplib::Server {
 public:
  explicit LodHttpServer(double headerSeconds)
      : header_(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(headerSeconds))) {}
  /// cpp-httplib 0.11 listens with a backlog of 5 (CPPHTTPLIB_LISTEN_BACKLOG, fixed in the shared
  /// library): a sixth connection made before the accepting thread runs has its SYN dropped and
  /// retried a second later. Listening again on the bound socket sets the kernel's queue.
  void widenBacklog(int n) { ::listen(svr_sock_, n); }
  /// Connections waiting for a thread (kept up to date by the ConnectionQueue).
  std::atomic<size_t>& waiting() { return waiting_; }
  /// Shuts every open connection down, and any later one at once: a client in the middle of a
  /// header or of a response keeps no thread once the server has stopped.
  void dropConnections() {
    std::lock_guard lock(mutex_);
    dropping_ = true;
    for (int s : open_) ::shutdown(s, SHUT_RDWR);
  }

 private:
  bool process_and_close_socket(socket_t sock) override {
    bool ret = false;
    if (!tRefused && track(sock)) {
      ConnectionStream strm(sock, int(write_timeout_sec_ * 1000 + write_timeout_usec_ / 1000));
      Clock::time_point deadline = tAccepted + header_;
      for (size_t left = keep_alive_max_count_; left > 0 && svr_sock_ != INVALID_SOCKET; --left) {
        if (left != keep_alive_max_count_) {
          // An idle kept-alive connection gives its thread up at once to a connection waiting.
          if (!strm.waitRequest(waiting_ ? 0 : int(keep_alive_timeout_sec_ * 1000))) break;
          deadline = Clock::now() + header_;
        }
        strm.startRequest(deadline);
        bool closed = false;
        ret = process_request(strm, left == 1, closed, nullptr);
        if (!ret || closed || strm.cutOff()) break;
      }
      untrack(sock);
    }
    ::shutdown(sock, SHUT_RDWR);
    ::close(sock);
    return ret;
  }
  bool track(int sock) {
    std::lock_guard lock(mutex_);
    if (dropping_) return false;
    open_.insert(sock);
    return true;
  }
  void untrack(int sock) {
    std::lock_guard lock(mutex_);
    open_.erase(sock);
  }
  const Clock::duration header_;
  std::atomic<size_t> waiting_{0};
  std::mutex mutex_;
  std::set<int> open_;
  bool dropping_ = false;
};

// ---------------------------------------------------------------------------------------------
// Ranges

// cpp-httplib 0.11 hands a request's ranges to a content provider as they came: a range past the
// end announced an absurd Content-Length, one reaching past it a length never sent, and 2,000
// copies of `0-` a response of 2,000 files. Normalises them in place against a file of `size`
// bytes (RFC 9110 §14): each clamped to the file (the last byte at most size - 1; a suffix range
// longer than the file is the whole file), the unsatisfiable ones dropped (first byte at or past
// the end, `-0`), the rest sorted and merged where they overlap or touch (§14.2 allows coalescing
// whatever their order), so the bytes answered never exceed the file. False (416) when none is
// left, or more than kMaxRequestRanges are.
bool fitRanges(httplib::Ranges& ranges, uint64_t size) {
  httplib::Ranges fit;
  for (auto [first, last] : ranges) {
    if (first < 0) {  // bytes=-N: the last N bytes
      if (last <= 0) continue;
      first = std::max<int64_t>(0, int64_t(size) - last);
      last = int64_t(size) - 1;
    } else {
      if (uint64_t(first) >= size) continue;
      if (last < 0 || uint64_t(last) >= size) last = int64_t(size) - 1;
      if (last < first) continue;
    }
    fit.emplace_back(first, last);
  }
  std::sort(fit.begin(), fit.end());
  ranges.clear();
  for (const auto& r : fit)
    if (!ranges.empty() && r.first <= ranges.back().second + 1) ranges.back().second = std::max(ranges.back().second, r.second);
    else ranges.push_back(r);
  return !ranges.empty() && ranges.size() <= kMaxRequestRanges;
}

// Up to 1 MB of the file from `offset` into the response; false when the file ends early (it
// shrank: the response ends short).
bool sendFileBytes(const ReadOnlyFile& file, uint64_t offset, uint64_t length, httplib::DataSink& sink) {
  std::vector<char> buf(size_t(std::min<uint64_t>(length, uint64_t(1) << 20)));
  const size_t got = file.read(offset, buf.data(), buf.size());
  return got > 0 && sink.write(buf.data(), got);
}

// Several ranges as one multipart/byteranges body (RFC 9110 §14.6), written here rather than by
// cpp-httplib: 0.11 labels each part of a provider's content `Content-Range: bytes A-B/0` (it
// takes the total from the in-memory body, empty here). The same framing as the library's.
void serveParts(httplib::Response& res, std::shared_ptr<ReadOnlyFile> file, uint64_t size, httplib::Ranges ranges) {
  struct Piece {
    std::string text;  ///< framing, or empty for file bytes
    uint64_t offset = 0, length = 0;  ///< in the file (bytes), or of the text
  };
  std::random_device rd;
  const char* alnum = "0123456789abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ";
  std::string boundary = "linesurf-parts-";
  for (int i = 0; i < 24; ++i) boundary += alnum[rd() % 62];
  auto pieces = std::make_shared<std::vector<Piece>>();
  auto text = [&](std::string t) { pieces->push_back({t, 0, t.size()}); };
  for (const auto& [first, last] : ranges) {
    text(fmt::format("--{}\r\nContent-Type: application/octet-stream\r\nContent-Range: bytes {}-{}/{}\r\n\r\n",
                     boundary, first, last, size));
    pieces->push_back({"", uint64_t(first), uint64_t(last - first + 1)});
    text("\r\n");
  }
  text(fmt::format("--{}--\r\n", boundary));
  uint64_t total = 0;
  for (const Piece& p : *pieces) total += p.length;
  res.status = 206;
  res.set_content_provider(size_t(total), "multipart/byteranges; boundary=" + boundary,
                           [file, pieces](size_t offset, size_t, httplib::DataSink& sink) {
                             uint64_t at = offset;
                             for (const Piece& p : *pieces) {
                               if (at >= p.length) {
                                 at -= p.length;
                                 continue;
                               }
                               if (!p.text.empty()) return sink.write(p.text.data() + at, size_t(p.length - at));
                               return sendFileBytes(*file, p.offset + at, p.length - at, sink);
                             }
                             return false;
                           });
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
  catchStopSignals();

  LodHttpServer server(o.headerSeconds);
  server.new_task_queue = [&o, &server] { return new ConnectionQueue(o.threads, o.queued, server.waiting()); };
  server.set_keep_alive_timeout(1);  // an idle kept-alive connection holds a thread for 1 s at most
  server.set_payload_max_length(kMaxRequestBytes);  // GETs only: no request needs a body
  server.Get("/", [&o](const httplib::Request&, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_content(o.page, "text/html; charset=utf-8");
  });
  server.Get("/model.lod", [file, size](const httplib::Request& req, httplib::Response& res) {
    res.set_header("Cache-Control", "no-store");
    res.set_header("Accept-Ranges", "bytes");
    // The request is the server's own non-const object, handed to handlers as const: adjusting
    // its ranges here is what makes the library answer the normalised ones.
    auto& ranges = const_cast<httplib::Request&>(req).ranges;
    if (!ranges.empty() && !fitRanges(ranges, size)) {
      ranges.clear();  // else the library would label the empty 416 body multipart
      res.status = 416;
      res.set_header("Content-Range", fmt::format("bytes */{}", size));
      return;
    }
    if (ranges.size() > 1) return serveParts(res, file, size, std::exchange(ranges, {}));
    // cpp-httplib applies one range to the provider: it asks for [offset, offset + length).
    res.set_content_provider(size, "application/octet-stream",
                             [file](size_t offset, size_t length, httplib::DataSink& sink) {
                               return sendFileBytes(*file, offset, length, sink);
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
  server.widenBacklog(128);
  std::atomic<bool> ended{false};
  std::thread loop([&server, &ended] {
    blockStopSignals();  // inherited by the connection threads, which this thread starts
    server.listen_after_bind();
    ended = true;
    onStopSignal(0);  // wakes the wait below if the server ended by itself
  });
  while (!server.is_running() && !ended) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  if (!ended) {
    if (o.listening) o.listening(port);
    waitForStop();
  }
  const bool byItself = ended;
  server.stop();
  server.dropConnections();
  loop.join();
  if (byItself) throw Error(Error::Kind::Io, fmt::format("{}:{}", o.host, port), "", "the server stopped by itself");
}

#else

void serveLod(const LodServeOptions&) {
  throwBadParameter("view", "this linesurf was built without cpp-httplib, which serves .lod hierarchies; "
                            "install libcpp-httplib-dev and rebuild");
}

#endif

}  // namespace linesurf::cli
