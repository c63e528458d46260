#!/usr/bin/env bash
# Installs the Debian 12 packages texwarp needs, only those missing (idempotent; a no-op when all are present).
# Usage: scripts/setup.sh            (uses sudo when not root)
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  pocl-opencl-icd ocl-icd-opencl-dev opencl-clhpp-headers opencl-c-headers clinfo
  libboost-dev nlohmann-json3-dev libopenimageio-dev openimageio-tools libeigen3-dev
  libtinyobjloader-dev libsqlite3-dev libssl-dev python3-jsonschema
  libopencv-imgproc-dev libopencv-shape-dev
  libcli11-dev libgtest-dev libgmock-dev libbenchmark-dev
  clang libclang-rt-14-dev  # libFuzzer and the sanitizer runtimes for scripts/fuzz.sh
)

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} packages present"
  exit 0
fi

sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
echo "setup: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "setup: done"
