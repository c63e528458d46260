#!/usr/bin/env bash
# The Docker image and the compose farm profile, built and run without a daemon or an image registry (issue 31):
#   1. installs what is missing from Debian: buildah, podman, runc, debootstrap, netavark, aardvark-dns, iptables, …
#   2. makes the base image: `debootstrap --variant=minbase bookworm`, imported and tagged debian:12 and
#      debian:12-slim (kept in the test's storage and reused by later runs)
#   3. builds docker/Dockerfile with buildah (--isolation chroot, docker format so HEALTHCHECK stays): the build stage
#      compiles texwarpd and texwarp
#   4. runs the image as compose's default service does (its own ENTRYPOINT, port 8080 published on a free loopback
#      port, a named volume): checks texwarpd runs as the unprivileged user, answers /readyz, passes the image's
#      HEALTHCHECK, runs examples/astronaut-job.json submitted with the image's own `texwarp submit`, and drains on
#      SIGTERM (`podman stop`, exit 0)
#   5. builds a PostgreSQL 15 stand-in for postgres:15-bookworm from Debian's postgresql-15
#      (tests/docker/postgres.Containerfile) unless that image is already in the test's storage
#   6. runs docker/compose.yaml's farm profile with podman (tests/docker/compose_profile.py: PostgreSQL, the one-shot
#      --migrate, three nodes on one network with DNS, one shared data volume, published ports): every node ready
#      and listed alive by the others, a job submitted to node 1 is seen and fetched from nodes 2 and 3.
# Usage: tests/docker/run_docker_test.sh [SOURCE_DIR]   (default: this repository; it is the build context)
# Needs root (re-runs itself with `sudo -n` otherwise; exit 77, a ctest skip, where that is not possible).
# Environment: TEXWARP_DOCKER_WORK (default /var/tmp/texwarp-docker: the storage, logs and outputs),
# TEXWARP_DOCKER_MIRROR (Debian mirror for debootstrap), TEXWARP_DOCKER_NICE (niceness of debootstrap and the
# builds, default 10), TEXWARP_DOCKER_FRESH=1 (remake the base image and rebuild without the layer cache).
set -euo pipefail
src=$(cd "${1:-$(dirname "$0")/../..}" && pwd)
here=$(cd "$(dirname "$0")" && pwd)
work=${TEXWARP_DOCKER_WORK:-/var/tmp/texwarp-docker}
mirror=${TEXWARP_DOCKER_MIRROR:-http://deb.debian.org/debian}
niceness=${TEXWARP_DOCKER_NICE:-10}

if [ "$(id -u)" -ne 0 ]; then
  if command -v sudo >/dev/null && sudo -n true 2>/dev/null; then
    exec sudo -n --preserve-env=TEXWARP_DOCKER_WORK,TEXWARP_DOCKER_MIRROR,TEXWARP_DOCKER_NICE,TEXWARP_DOCKER_FRESH \
      "$0" "$src"
  fi
  echo "SKIP: debootstrap, buildah and podman need root (or sudo without a password)" >&2
  exit 77
fi

timings=()
step_start=0
step() { step_start=$(date +%s); echo; echo "== $*"; }
step_done() {
  local s=$(($(date +%s) - step_start))
  timings+=("$(printf '%-44s %3d:%02d' "$1" $((s / 60)) $((s % 60)))")
}
summary() {
  echo
  echo "== minutes per step (m:ss)"
  printf '%s\n' "${timings[@]}"
}

# ---- 1. packages ---------------------------------------------------------------------------------------------
step "1. Debian packages"
packages=(buildah podman runc conmon debootstrap netavark aardvark-dns iptables fuse-overlayfs uidmap
  containers-storage golang-github-containers-common curl python3 python3-yaml ca-certificates)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "installing ${missing[*]}"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
step_done "1. packages"

mkdir -p "$work"
# The test's own storage (not the host's /var/lib/containers): overlay, or vfs where the folder is itself on overlayfs.
driver=${TEXWARP_DOCKER_STORAGE_DRIVER:-overlay}
if [ "$(stat -f -c %T "$work")" = overlayfs ]; then driver=vfs; fi
storage=(--root "$work/storage" --runroot "$work/runroot" --storage-driver "$driver")
buildah=(buildah "${storage[@]}")
# runc and cgroupfs: crun refuses a hybrid cgroup hierarchy, and there may be no systemd to ask for cgroups.
podman=(podman "${storage[@]}" --cgroup-manager cgroupfs --events-backend file --runtime runc)
# Limits a container may get without CAP_SYS_RESOURCE (podman's defaults for root exceed most hard limits).
hard_nofile=$(ulimit -Hn); [ "$hard_nofile" = unlimited ] && hard_nofile=1048576
nofile=$((hard_nofile < 65536 ? hard_nofile : 65536))
run_opts=(--ulimit "nofile=$nofile:$nofile" --ulimit nproc=4096:4096)
image=localhost/texwarpd:latest   # compose.yaml's texwarpd:latest
out="$work/out"
rm -rf "$out"
mkdir -p "$out"

# podman running an image with a HEALTHCHECK asks systemd for a timer; without systemd it logs errors and runs the
# container all the same (the test runs the check itself: `podman healthcheck run`). pm: podman without those lines.
pm() { "${podman[@]}" "$@" 2> >(grep -v 'unable to get systemd connection' >&2); }
free_port() { python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
wait_ready() {  # URL SECONDS: waits for /readyz to answer 200
  local deadline=$(($(date +%s) + $2))
  until curl -fsS -o /dev/null "$1/readyz" 2>/dev/null; do
    if [ "$(date +%s)" -ge "$deadline" ]; then echo "FAIL: $1/readyz not ready after $2 s" >&2; return 1; fi
    sleep 1
  done
}
texwarp() {  # the image's own client, on the host's network, with examples/ and the output folder mounted
  pm run --rm --network host "${run_opts[@]}" -v "$src/examples:/examples:ro" -v "$out:/out" \
    --entrypoint texwarp "$image" "$@"
}
process_uid() {  # CONTAINER: the uid of its first process, read on the host
  local pid
  pid=$(pm inspect -f '{{.State.Pid}}' "$1")
  awk '/^Uid:/ {print $2}' "/proc/$pid/status"
}
check_result() {  # DIR: warped.png (a 256x256 PNG) and report.json of the astronaut job
  python3 - "$1" <<'EOF'
import json, struct, sys
d = sys.argv[1]
png = open(f"{d}/warped.png", "rb").read()
assert png[:8] == b"\x89PNG\r\n\x1a\n", "warped.png is no PNG"
w, h = struct.unpack(">II", png[16:24])
assert (w, h) == (256, 256), f"warped.png is {w}x{h}"
report = json.load(open(f"{d}/report.json"))
cert = report["certificate"]
assert cert["min_jacobian_det"] > 0 and cert["nonpositive_jacobians"] == 0, cert
bound = cert.get("max_error_px_bound")
assert bound is None or bound <= cert["tolerance_px"] * (1 + 1e-9), cert
print(f"result: warped.png {w}x{h}, max_error_px_bound {bound} (tolerance {cert['tolerance_px']}), "
      f"min_jacobian_det {cert['min_jacobian_det']:.4g}")
EOF
}

project=texwarp-test
cleanup() {
  pm rm -f -v -t 30 texwarp-test-single >/dev/null 2>&1 || true
  pm volume rm -f texwarp-test-data >/dev/null 2>&1 || true
  /usr/bin/python3 "$here/compose_profile.py" down "$src/docker/compose.yaml" --profile farm --project "$project" \
    -- "${podman[@]}" >/dev/null 2>&1 || true
}
trap 'cleanup; summary' EXIT
cleanup

# ---- 2. base image -------------------------------------------------------------------------------------------
step "2. base image debian:12 (debootstrap --variant=minbase bookworm)"
if [ "${TEXWARP_DOCKER_FRESH:-0}" = 1 ]; then
  pm rmi -f docker.io/library/debian:12 docker.io/library/debian:12-slim >/dev/null 2>&1 || true
fi
if pm image exists docker.io/library/debian:12; then
  echo "reusing debian:12 from $work/storage (TEXWARP_DOCKER_FRESH=1 remakes it)"
else
  rootfs="$work/rootfs"
  rm -rf "$rootfs"
  nice -n "$niceness" debootstrap --variant=minbase bookworm "$rootfs" "$mirror" >"$work/debootstrap.log" 2>&1 ||
    { tail -20 "$work/debootstrap.log" >&2; exit 1; }
  {
    echo "deb $mirror bookworm main"
    echo "deb $mirror bookworm-updates main"
    echo "deb http://deb.debian.org/debian-security bookworm-security main"
  } >"$rootfs/etc/apt/sources.list"
  rm -rf "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/lib/apt/lists/*
  tar --numeric-owner -C "$rootfs" -c . |
    pm import --change 'CMD ["bash"]' - docker.io/library/debian:12 >/dev/null
  pm tag docker.io/library/debian:12 docker.io/library/debian:12-slim
  rm -rf "$rootfs"
fi
step_done "2. base image"

# ---- 3. the image --------------------------------------------------------------------------------------------
step "3. buildah build -f docker/Dockerfile (compiles texwarpd and texwarp)"
layers=(--layers)
[ "${TEXWARP_DOCKER_FRESH:-0}" = 1 ] && layers=(--layers --no-cache)
set +e
nice -n "$niceness" "${buildah[@]}" build --isolation chroot "${layers[@]}" --pull=never --format docker \
  -f "$src/docker/Dockerfile" -t "$image" "$src" 2>&1 | tee "$work/build.log" | grep --line-buffered -E '^\[|^--> |rror'
build_status=${PIPESTATUS[0]}
set -e
[ "$build_status" -eq 0 ] || { tail -40 "$work/build.log" >&2; echo "FAIL: the image did not build" >&2; exit 1; }
pm image inspect -f 'image {{.Id}}, {{.Size}} bytes, user {{.Config.User}}' "$image"
step_done "3. image build"

# ---- 4. one node, as compose's default service -----------------------------------------------------------------
step "4. texwarpd from the image: unprivileged, /readyz, HEALTHCHECK, the example job, SIGTERM"
pm run --rm "${run_opts[@]}" --entrypoint texwarpd "$image" --version
port=$(free_port)
pm run -d --name texwarp-test-single "${run_opts[@]}" -p "127.0.0.1:$port:8080" \
  -v texwarp-test-data:/var/lib/texwarpd "$image" >/dev/null
wait_ready "http://127.0.0.1:$port" 180 || { pm logs texwarp-test-single | tail -20; exit 1; }
uid=$(process_uid texwarp-test-single)
[ "$uid" = 10001 ] || { echo "FAIL: texwarpd runs as uid $uid, not 10001 (texwarpd)" >&2; exit 1; }
echo "texwarpd ready on 127.0.0.1:$port (published from the container's 8080), uid $uid"
pm healthcheck run texwarp-test-single >/dev/null || { echo "FAIL: the image's HEALTHCHECK says unhealthy" >&2; exit 1; }
echo "HEALTHCHECK: healthy"
chown 10001:10001 "$out"
texwarp submit /examples/astronaut-job.json --server "http://127.0.0.1:$port" --out /out/single >/dev/null
check_result "$out/single"
pm stop -t 30 texwarp-test-single >/dev/null
code=$(pm inspect -f '{{.State.ExitCode}}' texwarp-test-single)
[ "$code" = 0 ] || { echo "FAIL: texwarpd exited $code after SIGTERM" >&2; exit 1; }
echo "SIGTERM: drained, exit 0"
pm rm -v texwarp-test-single >/dev/null
step_done "4. one node"

# ---- 5. PostgreSQL -------------------------------------------------------------------------------------------
step "5. postgres:15-bookworm"
if pm image exists docker.io/library/postgres:15-bookworm; then
  echo "using postgres:15-bookworm from $work/storage"
else
  nice -n "$niceness" "${buildah[@]}" build --isolation chroot --layers --pull=never --format docker \
    -f "$here/postgres.Containerfile" -t docker.io/library/postgres:15-bookworm "$here" \
    >"$work/postgres-build.log" 2>&1 ||
    { tail -20 "$work/postgres-build.log" >&2; exit 1; }
  echo "built the stand-in (Debian's postgresql-15) as postgres:15-bookworm"
fi
step_done "5. postgres image"

# ---- 6. the farm profile -------------------------------------------------------------------------------------
step "6. docker/compose.yaml --profile farm with podman"
ports=()
declare -A node_port
for n in 1 2 3; do
  node_port[$n]=$(free_port)
  ports+=(--port "808$n=${node_port[$n]}")
done
/usr/bin/python3 "$here/compose_profile.py" up "$src/docker/compose.yaml" --profile farm --project "$project" \
  "${ports[@]}" -- "${podman[@]}" -- "${run_opts[@]}"
for n in 1 2 3; do
  wait_ready "http://127.0.0.1:${node_port[$n]}" 180 ||
    { pm logs "$project-farm-node-$n" | tail -20; exit 1; }
  uid=$(process_uid "$project-farm-node-$n")
  [ "$uid" = 10001 ] || { echo "FAIL: farm-node-$n runs as uid $uid" >&2; exit 1; }
  echo "farm-node-$n ready on 127.0.0.1:${node_port[$n]} (compose's 808$n), uid $uid"
done
alive=$(curl -fsS "http://127.0.0.1:${node_port[2]}/v1/nodes" |
  python3 -c 'import json, sys; print(" ".join(sorted(n["id"] for n in json.load(sys.stdin)["nodes"] if n["alive"])))')
[ "$alive" = "farm-node-1 farm-node-2 farm-node-3" ] || { echo "FAIL: nodes alive: $alive" >&2; exit 1; }
echo "GET /v1/nodes on farm-node-2: alive $alive"
job=$(texwarp submit /examples/astronaut-job.json --server "http://127.0.0.1:${node_port[1]}" --wait --quiet)
id=$(printf '%s' "$job" | python3 -c 'import json, sys; print(json.load(sys.stdin)["id"])')
for n in 2 3; do
  status=$(curl -fsS "http://127.0.0.1:${node_port[$n]}/v1/jobs/$id")
  printf '%s' "$status" | python3 -c '
import json, sys
s = json.load(sys.stdin)
assert s["state"] == "succeeded", s
print("job %s on farm-node-%s: %s, run by %s" % (s["id"], sys.argv[1], s["state"], s.get("node")))' "$n"
done
texwarp fetch "$id" --out /out/farm --server "http://127.0.0.1:${node_port[3]}" >/dev/null
check_result "$out/farm"
step_done "6. farm profile"
echo
echo "PASS"
