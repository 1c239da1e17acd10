#!/usr/bin/env bash
# bench/lod_frames.sh A.lod [B.lod ...]: frame times of `render --budget` on level-of-detail
# hierarchies of different sizes (does the frame time follow the budget, not the model?) and the
# picture against a larger budget. For each hierarchy and view: REPEATS renders at SIZE with -j
# THREADS at BUDGET, the median frame (select + load + render, as `render` reports them), and the
# SSIM of that picture against the same view at REF_BUDGET. Views orbit the model (AZIMUTHS,
# elevation 20) at the default distance, and at half of it (close-ups) with CLOSE=1.
# Environment: BUDGET (2000000), REF_BUDGET (20000000), SIZE (1024x1024), THREADS (2), REPEATS (3),
# AZIMUTHS ("30 150 270"), LINESURF_BUILD (build). Figures in docs/benchmarks.md.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
ls="${LINESURF_BUILD:-$root/build}/linesurf"
budget=${BUDGET:-2000000}
ref=${REF_BUDGET:-20000000}
size=${SIZE:-1024x1024}
threads=${THREADS:-2}
repeats=${REPEATS:-3}
azimuths=${AZIMUTHS:-30 150 270}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf '%-28s %5s %10s %8s %8s %8s %10s %7s\n' hierarchy view splats select load render frame_ms ssim
for lod in "$@"; do
  for az in $azimuths; do
    times=()
    for ((r = 0; r < repeats; ++r)); do
      out=$("$ls" render "$lod" -o "$tmp/b.png" --size "$size" --budget "$budget" -j "$threads" --azimuth "$az" 2>&1)
      sel=$(sed -n 's/.*select \([0-9.]*\) ms.*/\1/p' <<<"$out")
      load=$(sed -n 's/.*load \([0-9.]*\) ms.*/\1/p' <<<"$out")
      ren=$(sed -n 's/^render [0-9x]*: \([0-9.]*\) ms.*/\1/p' <<<"$out")
      splats=$(sed -n 's/.*nodes, \([0-9]*\) splats.*/\1/p' <<<"$out")
      times+=("$(awk -v a="$sel" -v b="$load" -v c="$ren" 'BEGIN { printf "%.1f %.1f %.1f %.1f", a, b, c, a + b + c }')")
    done
    med=$(printf '%s\n' "${times[@]}" | sort -k4 -n | sed -n "$(((repeats + 1) / 2))p")
    "$ls" render "$lod" -o "$tmp/ref.png" --size "$size" --budget "$ref" -j "$threads" --azimuth "$az" -q
    ssim=$("$ls" compare "$tmp/ref.png" "$tmp/b.png" --json | sed -n 's/.*"ssim": *\([0-9.]*\).*/\1/p')
    read -r s l rr f <<<"$med"
    printf '%-28s %5s %10s %8s %8s %8s %10s %7.4f\n' "$(basename "$lod")" "az$az" "$splats" "$s" "$l" "$rr" "$f" "$ssim"
  done
done
