#pragma once
/// A file opened read-only and read by byte range with pread, so that several threads may read it
/// at once (a level-of-detail hierarchy's nodes, the viewer server's ranges). Closed when destroyed.
#include <fcntl.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>

namespace linesurf {

class ReadOnlyFile {
 public:
  explicit ReadOnlyFile(const std::filesystem::path& p) : fd_(::open(p.c_str(), O_RDONLY | O_CLOEXEC)) {}
  ~ReadOnlyFile() {
    if (fd_ >= 0) ::close(fd_);
  }
  ReadOnlyFile(const ReadOnlyFile&) = delete;
  ReadOnlyFile& operator=(const ReadOnlyFile&) = delete;
  bool isOpen() const { return fd_ >= 0; }
  /// Reads up to n bytes at `offset`; returns the bytes read (fewer at the end of the file or on
  /// an error).
  size_t read(uint64_t offset, char* out, size_t n) const {
    size_t got = 0;
    while (got < n) {
      const ssize_t r = ::pread(fd_, out + got, n - got, off_t(offset + got));
      if (r <= 0) break;
      got += size_t(r);
    }
    return got;
  }

 private:
  int fd_ = -1;
};

}  // namespace linesurf
