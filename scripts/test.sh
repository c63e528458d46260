#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, checks the layout (scripts/lint.sh --format-only:
# any clang-format difference fails), runs a short fuzz run of every fuzz target (25 s each, under ASan + UBSan; a
# long one is `scripts/fuzz.sh --seconds 3600`), runs clang-tidy over the translation units of build/ and
# build-fuzz/ (the fuzz targets are in the latter's database only, which fuzz.sh configures: any finding fails;
# about an hour of one core, half an hour on two), then every test (ctest, without the 'soak' label, which holds long
# load runs:
# run those with `ctest --test-dir build -L soak`; nor the 'docker' label: the image built from a debootstrapped base
# and run with buildah and podman, about an hour on a first run: `ctest --test-dir build -L docker`, docs/service.md).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
scripts/lint.sh --format-only
scripts/fuzz.sh --seconds 25
scripts/lint.sh --tidy-only --build-dir build --build-dir build-fuzz
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$PWD/build/pocl-cache}"
ctest --test-dir build --output-on-failure --timeout 900 -LE 'soak|docker' -j "$(nproc)"
