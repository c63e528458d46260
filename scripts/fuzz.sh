#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ into build-fuzz/ (clang, ASan + UBSan) and runs each for a while on a copy
# of its seed corpus (fuzz/corpus/<target>/ and the reproducers of fuzz/regressions/<target>/); new inputs go to
# build-fuzz/corpus-new/<target>/, never into the repository. Exits non-zero on any finding and says where the
# input that causes it is. Installs nothing (scripts/setup.sh does).
# Usage: scripts/fuzz.sh [--seconds N] [--jobs J] [TARGET...]   (default: 60 s, 1 job, every target)
set -euo pipefail
cd "$(dirname "$0")/.."

all_targets=(fuzz_job_json fuzz_http_request fuzz_image_header fuzz_mesh_obj fuzz_mesh_gltf)
seconds=60
jobs=1
targets=()
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) seconds="${2:?--seconds needs a number}"; shift 2 ;;
    --jobs) jobs="${2:?--jobs needs a number}"; shift 2 ;;
    -h|--help) sed -n '2,7p' "$0"; exit 0 ;;
    fuzz_*) targets+=("$1"); shift ;;
    *) echo "fuzz.sh: unknown argument '$1' (targets: ${all_targets[*]})" >&2; exit 2 ;;
  esac
done
if ! [[ "$seconds" =~ ^[0-9]+$ && "$seconds" -ge 1 ]]; then echo "fuzz.sh: --seconds must be a whole number ≥ 1, got '$seconds'" >&2; exit 2; fi
if ! [[ "$jobs" =~ ^[0-9]+$ && "$jobs" -ge 1 ]]; then echo "fuzz.sh: --jobs must be a whole number ≥ 1, got '$jobs'" >&2; exit 2; fi
if [ ${#targets[@]} -eq 0 ]; then targets=("${all_targets[@]}"); fi
for t in "${targets[@]}"; do
  if [[ ! " ${all_targets[*]} " =~ " $t " ]]; then echo "fuzz.sh: unknown target '$t' (targets: ${all_targets[*]})" >&2; exit 2; fi
done
for tool in clang clang++ cmake ninja; do
  command -v "$tool" >/dev/null 2>&1 || { echo "fuzz.sh: $tool not found: run scripts/setup.sh" >&2; exit 2; }
done

# Longest input per target: above the 16 KiB header limit for HTTP, room for a small job, image or mesh otherwise.
max_len() {
  case "$1" in
    fuzz_http_request) echo 20000 ;;
    *) echo 16384 ;;
  esac
}

build=build-fuzz
if [ ! -f "$build/CMakeCache.txt" ]; then
  CC=clang CXX=clang++ cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DTEXWARP_BUILD_FUZZ=ON -DTEXWARP_BUILD_TESTS=OFF -DTEXWARP_BUILD_BENCH=OFF
fi
cmake --build "$build" --parallel "$(nproc)" --target "${targets[@]}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:allocator_may_return_null=0:handle_abort=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# Leaks inside third-party libraries (named there, with the reason) are not findings.
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$PWD/scripts/sanitizer-suppressions/lsan.supp:print_suppressions=0}"
# The image target writes one temporary file per input: keep them in memory when possible.
if [ -z "${TMPDIR:-}" ] && [ -d /dev/shm ] && [ -w /dev/shm ]; then export TMPDIR=/dev/shm; fi

failed=()
for t in "${targets[@]}"; do
  new="$build/corpus-new/$t"
  crashes="$build/crashes/$t"
  log="$build/logs/$t.log"
  mkdir -p "$new" "$crashes" "$(dirname "$log")"
  seeds=("fuzz/corpus/$t")
  if [ -d "fuzz/regressions/$t" ]; then seeds+=("fuzz/regressions/$t"); fi
  extra=()
  if [ "$jobs" -gt 1 ]; then extra+=("-fork=$jobs"); fi
  if [ -f "fuzz/dict/$t.dict" ]; then extra+=("-dict=fuzz/dict/$t.dict"); fi
  # Suppressions match whole stacks: the image target's third-party leaks need the slow unwinder to be seen whole.
  asan_options="$ASAN_OPTIONS"
  if [ "$t" = fuzz_image_header ]; then asan_options="$asan_options:fast_unwind_on_malloc=0"; fi
  echo "fuzz.sh: $t for ${seconds} s (log: $log)"
  status=0
  ASAN_OPTIONS="$asan_options" "$build/fuzz/$t" "${extra[@]}" -max_total_time="$seconds" -max_len="$(max_len "$t")" -timeout=30 -malloc_limit_mb=512 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$crashes/" "$new" "${seeds[@]}" >"$log" 2>&1 || status=$?
  rm -f "${TMPDIR:-/tmp}"/texwarp-fuzz-image-*  # left behind when an input ended the process
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || true)
  cov=$(grep -o 'cov: [0-9]*' "$log" | tail -1 | grep -o '[0-9]*$' || true)
  if [ "$status" -ne 0 ]; then
    failed+=("$t")
    echo "fuzz.sh: $t FOUND A PROBLEM (exit $status; ${execs:-?} inputs run)" >&2
    grep -E '^==[0-9]+== ?ERROR|runtime error|finding:|deadly signal|Test unit written to' "$log" | head -6 >&2 || true
    grep -E '^ +#[0-9]+ 0x' "$log" | grep -vE ' in (fuzzer::|__sanitizer|__asan|__ubsan|operator new|std::|__libc_start|_start )' | head -10 >&2 || true
    echo "fuzz.sh: reproduce with: $build/fuzz/$t <input above>   (whole log: $log)" >&2
  else
    echo "fuzz.sh: $t ok: ${execs:-?} inputs, ${cov:-?} coverage points, corpus $new: $(ls "$new" | wc -l) inputs"
  fi
done

if [ ${#failed[@]} -ne 0 ]; then
  echo "fuzz.sh: findings in ${failed[*]}; inputs under $build/crashes/" >&2
  exit 1
fi
