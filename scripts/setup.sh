#!/usr/bin/env bash
# Installs every dependency of linesurf from Debian packages. Idempotent.
set -euo pipefail
PKGS=(
  build-essential cmake ninja-build ccache pkg-config clang libclang-rt-14-dev
  libeigen3-dev libnanoflann-dev libcgal-dev libgmp-dev libmpfr-dev libboost-dev libtbb-dev
  libstb-dev libcli11-dev libfmt-dev nlohmann-json3-dev libtinyobjloader-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  chromium  # headless browser test of `linesurf view` (tests/browser)
  libhwy-dev
  libcpp-httplib-dev  # optional: `linesurf view MODEL.lod` serves the streaming viewer
  openmpi-bin libopenmpi-dev  # optional: `mpirun -n N linesurf normals` (out-of-core tiles over ranks)
  python3 python3-dev python3-numpy python3-pytest pybind11-dev
)
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#PKGS[@]} packages already installed"
  exit 0
fi
echo "setup: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
