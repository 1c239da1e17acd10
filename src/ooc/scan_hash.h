#pragma once
// The hashing of the synthetic scans (synthetic_scan.cpp, synthetic_scene.cpp): every deviate of
// point i comes from (seed, i), so any N is generated in chunks, the same for any thread count.
#include <cstdint>
#include <cstring>
#include <string>

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

/// A fast streaming 64-bit hash over 8-byte words, SplitMix64's finaliser between them: the
/// checksum of the tile folder's working files and the input's content identity. No hash library
/// is among the project's Debian packages; this runs near memory speed (one multiply-xorshift
/// round a word) and a flipped bit anywhere changes the result with full avalanche.
struct Hasher {
  explicit Hasher(uint64_t seed = 0) : h_(seed ^ 0x6c696e6573757266ull) {}
  void add(const char* data, size_t n) {
    if (tailN_) {
      while (tailN_ < 8 && n) tail_[tailN_++] = *data++, --n;
      if (tailN_ < 8) return;
      word(tail_), tailN_ = 0;
    }
    for (; n >= 8; data += 8, n -= 8) word(data);
    std::memcpy(tail_, data, n), tailN_ = n;
  }
  uint64_t finish() const {
    uint64_t w = 0;
    std::memcpy(&w, tail_, tailN_);
    return splitmix(splitmix(h_ ^ w) ^ (words_ * 8 + tailN_));
  }

 private:
  void word(const char* p) {
    uint64_t w;
    std::memcpy(&w, p, 8);
    h_ = splitmix(h_ ^ w), ++words_;
  }
  uint64_t h_, words_ = 0;
  char tail_[8] = {};
  size_t tailN_ = 0;
};

inline uint64_t hash64(const char* data, size_t n, uint64_t seed = 0) {
  Hasher x(seed);
  x.add(data, n);
  return x.finish();
}

}  // namespace linesurf::ooc::detail
