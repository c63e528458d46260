#!/usr/bin/env bash
# The farm's figures (not pass/fail): jobs/s and idle claim latency p50/p99 (submission → started_at) with the
# smallest real job, SQLite (one node) against PostgreSQL with 1, 2 and 3 nodes, and the recovery time after a node's
# kill -9 (kill → the job succeeded on another node); medians over --runs runs. Real texwarpd processes on loopback
# and a throw-away PostgreSQL cluster of its own (scripts/pg_test_cluster.sh --durable: fsync on).
# Usage: scripts/bench_farm.sh [--build DIR] [--runs N] [--jobs N] [--latency-jobs N] [--lease-s S] [--poll-ms MS]
set -euo pipefail
cd "$(dirname "$0")/.."
exec python3 - "$@" <<'PY'
import argparse, base64, http.client, json, os, shutil, signal, socket, statistics, struct, subprocess, sys
import tempfile, time, zlib

ap = argparse.ArgumentParser(prog="scripts/bench_farm.sh")
ap.add_argument("--build", default="build", help="the build folder holding server/texwarpd (build)")
ap.add_argument("--runs", type=int, default=3, help="runs per configuration; the median is reported (3)")
ap.add_argument("--jobs", type=int, default=60, help="jobs submitted at once for the throughput (60)")
ap.add_argument("--latency-jobs", type=int, default=40, help="jobs submitted one by one for the claim latency (40)")
ap.add_argument("--lease-s", type=float, default=5, help="--lease-s of the nodes in the kill -9 runs (5)")
ap.add_argument("--poll-ms", type=int, default=250, help="--poll-ms of every node (250, texwarpd's default)")
args = ap.parse_args()
texwarpd = os.path.abspath(os.path.join(args.build, "server", "texwarpd"))
if not os.access(texwarpd, os.X_OK):
    sys.exit(f"bench_farm: no {texwarpd}; build it first (scripts/build.sh --target texwarpd)")


def png(size):
    """An RGB gradient with a checkerboard, as PNG bytes."""
    rows = b"".join(b"\0" + bytes(v for x in range(size) for v in
                                  (x * 255 // size, y * 255 // size, 230 if (x // 8 + y // 8) % 2 else 25))
                    for y in range(size))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", size, size, 8, 2, 0, 0, 0)) +
            chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))


SMALLEST = {"name": "bench: the smallest real job", "image": {"base64": base64.b64encode(png(16)).decode()},
            "warp": {"features": [{"source": [4, 4], "target": [5, 4]}, {"source": [12, 12], "target": [11, 12]}]}}
SLOW = {"name": "bench: a slow job (exact, 500²)", "image": {"base64": base64.b64encode(png(64)).decode()},
        "warp": {"alpha": 2.0, "tolerance_px": 0.001,
                 "features": [{"source": [6 + i * 10.4, 6 + j * 10.4], "target": [7 + i * 10.4, 5.5 + j * 10.4]}
                              for i in range(6) for j in range(6)]},
        "output": {"width": 500, "height": 500}, "options": {"exact": True}}


def request(port, method, path, body=None, timeout=120):
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=timeout)
    c.request(method, path, body=json.dumps(body) if body is not None else None,
              headers={"Content-Type": "application/json"} if body is not None else {})
    r = c.getresponse()
    data = r.read()
    c.close()
    return r.status, (json.loads(data) if data else None)


def ms(ts):
    import datetime
    return datetime.datetime.strptime(ts, "%Y-%m-%dT%H:%M:%S.%fZ").replace(
        tzinfo=datetime.timezone.utc).timestamp() * 1000


def submit(port, job):
    status, body = request(port, "POST", "/v1/jobs", job)
    if status != 202:
        sys.exit(f"bench_farm: submit answered {status}: {body}")
    return body["id"]


def wait_done(port, job_id, timeout=600):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        status, s = request(port, "GET", f"/v1/jobs/{job_id}?wait=20", timeout=60)
        if status == 400:  # no long-poll on this server: poll
            status, s = request(port, "GET", f"/v1/jobs/{job_id}")
            time.sleep(0.02)
        if s and s.get("state") in ("succeeded", "failed", "canceled"):
            if s["state"] != "succeeded":
                sys.exit(f"bench_farm: job {job_id} ended {s['state']}: {s}")
            return s
    sys.exit(f"bench_farm: job {job_id} did not finish in {timeout} s")


class Postgres:
    """A throw-away cluster (scripts/pg_test_cluster.sh) on a free loopback port, fsync on (--durable, as SQLite's
    synchronous=FULL)."""

    def __init__(self, root):
        self.dir = os.path.join(root, "pg")
        s = socket.socket()
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
        s.close()
        self.url = subprocess.run(["scripts/pg_test_cluster.sh", "start", self.dir, "--tcp", str(port), "--durable"],
                                  check=True, capture_output=True, text=True).stdout.strip().splitlines()[-1]

    def database(self, name):
        subprocess.run(["psql", self.url, "-q", "-v", "ON_ERROR_STOP=1", "-c", f"CREATE DATABASE {name}"], check=True)
        url = self.url.rsplit("/", 1)[0] + "/" + name
        out = subprocess.run([texwarpd, "--store", url, "--migrate"], capture_output=True, text=True)
        if out.returncode != 0:
            sys.exit(f"bench_farm: texwarpd --migrate: {out.stdout}{out.stderr}")
        return url

    def stop(self):
        subprocess.run(["scripts/pg_test_cluster.sh", "stop", self.dir], check=True)


class Farm:
    """texwarpd nodes on one store and one data folder, one worker each."""

    def __init__(self, root, store, nodes, extra=()):
        self.data = os.path.join(root, "data")
        self.procs, self.ports = [], []
        for i in range(nodes):
            port_file = os.path.join(root, f"node-{i + 1}.port")
            argv = [texwarpd, "--listen", "127.0.0.1:0", "--port-file", port_file, "--data-dir", self.data,
                    "--device", "cpu", "--workers", "1", "--threads-per-job", "1", "--poll-ms", str(args.poll_ms)]
            if store:
                argv += ["--store", store, "--node-id", f"bench-node-{i + 1}", *extra]
            log = open(os.path.join(root, f"node-{i + 1}.log"), "ab")
            self.procs.append(subprocess.Popen(argv, stdout=log, stderr=log))
            deadline = time.monotonic() + 30
            while not (os.path.exists(port_file) and open(port_file).read().strip()):
                if time.monotonic() > deadline or self.procs[-1].poll() is not None:
                    sys.exit(f"bench_farm: texwarpd did not start; see {root}/node-{i + 1}.log")
                time.sleep(0.02)
            self.ports.append(int(open(port_file).read()))

    def stop(self):
        for p in self.procs:
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        for p in self.procs:
            try:
                p.wait(30)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait()


def throughput_and_latency(root, store, nodes):
    farm = Farm(root, store, nodes)
    try:
        n = len(farm.ports)
        ids = [submit(farm.ports[i % n], SMALLEST) for i in range(args.jobs)]
        rows = [wait_done(farm.ports[0], i) for i in ids]
        span_s = (max(ms(r["finished_at"]) for r in rows) - min(ms(r["created_at"]) for r in rows)) / 1000
        latencies = []
        for k in range(args.latency_jobs):
            r = wait_done(farm.ports[k % n], submit(farm.ports[k % n], SMALLEST))
            latencies.append(ms(r["started_at"]) - ms(r["created_at"]))
        return args.jobs / span_s, latencies
    finally:
        farm.stop()


def recovery(root, store):
    extra = ["--lease-s", str(args.lease_s), "--heartbeat-s", str(min(1.0, args.lease_s / 4))]
    farm = Farm(root, store, 3, extra)
    try:
        job_id = submit(farm.ports[0], SLOW)
        while True:
            _, s = request(farm.ports[0], "GET", f"/v1/jobs/{job_id}")
            if s["state"] == "running" and s.get("progress", 0) >= 5 and s.get("node"):
                break
            time.sleep(0.05)
        victim = int(s["node"].rsplit("-", 1)[1]) - 1
        killed_ms = time.time() * 1000
        farm.procs[victim].kill()
        farm.procs[victim].wait()
        r = wait_done(farm.ports[(victim + 1) % 3], job_id)
        if r["attempts"] != 2:
            sys.exit(f"bench_farm: after a kill -9 the job ran {r['attempts']} times: {r}")
        return (ms(r["finished_at"]) - killed_ms) / 1000, (ms(r["started_at"]) - killed_ms) / 1000
    finally:
        farm.stop()


def pct(values, q):
    v = sorted(values)
    return v[min(len(v) - 1, int(round(q / 100 * (len(v) - 1))))]


root = tempfile.mkdtemp(prefix="texwarp-bench-farm-")
os.chmod(root, 0o755)
pg = Postgres(root)
finished = False
try:
    print(f"bench_farm: {os.cpu_count()} cores, {args.runs} runs, {args.jobs} jobs for jobs/s, "
          f"{args.latency_jobs} one by one for the claim latency, --poll-ms {args.poll_ms}", flush=True)
    print("| store | nodes | jobs/s (median) | runs | claim latency p50 | p99 |")
    print("| --- | --- | --- | --- | --- | --- |")
    for store, nodes in (("sqlite", 1), ("postgresql", 1), ("postgresql", 2), ("postgresql", 3)):
        rates, latencies = [], []
        for run in range(args.runs):
            where = os.path.join(root, f"{store}-{nodes}-{run}")
            os.makedirs(where)
            url = pg.database(f"bench_{nodes}_{run}") if store == "postgresql" else ""
            rate, lat = throughput_and_latency(where, url, nodes)
            rates.append(rate)
            latencies += lat
        print(f"| {store} | {nodes} | {statistics.median(rates):.1f} | "
              f"{' '.join(f'{r:.1f}' for r in rates)} | {pct(latencies, 50):.0f} ms | {pct(latencies, 99):.0f} ms |",
              flush=True)
    recoveries, reclaims = [], []
    for run in range(args.runs):
        where = os.path.join(root, f"recovery-{run}")
        os.makedirs(where)
        total, reclaim = recovery(where, pg.database(f"bench_recovery_{run}"))
        recoveries.append(total)
        reclaims.append(reclaim)
    print(f"\nrecovery after kill -9 of the node running a job (3 nodes, --lease-s {args.lease_s:g}): "
          f"kill → succeeded {statistics.median(recoveries):.2f} s median "
          f"({' '.join(f'{r:.2f}' for r in recoveries)}), kill → running again on another node "
          f"{statistics.median(reclaims):.2f} s median ({' '.join(f'{r:.2f}' for r in reclaims)})")
    finished = True
finally:
    pg.stop()
    if finished:
        shutil.rmtree(root, ignore_errors=True)
    else:
        print(f"bench_farm: stopped; the nodes' logs are kept in {root}", file=sys.stderr)
PY
