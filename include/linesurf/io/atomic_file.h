#pragma once
/// Writing outputs so that no half-written file is ever left, and so that a command that fails
/// or is interrupted leaves every existing file as it was.
///
/// writeFileAtomically() puts the bytes in a temporary file beside the destination (a short
/// hidden name, so that any legal file name stays legal). Outside an OutputTransaction that file
/// is renamed into place at once. While a transaction is open (the CLI opens one per command),
/// the temporary files are only staged: OutputTransaction::commit() renames them all into place
/// once the whole command has succeeded; a transaction destroyed without commit removes them, so
/// no existing file is touched and no temporary file is left.
///
/// makeOutputFolder() does the same for a folder of outputs (an experiment's run): the folder is
/// built under a hidden temporary name and takes its place (replacing an earlier folder of that
/// name whole) only at commit; files written under its path go into the temporary folder.
///
/// Every temporary file and folder is also recorded in a process-wide cleanup registry that
/// removeTemporaryOutputs() empties with async-signal-safe calls only; installCleanupOnSignals()
/// runs it on SIGINT, SIGTERM, SIGHUP and SIGQUIT before the signal takes its default effect, so
/// an interrupted command leaves no temporary file behind and still dies by its signal.
///
/// Staging an output onto a file the command has read (see noteInput), or the same output twice,
/// is refused (Error::Kind::BadParameter).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string_view>

namespace linesurf {

/// Writes `bytes` to `path` atomically (staged when a transaction is open); throws
/// linesurf::Error (Kind::Io) when it cannot write.
void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

/// writeFileAtomically for outputs too large to hold: a temporary file beside the destination
/// (registered for cleanup on signals) written in pieces, in order or at offsets, and put in
/// place (or staged, inside a transaction) by commit(). Destroyed without commit, it removes the
/// temporary. The checks of writeFileAtomically (output onto an input, one output twice, missing
/// folder) run in the constructor, before anything is written. Throws Error (Kind::Io).
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(const std::filesystem::path& path);
  ~AtomicFileWriter();
  AtomicFileWriter(const AtomicFileWriter&) = delete;
  AtomicFileWriter& operator=(const AtomicFileWriter&) = delete;
  void write(const void* data, size_t bytes);  ///< appends at the current position
  void writeAt(uint64_t offset, const void* data, size_t bytes);
  void readAt(uint64_t offset, void* data, size_t bytes);  ///< reads back what was written
  void commit();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// A hidden working folder (`.ls-XXXXXX` in `parent`) for the temporaries of one run, removed
/// with everything in it when destroyed, and by the signal cleanup (removeTemporaryOutputs).
class TemporaryFolder {
 public:
  explicit TemporaryFolder(const std::filesystem::path& parent);  ///< throws Error (Kind::Io)
  ~TemporaryFolder();
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
  void* slot_ = nullptr;
};

/// Makes `path` a folder for outputs (its parents must exist or be output folders themselves).
/// Outside a transaction it is created at once (nothing happens when it exists). Inside one, a
/// folder that does not exist yet, or any folder when `replace` is true, is built under a hidden
/// temporary name beside it and put in place by commit(): with `replace`, an existing folder of
/// that name is swapped out whole (atomically) and removed. A folder inside a staged folder is
/// created at once in the staged copy. Throws Error (Kind::Io) when it cannot be made.
void makeOutputFolder(const std::filesystem::path& path, bool replace = false);

/// Where a write to `path` lands now: inside a staged folder's temporary copy when `path` lies
/// under a folder staged by makeOutputFolder, else `path` itself.
std::filesystem::path stagedLocation(const std::filesystem::path& path);

/// Records that the open transaction (if any) reads `path`: an output onto it is refused.
/// Called by every reader of model_io.h and image_io.h.
void noteInput(const std::filesystem::path& path);

/// One command's outputs (process-wide: at most one open at a time; thread-safe).
class OutputTransaction {
 public:
  OutputTransaction();
  ~OutputTransaction();  ///< removes every staged file and folder unless committed
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;
  /// Puts every staged folder, then every staged file (in staging order) in place. Throws Error
  /// (Kind::Io) when a rename fails; what was not yet in place is removed.
  void commit();
  /// Number of files and folders staged so far.
  size_t staged() const;

  struct State;

 private:
  std::unique_ptr<State> state_;
};

/// Removes every temporary file and folder the process has made for outputs and not yet put in
/// place or removed. Only async-signal-safe calls: may run in a signal handler.
void removeTemporaryOutputs() noexcept;
/// Installs handlers for SIGINT, SIGTERM, SIGHUP and SIGQUIT that call removeTemporaryOutputs()
/// and re-raise the signal with its default action (the exit status stays the signal's).
/// For programs (the CLI); a library embedded elsewhere leaves the host's handlers alone.
void installCleanupOnSignals();

/// Identity of an existing file (device, inode), or {0, 0} when it does not exist.
struct FileId {
  unsigned long long dev = 0, ino = 0;
  bool exists() const { return dev != 0 || ino != 0; }
  bool operator==(const FileId&) const = default;
};
FileId fileId(const std::filesystem::path& path);

}  // namespace linesurf
