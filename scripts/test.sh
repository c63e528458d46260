#!/usr/bin/env bash
# The README's test command: installs what is missing, builds, checks the layout (scripts/lint.sh --format-only:
# any clang-format difference fails; clang-tidy's gate, `scripts/lint.sh --tidy-only`, is not yet clean), runs a short fuzz run of every fuzz target (25 s each, under ASan + UBSan; a long one is
# `scripts/fuzz.sh --seconds 3600`), then every test (ctest, without the 'soak' label, which holds long load runs:
# run those with `ctest --test-dir build -L soak`; nor the 'docker' label: the image built from a debootstrapped base
# and run with buildah and podman, about an hour on a first run: `ctest --test-dir build -L docker`, docs/service.md).
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
scripts/lint.sh --format-only
scripts/fuzz.sh --seconds 25
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$PWD/build/pocl-cache}"
ctest --test-dir build --output-on-failure --timeout 900 -LE 'soak|docker' -j "$(nproc)"
