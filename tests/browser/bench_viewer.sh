#!/usr/bin/env bash
# Frame time of the viewer page (linesurf view) in headless Chromium with software GL
# (SwiftShader), beside `linesurf render` of the same default view, for igea points and its
# hybrids. Usage: bench_viewer.sh [LINESURF] [FRAMES]. Prints a markdown table (docs/benchmarks.md).
set -euo pipefail
LS=$(realpath "${1:-build/linesurf}")
FRAMES=${2:-10}
SRC=$(cd "$(dirname "$0")/../.." && pwd)
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"
"$LS" extract shape-approx "$SRC/data/igea_points.ply" -o igea_greedy.ply -q
"$LS" extract eps-delta "$SRC/data/igea_points.ply" -o igea_eps_delta.ply -q
echo "| model | points | segments | viewer frame, median of $FRAMES (min-max), ms | linesurf render, ms |"
echo "|---|---:|---:|---|---:|"
for m in "$SRC/data/igea_points.ply" igea_greedy.ply igea_eps_delta.ply; do
  name=$(basename "$m" .ply)
  "$LS" view "$m" -o "$name.html" -q
  profile=$(mktemp -d "$WORK/profile.XXXXXX")
  line=$(timeout 300 chromium --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader \
    --disable-background-networking --disable-component-update --disable-sync --no-first-run \
    --force-device-scale-factor=1 --window-size=512,512 --user-data-dir="$profile" \
    --dump-dom "file://$WORK/$name.html#ui=0&bench=$FRAMES&size=512x512" 2>/dev/null | grep -o 'id="bench">bench frames=[^<]*')
  get() { sed -n "s/.*$1=\([^ ]*\).*/\1/p" <<<"$line"; }
  cpu=$("$LS" render "$m" -o "$name.png" --size 512x512 | sed -n 's/^render 512x512: \([0-9.]*\) ms.*/\1/p')
  echo "| $name | $(get points) | $(get segments) | $(get median_ms) ($(get min_ms)-$(get max_ms)) | $cpu |"
done
