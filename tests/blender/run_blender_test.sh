#!/usr/bin/env bash
# ctest driver of the Blender test: installs the project (the texwarp package with it) into a fresh prefix, then runs
# SCRIPT in `blender -b --factory-startup` (test_blender_ui.py: in a window on Xvfb) with the add-on zip and that
# prefix's site-packages.
# Usage: run_blender_test.sh BUILD_DIR PREFIX SITE ADDON_ZIP TEXWARP_CLI TEXWARPD SCRIPT; exit 77 (skip) without
# blender.
set -euo pipefail
build=$1 prefix=$2 site=$3 zip=$4 cli=$5 texwarpd=$6 script=$7
if ! command -v blender >/dev/null; then
  echo "SKIP: blender is not installed (Debian: apt-get install blender; scripts/setup.sh installs it)"
  exit 77
fi
rm -rf "$prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
export TEXWARP_ADDON_ZIP=$zip TEXWARP_PYTHON_PATH=$prefix/$site TEXWARP_CLI=$cli TEXWARPD=$texwarpd
export POCL_CACHE_DIR=$build/pocl-cache
home=$(mktemp -d)
trap 'rm -rf "$home"' EXIT
# A scratch user folder: the add-on is installed there, not into the user's own Blender configuration.
export BLENDER_USER_CONFIG=$home/config BLENDER_USER_SCRIPTS=$home/scripts
case $(basename "$script") in
  test_blender_ui.py)  # a real window: Xvfb
    if ! command -v xvfb-run >/dev/null; then
      echo "SKIP: xvfb-run is not installed (Debian: apt-get install xvfb xauth; scripts/setup.sh installs it)"
      exit 77
    fi
    exec xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup --enable-event-simulate --python "$script" ;;
  *) exec blender -b --factory-startup --python-exit-code 1 --python "$script" ;;
esac
