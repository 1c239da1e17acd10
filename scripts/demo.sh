#!/usr/bin/env bash
# The main job on the bundled model: info + normals (extended by later stages).
set -euo pipefail
CLI=${1:-build/linesurf}
OUT=${2:-out/demo}
mkdir -p "$OUT"
"$CLI" --version
echo "demo: outputs in $OUT"
