#!/usr/bin/env bash
# Installs every Debian package nimbus needs to build, test, fuzz (clang-14 + its libFuzzer runtime)
# and validate.
# Idempotent: does nothing when everything is already present. Needs root (or sudo) on Debian 12.
set -euo pipefail

packages=(
  cmake ninja-build g++ make pkg-config
  libopenvdb-dev libnanovdb-dev libblosc-dev zlib1g-dev
  libopenexr-dev libimath-dev libpng-dev
  libboost-iostreams-dev libtbb-dev nlohmann-json3-dev libcli11-dev libfmt-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  libembree-dev libtinyobjloader-dev
  clang-14 libclang-rt-14-dev
  python3 python3-numpy python3-matplotlib python3-dev pybind11-dev python3-pybind11
  slurm-wlm munge
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi

echo "nimbus: installing missing packages: ${missing[*]}" >&2
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null 2>&1; then SUDO="sudo"; else
    echo "nimbus: need root to install: ${missing[*]}" >&2; exit 1
  fi
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
