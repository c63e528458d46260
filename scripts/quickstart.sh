#!/usr/bin/env bash
# The README's main job: installs what is missing, builds, and warps the shipped example image with its
# 20-feature file. Outputs: out/astronaut-warped.png (the warp) and out/astronaut-check.json (its report).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$PWD/build/pocl-cache}"
mkdir -p out
build/client/texwarp warp --features examples/astronaut-features.json --in examples/astronaut.png \
  --out out/astronaut-warped.png
build/client/texwarp check --features examples/astronaut-features.json --width 512 --height 512 \
  > out/astronaut-check.json
echo "quickstart: wrote out/astronaut-warped.png and out/astronaut-check.json"
