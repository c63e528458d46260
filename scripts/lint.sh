#!/usr/bin/env bash
# Lint: clang-format (.clang-format) over every first-party C++ source, then clang-tidy (.clang-tidy) over the
# project's translation units in the build's compile_commands.json, both in parallel on every core. Exits non-zero
# on any finding and ends with a count per check. Installs nothing (scripts/setup.sh does); needs a configured
# build (scripts/build.sh). Fix formatting with: clang-format-14 -i $(git ls-files '*.cpp' '*.hpp')
# --build-dir may be given more than once: the units of every tree's database are checked, each once (the first
# tree's command wins), e.g. build and build-fuzz, whose clang tree alone compiles the fuzz targets. A first-party
# translation unit in no database is named at the end (not an error: the package test's consumers are built by it).
# Usage: scripts/lint.sh [--build-dir DIR]... [--format-only | --tidy-only] [PATH...]   (PATHs: only files under these)
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD

builds=()
run_format=1
run_tidy=1
paths=()
while [ $# -gt 0 ]; do
  case "$1" in
    --build-dir) builds+=("${2:?--build-dir needs a folder}"); shift 2 ;;
    --format-only) run_tidy=0; shift ;;
    --tidy-only) run_format=0; shift ;;
    -h|--help) sed -n '2,9p' "$0"; exit 0 ;;
    -*) echo "lint.sh: unknown option '$1'" >&2; exit 2 ;;
    *) paths+=("$1"); shift ;;
  esac
done

find_tool() {
  for t in "$1-14" "$1"; do
    if command -v "$t" >/dev/null 2>&1; then echo "$t"; return; fi
  done
  echo "lint.sh: $1 not found: run scripts/setup.sh" >&2
  exit 2
}

# First-party sources: the C++ files git tracks (every file in the tree when this is no git checkout). The OpenCL C
# kernels (*.cl) are left out: their statement macros (TW_EACH_VEC) are laid out by hand and clang-format collapses
# them.
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t sources < <(git ls-files -- ${paths[@]+"${paths[@]}"} | grep -E '\.(cpp|hpp|h)$')
else
  mapfile -t sources < <(find "${paths[@]:-.}" -path ./.git -prune -o -path './build*' -prune -o -path ./out -prune \
    -o -type f \( -name '*.cpp' -o -name '*.hpp' -o -name '*.h' \) -print | sed 's|^\./||' | sort -u)
fi
if [ ${#sources[@]} -eq 0 ]; then
  echo "lint.sh: no C++ sources under ${paths[*]:-.}" >&2
  exit 2
fi
jobs=$(nproc)
status=0
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
export out

if [ "$run_format" -eq 1 ]; then
  clang_format=$(find_tool clang-format)
  echo "lint.sh: $clang_format on ${#sources[@]} files"
  # Batches of 8 files in parallel, each batch's report in a file of its own (parallel output would interleave).
  mkdir "$out/format"
  printf '%s\0' "${sources[@]}" | xargs -0 -P "$jobs" -n 8 bash -c \
    '"$0" --style=file --dry-run -Werror "$@" >"$(mktemp -p "$out/format")" 2>&1 || touch "$out/format-failed"' \
    "$clang_format"
  cat "$out"/format/*
  if [ -e "$out/format-failed" ]; then
    differing=$(cat "$out"/format/* | grep -E '^[^ ]+:[0-9]+:[0-9]+: error: ' | cut -d: -f1 | sort -u | grep -c . || true)
    echo "lint.sh: clang-format: $differing of ${#sources[@]} files differ from .clang-format's layout" >&2
    status=1
  fi
fi

if [ "$run_tidy" -eq 1 ]; then
  clang_tidy=$(find_tool clang-tidy)
  [ ${#builds[@]} -gt 0 ] || builds=(build)
  for b in "${builds[@]}"; do
    if [ ! -f "$b/compile_commands.json" ]; then
      echo "lint.sh: $b/compile_commands.json not found: configure first (scripts/build.sh)" >&2
      exit 2
    fi
  done
  # The project's translation units: the databases' files that are first-party sources (generated sources in the
  # build folders are not), written into one database. Diagnostics in headers: those of the first-party top-level
  # folders only.
  build="$out/database"
  mkdir "$build"
  mapfile -t units < <(python3 - "$build" "$root" "${builds[@]}" -- "${sources[@]}" <<'EOF'
import json, os, sys
merged, root = sys.argv[1], sys.argv[2]
split = sys.argv.index("--")
databases, sources = sys.argv[3:split], set(sys.argv[split + 1:])
entries = {}
for database in databases:
    for entry in json.load(open(os.path.join(database, "compile_commands.json"))):
        path = os.path.relpath(os.path.join(entry["directory"], entry["file"]), root)
        if path in sources and path not in entries:
            entries[path] = entry
json.dump(list(entries.values()), open(os.path.join(merged, "compile_commands.json"), "w"))
for path in sorted(entries):
    print(path)
missing = sorted(s for s in sources if s.endswith(".cpp") and s not in entries)
if missing:
    print("lint.sh: in no compile database, not checked by clang-tidy: " + " ".join(missing), file=sys.stderr)
EOF
  )
  folders=$(printf '%s\n' "${sources[@]}" | grep / | cut -d/ -f1 | sort -u | paste -sd'|')
  header_filter="^$(printf '%s' "$root" | sed 's/[][\.*^$+?(){}|]/\\&/g')/($folders)/"
  mkdir "$out/tidy"
  echo "lint.sh: $clang_tidy on ${#units[@]} translation units ($jobs at a time)"
  export clang_tidy build header_filter
  # One clang-tidy per unit, its output kept whole in a file of its own; every finding is an error.
  printf '%s\0' "${units[@]}" | xargs -0 -P "$jobs" -I{} bash -c '
    log="$out/tidy/$(printf "%s" "$1" | tr / _).log"
    "$clang_tidy" -p "$build" --quiet --warnings-as-errors="*" --header-filter="$header_filter" "$1" >"$log" 2>&1 \
      || echo "$1" >>"$out/tidy-failed"' _ {}
  cat "$out"/tidy/*.log 2>/dev/null | grep -v '^[0-9]* warnings\? \(and [0-9]* errors\? \)\?generated\.$' || true
  if [ -s "$out/tidy-failed" ]; then
    # A header's finding shows once per unit that includes it: count each place once.
    findings=$(cat "$out"/tidy/*.log | grep -E '^[^ ].*:[0-9]+:[0-9]+: (warning|error): .*\[[a-z0-9.,-]+\]$' | sort -u || true)
    echo "lint.sh: clang-tidy: $(printf '%s\n' "$findings" | grep -c . || true) findings in $(wc -l <"$out/tidy-failed") units, per check:" >&2
    printf '%s\n' "$findings" | sed -E 's/.*\[([a-z0-9.-]+).*\]$/\1/' | sort | uniq -c | sort -rn >&2
    status=1
  fi
fi

if [ "$status" -ne 0 ]; then
  echo "lint.sh: FAILED" >&2
  exit 1
fi
echo "lint.sh: no findings"
