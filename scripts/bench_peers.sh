#!/usr/bin/env bash
# Side-by-side benchmark of the §6.1 geometry stages against Open3D and CGAL (Debian packages;
# run scripts/install_peers.sh first). Builds bench/peers/ into build-peers/ and runs it on the
# shared igea, armadillo and dragon (vertices of the mesh) clouds.
#   scripts/bench_peers.sh [--reps N] [--no-open3d-orient] [FILES...]
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
BUILD="${LINESURF_PEERS_BUILD:-$ROOT/build-peers}"
DATA="${LINESURF_SHARED_DATA:-$ROOT/../shared/data}"
if [ ! -f /usr/lib/x86_64-linux-gnu/cmake/Open3D/Open3DConfig.cmake ] && ! pkg-config --exists Open3D 2>/dev/null; then
  echo "Open3D not found: run scripts/install_peers.sh first" >&2
  exit 1
fi
cmake -S "$ROOT/bench/peers" -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD" -j2 --target geometry_peers
ARGS=()
FILES=()
while [ $# -gt 0 ]; do
  case "$1" in
    --reps) ARGS+=("$1" "$2"); shift 2 ;;
    --*) ARGS+=("$1"); shift ;;
    *) FILES+=("$1"); shift ;;
  esac
done
if [ ${#FILES[@]} -eq 0 ]; then
  FILES=("$DATA/igea_points.ply" "$DATA/armadillo_points.ply" "$DATA/dragon_mesh.ply")
fi
"$BUILD/geometry_peers" "${ARGS[@]}" "${FILES[@]}"
