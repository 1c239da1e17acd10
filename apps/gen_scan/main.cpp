// linesurf_gen_scan OUT.ply N [SEED] [NOISE]: writes a synthetic scan (ooc/synthetic_scan.h) of N
// points as binary PLY, streamed in chunks (bounded memory for any N). Deterministic for a seed.
#include <cstdio>
#include <cstdlib>
#include <string>

#include "linesurf/core/error.h"
#include "linesurf/ooc/synthetic_scan.h"

int main(int argc, char** argv) {
  if (argc < 3 || argc > 5) {
    std::fprintf(stderr, "usage: %s OUT.ply N [SEED=1] [NOISE=0.1 (fraction of the spacing)]\n", argv[0]);
    return 1;
  }
  linesurf::ooc::SyntheticScanOptions o;
  try {
    const long long n = std::stoll(argv[2]);
    if (n < 1) throw std::invalid_argument("N");
    o.count = uint64_t(n);
    if (argc > 3) o.seed = std::stoull(argv[3]);
    if (argc > 4) o.noise = std::stod(argv[4]);
    if (!(o.noise >= 0)) throw std::invalid_argument("NOISE");
  } catch (const std::exception&) {
    std::fprintf(stderr, "%s: N must be a positive integer, SEED a non-negative integer, NOISE >= 0\n", argv[0]);
    return 1;
  }
  try {
    linesurf::ooc::writeSyntheticScan(argv[1], o);
  } catch (const linesurf::Error& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 3;
  }
  return 0;
}
