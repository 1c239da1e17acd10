#pragma once
/// CPU time of the calling thread: the pipeline's per-stage thread times (RenderStats), robust
/// against other processes on a shared machine.
#include <ctime>

namespace linesurf::detail {

inline double threadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace linesurf::detail
