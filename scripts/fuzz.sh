#!/usr/bin/env bash
# Bounded libFuzzer runs of the model and hierarchy readers: scripts/fuzz.sh [SECS] [TARGET...]
#   SECS     seconds per target (default 30)
#   TARGET   any of ply_fuzz obj_fuzz xyz_fuzz las_fuzz roundtrip_fuzz lod_fuzz (default: all six, one after another)
# Configures a separate clang build folder (build-fuzz, or $FUZZ_BUILD) with LINESURF_FUZZ=ON,
# builds only the fuzz targets (an instrumented copy of src/core + src/io and the .lod reader, no
# CGAL units) and runs each on a copy of tests/fuzz/corpus_<name> with tests/fuzz/<name>.dict. Exits non-zero when
# libFuzzer finds a crash, a leak, an uncaught exception, a timeout or an allocation over the RSS
# limit; the reproducer is left in build-fuzz/fuzz-artifacts/. Prints executions per target.
set -euo pipefail
SECS=${1:-30}
shift || true
TARGETS=("$@")
[ ${#TARGETS[@]} -eq 0 ] && TARGETS=(ply_fuzz obj_fuzz xyz_fuzz las_fuzz roundtrip_fuzz lod_fuzz)
ROOT=$(cd "$(dirname "$0")/.." && pwd)
BUILD=${FUZZ_BUILD:-$ROOT/build-fuzz}
if ! command -v clang++ >/dev/null; then echo "fuzz: clang++ not found, skipped"; exit 0; fi
CC=clang CXX=clang++ cmake -S "$ROOT" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DLINESURF_FUZZ=ON -DLINESURF_BENCH=OFF >"$BUILD.configure.log" 2>&1 || { cat "$BUILD.configure.log"; exit 1; }
cmake --build "$BUILD" --target "${TARGETS[@]}" -j "$(nproc)"
mkdir -p "$BUILD/fuzz-artifacts"
for t in "${TARGETS[@]}"; do
  name=${t%_fuzz}
  WORK=$(mktemp -d)
  cp "$ROOT/tests/fuzz/corpus_$name"/* "$WORK/"
  DICT=()
  [ -f "$ROOT/tests/fuzz/$name.dict" ] && DICT=(-dict="$ROOT/tests/fuzz/$name.dict")
  echo "fuzz: running $t for ${SECS}s"
  LOG="$BUILD/fuzz-$name.log"
  rc=0
  "$BUILD/$t" "$WORK" -max_total_time="$SECS" -rss_limit_mb=2048 -max_len=65536 -timeout=10 "${DICT[@]}" \
    -artifact_prefix="$BUILD/fuzz-artifacts/$name-" -print_final_stats=1 >"$LOG" 2>&1 || rc=$?
  rm -rf "$WORK"
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$LOG" | grep -o '[0-9]*$' || echo "?")
  if [ $rc -ne 0 ]; then
    tail -40 "$LOG"
    echo "fuzz: $t FOUND A PROBLEM after $execs executions (exit $rc); reproducer in $BUILD/fuzz-artifacts/"
    exit 1
  fi
  echo "fuzz: $t: $execs executions in ${SECS}s, no findings"
done
