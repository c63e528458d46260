#!/usr/bin/python3
"""Whole-command benchmark (issue 15): the real `texwarp warp` CLI as a user runs it against OpenCV's thin-plate
spline (Debian's python3-opencv) as a whole command too, alternating, medians of 5; figures, not pass/fail. TPS is
also timed in-process (its fit and warp alone, in a started process with the image decoded); both ratios are
texwarp's whole command over TPS.

Families: smooth (neighbours move together), independent (each feature displaced on its own by up to 4 % of the
size), clustered (a few tight groups, each moved rigidly); sizes 512, 1024, 2048; 10, 50, 200 features; plus a
cold-start row (in fresh cache folders: the first warp with empty caches, and the first after `texwarp warm`).
Run it with Debian's /usr/bin/python3 (cv2 from python3-opencv, scripts/setup.sh). Usage:
  whole_command_bench.py [--texwarp PATH] [--baseline PATH] [--quick] [--rows FAMILY:N:SIZE,...] [--runs 5]
                         (FAMILY also `identity`: no features, texwarp alone, e.g. identity:0:1024)
                         [--cold | --cold-only] [--work DIR]
  whole_command_bench.py features FAMILY N SIZE OUT.json      (the feature set a row uses)
  whole_command_bench.py tps FEATURES.json IN.png OUT.png       (OpenCV's TPS warp as one command)
"""
import argparse
import json
import math
import os
import random
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

FAMILIES = ("smooth", "independent", "clustered")
SIZES = (512, 1024, 2048)
COUNTS = (10, 50, 200)


def jittered_grid(n, size, rng):
    """n points on a jittered grid over the middle 80 % of the image (bench/certified_warp_bench.cpp's layout)."""
    side = max(1, math.ceil(math.sqrt(n)))
    spacing = 0.8 * size / max(1, side - 1)
    return [(0.1 * size + (k % side) * spacing + 0.2 * spacing * rng.uniform(-1, 1),
             0.1 * size + (k // side) * spacing + 0.2 * spacing * rng.uniform(-1, 1)) for k in range(n)]


def independent_move(p, size, rng):
    return (p[0] + 0.04 * size * rng.uniform(-1, 1), p[1] + 0.04 * size * rng.uniform(-1, 1))


def independent(n, size, rng):
    return [(p, independent_move(p, size, rng)) for p in jittered_grid(n, size, rng)]


def smooth(n, size, rng):
    bumps = [((0.5 * size * (1 + rng.uniform(-1, 1)), 0.5 * size * (1 + rng.uniform(-1, 1))),
              (rng.uniform(-1, 1), rng.uniform(-1, 1))) for _ in range(8)]
    sigma = 0.2 * size

    def field(p):
        w = [math.exp(-((p[0] - c[0]) ** 2 + (p[1] - c[1]) ** 2) / (2 * sigma * sigma)) for c, _ in bumps]
        return (sum(wk * a[0] for wk, (_, a) in zip(w, bumps)), sum(wk * a[1] for wk, (_, a) in zip(w, bumps)))

    sources = jittered_grid(n, size, rng)
    disp = [field(p) for p in sources]
    scale = 0.04 * size / max(math.hypot(*d) for d in disp)
    return [(p, (p[0] + scale * d[0], p[1] + scale * d[1])) for p, d in zip(sources, disp)]


def clustered_groups(size, rng):
    return [((size * rng.uniform(0.2, 0.8), size * rng.uniform(0.2, 0.8)),
             (0.04 * size * rng.uniform(-1, 1), 0.04 * size * rng.uniform(-1, 1)),
             math.radians(rng.uniform(-10, 10))) for _ in range(5)]


def clustered_member(group, n, size, rng):
    """A feature of a group (centre, shift, turn) of a set of n: placed at random in its disc, moved with it."""
    (cx, cy), (dx, dy), turn = group
    r = min(0.06 * size * max(1.0, math.sqrt(n / 50)), 0.2 * size) * math.sqrt(rng.random())  # inside the image
    a = rng.uniform(0, 2 * math.pi)
    ox, oy = r * math.cos(a), r * math.sin(a)
    tx = cx + dx + ox * math.cos(turn) - oy * math.sin(turn) + 0.003 * size * rng.uniform(-1, 1)
    ty = cy + dy + ox * math.sin(turn) + oy * math.cos(turn) + 0.003 * size * rng.uniform(-1, 1)
    return (cx + ox, cy + oy), (tx, ty)


def clustered(n, size, rng):
    """Five groups (radius 6 % of the size, more for n > 50, at most 20 %), each moved rigidly (shift ≤ 4 %, turn
    ≤ 10°)."""
    groups = clustered_groups(size, rng)
    return [clustered_member(groups[k % len(groups)], n, size, rng) for k in range(n)]


def dense(family, n, size, rng):
    """A set too dense for whole draws to keep sources and targets apart (independent or clustered, thousands of
    features): drawn feature by feature, each redrawn (up to 1000 times) until its source and target are at least
    0.2 % of the size (1 px or more) from every feature's before it; None if one cannot be placed."""
    reach = max(1.0, 0.002 * size)
    kept = ({}, {})  # grid cells of the sources and of the targets kept

    def free(cells, x, y):
        key = (int(x // reach), int(y // reach))
        return all(math.hypot(x - u, y - v) >= reach for dx in (-1, 0, 1) for dy in (-1, 0, 1)
                   for u, v in cells.get((key[0] + dx, key[1] + dy), ()))

    def keep(cells, x, y):
        cells.setdefault((int(x // reach), int(y // reach)), []).append((x, y))

    groups = clustered_groups(size, rng) if family == "clustered" else None
    grid = jittered_grid(n, size, rng) if family == "independent" else None
    out = []
    for k in range(n):
        for _ in range(1000):
            if groups:
                s, t = clustered_member(groups[k % len(groups)], n, size, rng)
            else:
                s, t = grid[k], independent_move(grid[k], size, rng)
            if free(kept[0], *s) and free(kept[1], *t):
                break
        else:
            return None
        keep(kept[0], *s)
        keep(kept[1], *t)
        out.append((s, t))
    return out


def well_separated(pairs, size):
    """No two straight trajectories (after the CLI's similarity pre-alignment) pass within 0.2 % of the size."""
    p = [complex(*s) for s, _ in pairs]
    q = [complex(*t) for _, t in pairs]
    pm, qm = sum(p) / len(p), sum(q) / len(q)
    den = sum(abs(z - pm) ** 2 for z in p)
    a = sum((w - qm) * (z - pm).conjugate() for z, w in zip(p, q)) / den if den > 0 else 1
    start = [a * (z - pm) + qm for z in p]
    for i in range(len(p)):
        for j in range(i + 1, len(p)):
            d0, dd = start[i] - start[j], (q[i] - start[i]) - (q[j] - start[j])
            t = min(1.0, max(0.0, -(d0 * dd.conjugate()).real / abs(dd) ** 2)) if abs(dd) > 0 else 0.0
            if abs(d0 + t * dd) < max(1.0, 0.002 * size):
                return False
    return True


def distinct(points, size):
    """No two of the points within 0.2 % of the size (at least 1 px): what texwarp needs of sources and of targets
    (its minimum separation is 0.5 px); trajectories between them may cross, which its planner resolves."""
    reach = max(1.0, 0.002 * size)
    cells = {}
    for x, y in points:
        key = (int(x // reach), int(y // reach))
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                for u, v in cells.get((key[0] + dx, key[1] + dy), ()):
                    if math.hypot(x - u, y - v) < reach:
                        return False
        cells.setdefault(key, []).append((x, y))
    return True


def features(family, n, size, seed=1):
    """A row's feature set: the first of up to 1000 seeded draws whose straight trajectories keep apart; where none
    does (dense independent sets: 500 at 512², as issue 29's table), the first draw whose sources and targets are
    distinct, so that paths cross and texwarp's planner is part of the row; where no whole draw is distinct either
    (thousands of features), one drawn feature by feature (dense)."""
    if family == "identity":  # no features: the identity warp (the closed form), texwarp alone
        return {"features": []}
    rng = random.Random(seed * 7919 + n * 31 + size)
    make = {"smooth": smooth, "independent": independent, "clustered": clustered}[family]
    crossing = None
    for _ in range(1000):  # clustered 200 at 2048² needs a few hundred draws
        pairs = make(n, size, rng)
        if well_separated(pairs, size):
            break
        if crossing is None and distinct([s for s, _ in pairs], size) and distinct([t for _, t in pairs], size):
            crossing = pairs
    else:
        if crossing is None and family != "smooth":
            crossing = dense(family, n, size, rng)
        if crossing is None:
            raise SystemExit(f"no {family} set of {n} features at {size}² with distinct sources and targets in 1000 "
                             "draws")
        pairs = crossing
    return {"features": [{"id": f"f{k}", "source": [round(s[0], 3), round(s[1], 3)],
                          "target": [round(t[0], 3), round(t[1], 3)]} for k, (s, t) in enumerate(pairs)]}


def write_texture(path, size):
    import cv2
    import numpy as np
    y, x = np.mgrid[0:size, 0:size].astype(np.float32)
    img = np.stack([127 + 120 * np.sin(x / 7.0) * np.cos(y / 11.0), 255 * x / size, 255 * y / size], axis=-1)
    img[((x // 32 + y // 32) % 2) == 0] *= 0.6
    cv2.imwrite(path, img.astype(np.uint8))


def tps_command(features_path, in_path, out_path):
    """OpenCV's TPS warp of in_path so that every source lands on its target, written to out_path. The in-process
    seconds (the fit and the warp in a process that has already started, imported cv2 and decoded the image) go to
    out_path + ".seconds"."""
    import cv2
    import numpy as np
    with open(features_path) as f:
        spec = json.load(f)
    src = np.array([f["source"] for f in spec["features"]], np.float32).reshape(1, -1, 2)
    dst = np.array([f["target"] for f in spec["features"]], np.float32).reshape(1, -1, 2)
    matches = [cv2.DMatch(i, i, 0) for i in range(src.shape[1])]
    image = cv2.imread(in_path, cv2.IMREAD_UNCHANGED)
    t = time.perf_counter()
    tps = cv2.createThinPlateSplineShapeTransformer()
    tps.estimateTransformation(dst, src, matches)  # warpImage pulls: estimate the map from targets to sources
    out = tps.warpImage(image)
    seconds = time.perf_counter() - t
    cv2.imwrite(out_path, out)
    with open(out_path + ".seconds", "w") as f:
        f.write(f"{seconds:.6f}\n")


def timed(cmd, env):
    """Wall seconds and CPU seconds (user + system) of one whole command."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    r = subprocess.run(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    dt = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {r.returncode}: {r.stderr.strip()[-400:]}")
    return dt, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def row_files(work, family, n, size):
    base = os.path.join(work, f"{family}-{n}-{size}")
    img = os.path.join(work, f"texture-{size}.png")
    if not os.path.exists(img):
        write_texture(img, size)
    with open(base + ".json", "w") as f:
        json.dump(features(family, n, size), f)
    return base + ".json", img, base


def run_row(args, family, n, size, env):
    feats, img, base = row_files(args.work, family, n, size)
    commands = {} if family == "identity" else {
        "tps": [sys.executable, os.path.abspath(__file__), "tps", feats, img, base + "-tps.png"]}
    for name, exe in (("texwarp", args.texwarp), ("baseline", args.baseline)):
        if exe:
            commands[name] = [exe, "warp", "--features", feats, "--in", img, "--out", base + f"-{name}.png",
                              "--certificate", base + f"-{name}-cert.json"]
    times = {k: [] for k in commands}
    cpu = {k: [] for k in commands}
    if "tps" in commands:
        times["tps in-process"] = []
    for _ in range(args.runs):  # alternating: every run of every command before the next round
        for name, cmd in commands.items():
            wall, used = timed(cmd, env)
            times[name].append(wall)
            cpu[name].append(used)
            if name == "tps":
                with open(base + "-tps.png.seconds") as f:
                    times["tps in-process"].append(float(f.read()))
    med = {k: statistics.median(v) for k, v in times.items()}
    med.update({k + " cpu": statistics.median(v) for k, v in cpu.items()})
    cert = {}
    for name in ("texwarp", "baseline"):
        if name in commands:
            with open(base + f"-{name}-cert.json") as f:
                cert[name] = json.load(f)
    return med, cert


def cold_row(args, env):
    """The first warp on a new machine (512², 50 independent features), each run in a fresh cache folder: with empty
    caches, and after `texwarp warm`, against a warm second warp. The user sets no POCL_CACHE_DIR: texwarp keeps
    PoCL's cache in its own folder (TEXWARP_CACHE_DIR/pocl). Medians of wall seconds."""
    feats, img, base = row_files(args.work, "independent", 50, 512)
    cmd = [args.texwarp, "warp", "--features", feats, "--in", img, "--out", base + "-cold.png"]
    out = {"cold": [], "warm": [], "warm command": [], "after warm": []}
    cpu = {k: [] for k in out}

    def record(name, command, e):
        wall, used = timed(command, e)
        out[name].append(wall)
        cpu[name].append(used)

    for _ in range(args.runs):
        empty = tempfile.mkdtemp(prefix="cold-", dir=args.work)
        e = {k: v for k, v in env.items() if k != "POCL_CACHE_DIR"}
        e["TEXWARP_CACHE_DIR"] = empty
        record("cold", cmd, e)
        record("warm", cmd, e)
        shutil.rmtree(empty, ignore_errors=True)
        warmed = tempfile.mkdtemp(prefix="warmed-", dir=args.work)
        e["TEXWARP_CACHE_DIR"] = warmed
        record("warm command", [args.texwarp, "warm"], e)
        record("after warm", cmd, e)
        shutil.rmtree(warmed, ignore_errors=True)
    return {k: statistics.median(v) for k, v in out.items()}, {k: statistics.median(v) for k, v in cpu.items()}


def parse_rows(text):
    rows = []
    for item in text.split(","):
        family, n, size = item.split(":")
        if family == "identity":
            rows.append((family, 0, int(size)))
            continue
        if family not in FAMILIES:
            raise SystemExit(f"--rows: unknown family '{family}' in '{item}' (one of {', '.join(FAMILIES)})")
        rows.append((family, int(n), int(size)))
    return rows


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "features":
        family, n, size, out = sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
        with open(out, "w") as f:
            json.dump(features(family, n, size), f, indent=1)
        return
    if len(sys.argv) > 1 and sys.argv[1] == "tps":
        tps_command(*sys.argv[2:5])
        return
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--texwarp", default=os.path.join(os.path.dirname(__file__), "..", "build", "client", "texwarp"))
    p.add_argument("--baseline", help="an older texwarp binary run side by side (before/after)")
    p.add_argument("--quick", action="store_true", help="512² and 1024² rows only, 3 runs")
    p.add_argument("--rows", help="FAMILY:N:SIZE,... (default: the whole table)")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--cold", action="store_true", help="also the cold-start row")
    p.add_argument("--cold-only", action="store_true", help="the cold-start row alone")
    p.add_argument("--work", default=None, help="folder for inputs and outputs (default: a temporary one)")
    args = p.parse_args()
    args.work = args.work or tempfile.mkdtemp(prefix="texwarp-bench-")
    os.makedirs(args.work, exist_ok=True)
    if args.quick:
        args.runs = min(args.runs, 3)
    rows = parse_rows(args.rows) if args.rows else [
        (f, n, s) for f in FAMILIES for s in SIZES if not (args.quick and s > 1024) for n in COUNTS]
    if args.cold_only:
        args.cold, rows = True, []
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", os.path.join(args.work, "pocl-cache"))
    cols = "| family | n | size | texwarp s | TPS s | ratio | TPS in-process s | ratio | texwarp CPU s | TPS CPU s |"
    cols += " before s | before CPU s |" if args.baseline else ""
    if rows:
        print(f"whole commands, median of {args.runs}, alternating (wall and CPU = user + system); "
              f"texwarp: {args.texwarp}")
        print(cols + " pathlines | pixel pathlines | cells | exact |")
        print("|" + "---|" * (cols.count("|") - 1 + 4))  # and the four certificate columns
    for family, n, size in rows:
        med, cert = run_row(args, family, n, size, env)
        c = cert.get("texwarp", {})
        if "tps" in med:
            line = f"| {family} | {n} | {size} | {med['texwarp']:.2f} | {med['tps']:.2f} |"
            line += f" {med['texwarp'] / med['tps']:.2f} |"
            line += f" {med['tps in-process']:.2f} | {med['texwarp'] / med['tps in-process']:.2f} |"
            line += f" {med['texwarp cpu']:.2f} | {med['tps cpu']:.2f} |"
        else:
            line = f"| {family} | {n} | {size} | {med['texwarp']:.3f} | — | — | — | — | {med['texwarp cpu']:.3f} | — |"
        if args.baseline:
            line += f" {med['baseline']:.2f} | {med['baseline cpu']:.2f} |"
        print(line + f" {c.get('pathlines', '')} | {c.get('pixel_pathlines', '')} | {c.get('cells', '')} |"
              f" {c.get('exact', '')} |", flush=True)
    if args.cold:
        m, c = cold_row(args, env)
        print(f"cold start, 512², 50 independent, median of {args.runs}, each in a fresh cache folder "
              f"(wall s / CPU s): "
              f"empty caches {m['cold']:.2f} / {c['cold']:.2f}, after `texwarp warm` {m['after warm']:.2f} / "
              f"{c['after warm']:.2f}, warm {m['warm']:.2f} / {c['warm']:.2f}; beyond warm (wall): "
              f"{m['cold'] - m['warm']:.2f} empty, {m['after warm'] - m['warm']:.2f} after warm; `texwarp warm` "
              f"itself {m['warm command']:.2f} / {c['warm command']:.2f}", flush=True)

if __name__ == "__main__":
    main()
