#!/usr/bin/env bash
# Builds the project with a sanitizer into a tree of its own and runs the tests there; any finding fails.
#   asan: build-asan, gcc -fsanitize=address,undefined; every test but the 'soak' and 'docker' labels
#         (ctest -LE 'soak|docker', as scripts/test.sh: long load runs, and an image build of about an hour) and
#         'package' (see below); 'python' and 'blender' in a second pass with the runtime preloaded.
#   tsan: build-tsan, gcc -fsanitize=thread; the server, farm and client suites (the binaries in tsan_suites below,
#         every test they hold but the 'soak' and 'docker' labels; only they and what they need are built). They are
#         chosen by executable: ctest names a discovered test Suite.Case, so no name pattern (-R) picks a binary.
# Both at -O1 (what the sanitizers' documentation advises; it builds in about half the time of -O3) with NDEBUG.
# Reports of every process (tests and the texwarpd they start) go to <tree>/sanitizer-logs/, printed at the end.
# Suppressions (third-party frames only): scripts/sanitizer-suppressions/. Installs nothing (scripts/setup.sh does).
# Usage: scripts/sanitize.sh asan|tsan [extra ctest arguments...]
set -euo pipefail
cd "$(dirname "$0")/.."

kind="${1:-}"
case "$kind" in
  # UBSan checks stay recoverable so that ubsan.supp applies; halt_on_error=1 makes any other report fatal.
  asan) flags="-fsanitize=address,undefined -fno-omit-frame-pointer -g1"
        # 'package' builds consumers with a plugin author's plain flags against the installed library, which an
        # instrumented library cannot link with: left out. 'python' and 'blender' load the instrumented module into
        # interpreters that are not: a second pass, below, with the runtime preloaded.
        tests=(-LE 'soak|docker|package|python|blender') ;;
  tsan) flags="-fsanitize=thread -fno-omit-frame-pointer -g1"
        tests=(-LE 'soak|docker')
        # Add a new suite of tests/server or tests/client here.
        tsan_suites=(texwarp_server_unit_tests texwarp_store_tests texwarp_server_e2e_tests texwarp_farm_service_tests
                     texwarp_server_hostile_tests texwarp_server_operations_tests texwarp_server_bomb_tests
                     texwarp_server_memory_tests texwarp_farm_tests texwarp_client_tests texwarp_cli_farm_tests) ;;
  *) echo "usage: scripts/sanitize.sh asan|tsan [ctest arguments...] (got '${kind}')" >&2; exit 2 ;;
esac
shift
build="build-$kind"
supp="$PWD/scripts/sanitizer-suppressions"
logs="$PWD/$build/sanitizer-logs"

generator=()
if command -v ninja >/dev/null 2>&1; then generator=(-G Ninja); fi
if [ ! -f "$build/CMakeCache.txt" ]; then
  cmake -S . -B "$build" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release -DTEXWARP_BUILD_BENCH=OFF \
    -DCMAKE_CXX_FLAGS_RELEASE="-O1 -DNDEBUG" -DCMAKE_C_FLAGS_RELEASE="-O1 -DNDEBUG" \
    -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags" -DCMAKE_SHARED_LINKER_FLAGS="$flags"
fi

# Test discovery runs the test binaries during the build: they run with the same options.
# use_sigaltstack=0: with its own alternate signal stack per thread, ASan's thread exit failed to unmap it ("CHECK
# failed: unable to unmap", exit 1) in processes whose threads open PoCL's device together (texwarpd's workers, the
# OpenClStartup tests); without it a stack overflow is reported as a plain SEGV.
export ASAN_OPTIONS="use_sigaltstack=0:detect_leaks=1:halt_on_error=1:abort_on_error=0:detect_stack_use_after_return=1:check_initialization_order=1:strict_init_order=1:log_path=$logs/asan"
export LSAN_OPTIONS="suppressions=$supp/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1:suppressions=$supp/ubsan.supp:log_path=$logs/ubsan"
export TSAN_OPTIONS="halt_on_error=1:second_deadlock_stack=1:suppressions=$supp/tsan.supp:log_path=$logs/tsan"
export POCL_CACHE_DIR="${POCL_CACHE_DIR:-$PWD/$build/pocl-cache}"
# Tests wait this many times longer for jobs to finish (tests/support/test_time.hpp): -O1 and the sanitizers' checks
# make a job several times slower, so a wait sized for CI's build ran out before the job ended.
if [ "$kind" = asan ]; then export TEXWARP_TEST_TIME_SCALE=4; else export TEXWARP_TEST_TIME_SCALE=10; fi
rm -rf "$logs"
mkdir -p "$logs"

if [ -n "${tsan_suites+x}" ]; then
  # ctest's -I selection below also ran texwarp_schema_validation (its samples binary and the CLI) and the placeholder
  # of the soak-labelled load tests (texwarp_load_tests_NOT_BUILT, "Not Run" = failed): both built here too, so the
  # one passes and the other, built, is left out with its label.
  cmake --build "$build" --parallel "$(nproc)" --target "${tsan_suites[@]}" texwarp_wire_samples texwarp texwarp_load_tests
  # ctest -I takes test numbers (after 'Start,End,Stride,' given as 0,0,0: no range): the tests those binaries run.
  numbers=$(ctest --test-dir "$build" --show-only=json-v1 | python3 -c '
import json, os, sys
suites = set(sys.argv[1:])
tests = json.load(sys.stdin)["tests"]
print(",".join(str(n) for n, t in enumerate(tests, 1) if os.path.basename(t.get("command", [""])[0]) in suites))
' "${tsan_suites[@]}")
  if [ -z "$numbers" ]; then
    echo "sanitize.sh: no tests of ${tsan_suites[*]} in $build" >&2
    exit 1
  fi
  echo "sanitize.sh: $kind: the $(printf '%s' "$numbers" | tr ',' '\n' | grep -c .) tests of ${tsan_suites[*]}"
  tests+=(-I "0,0,0,$numbers")
else
  cmake --build "$build" --parallel "$(nproc)"
fi
status=0
ctest --test-dir "$build" --output-on-failure --timeout 1800 "${tests[@]}" -j "$(nproc)" "$@" || status=$?
if [ "$kind" = asan ]; then
  # python3 and Blender are not instrumented: the ASan runtime (and libstdc++, whose __cxa_throw it intercepts) is
  # preloaded into them; their own allocations at exit are not texwarp's, so leak checking is off for this pass.
  LD_PRELOAD="$(gcc -print-file-name=libasan.so) $(gcc -print-file-name=libstdc++.so.6)" \
    ASAN_OPTIONS="${ASAN_OPTIONS/detect_leaks=1/detect_leaks=0}" \
    ctest --test-dir "$build" --output-on-failure --timeout 1800 -L 'python|blender' -LE 'soak|docker' "$@" ||
    status=$?
fi

# A finding in a child process (texwarpd, the CLI) does not always fail the test that started it: the logs do.
reports=$(find "$logs" -type f -size +0 | sort)
if [ -n "$reports" ]; then
  echo "sanitize.sh: $kind reports (one file per process that found something):" >&2
  for f in $reports; do
    echo "=== $f" >&2
    head -60 "$f" >&2
  done
  status=1
fi
if [ "$status" -ne 0 ]; then
  echo "sanitize.sh: $kind FAILED (ctest or sanitizer reports above; logs in $logs)" >&2
  exit 1
fi
echo "sanitize.sh: $kind: no findings"
