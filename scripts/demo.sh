#!/usr/bin/env bash
# The main job on the bundled models: geometry, both point-cloud extractions, contour extraction,
# renderings of point and hybrid models side by side, and their image comparison.
# Usage: scripts/demo.sh [path/to/linesurf] [output folder]
set -euo pipefail
CLI=${1:-build/linesurf}
OUT=${2:-out/demo}
DATA="$(cd "$(dirname "$0")/.." && pwd)/data"
mkdir -p "$OUT"
run() { echo; echo "\$ linesurf $*"; "$CLI" "$@"; }

run info "$DATA/santa_points.ply"
run normals "$DATA/santa_points.ply" -o "$OUT/santa_normals.ply" --curvature
run extract eps-delta "$OUT/santa_normals.ply" -o "$OUT/santa_eps_delta.ply"
run extract shape-approx "$OUT/santa_normals.ply" -o "$OUT/santa_shape_approx.ply" \
    --clustering greedy --clusters-out "$OUT/santa_clusters.ply"
run render "$OUT/santa_normals.ply" -o "$OUT/santa_points.png" --size 512x512 --azimuth 30 --elevation 15
run render "$OUT/santa_eps_delta.ply" -o "$OUT/santa_eps_delta.png" --size 512x512 --azimuth 30 --elevation 15
run render "$OUT/santa_shape_approx.ply" -o "$OUT/santa_shape_approx.png" --size 512x512 --azimuth 30 --elevation 15
run render "$OUT/santa_clusters.ply" -o "$OUT/santa_clusters.png" --size 512x512 --azimuth 30 --elevation 15
run compare "$OUT/santa_points.png" "$OUT/santa_eps_delta.png" --diff "$OUT/santa_eps_delta_diff.png"
run extract contour "$DATA/al_mesh.ply" -o "$OUT/al_segments.ply" --seed 1
run extract contour "$DATA/al_mesh.ply" -o "$OUT/al_points.ply" --seed 1 --all-points
run render "$OUT/al_segments.ply" -o "$OUT/al_segments.png" --size 512x512 --azimuth 20 --elevation 10
run render "$OUT/al_points.ply" -o "$OUT/al_points.png" --size 512x512 --azimuth 20 --elevation 10
run compare "$OUT/al_points.png" "$OUT/al_segments.png" --diff "$OUT/al_diff.png"
echo
echo "demo: pictures and models in $OUT:"
ls "$OUT"
