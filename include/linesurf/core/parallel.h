#pragma once
/// The project's one parallel wrapper (over oneTBB). Each task must write only its own output
/// slots so that results are identical for any thread count.
#include <cstddef>
#include <functional>

namespace linesurf {

/// Calls f(i) for i in [begin, end), in parallel, in chunks of at least `grain` indices.
void parallelFor(size_t begin, size_t end, const std::function<void(size_t)>& f, size_t grain = 256);
/// Calls f(chunkBegin, chunkEnd) over disjoint chunks covering [begin, end).
void parallelForRange(size_t begin, size_t end, const std::function<void(size_t, size_t)>& f, size_t grain = 256);

/// Limits the worker threads of every later parallel call (0 = hardware concurrency).
/// Lives until the returned object is destroyed; the CLI keeps one for its lifetime.
class ThreadLimit {
 public:
  explicit ThreadLimit(int threads);
  ~ThreadLimit();
  ThreadLimit(const ThreadLimit&) = delete;
  ThreadLimit& operator=(const ThreadLimit&) = delete;
 private:
  void* control_ = nullptr;
};

/// Number of threads parallel calls will use now.
int currentThreadCount();

}  // namespace linesurf
