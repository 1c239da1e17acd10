#include "linesurf/io/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "linesurf/core/error.h"

namespace linesurf {

struct OutputTransaction::State {
  mutable std::mutex mutex;
  std::vector<std::pair<std::string, std::string>> staged;  ///< (temporary, target)
  std::vector<std::filesystem::path> stagedCanonical;
  std::vector<std::pair<FileId, std::string>> inputs;
  bool committed = false;
};

namespace {
std::mutex activeMutex;
OutputTransaction::State* active = nullptr;

std::filesystem::path canonicalTarget(const std::filesystem::path& p) {
  std::error_code ec;
  auto c = std::filesystem::weakly_canonical(std::filesystem::absolute(p, ec), ec);
  return ec ? p.lexically_normal() : c;
}
}  // namespace

FileId fileId(const std::filesystem::path& path) {
  struct stat st;
  if (::stat(path.c_str(), &st) != 0) return {};
  return {static_cast<unsigned long long>(st.st_dev), static_cast<unsigned long long>(st.st_ino)};
}

void noteInput(const std::filesystem::path& path) {
  std::lock_guard<std::mutex> lock(activeMutex);
  if (!active) return;
  FileId id = fileId(path);
  if (!id.exists()) return;
  std::lock_guard<std::mutex> l2(active->mutex);
  active->inputs.emplace_back(id, path.string());
}

OutputTransaction::OutputTransaction() : state_(std::make_unique<State>()) {
  std::lock_guard<std::mutex> lock(activeMutex);
  if (active) throw std::logic_error("OutputTransaction: one is already open");
  active = state_.get();
}

OutputTransaction::~OutputTransaction() {
  {
    std::lock_guard<std::mutex> lock(activeMutex);
    if (active == state_.get()) active = nullptr;
  }
  if (!state_->committed)
    for (auto& [tmp, target] : state_->staged) ::unlink(tmp.c_str());
}

size_t OutputTransaction::staged() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->staged.size();
}

void OutputTransaction::commit() {
  {
    std::lock_guard<std::mutex> lock(activeMutex);
    if (active == state_.get()) active = nullptr;  // later writes go straight to their targets
  }
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->committed = true;
  for (size_t i = 0; i < state_->staged.size(); ++i) {
    auto& [tmp, target] = state_->staged[i];
    if (std::rename(tmp.c_str(), target.c_str()) != 0) {
      int e = errno;
      for (size_t j = i; j < state_->staged.size(); ++j) ::unlink(state_->staged[j].first.c_str());
      state_->staged.clear();
      throw Error(Error::Kind::Io, target, "", std::string("rename failed: ") + std::strerror(e));
    }
  }
  state_->staged.clear();
}

void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
  const std::string target = path.string();
  std::filesystem::path dir = path.parent_path();
  if (dir.empty()) dir = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec))
    throw Error(Error::Kind::Io, target, "", "output folder does not exist");
  if (std::filesystem::is_directory(path, ec)) throw Error(Error::Kind::Io, target, "", "is a directory");
  {
    // Refuse before writing anything: an output onto an input, or one output twice.
    std::lock_guard<std::mutex> lock(activeMutex);
    if (active) {
      std::lock_guard<std::mutex> l2(active->mutex);
      const FileId id = fileId(path);
      for (auto& [in, name] : active->inputs)
        if (id.exists() && id == in)
          throw Error(Error::Kind::BadParameter, target, "", "is also an input of this command (not overwritten)");
      const std::filesystem::path c = canonicalTarget(path);
      for (const auto& s : active->stagedCanonical)
        if (s == c) throw Error(Error::Kind::BadParameter, target, "", "written twice by this command (two outputs with one path)");
    }
  }
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
  {
    std::lock_guard<std::mutex> lock(activeMutex);
    if (active) {
      std::lock_guard<std::mutex> l2(active->mutex);
      const std::filesystem::path c = canonicalTarget(path);
      for (const auto& s : active->stagedCanonical)
        if (s == c) {
          ::unlink(tmpl.c_str());
          throw Error(Error::Kind::BadParameter, target, "", "written twice by this command (two outputs with one path)");
        }
      active->staged.emplace_back(tmpl, target);
      active->stagedCanonical.push_back(c);
      return;
    }
  }
  if (std::rename(tmpl.c_str(), target.c_str()) != 0) {
    int e = errno;
    ::unlink(tmpl.c_str());
    throw Error(Error::Kind::Io, target, "", std::string("rename failed: ") + std::strerror(e));
  }
}

}  // namespace linesurf
