#include "linesurf/core/parallel.h"

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

namespace linesurf {

void parallelFor(size_t begin, size_t end, const std::function<void(size_t)>& f, size_t grain) {
  if (begin >= end) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, grain > 0 ? grain : 1),
                    [&](const tbb::blocked_range<size_t>& r) {
                      for (size_t i = r.begin(); i != r.end(); ++i) f(i);
                    });
}

void parallelForRange(size_t begin, size_t end, const std::function<void(size_t, size_t)>& f, size_t grain) {
  if (begin >= end) return;
  tbb::parallel_for(tbb::blocked_range<size_t>(begin, end, grain > 0 ? grain : 1),
                    [&](const tbb::blocked_range<size_t>& r) { f(r.begin(), r.end()); });
}

ThreadLimit::ThreadLimit(int threads) {
  if (threads > 0)
    control_ = new tbb::global_control(tbb::global_control::max_allowed_parallelism, size_t(threads));
}

ThreadLimit::~ThreadLimit() { delete static_cast<tbb::global_control*>(control_); }

int currentThreadCount() {
  return int(tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism));
}

}  // namespace linesurf
