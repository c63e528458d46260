#!/usr/bin/python3
"""Resampling benchmark (issue 27): what the warped pixels are worth and what they cost, through the real
`texwarp warp` command line as a user runs it; figures, not pass/fail. Run it with Debian's /usr/bin/python3 (numpy,
cv2 from python3-opencv: scripts/setup.sh).

Quality, on warps whose right answer is known:
- similarity minifications 2×, 4×, 8× of a zone plate (a closed form: three features on a scaled copy), alias RMS
  against the input averaged exactly over each output pixel's footprint (its s×s block), --filter point and
  footprint, bilinear and bicubic;
- a disc shrunk 3× inside an ordinary warp (twelve features on a ring, eight anchors), PSNR against the footprint
  average from 8×8 subpixels per output pixel, each mapped by its own exact pathline (`texwarp map --inverse
  --backend cpu`);
- a 1 px sRGB checker minified 2× (colour: light averages to sRGB 188; the codes to 128);
- a tilted constant normal map turned by 90° and 30° (features on a rotated copy): the angle between each output
  normal and the input's turned with the texture.
Cost: whole `texwarp warp` commands with 50 smooth features at 1024² and 4096², the new build against an older one
(--baseline) side by side, alternating, medians of --runs: wall seconds, the sampling stage's seconds
(--timings=json), peak RSS.

Usage: resampling_bench.py [--texwarp PATH] [--baseline PATH] [--runs 5] [--sizes 1024,4096] [--work DIR]
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile

import cv2
import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import whole_command_bench  # noqa: E402  (the feature families and the benchmark texture)


def run(cmd, env):
    r = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} exited {r.returncode}: {r.stderr.strip()[-600:]}")
    return r


def write_features(path, pairs):
    with open(path, "w") as f:
        json.dump({"features": [{"source": list(s), "target": list(t)} for s, t in pairs]}, f)


def zone_plate(n):
    y, x = np.mgrid[0:n, 0:n].astype(np.float64) + 0.5 - n / 2.0
    return 0.5 + 0.5 * np.cos(math.pi * (x * x + y * y) / n)


def read_grey(path):
    img = cv2.imread(path, cv2.IMREAD_UNCHANGED).astype(np.float64)
    img /= 65535.0 if img.max() > 255 else 255.0
    return img if img.ndim == 2 else img[..., 0]


def warp(args, env, exe, features, src, out, extra):
    return run([exe, "warp", "--features", features, "--in", src, "--out", out, "--border", "clamp"] + extra, env)


def similarity_rows(args, env):
    n = 512
    plate = zone_plate(n)
    src = os.path.join(args.work, "plate.png")
    cv2.imwrite(src, np.round(plate * 65535).astype(np.uint16))
    plate = read_grey(src)
    print("\n| similarity minification | interpolation | alias RMS point | alias RMS footprint |")
    print("|---|---|---|---|")
    for s in (2, 4, 8):
        m = n // s
        feats = os.path.join(args.work, f"similarity-{s}.json")
        write_features(feats, [((40, 60), (40 / s, 60 / s)), ((400, 100), (400 / s, 100 / s)),
                               ((200, 450), (200 / s, 450 / s))])
        reference = plate.reshape(m, s, m, s).mean(axis=(1, 3))
        for interp in ("bilinear", "bicubic"):
            rms = {}
            for flt in ("point", "footprint"):
                out = os.path.join(args.work, f"sim-{s}-{interp}-{flt}.png")
                warp(args, env, args.texwarp, feats, "data=" + src, out,
                     ["--width", str(m), "--height", str(m), "--interp", interp, "--filter", flt, "--format",
                      "uint16"])
                rms[flt] = float(np.sqrt(np.mean((read_grey(out) - reference) ** 2)))
            print(f"| {s}× | {interp} | {rms['point']:.4f} | {rms['footprint']:.4f} |", flush=True)


def oiio_texture_rows(args, env):
    """OpenImageIO's TextureSystem (what VFX renderers sample with) on the same similarity minifications: a tiled,
    MIP-mapped copy made by maketx, each output pixel looked up with its exact derivatives (s, t in [0, 1]); its
    default anisotropic MIP filter, and its EWA-like 'smartcubic' interpolation."""
    try:
        import OpenImageIO as oiio
    except ImportError:
        print("\n(OpenImageIO's Python module missing: apt-get install python3-openimageio for the TextureSystem row)")
        return
    n = 512
    src = os.path.join(args.work, "plate.png")
    tx = os.path.join(args.work, "plate.tx")
    run(["maketx", "-o", tx, "--filter", "lanczos3", src], env)
    plate = read_grey(src)
    ts = oiio.TextureSystem(shared=False)
    print("\n| similarity minification | OpenImageIO TextureSystem, alias RMS (bilinear MIP, aniso 16) |"
          " (smartcubic) | texwarp footprint bilinear | texwarp footprint bicubic |")
    print("|---|---|---|---|---|")
    for s in (2, 4, 8):
        m = n // s
        reference = plate.reshape(m, s, m, s).mean(axis=(1, 3))
        rms = []
        for interp in (oiio.InterpMode.Bilinear, oiio.InterpMode.SmartBicubic):
            opt = oiio.TextureOpt()
            opt.interpmode = interp
            opt.anisotropic = 16
            opt.swrap = opt.twrap = oiio.Wrap.Clamp
            out = np.zeros((m, m))
            d = s / n  # s, t per output pixel
            for y in range(m):
                for x in range(m):
                    out[y, x] = ts.texture(tx, opt, (x + 0.5) * d, (y + 0.5) * d, d, 0.0, 0.0, d, 1)[0]
            rms.append(float(np.sqrt(np.mean((out - reference) ** 2))))
        ours = []
        for interp in ("bilinear", "bicubic"):
            ours.append(float(np.sqrt(np.mean((read_grey(os.path.join(args.work, f"sim-{s}-{interp}-footprint.png"))
                                               - reference) ** 2))))
        print(f"| {s}× | {rms[0]:.4f} | {rms[1]:.4f} | {ours[0]:.4f} | {ours[1]:.4f} |", flush=True)


def disc_row(args, env):
    n, c = 512, 256.0
    src = os.path.join(args.work, "plate.png")
    plate = read_grey(src)
    pairs = []
    for k in range(12):
        a = 2 * math.pi * k / 12
        pairs.append(((c + 96 * math.cos(a), c + 96 * math.sin(a)), (c + 32 * math.cos(a), c + 32 * math.sin(a))))
    for k in range(8):
        a = 2 * math.pi * k / 8 + 0.2
        p = (c + 230 * math.cos(a), c + 230 * math.sin(a))
        pairs.append((p, p))
    feats = os.path.join(args.work, "disc.json")
    write_features(feats, pairs)
    # The reference over the shrunk disc's square: 8×8 subpixels per output pixel, exact pathlines.
    lo, hi, k = int(c - 40), int(c + 40), 8
    sub = (np.arange(k) + 0.5) / k
    ys, xs = np.mgrid[lo:hi, lo:hi]
    px = (xs[..., None, None] + sub[None, None, None, :]).repeat(k, axis=2)
    py = (ys[..., None, None] + sub[None, None, :, None]).repeat(k, axis=3)
    points = np.stack([px.ravel(), py.ravel()], axis=1)
    points_file = os.path.join(args.work, "disc-points.json")
    with open(points_file, "w") as f:
        json.dump(points.tolist(), f)
    mapped = np.array(json.loads(run([args.texwarp, "map", "--features", feats, "--points", points_file, "--inverse",
                                      "--backend", "cpu"], env).stdout))
    # Bilinear samples of the source at the mapped subpixels (clamped), averaged per output pixel.
    x = np.clip(mapped[:, 0] - 0.5, 0, n - 1.000001)
    y = np.clip(mapped[:, 1] - 0.5, 0, n - 1.000001)
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - x0, y - y0
    v = (plate[y0, x0] * (1 - fx) * (1 - fy) + plate[y0, x0 + 1] * fx * (1 - fy) + plate[y0 + 1, x0] * (1 - fx) * fy
         + plate[y0 + 1, x0 + 1] * fx * fy)
    reference = v.reshape(hi - lo, hi - lo, k * k).mean(axis=2)
    row = {}
    for flt in ("point", "footprint"):
        out = os.path.join(args.work, f"disc-{flt}.png")
        warp(args, env, args.texwarp, feats, "data=" + src, out, ["--filter", flt, "--format", "uint16"])
        got = read_grey(out)[lo:hi, lo:hi]
        mse = float(np.mean((got - reference) ** 2))
        row[flt] = (10 * math.log10(1.0 / mse), math.sqrt(mse))
    print(f"\ndisc shrunk 3× (12 ring features, 8 anchors), {hi - lo}² px around it against 8×8 exact subpixels: "
          f"point PSNR {row['point'][0]:.1f} dB (RMS {row['point'][1]:.4f}), footprint PSNR {row['footprint'][0]:.1f} dB "
          f"(RMS {row['footprint'][1]:.4f})", flush=True)


def checker_row(args, env):
    n = 256
    y, x = np.mgrid[0:n, 0:n]
    checker = (((x + y) % 2) * 255).astype(np.uint8)
    src = os.path.join(args.work, "checker.png")
    cv2.imwrite(src, np.stack([checker] * 3, axis=-1))
    feats = os.path.join(args.work, "half.json")
    write_features(feats, [((10, 20), (5, 10)), ((200, 30), (100, 15)), ((60, 220), (30, 110))])
    means = {}
    for role in ("color", "data"):
        out = os.path.join(args.work, f"checker-{role}.png")
        warp(args, env, args.texwarp, feats, f"{role}={src}", out, ["--width", "128", "--height", "128"])
        means[role] = float(cv2.imread(out, cv2.IMREAD_UNCHANGED)[8:-8, 8:-8, 0].mean())
    print(f"\n1 px black/white sRGB checker minified 2×: colour {means['color']:.1f}, data {means['data']:.1f} "
          f"(light 0.5 is sRGB 187.5)", flush=True)


def normal_rows(args, env):
    n = 256
    tilt = np.array([0.5, 0.2, 1.0]) / np.linalg.norm([0.5, 0.2, 1.0])  # image coordinates: x right, y down
    stored = np.array([tilt[0], -tilt[1], tilt[2]])  # OpenGL: green up
    texel = np.round((stored + 1) / 2 * 65535).astype(np.uint16)
    img = np.tile(texel[::-1], (n, n, 1))  # cv2 writes BGR
    src = os.path.join(args.work, "normal.png")
    cv2.imwrite(src, img)
    print("\n| normal map turned | mean angle error | max angle error | as colour (max) |")
    print("|---|---|---|---|")
    c = np.array([n / 2, n / 2])
    for degrees in (90, 30):
        a = math.radians(degrees)
        rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
        pts = [np.array(p, float) for p in ((60, 70), (190, 80), (120, 200), (80, 150))]
        feats = os.path.join(args.work, f"rot-{degrees}.json")
        write_features(feats, [(tuple(p), tuple(c + rot @ (p - c))) for p in pts])
        turned = np.concatenate([rot @ tilt[:2], tilt[2:]])
        errors = {}
        for role in ("normal", "data"):
            out = os.path.join(args.work, f"rot-{degrees}-{role}.png")
            warp(args, env, args.texwarp, feats, f"{role}={src}", out, ["--format", "uint16"])
            got = cv2.imread(out, cv2.IMREAD_UNCHANGED)[..., :3][..., ::-1].astype(np.float64) / 65535 * 2 - 1
            got = got[n // 4:-n // 4, n // 4:-n // 4].reshape(-1, 3)
            got[:, 1] *= -1
            got /= np.linalg.norm(got, axis=1, keepdims=True)
            angles = np.degrees(np.arccos(np.clip(got @ turned, -1, 1)))
            errors[role] = (float(angles.mean()), float(angles.max()))
        print(f"| {degrees}° | {errors['normal'][0]:.3f}° | {errors['normal'][1]:.3f}° | {errors['data'][1]:.1f}° |",
              flush=True)


def peak_rss_and_times(cmd, env):
    r = run(["/usr/bin/time", "-f", "%M %e"] + cmd + ["--timings=json"], env)
    lines = r.stderr.strip().splitlines()
    rss_kb, wall = lines[-1].split()
    stages = next(json.loads(line) for line in lines if line.startswith("{\"timings\""))["timings"]["stages"]
    return float(wall), stages.get("sampling", 0.0), int(rss_kb) / 1024.0


def cost_rows(args, env):
    print(f"\nwhole `texwarp warp`, 50 smooth features, median of {args.runs}, alternating; "
          f"after: {args.texwarp}; before: {args.baseline}")
    print("| size | before wall s | after wall s | ratio | before sampling s | after sampling s | before RSS MiB |"
          " after RSS MiB | RSS ratio |")
    print("|---|---|---|---|---|---|---|---|---|")
    for size in args.sizes:
        feats, img, base = whole_command_bench.row_files(args.work, "smooth", 50, size)
        builds = {"after": args.texwarp, "before": args.baseline}
        got = {k: [] for k in builds}
        for _ in range(args.runs):
            for name, exe in builds.items():
                got[name].append(peak_rss_and_times([exe, "warp", "--features", feats, "--in", img, "--out",
                                                     f"{base}-{name}.png"], env))
        med = {k: [statistics.median(x[i] for x in v) for i in range(3)] for k, v in got.items()}
        b, a = med["before"], med["after"]
        print(f"| {size}² | {b[0]:.2f} | {a[0]:.2f} | {a[0] / b[0]:.2f} | {b[1]:.3f} | {a[1]:.3f} | {b[2]:.0f} |"
              f" {a[2]:.0f} | {a[2] / b[2]:.2f} |", flush=True)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--texwarp", default=os.path.join(os.path.dirname(__file__), "..", "build", "client", "texwarp"))
    p.add_argument("--baseline", help="an older texwarp binary for the cost rows (before/after)")
    p.add_argument("--runs", type=int, default=5)
    p.add_argument("--sizes", default="1024,4096")
    p.add_argument("--work", default=None)
    p.add_argument("--cost-only", action="store_true")
    args = p.parse_args()
    args.sizes = [int(s) for s in args.sizes.split(",")]
    args.work = args.work or tempfile.mkdtemp(prefix="texwarp-resampling-")
    os.makedirs(args.work, exist_ok=True)
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", os.path.join(args.work, "pocl-cache"))
    if not args.cost_only:
        similarity_rows(args, env)
        oiio_texture_rows(args, env)
        disc_row(args, env)
        checker_row(args, env)
        normal_rows(args, env)
    if args.baseline:
        cost_rows(args, env)


if __name__ == "__main__":
    main()
