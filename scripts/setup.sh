#!/usr/bin/env bash
# Installs the Debian 12 packages texwarp needs, only those missing (idempotent; a no-op when all are present).
# Usage: scripts/setup.sh           everything: build, tests, benchmarks, fuzzing, lint (uses sudo when not root)
#        scripts/setup.sh --build   only what building texwarpd and texwarp needs (docker/Dockerfile's build stage)
set -euo pipefail

# Building the libraries, texwarpd and the texwarp command line.
build_packages=(
  build-essential cmake ninja-build pkg-config
  ocl-icd-opencl-dev opencl-clhpp-headers opencl-c-headers
  libboost-dev nlohmann-json3-dev libopenimageio-dev libeigen3-dev
  libtinyobjloader-dev libsqlite3-dev libssl-dev libcli11-dev
  libpqxx-dev                     # the PostgreSQL job store (pulls libpq-dev)
  python3-dev pybind11-dev        # the texwarp Python module (client/python; skipped when missing)
  libtinygltf-dev                 # glTF meshes (its header; compiled into texwarp_mesh without image codecs)
  liblbfgspp-dev                  # L-BFGS (header-only, on Eigen) of the UV untangling (core/mesh)
  libsuitesparse-dev              # CHOLMOD: the sparse Cholesky factor of LSCM and the UV optimisation (core/mesh)
  libopenblas0-pthread            # the BLAS CHOLMOD's supernodes run on (Debian's reference BLAS is ~3× slower)
  libpng-dev                      # PNG read and written directly (core); OpenImageIO only in the image module
  # Debian's OpenImageIO CMake package (libopenimageio-dev) fails find_package unless the files it names exist:
  # its tools' binaries (/usr/bin/iconvert, …) and the include folder /usr/include/opencv4.
  openimageio-tools libopencv-core-dev
  libopencolorio-dev              # the image module asks the $OCIO config which spaces are data (OpenImageIO cannot)
)
# Running and testing: PoCL (the OpenCL device), the test suites, benchmarks, fuzzing and lint.
dev_packages=(
  pocl-opencl-icd clinfo python3-jsonschema
  libopencv-imgproc-dev libopencv-shape-dev
  libgtest-dev libgmock-dev libbenchmark-dev
  python3-opencv                  # OpenCV's TPS in bench/whole_command_bench.py (run it with /usr/bin/python3)
  python3-openimageio             # OpenImageIO's TextureSystem row of bench/resampling_bench.py
  time                            # GNU time: the peak RSS of commands in bench/resampling_bench.py, texture_set_bench.py
  python3-mypy                    # the Python module's type stubs checked by tests/python (mypy --strict)
  postgresql-15                   # the throw-away test clusters of scripts/pg_test_cluster.sh
  clang libclang-rt-14-dev        # libFuzzer and the sanitizer runtimes for scripts/fuzz.sh
  clang-format-14 clang-tidy-14   # scripts/lint.sh
  blender                         # the Blender add-on's headless test (tests/blender; Blender 3.4, python3.11)
  xvfb xauth                      # the add-on from Blender's UI in a window (tests/blender/test_blender_ui.py)
)

case "${1:-}" in
  "") packages=("${build_packages[@]}" "${dev_packages[@]}") ;;
  --build) packages=("${build_packages[@]}") ;;
  *) echo "usage: scripts/setup.sh [--build] (got '$1')" >&2; exit 2 ;;
esac

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
