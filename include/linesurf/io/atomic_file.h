#pragma once
/// Writing outputs so that no half-written file is ever left, and so that a command that fails
/// leaves every existing file as it was.
///
/// writeFileAtomically() puts the bytes in a temporary file beside the destination. Outside an
/// OutputTransaction that file is renamed into place at once. While a transaction is open (the
/// CLI opens one per command), the temporary files are only staged: OutputTransaction::commit()
/// renames them all into place once the whole command has succeeded; a transaction destroyed
/// without commit removes them, so no existing file is touched and no temporary file is left.
/// Staging an output onto a file the command has read (see noteInput), or the same output twice,
/// is refused (Error::Kind::BadParameter).
#include <filesystem>
#include <memory>
#include <string_view>

namespace linesurf {

/// Writes `bytes` to `path` atomically (staged when a transaction is open); throws
/// linesurf::Error (Kind::Io) when it cannot write.
void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

/// Records that the open transaction (if any) reads `path`: an output onto it is refused.
/// Called by every reader of model_io.h and image_io.h.
void noteInput(const std::filesystem::path& path);

/// One command's outputs (process-wide: at most one open at a time; thread-safe).
class OutputTransaction {
 public:
  OutputTransaction();
  ~OutputTransaction();  ///< removes every staged file unless committed
  OutputTransaction(const OutputTransaction&) = delete;
  OutputTransaction& operator=(const OutputTransaction&) = delete;
  /// Renames every staged file into place (in staging order). Throws Error (Kind::Io) when a
  /// rename fails; the files not yet renamed are removed.
  void commit();
  /// Number of files staged so far.
  size_t staged() const;

  struct State;

 private:
  std::unique_ptr<State> state_;
};

/// Identity of an existing file (device, inode), or {0, 0} when it does not exist.
struct FileId {
  unsigned long long dev = 0, ino = 0;
  bool exists() const { return dev != 0 || ino != 0; }
  bool operator==(const FileId&) const = default;
};
FileId fileId(const std::filesystem::path& path);

}  // namespace linesurf
