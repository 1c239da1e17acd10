#pragma once
/// Writing an output so that no half-written file is ever left: the bytes go to a temporary
/// file beside the destination, which is renamed into place only after a successful close.
#include <filesystem>
#include <string_view>

namespace linesurf {

/// Writes `bytes` to `path` atomically; throws linesurf::Error (Kind::Io) on failure.
void writeFileAtomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace linesurf
