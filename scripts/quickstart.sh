#!/usr/bin/env bash
# The README's main job: installs what is missing, builds, and warps the shipped example image with its
# 20-feature file. Outputs: out/astronaut-warped.png (the warp) and out/astronaut-check.json (its report).
# Then the service: starts texwarpd on its defaults (127.0.0.1:8080, or a free port if 8080 is taken; data in
# out/texwarpd-data), sends the shipped job examples/astronaut-job.json through the client (texwarp submit),
# downloads its results to out/astronaut-job/ (warped.png, report.json) and stops the server.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
mkdir -p out
# The kernels compiled once into the cache folder (docs/user-guide.md: "Compiled kernels"; PoCL's cache inside
# it): the first warp, and the service's jobs below, start warm.
build/client/texwarp warm
build/client/texwarp warp --features examples/astronaut-features.json --in examples/astronaut.png \
  --out out/astronaut-warped.png
build/client/texwarp check --features examples/astronaut-features.json --width 512 --height 512 \
  > out/astronaut-check.json
echo "quickstart: wrote out/astronaut-warped.png and out/astronaut-check.json"

# The service, end to end.
port=8080
if (exec 3<>/dev/tcp/127.0.0.1/$port) 2>/dev/null; then port=0; fi  # 8080 is taken: any free port
rm -f out/texwarpd.port
build/server/texwarpd --listen "127.0.0.1:$port" --data-dir out/texwarpd-data --port-file out/texwarpd.port \
  2> out/texwarpd.log &
server_pid=$!
trap 'kill -TERM "$server_pid" 2>/dev/null || true' EXIT
for _ in $(seq 1 200); do
  [ -s out/texwarpd.port ] && break
  kill -0 "$server_pid" 2>/dev/null || { cat out/texwarpd.log >&2; exit 1; }
  sleep 0.05
done
url="http://127.0.0.1:$(cat out/texwarpd.port)"
echo "quickstart: texwarpd listening on $url (log: out/texwarpd.log)"
build/client/texwarp submit examples/astronaut-job.json --server "$url" --out out/astronaut-job
kill -TERM "$server_pid"
wait "$server_pid"
trap - EXIT
echo "quickstart: the service wrote out/astronaut-job/warped.png and out/astronaut-job/report.json"
