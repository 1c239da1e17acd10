#!/usr/bin/env bash
# Installs the peer libraries of the side-by-side geometry benchmark (scripts/bench_peers.sh):
# Open3D from Debian (CGAL is already a build dependency of linesurf). Optional: the main build,
# the tests and the CLI never need Open3D.
set -euo pipefail
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update
$SUDO apt-get install -y --no-install-recommends libopen3d-dev libcgal-dev
