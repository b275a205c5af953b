#!/usr/bin/env bash
# Installs the Debian 12 packages liedyn needs. Idempotent; run as root (or with sudo).
set -euo pipefail
packages=(
  build-essential cmake ninja-build pkg-config ccache
  libeigen3-dev libsuitesparse-dev
  libceres-dev coinor-libipopt-dev libnlopt-cxx-dev
  nlohmann-json3-dev libcli11-dev
  libcairo2-dev fonts-dejavu-core libtinyobjloader-dev libtinygltf-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libfcl-dev
  pybind11-dev python3-dev python3-numpy python3-pytest python3-scipy python3-torch
  libopenmpi-dev openmpi-bin
  libjs-three chromium
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed' || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
sudo_cmd=()
[ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update
"${sudo_cmd[@]}" apt-get install -y --no-install-recommends "${missing[@]}"
