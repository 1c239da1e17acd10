#pragma once
/// Progress reporting without printing: long library calls take an optional callback that
/// receives the fraction done in [0, 1] (and a stage label). The CLI turns it into a bar on a TTY.
#include <functional>
#include <string_view>

namespace linesurf {

using ProgressFn = std::function<void(std::string_view stage, double fraction)>;

/// Calls fn if set. Safe to call from worker threads only when fn is thread-safe; library code
/// reports from the calling thread (e.g. after each parallel chunk).
inline void reportProgress(const ProgressFn& fn, std::string_view stage, double fraction) {
  if (fn) fn(stage, fraction);
}

}  // namespace linesurf
