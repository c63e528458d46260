#!/usr/bin/env bash
# A client generated from the API's OpenAPI document, as a user would: installs Redocly CLI, openapi-typescript and
# TypeScript from the npm registry (client-tools/package-lock.json, `npm ci` into BUILD_DIR/npm-tools, again only when
# the lock changes), lints with Redocly's recommended rules the repository's proto/schema/openapi.json and the document
# a real texwarpd serves (GET /v1/openapi.json: the build's bundle, byte for byte), bundles both with Redocly,
# generates TypeScript types from both with openapi-typescript, checks they name the job-submission operation and the
# job's schema, and type-checks a small client file against them with tsc. Fails on any Redocly error (warnings are
# printed); fails with a clear message when the registry cannot be reached. Exit 77 (skipped): no Node.js >= 20.19.
# Usage: generate_client.sh SOURCE_DIR BUILD_DIR TEXWARPD BUNDLED_OPENAPI
set -euo pipefail
source_dir=$(realpath "$1")
tools=$(realpath "$2")/npm-tools
texwarpd=$(realpath "$3")
bundled=$(realpath "$4")
manifest=$source_dir/tests/server/client-tools
work=$(mktemp -d "${TMPDIR:-/tmp}/texwarp-client.XXXXXX")
server_pid=""
cleanup() {
  if [ -n "$server_pid" ]; then
    kill "$server_pid" 2>/dev/null || true
    wait "$server_pid" 2>/dev/null || true
  fi
  rm -rf "$work"
}
trap cleanup EXIT
fail() {
  echo "FAIL: $*" >&2
  exit 1
}
step() { echo "== $*"; }

if ! command -v node > /dev/null || ! command -v npm > /dev/null; then
  echo "Node.js and npm are not installed: skipped (Redocly CLI 2 needs Node.js >= 20.19)"
  exit 77
fi
node_version=$(node --version)
if ! node -e 'const [a, b] = process.versions.node.split(".").map(Number); process.exit(a > 20 || (a === 20 && b >= 19) ? 0 : 1)'; then
  echo "Node.js $node_version is older than 20.19, which Redocly CLI 2 needs: skipped"
  exit 77
fi

# The tools, at the lock's versions. The stamp (a copy of the lock) is written once npm ci has succeeded.
if ! cmp -s "$manifest/package-lock.json" "$tools/installed-package-lock.json" || [ ! -x "$tools/node_modules/.bin/redocly" ]; then
  registry=$(npm config get registry)
  step "npm ci into $tools (Node.js $node_version, registry $registry)"
  rm -rf "$tools"
  mkdir -p "$tools"
  cp "$manifest/package.json" "$manifest/package-lock.json" "$tools/"
  started=$SECONDS
  if ! npm ci --prefix "$tools" --no-audit --no-fund --fetch-retries=1 --fetch-retry-mintimeout=2000 \
      --fetch-retry-maxtimeout=5000 --fetch-timeout=60000 > "$work/npm.log" 2>&1; then
    tail -n 20 "$work/npm.log" >&2
    fail "could not install @redocly/cli, openapi-typescript and typescript from the npm registry ($registry):" \
      "is the network (or a registry mirror: npm config set registry URL) reachable from here? npm's log is above"
  fi
  cp "$manifest/package-lock.json" "$tools/installed-package-lock.json"
  echo "installed in $((SECONDS - started)) s"
fi
bin=$tools/node_modules/.bin
# No telemetry, no update notices; Redocly run from $work so that no redocly.yaml on the way changes its rules.
export REDOCLY_TELEMETRY=off REDOCLY_SUPPRESS_UPDATE_NOTICE=true NO_COLOR=1
cd "$work"

# redocly lint: exit 1 on any error; the summary lines (and warnings) are printed.
lint() {
  step "redocly lint --extends recommended $1"
  if ! "$bin/redocly" lint --extends recommended --format stylish "$1" > "$work/lint.log" 2>&1; then
    grep -v '[║╔╚]' "$work/lint.log" >&2
    fail "Redocly's recommended rules find errors in $1"
  fi
  grep -E '(warning|error) ' "$work/lint.log" || true
  grep -E 'valid|Validation' "$work/lint.log" || true
}

# The repository's document: its $refs are file names beside it.
repo_doc=$source_dir/proto/schema/openapi.json
lint "$repo_doc"

# The served document: a real texwarpd on a free loopback port.
step "texwarpd on 127.0.0.1:0"
"$texwarpd" --listen 127.0.0.1:0 --data-dir "$work/data" --port-file "$work/port" --device cpu --workers 1 \
  > "$work/texwarpd.log" 2>&1 &
server_pid=$!
for _ in $(seq 200); do
  [ -s "$work/port" ] && break
  kill -0 "$server_pid" 2>/dev/null || { cat "$work/texwarpd.log" >&2; fail "texwarpd exited"; }
  sleep 0.1
done
[ -s "$work/port" ] || { cat "$work/texwarpd.log" >&2; fail "texwarpd wrote no port in 20 s"; }
url=http://127.0.0.1:$(cat "$work/port")/v1/openapi.json
# shellcheck disable=SC2016 # JavaScript's template string, not the shell's
node -e 'fetch(process.argv[1]).then(async r => { if (r.status !== 200) throw new Error(`HTTP ${r.status}`);
  require("fs").writeFileSync(process.argv[2], Buffer.from(await r.arrayBuffer())); })' "$url" "$work/served.json" ||
  fail "GET $url"
cmp -s "$work/served.json" "$bundled" || fail "GET $url is not the build's bundle $bundled"
lint "$url"

step "redocly bundle"
"$bin/redocly" bundle "$repo_doc" -o "$work/bundle-of-repo.json" > "$work/bundle.log" 2>&1 ||
  { cat "$work/bundle.log" >&2; fail "redocly bundle $repo_doc"; }
"$bin/redocly" bundle "$url" -o "$work/bundle-of-served.json" > "$work/bundle.log" 2>&1 ||
  { cat "$work/bundle.log" >&2; fail "redocly bundle $url"; }

# TypeScript types: from the served document (what a client's build would fetch) and from the repository's file.
# --default-non-nullable false: a property with a default stays optional (a job need not say "priority": 0).
for input in "$url" "$repo_doc"; do
  out=$work/texwarp-api.d.ts
  [ "$input" = "$url" ] || out=$work/texwarp-api-from-repo.d.ts
  step "openapi-typescript $input"
  "$bin/openapi-typescript" "$input" --default-non-nullable false -o "$out" > "$work/ots.log" 2>&1 ||
    { cat "$work/ots.log" >&2; fail "openapi-typescript $input"; }
  for expected in '"/v1/jobs": {' '"/v1/jobs/{id}/result": {' 'submitJob: {' 'getResult: {' 'listJobs: {'; do
    grep -qF "$expected" "$out" || fail "$out has no $expected"
  done
done
# The served bundle names every schema as a component of its own.
for expected in '        Job: {' '        JobStatus: {' '        Problem: {' '        imageSource: {' '        jobReport:'; do
  grep -qF "$expected" "$work/texwarp-api.d.ts" || fail "texwarp-api.d.ts has no components.schemas entry '$expected'"
done

step "tsc: a client file against the generated types"
cat > "$work/client.ts" << 'EOF'
import type { components, operations, paths } from "./texwarp-api";

type Job = components["schemas"]["Job"];
type JobStatus = operations["submitJob"]["responses"][202]["content"]["application/json"];

const job: paths["/v1/jobs"]["post"]["requestBody"]["content"]["application/json"] = {
  image: { blob: "sha256:" + "0".repeat(64) },
  warp: { features: [{ source: [10, 20], target: [12, 24] }] },
  output: { interpolation: "bilinear" },
};
const same: Job = job;

export function finished(s: JobStatus): boolean {
  return s.state === "succeeded" || s.state === "failed" || s.state === "canceled";
}

// @ts-expect-error: a job's keys are closed (additionalProperties: false)
const unknownKey: Job = { image: { blob: "x" }, colour: "red" };
// @ts-expect-error: interpolation is one of the schema's names
const wrongEnum: Job = { image: { blob: "x" }, output: { interpolation: "cubic-ish" } };
export { same, unknownKey, wrongEnum };
EOF
"$bin/tsc" --noEmit --strict --target es2022 --module es2022 --moduleResolution bundler "$work/client.ts" ||
  fail "the client file does not type-check against the generated types"
echo "OK: both documents lint clean; clients generated and type-checked"
