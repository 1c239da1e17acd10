#!/usr/bin/env bash
# Bounded libFuzzer run of the PLY reader: scripts/fuzz.sh [SECS] (default 60).
# Configures a separate clang build folder (build-fuzz, or $FUZZ_BUILD) with LINESURF_FUZZ=ON,
# builds only the fuzz target (an instrumented copy of src/core + src/io, no CGAL units) and runs
# it on a copy of tests/fuzz/corpus_ply. Exits non-zero when libFuzzer finds a crash, a leak, an
# uncaught exception, a timeout or an allocation over the RSS limit; the reproducer is left in
# build-fuzz/fuzz-artifacts/.
set -euo pipefail
SECS=${1:-60}
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${FUZZ_BUILD:-$ROOT/build-fuzz}
if ! command -v clang++ >/dev/null; then echo "fuzz: clang++ not found, skipped"; exit 0; fi
CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DLINESURF_FUZZ=ON -DLINESURF_BENCH=OFF >"$BUILD.configure.log" 2>&1 || { cat "$BUILD.configure.log"; exit 1; }
cmake --build "$BUILD" --target ply_fuzz -j "$(nproc)"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cp "$ROOT"/tests/fuzz/corpus_ply/* "$WORK/"
mkdir -p "$BUILD/fuzz-artifacts"
echo "fuzz: running ply_fuzz for ${SECS}s"
"$BUILD/ply_fuzz" "$WORK" -max_total_time="$SECS" -rss_limit_mb=2048 -max_len=65536 -timeout=10 \
  -dict="$ROOT/tests/fuzz/ply.dict" -artifact_prefix="$BUILD/fuzz-artifacts/" -print_final_stats=1
echo "fuzz: no findings in ${SECS}s"
