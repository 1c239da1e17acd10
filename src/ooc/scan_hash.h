#pragma once
// The hashing of the synthetic scans (synthetic_scan.cpp, synthetic_scene.cpp): every deviate of
// point i comes from (seed, i), so any N is generated in chunks, the same for any thread count.
#include <cstdint>

namespace linesurf::ooc::detail {

/// SplitMix64's finaliser: a 64-bit hash with full avalanche.
inline uint64_t splitmix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
/// The top 53 bits as a double in [0, 1).
inline double unit(uint64_t x) { return double(x >> 11) * (1.0 / 9007199254740992.0); }

}  // namespace linesurf::ooc::detail
