#include "linesurf/io/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include "linesurf/core/error.h"

namespace linesurf {

void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
  const std::string target = path.string();
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw Error(Error::Kind::Io, target, "", "output folder does not exist");
  if (std::filesystem::is_directory(path, ec))
    throw Error(Error::Kind::Io, target, "", "is a directory");
  std::string tmpl = (dir / ("." + path.filename().string() + ".tmp-XXXXXX")).string();
  int fd = mkstemp(tmpl.data());
  if (fd < 0) throw Error(Error::Kind::Io, target, "", std::string("cannot create file: ") + std::strerror(errno));
  size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      int e = errno;
      ::close(fd);
      ::unlink(tmpl.c_str());
      throw Error(Error::Kind::Io, target, "", std::string("write failed: ") + std::strerror(e));
    }
    done += size_t(n);
  }
  if (::close(fd) != 0) {
    ::unlink(tmpl.c_str());
    throw Error(Error::Kind::Io, target, "", "close failed");
  }
  ::chmod(tmpl.c_str(), 0644);
  if (std::rename(tmpl.c_str(), target.c_str()) != 0) {
    int e = errno;
    ::unlink(tmpl.c_str());
    throw Error(Error::Kind::Io, target, "", std::string("rename failed: ") + std::strerror(e));
  }
}

}  // namespace linesurf
