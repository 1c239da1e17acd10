#!/usr/bin/env bash
# bench/ooc_bench.sh [N...]: in-memory vs out-of-core `normals` and `extract eps-delta` on synthetic
# scans of N points (default 1000000 10000000), measured with /usr/bin/time -v (wall, CPU, peak
# RSS). Scans and outputs go to ${OOC_BENCH_DIR:-/tmp/linesurf_ooc_bench}; the out-of-core runs use
# --max-mb ${OOC_MAX_MB:-1024}. Figures in docs/benchmarks.md ("Out of core").
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${LINESURF_BUILD:-$root/build}"
dir="${OOC_BENCH_DIR:-/tmp/linesurf_ooc_bench}"
mb="${OOC_MAX_MB:-1024}"
mkdir -p "$dir"
sizes=("$@")
[[ ${#sizes[@]} -gt 0 ]] || sizes=(1000000 10000000)
measure() {  # label, command...
  local label=$1
  shift
  /usr/bin/time -v "$@" > "$dir/last.out" 2> "$dir/last.time"
  local wall cpu rss
  wall=$(grep "Elapsed" "$dir/last.time" | awk '{print $NF}')
  cpu=$(awk '/User time|System time/ {s += $NF} END {print s}' "$dir/last.time")
  rss=$(grep "Maximum resident" "$dir/last.time" | awk '{print $NF}')
  printf '%-34s wall %-9s cpu %8.1f s  peak RSS %6.0f MB\n' "$label" "$wall" "$cpu" "$((rss / 1024))"
}
for n in "${sizes[@]}"; do
  scan="$dir/scan_$n.ply"
  [[ -f "$scan" ]] || "$build/linesurf_gen_scan" "$scan" "$n" 1
  measure "normals $n in memory" "$build/linesurf" normals "$scan" -o "$dir/n_mem.ply" --max-mb 1000000
  measure "normals $n out of core" "$build/linesurf" normals "$scan" -o "$dir/n_ooc.ply" --out-of-core --max-mb "$mb"
  cmp -s "$dir/n_mem.ply" "$dir/n_ooc.ply" && echo "  outputs byte-identical" || echo "  outputs differ"
  measure "eps-delta $n in memory" "$build/linesurf" extract eps-delta "$scan" -o "$dir/e_mem.ply" --max-mb 1000000
  measure "eps-delta $n out of core" "$build/linesurf" extract eps-delta "$scan" -o "$dir/e_ooc.ply" --out-of-core --max-mb "$mb"
done
