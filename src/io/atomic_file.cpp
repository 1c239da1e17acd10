#include "linesurf/io/atomic_file.h"

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "linesurf/core/error.h"

namespace linesurf {

// ---------------------------------------------------------------------------------------------
// The cleanup registry: every temporary file or folder made for an output, in fixed slots that a
// signal handler can walk without locks or allocation. Slots are never freed, only reused, so a
// handler never follows a dangling pointer; their number is the most temporaries alive at once.

namespace {

struct TempSlot {
  enum : int { Free = 0, Claimed = 1, File = 2, Folder = 3 };
  std::atomic<int> state{Free};
  std::atomic<TempSlot*> next{nullptr};
  char path[4096];
};
std::atomic<TempSlot*> slotList{nullptr};

/// A slot holding `path` (absolute, so that a handler needs no working directory), or null when
/// the path is too long to record (the temporary is still removed by the transaction).
TempSlot* claimSlot(const std::string& path, int kind) {
  if (path.size() + 1 > sizeof(TempSlot::path)) return nullptr;
  TempSlot* s = nullptr;
  for (TempSlot* t = slotList.load(std::memory_order_acquire); t && !s; t = t->next.load(std::memory_order_acquire)) {
    int expected = TempSlot::Free;
    if (t->state.compare_exchange_strong(expected, TempSlot::Claimed)) s = t;
  }
  if (!s) {
    s = new TempSlot;
    s->state.store(TempSlot::Claimed);
    TempSlot* head = slotList.load(std::memory_order_acquire);
    do s->next.store(head, std::memory_order_relaxed);
    while (!slotList.compare_exchange_weak(head, s, std::memory_order_acq_rel));
  }
  std::memcpy(s->path, path.c_str(), path.size() + 1);
  s->state.store(kind, std::memory_order_release);
  return s;
}

void releaseSlot(TempSlot* s) {
  if (s) s->state.store(TempSlot::Free, std::memory_order_release);
}

/// Removes the folder `name` (relative to dirfd) and everything in it; async-signal-safe (open,
/// getdents64, unlinkat, close only).
void removeTreeAt(int dirfd, const char* name, int depth) {
  if (depth > 64) return;
  const int fd = ::openat(dirfd, name, O_RDONLY | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (fd >= 0) {
    struct Dirent64 {
      unsigned long long ino;
      long long off;
      unsigned short reclen;
      unsigned char type;
      char name[1];
    };
    alignas(8) char buf[4096];
    for (int pass = 0; pass < 4; ++pass) {
      bool removed = false;
      ::lseek(fd, 0, SEEK_SET);
      for (;;) {
        const long n = ::syscall(SYS_getdents64, fd, buf, sizeof buf);
        if (n <= 0) break;
        for (long off = 0; off < n;) {
          const auto* d = reinterpret_cast<const Dirent64*>(buf + off);
          off += d->reclen;
          const char* e = d->name;
          if (e[0] == '.' && (e[1] == 0 || (e[1] == '.' && e[2] == 0))) continue;
          if (d->type == DT_DIR || (::unlinkat(fd, e, 0) != 0 && errno == EISDIR)) removeTreeAt(fd, e, depth + 1);
          removed = true;
        }
      }
      if (!removed) break;
    }
    ::close(fd);
  }
  ::unlinkat(dirfd, name, AT_REMOVEDIR);
}

void removeTree(const std::string& path) { removeTreeAt(AT_FDCWD, path.c_str(), 0); }

std::string absoluteString(const std::filesystem::path& p) {
  std::error_code ec;
  std::filesystem::path a = std::filesystem::absolute(p, ec);
  a = (ec ? p : a).lexically_normal();
  if (a.has_parent_path() && a.filename().empty()) a = a.parent_path();  // "out/" is the folder "out"
  return a.string();
}

}  // namespace

void removeTemporaryOutputs() noexcept {
  for (TempSlot* s = slotList.load(std::memory_order_acquire); s; s = s->next.load(std::memory_order_acquire)) {
    const int kind = s->state.load(std::memory_order_acquire);
    if (kind == TempSlot::File) ::unlink(s->path);
    else if (kind == TempSlot::Folder) removeTree(s->path);
  }
}

namespace {
extern "C" void cleanupAndReraise(int sig) {
  const int saved = errno;
  removeTemporaryOutputs();
  errno = saved;
  // SA_RESETHAND restored the default action and SA_NODEFER leaves the signal unblocked: this
  // ends the process the way the signal would have.
  ::raise(sig);
}
}  // namespace

void installCleanupOnSignals() {
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) {
    struct sigaction old{};
    if (::sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;  // e.g. nohup: keep ignoring
    struct sigaction sa{};
    sa.sa_handler = cleanupAndReraise;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESETHAND | SA_NODEFER;
    ::sigaction(sig, &sa, nullptr);
  }
}

// ---------------------------------------------------------------------------------------------
// The transaction

namespace {
struct StagedFile {
  std::string tmp, target;
  TempSlot* slot = nullptr;
};
struct StagedFolder {
  std::filesystem::path target;  ///< absolute, normal
  std::string tmp;               ///< absolute
  bool replace = false;
  TempSlot* slot = nullptr;
};
}  // namespace

struct OutputTransaction::State {
  mutable std::mutex mutex;
  std::vector<StagedFile> staged;
  std::vector<std::filesystem::path> stagedCanonical;
  std::vector<StagedFolder> folders;
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

/// `path` mapped into the staged folder it lies under (caller holds the state's mutex), or empty.
std::filesystem::path resolveLocked(const OutputTransaction::State& s, const std::filesystem::path& path) {
  if (s.folders.empty()) return {};
  const std::filesystem::path abs = absoluteString(path);
  for (const StagedFolder& f : s.folders) {
    auto [fi, ai] = std::mismatch(f.target.begin(), f.target.end(), abs.begin(), abs.end());
    if (fi != f.target.end()) continue;
    std::filesystem::path out = f.tmp;
    for (; ai != abs.end(); ++ai)
      if (!ai->empty()) out /= *ai;
    return out;
  }
  return {};
}

/// A temporary file beside `target` (a short hidden name: any legal target name keeps the
/// temporary's legal too), registered for cleanup. Returns the descriptor; throws Io.
int makeTemporary(const std::filesystem::path& dir, const std::string& target, std::string& tmp, TempSlot*& slot) {
  tmp = absoluteString(dir / ".ls-XXXXXX");
  // Registered before it exists, so that a signal between creation and registration cannot leak it.
  slot = claimSlot(tmp, TempSlot::File);
  int fd;
  if (slot) {
    fd = ::mkstemp(slot->path);
    tmp = slot->path;
  } else {
    fd = ::mkstemp(tmp.data());
  }
  if (fd < 0) {
    const int e = errno;
    releaseSlot(slot);
    slot = nullptr;
    throw Error(Error::Kind::Io, target, "", std::string("cannot create file: ") + std::strerror(e));
  }
  return fd;
}

void discard(StagedFile& f) {
  ::unlink(f.tmp.c_str());
  releaseSlot(f.slot);
  f.slot = nullptr;
}
void discard(StagedFolder& f) {
  removeTree(f.tmp);
  releaseSlot(f.slot);
  f.slot = nullptr;
}
}  // namespace

std::filesystem::path stagedLocation(const std::filesystem::path& path) {
  std::lock_guard<std::mutex> lock(activeMutex);
  if (!active) return path;
  std::lock_guard<std::mutex> l2(active->mutex);
  std::filesystem::path r = resolveLocked(*active, path);
  return r.empty() ? path : r;
}

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
  if (!state_->committed) {
    for (StagedFile& f : state_->staged) discard(f);
    for (StagedFolder& f : state_->folders) discard(f);
  }
}

size_t OutputTransaction::staged() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->staged.size() + state_->folders.size();
}

void OutputTransaction::commit() {
  {
    std::lock_guard<std::mutex> lock(activeMutex);
    if (active == state_.get()) active = nullptr;  // later writes go straight to their targets
  }
  std::lock_guard<std::mutex> lock(state_->mutex);
  State& s = *state_;
  s.committed = true;
  auto fail = [&](size_t folderFrom, size_t fileFrom, const std::string& target, int e) {
    for (size_t j = folderFrom; j < s.folders.size(); ++j) discard(s.folders[j]);
    for (size_t j = fileFrom; j < s.staged.size(); ++j) discard(s.staged[j]);
    s.folders.clear();
    s.staged.clear();
    throw Error(Error::Kind::Io, target, "", std::string("rename failed: ") + std::strerror(e));
  };
  // Folders first: a file staged beside them (an experiment's results.json) names what they hold.
  for (size_t i = 0; i < s.folders.size(); ++i) {
    StagedFolder& f = s.folders[i];
    const std::string target = f.target.string();
    struct stat st;
    const bool exists = ::lstat(target.c_str(), &st) == 0;
    if (exists && f.replace && S_ISDIR(st.st_mode)) {
      // Swap the two folders in one step, then remove the earlier one (now under the temporary name).
      if (::renameat2(AT_FDCWD, f.tmp.c_str(), AT_FDCWD, target.c_str(), RENAME_EXCHANGE) != 0) {
        // A file system without the exchange: move the earlier folder aside, then the new one in.
        // The folder aside is not in the cleanup registry: a signal between the two renames
        // leaves it (hidden, whole) rather than losing both runs.
        std::string aside = absoluteString(f.target.parent_path() / ".ls-XXXXXX");
        if (!::mkdtemp(aside.data()) || ::rename(target.c_str(), aside.c_str()) != 0) {
          const int e = errno;
          ::rmdir(aside.c_str());
          fail(i, 0, target, e);
        }
        if (::rename(f.tmp.c_str(), target.c_str()) != 0) {
          const int e = errno;
          ::rename(aside.c_str(), target.c_str());  // put the earlier folder back
          fail(i, 0, target, e);
        }
        removeTree(aside);
        releaseSlot(f.slot);
        f.slot = nullptr;
        continue;
      }
      // f.tmp now names the earlier folder: the slot still removes it if a signal comes now.
      removeTree(f.tmp);
    } else if (::rename(f.tmp.c_str(), target.c_str()) != 0) {
      fail(i, 0, target, errno);
    }
    releaseSlot(f.slot);
    f.slot = nullptr;
  }
  for (size_t i = 0; i < s.staged.size(); ++i) {
    StagedFile& f = s.staged[i];
    if (std::rename(f.tmp.c_str(), f.target.c_str()) != 0) fail(s.folders.size(), i, f.target, errno);
    releaseSlot(f.slot);
    f.slot = nullptr;
  }
  s.staged.clear();
  s.folders.clear();
}

void makeOutputFolder(const std::filesystem::path& path, bool replace) {
  const std::string name = path.string();
  std::error_code ec;
  std::lock_guard<std::mutex> lock(activeMutex);
  if (!active) {
    std::filesystem::create_directories(path, ec);
    if (!std::filesystem::is_directory(path))
      throw Error(Error::Kind::Io, name, "", "cannot create folder" + (ec ? ": " + ec.message() : std::string()));
    return;
  }
  std::lock_guard<std::mutex> l2(active->mutex);
  OutputTransaction::State& s = *active;
  if (std::filesystem::path inside = resolveLocked(s, path); !inside.empty()) {
    std::filesystem::create_directories(inside, ec);
    if (!std::filesystem::is_directory(inside))
      throw Error(Error::Kind::Io, name, "", "cannot create folder" + (ec ? ": " + ec.message() : std::string()));
    return;
  }
  const std::filesystem::path abs = absoluteString(path);
  if (std::filesystem::is_directory(abs, ec) && !replace) return;
  if (std::filesystem::exists(std::filesystem::symlink_status(abs, ec)) && !std::filesystem::is_directory(abs, ec))
    throw Error(Error::Kind::Io, name, "", "exists and is not a folder");
  // Stage the outermost folder that does not exist yet (or `path` itself when replacing); the
  // rest of the path is made inside the staged copy.
  std::filesystem::path top = abs;
  if (!replace || !std::filesystem::is_directory(abs, ec))
    while (top.has_parent_path() && top.parent_path() != top && !std::filesystem::exists(top.parent_path(), ec))
      top = top.parent_path();
  const std::filesystem::path parent = top.parent_path();
  if (!std::filesystem::is_directory(parent, ec))
    throw Error(Error::Kind::Io, name, "", "the folder above it is not a folder");
  StagedFolder f;
  f.target = top;
  f.replace = replace && top == abs;
  f.slot = claimSlot(absoluteString(parent / ".ls-XXXXXX"), TempSlot::Folder);
  std::string tmpl = absoluteString(parent / ".ls-XXXXXX");
  char* made = f.slot ? ::mkdtemp(f.slot->path) : ::mkdtemp(tmpl.data());
  if (!made) {
    const int e = errno;
    releaseSlot(f.slot);
    throw Error(Error::Kind::Io, name, "", std::string("cannot create folder: ") + std::strerror(e));
  }
  f.tmp = made;
  ::chmod(f.tmp.c_str(), 0755);
  s.folders.push_back(f);
  if (top != abs) {
    const std::filesystem::path inside = resolveLocked(s, abs);
    std::filesystem::create_directories(inside, ec);
    if (!std::filesystem::is_directory(inside))
      throw Error(Error::Kind::Io, name, "", "cannot create folder" + (ec ? ": " + ec.message() : std::string()));
  }
}

struct AtomicFileWriter::Impl {
  std::string target, tmp;
  std::filesystem::path path, where;  // where the file goes: inside a staged folder's copy, or path
  bool inStagedFolder = false;
  TempSlot* slot = nullptr;
  int fd = -1;
  bool done = false;
  void drop() {
    if (fd >= 0) ::close(fd);
    fd = -1;
    ::unlink(tmp.c_str());
    releaseSlot(slot);
    slot = nullptr;
  }
  [[noreturn]] void failWith(const char* what, int e) {
    drop();
    done = true;
    throw Error(Error::Kind::Io, target, "", std::string(what) + std::strerror(e));
  }
};

AtomicFileWriter::AtomicFileWriter(const std::filesystem::path& path) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.target = path.string();
  m.path = path;
  m.where = path;
  std::error_code ec;
  {
    // Refuse before writing anything: an output onto an input, or one output twice.
    std::lock_guard<std::mutex> lock(activeMutex);
    if (active) {
      std::lock_guard<std::mutex> l2(active->mutex);
      const FileId id = fileId(path);
      for (auto& [in, name] : active->inputs)
        if (id.exists() && id == in)
          throw Error(Error::Kind::BadParameter, m.target, "", "is also an input of this command (not overwritten)");
      const std::filesystem::path c = canonicalTarget(path);
      for (const auto& s : active->stagedCanonical)
        if (s == c)
          throw Error(Error::Kind::BadParameter, m.target, "", "written twice by this command (two outputs with one path)");
      if (std::filesystem::path r = resolveLocked(*active, path); !r.empty()) {
        m.where = r;
        m.inStagedFolder = true;
      }
    }
  }
  std::filesystem::path dir = m.where.parent_path();
  if (dir.empty()) dir = ".";
  if (!std::filesystem::is_directory(dir, ec)) throw Error(Error::Kind::Io, m.target, "", "output folder does not exist");
  if (std::filesystem::is_directory(m.where, ec)) throw Error(Error::Kind::Io, m.target, "", "is a directory");
  m.fd = makeTemporary(dir, m.target, m.tmp, m.slot);
}

AtomicFileWriter::~AtomicFileWriter() {
  if (impl_ && !impl_->done) impl_->drop();
}

void AtomicFileWriter::write(const void* data, size_t bytes) {
  Impl& m = *impl_;
  const char* p = static_cast<const char*>(data);
  size_t done = 0;
  while (done < bytes) {
    ssize_t n = ::write(m.fd, p + done, bytes - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      m.failWith("write failed: ", errno);
    }
    done += size_t(n);
  }
}

void AtomicFileWriter::writeAt(uint64_t offset, const void* data, size_t bytes) {
  Impl& m = *impl_;
  const char* p = static_cast<const char*>(data);
  size_t done = 0;
  while (done < bytes) {
    ssize_t n = ::pwrite(m.fd, p + done, bytes - done, off_t(offset + done));
    if (n < 0) {
      if (errno == EINTR) continue;
      m.failWith("write failed: ", errno);
    }
    done += size_t(n);
  }
}

void AtomicFileWriter::readAt(uint64_t offset, void* data, size_t bytes) {
  Impl& m = *impl_;
  char* p = static_cast<char*>(data);
  size_t done = 0;
  while (done < bytes) {
    ssize_t n = ::pread(m.fd, p + done, bytes - done, off_t(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) m.failWith("read back failed: ", n < 0 ? errno : EIO);
    done += size_t(n);
  }
}

void AtomicFileWriter::commit() {
  Impl& m = *impl_;
  if (m.done) throw std::logic_error("AtomicFileWriter::commit twice");
  m.done = true;
  const int fd = m.fd;
  m.fd = -1;
  if (::close(fd) != 0) {
    const int e = errno;
    m.drop();
    throw Error(Error::Kind::Io, m.target, "", std::string("close failed: ") + std::strerror(e));
  }
  ::chmod(m.tmp.c_str(), 0644);
  if (!m.inStagedFolder) {
    std::lock_guard<std::mutex> lock(activeMutex);
    if (active) {
      std::lock_guard<std::mutex> l2(active->mutex);
      const std::filesystem::path c = canonicalTarget(m.path);
      for (const auto& s : active->stagedCanonical)
        if (s == c) {
          m.drop();
          throw Error(Error::Kind::BadParameter, m.target, "", "written twice by this command (two outputs with one path)");
        }
      active->staged.push_back({m.tmp, m.target, m.slot});
      active->stagedCanonical.push_back(c);
      return;
    }
  } else {
    // The whole folder is the unit of the transaction: the file goes to its place in the copy now.
    std::lock_guard<std::mutex> lock(activeMutex);
    if (active) {
      std::lock_guard<std::mutex> l2(active->mutex);
      active->stagedCanonical.push_back(canonicalTarget(m.path));
    }
  }
  if (std::rename(m.tmp.c_str(), m.where.c_str()) != 0) {
    const int e = errno;
    m.drop();
    throw Error(Error::Kind::Io, m.target, "", std::string("rename failed: ") + std::strerror(e));
  }
  releaseSlot(m.slot);
  m.slot = nullptr;
}

TemporaryFolder::TemporaryFolder(const std::filesystem::path& parent) {
  std::filesystem::path dir = parent.empty() ? std::filesystem::path(".") : parent;
  std::string tmp = absoluteString(dir / ".ls-XXXXXX");
  TempSlot* slot = claimSlot(tmp, TempSlot::Folder);
  char* made = slot ? ::mkdtemp(slot->path) : ::mkdtemp(tmp.data());
  if (!made) {
    const int e = errno;
    releaseSlot(slot);
    throw Error(Error::Kind::Io, dir.string(), "", std::string("cannot create a working folder: ") + std::strerror(e));
  }
  path_ = made;
  slot_ = slot;
}

TemporaryFolder::~TemporaryFolder() {
  removeTree(path_.string());
  releaseSlot(static_cast<TempSlot*>(slot_));
}

void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes) {
  AtomicFileWriter w(path);
  w.write(bytes.data(), bytes.size());
  w.commit();
}

}  // namespace linesurf
