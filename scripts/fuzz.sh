#!/usr/bin/env bash
# Bounded libFuzzer run of the PLY reader (seconds given as $1). Needs clang.
set -euo pipefail
SECS=${1:-60}
if ! command -v clang++ >/dev/null; then echo "fuzz: clang++ not found, skipped"; exit 0; fi
echo "fuzz: no fuzz targets yet"
