#!/usr/bin/env bash
# The main job on the bundled models: geometry (§6.1), the point-cloud extractions (§3.1, §3.2,
# the lines of curvature of §9.2), contour extraction (§3.3), renderings of point and hybrid models from the same view (§4-§6.2)
# and their image comparison (§7).
# Usage: scripts/demo.sh [path/to/linesurf] [output folder]
set -euo pipefail
CLI=${1:-build/linesurf}
OUT=${2:-out/demo}
DATA="$(cd "$(dirname "$0")/.." && pwd)/data"
mkdir -p "$OUT"
run() { echo; echo "\$ linesurf $*"; "$CLI" "$@"; }
VIEW=(--size 512x512 --azimuth 0 --elevation 10)

# Point cloud: the Igea artifact scan (134,345 points, the thesis's own model).
run info "$DATA/igea_points.ply"
run normals "$DATA/igea_points.ply" -o "$OUT/igea_normals.ply" --curvature
run extract eps-delta "$OUT/igea_normals.ply" -o "$OUT/igea_eps_delta.ply"
run extract shape-approx "$OUT/igea_normals.ply" -o "$OUT/igea_shape_approx.ply" \
    --clustering greedy --clusters-out "$OUT/igea_clusters.ply"
run extract curvature-lines "$OUT/igea_normals.ply" -o "$OUT/igea_curvature_lines.ply"
run render "$OUT/igea_normals.ply" -o "$OUT/igea_points.png" "${VIEW[@]}"
run render "$OUT/igea_eps_delta.ply" -o "$OUT/igea_eps_delta.png" "${VIEW[@]}"
run render "$OUT/igea_shape_approx.ply" -o "$OUT/igea_shape_approx.png" "${VIEW[@]}"
run render "$OUT/igea_clusters.ply" -o "$OUT/igea_clusters.png" "${VIEW[@]}"
run render "$OUT/igea_curvature_lines.ply" -o "$OUT/igea_curvature_lines.png" "${VIEW[@]}"
run compare "$OUT/igea_points.png" "$OUT/igea_eps_delta.png" --diff "$OUT/igea_eps_delta_diff.png"
run compare "$OUT/igea_points.png" "$OUT/igea_shape_approx.png" --diff "$OUT/igea_shape_approx_diff.png"
run compare "$OUT/igea_points.png" "$OUT/igea_curvature_lines.png"

# Triangle mesh: Al, cut into a pure line-segment model and a pure point model.
run extract contour "$DATA/al_mesh.ply" -o "$OUT/al_segments.ply" --seed 1
run extract contour "$DATA/al_mesh.ply" -o "$OUT/al_points.ply" --seed 1 --all-points
run render "$OUT/al_segments.ply" -o "$OUT/al_segments.png" --size 512x512 --azimuth 20 --elevation 10
run render "$OUT/al_points.ply" -o "$OUT/al_points.png" --size 512x512 --azimuth 20 --elevation 10
run compare "$OUT/al_points.png" "$OUT/al_segments.png" --diff "$OUT/al_diff.png"

# Interactive pages (WebGL2, open offline in a browser): the hybrid and the line model.
run view "$OUT/igea_eps_delta.ply" -o "$OUT/igea_eps_delta.html"
run view "$OUT/al_segments.ply" -o "$OUT/al_segments.html"

# A real scan as it comes, where ../shared is beside the clone: the coloured photogrammetric lion
# (LAS 1.2, z-up, vegetation and outliers) cleaned, oriented, extracted with a tolerance relative
# to its noise, put into a hierarchy and drawn from it.
LION="$(dirname "$DATA")/../shared/data/lion_takanawa.las"
if [ -f "$LION" ]; then
  run clean "$LION" -o "$OUT/lion_clean.ply"
  run normals "$OUT/lion_clean.ply" -o "$OUT/lion_normals.ply"
  run extract eps-delta "$OUT/lion_normals.ply" -o "$OUT/lion_eps_delta.ply" --epsilon-noise 2
  run lod build "$OUT/lion_eps_delta.ply" -o "$OUT/lion.lod"
  run render "$OUT/lion_normals.ply" -o "$OUT/lion_points.png"
  run render "$OUT/lion_eps_delta.ply" -o "$OUT/lion_eps_delta.png"
  run render "$OUT/lion.lod" -o "$OUT/lion_lod.png" --budget 100000
  run compare "$OUT/lion_points.png" "$OUT/lion_eps_delta.png"
  run view "$OUT/lion_eps_delta.ply" -o "$OUT/lion_eps_delta.html"
else
  echo; echo "demo: no ../shared/data/lion_takanawa.las beside the clone: the real-scan part is skipped"
fi
echo
echo "demo: pictures (*.png), models (*.ply) and viewer pages (*.html) in $OUT"
