#!/usr/bin/python3
"""Texture-set benchmark (issue 30): four maps of one asset (sRGB colour RGB 8-bit PNG, data grey 16-bit PNG,
tangent-space normals RGB 16-bit PNG, float height EXR) warped by one `texwarp warp --in … --out-dir` against the
colour map warped alone and against the four maps as four commands, whole commands, alternating, medians; peak RSS
of each command (its own rusage). Then the
checks the figures rest on: each output of the set equal to that map warped alone; the colour map cut into four
UDIM tiles (1001, 1002, 1011, 1012) warped as `<UDIM>` equal to the whole map warped and cut again; a .tx output
read back tiled with every MIP level. Figures, not pass/fail (a failed check exits 1).
Run it with Debian's /usr/bin/python3 (numpy, OpenImageIO). Usage:
  texture_set_bench.py [--texwarp PATH] [--baseline OLD_TEXWARP] [--size 2048] [--features 50] [--runs 5] [--work DIR]
                       [--backend opencl]
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import OpenImageIO as oiio

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import whole_command_bench  # noqa: E402  (its smooth feature family)


def write(path, pixels, type_desc):
    h, w = pixels.shape[:2]
    c = 1 if pixels.ndim == 2 else pixels.shape[2]
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(w, h, c, type_desc))
    out.write_image(np.ascontiguousarray(pixels.reshape(h, w, c), dtype=np.float32))
    out.close()


def read(path):
    buf = oiio.ImageBuf(path)
    return buf.get_pixels(oiio.FLOAT)


def make_maps(work, size):
    """The asset's four maps: base.png (sRGB colour), rough.png (data), nrm.png (normals), height.exr (float)."""
    y, x = np.mgrid[0:size, 0:size].astype(np.float64) / size
    color = np.stack([0.5 + 0.5 * np.sin(40 * x) * np.cos(30 * y), x, ((np.floor(64 * x) + np.floor(64 * y)) % 2)],
                     axis=2)
    rough = (0.5 + 0.5 * np.sin(25 * x + 17 * y))
    tx = 0.4 * np.sin(60 * x)
    ty = 0.3 * np.cos(45 * y)
    tz = np.sqrt(1 - tx * tx - ty * ty)
    nrm = 0.5 * (np.stack([tx, ty, tz], axis=2) + 1)
    height = 3.0 * np.sin(12 * x) * np.cos(9 * y)
    maps = {"base.png": (color, oiio.UINT8), "rough.png": (rough, oiio.UINT16), "nrm.png": (nrm, oiio.UINT16),
            "height.exr": (height, oiio.FLOAT)}
    for name, (pixels, t) in maps.items():
        write(os.path.join(work, "maps", name), pixels, t)
    roles = {"base.png": "color=", "rough.png": "data=", "nrm.png": "normal=", "height.exr": ""}
    return roles


def run(cmd):
    """Wall seconds and peak RSS (KiB) of one whole command. The RSS is GNU time's (%M) of the command it starts, as in
    resampling_bench.py: a child of this script would count the script's own pages at its fork in its peak (Linux keeps
    the larger across exec), hundreds of MiB once the maps are made."""
    t = time.perf_counter()
    p = subprocess.run(["/usr/bin/time", "-f", "%M"] + cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                       text=True)
    dt = time.perf_counter() - t
    err = p.stderr.strip()
    if p.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed: {err[-400:]}")
    return dt, int(err.splitlines()[-1])


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--texwarp", default=os.path.join(os.path.dirname(__file__), "..", "build", "client", "texwarp"))
    ap.add_argument("--size", type=int, default=2048)
    ap.add_argument("--features", type=int, default=50)
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--backend", default="opencl")
    ap.add_argument("--baseline", help="an older texwarp binary: its one map and four maps, alternating with these")
    ap.add_argument("--work")
    args = ap.parse_args()
    work = args.work or tempfile.mkdtemp(prefix="texwarp-set-bench-")
    os.makedirs(os.path.join(work, "maps"), exist_ok=True)
    roles = make_maps(work, args.size)
    feats = os.path.join(work, "features.json")
    with open(feats, "w") as f:
        json.dump(whole_command_bench.features("smooth", args.features, args.size), f)
    base = [args.texwarp, "warp", "--features", feats, "--backend", args.backend, "--border", "clamp"]
    one = base + ["--in", "color=" + os.path.join(work, "maps", "base.png"), "--out", os.path.join(work, "one.png")]
    four = base + sum((["--in", r + os.path.join(work, "maps", n)] for n, r in roles.items()), []) + [
        "--out-dir", os.path.join(work, "set")]
    separately = [base + ["--in", r + os.path.join(work, "maps", n), "--out", os.path.join(work, "sep-" + n)]
                  for n, r in roles.items()]
    run(one)  # warm caches (kernels, files) before timing
    times = {"one": [], "four": [], "separately": []}
    rss = {"one": [], "four": [], "separately": []}
    # With --baseline: the older build's one map and four maps too, each command right after the same of this build.
    old_times = {"one": [], "four": []}
    old_rss = {"one": [], "four": []}
    if args.baseline:
        run([args.baseline] + one[1:-1] + [os.path.join(work, "one-baseline.png")])
    for _ in range(args.runs):
        for name, cmds in (("one", [one]), ("four", [four]), ("separately", separately)):
            total, peak = 0.0, 0
            for cmd in cmds:
                dt, kib = run(cmd)
                total += dt
                peak = max(peak, kib)
            times[name].append(total)
            rss[name].append(peak)
            if args.baseline and name in old_times:
                out = os.path.join(work, "one-baseline.png" if name == "one" else "set-baseline")
                dt, kib = run([args.baseline] + cmds[0][1:-1] + [out])
                old_times[name].append(dt)
                old_rss[name].append(kib)
    m1 = statistics.median(times["one"])
    m4 = statistics.median(times["four"])
    ms = statistics.median(times["separately"])
    print(f"{args.size}², {args.features} smooth features, {args.backend}, medians of {args.runs} alternating:")
    print(f"  one map (sRGB colour PNG):       {m1:.2f} s, peak RSS {max(rss['one']) / 1024:.0f} MiB")
    print(f"  four maps in one warp:           {m4:.2f} s ({m4 / m1:.2f}× one map), "
          f"peak RSS {max(rss['four']) / 1024:.0f} MiB")
    print(f"  the four maps as four commands:  {ms:.2f} s ({m4 / ms:.2f}× of it in one), "
          f"largest peak RSS {max(rss['separately']) / 1024:.0f} MiB")
    if args.baseline:
        b1 = statistics.median(old_times["one"])
        b4 = statistics.median(old_times["four"])
        print(f"  baseline {args.baseline}:")
        print(f"    one map:    {b1:.2f} s (this build {m1 / b1:.2f}× of it), peak RSS "
              f"{max(old_rss['one']) / 1024:.0f} MiB")
        print(f"    four maps:  {b4:.2f} s ({b4 / b1:.2f}× one map; this build {m4 / b4:.2f}× of it), peak RSS "
              f"{max(old_rss['four']) / 1024:.0f} MiB")

    ok = True
    # Each output of the set equals that map warped alone.
    for name, role in roles.items():
        alone = os.path.join(work, "alone-" + name)
        run(base + ["--in", role + os.path.join(work, "maps", name), "--out", alone])
        a = read(alone)
        b = read(os.path.join(work, "set", name))
        same = a.shape == b.shape and np.array_equal(a, b)
        ok &= same
        print(f"  {name}: set output {'equals' if same else 'DIFFERS FROM'} the map warped alone")
    # UDIM: the colour map as four tiles against the whole map warped and cut again.
    color = read(os.path.join(work, "maps", "base.png"))
    half = args.size // 2
    tiles = {1011: (0, 0), 1012: (half, 0), 1001: (0, half), 1002: (half, half)}  # row v = 1 on top
    os.makedirs(os.path.join(work, "udim"), exist_ok=True)
    os.makedirs(os.path.join(work, "udim-out"), exist_ok=True)
    for n, (x0, y0) in tiles.items():
        write(os.path.join(work, "udim", f"base.{n}.png"), color[y0:y0 + half, x0:x0 + half], oiio.UINT8)
    dt, _ = run(base + ["--in", "color=" + os.path.join(work, "udim", "base.<UDIM>.png"), "--out",
                        os.path.join(work, "udim-out", "base.<UDIM>.png")])
    whole = read(os.path.join(work, "one.png"))
    for n, (x0, y0) in tiles.items():
        tile = read(os.path.join(work, "udim-out", f"base.{n}.png"))
        same = np.array_equal(tile, whole[y0:y0 + half, x0:x0 + half])
        ok &= same
        print(f"  UDIM tile {n}: {'equals' if same else 'DIFFERS FROM'} the whole map warped and cut ({dt:.2f} s for 4)")
    # .tx: tiled, every MIP level down to 1×1.
    tx = os.path.join(work, "base.tx")
    dt, _ = run(base + ["--in", "color=" + os.path.join(work, "maps", "base.png"), "--out", tx])
    inp = oiio.ImageInput.open(tx)
    levels = []
    while inp.seek_subimage(0, len(levels)):
        s = inp.spec()
        levels.append((s.width, s.tile_width))
    expected = 1 + int(math.log2(args.size))
    tiled = all(t > 0 for _, t in levels)
    level0 = np.array_equal(read(tx).reshape(whole.shape), whole)
    ok &= tiled and len(levels) == expected and levels[-1][0] == 1 and level0
    print(f"  base.tx ({dt:.2f} s): {len(levels)} MIP levels (expected {expected}), "
          f"tiles {levels[0][1]}², {'all tiled' if tiled else 'NOT TILED'}, colour space "
          f"{inp.spec().get_string_attribute('oiio:ColorSpace')!r}, level 0 "
          f"{'equals' if level0 else 'DIFFERS FROM'} the PNG warp")
    inp.close()
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
