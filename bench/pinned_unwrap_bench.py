#!/usr/bin/python3
"""Pinned unwrap benchmark (issue 28): texwarp's Blender add-on against Blender's own pinned unwrap on the same pins.

Runs bench/pinned_unwrap_blender.py in headless Blender (Debian's 3.4) over seeded cases (mesh × pin family × move
size × Blender's starting unwrap method), with texwarp's Python module from a build tree and the add-on from
client/blender; writes every case to a JSON file and a Markdown summary: flip-free cases, faces ratio, L² stretch
ratio to Blender, seconds. Blender is restarted after a case that crashes it or runs past --case-timeout (that case
is recorded as failed). Figures, not pass/fail.

  /usr/bin/python3 bench/pinned_unwrap_bench.py --build build --cases 30 --seed 1 --quick \
      --texwarp-options '{"refine": true}' --out out/pinned-refine.json

With TEXWARP_BENCH_JOBS=DIR set, each case's job (as the add-on made it, mesh inline) is written to DIR/NAME.json,
to run one again alone: `texwarp run DIR/NAME.json --out O` (its image path is a temporary file: point it at any
image of the texture's size).
"""

import argparse
import itertools
import json
import os
import queue
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MESHES = ("grid", "cylinder", "cap")
FAMILIES = ("random", "crossing", "cluster", "boundary")
MOVES = (0.08, 0.15, 0.25)
METHODS = ("CONFORMAL", "ANGLE_BASED")


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--build", default=os.path.join(ROOT, "build"),
                   help="the build tree holding client/python/texwarp (default: build)")
    p.add_argument("--addon", default=os.path.join(ROOT, "client", "blender"),
                   help="the folder holding the texwarp_blender package (default: client/blender)")
    p.add_argument("--blender", default="blender", help="the Blender executable (default: blender)")
    p.add_argument("--cases", type=int, default=None,
                   help="number of cases, cycling over the combinations (default: one per combination; --quick: 30)")
    p.add_argument("--seed", type=int, default=1, help="seed of the pin sets (case i uses seed S·100000 + i)")
    p.add_argument("--quick", action="store_true",
                   help="the bent 30×30 grid alone, 30 cases by default: a few minutes")
    p.add_argument("--meshes", default=",".join(MESHES), help="comma-separated of %s" % ", ".join(MESHES))
    p.add_argument("--families", default=",".join(FAMILIES), help="comma-separated of %s" % ", ".join(FAMILIES))
    p.add_argument("--moves", default=",".join(str(m) for m in MOVES), help="move sizes, UV units (default %s)" %
                   ",".join(str(m) for m in MOVES))
    p.add_argument("--methods", default=",".join(METHODS), help="Blender's unwrap methods (default %s)" %
                   ",".join(METHODS))
    p.add_argument("--pins", type=int, default=12, help="pinned vertices per case (default 12)")
    p.add_argument("--texture-px", type=int, default=512, help="the square texture's size (default 512)")
    p.add_argument("--texwarp-options", default="{}",
                   help="JSON object merged into each job's options, e.g. '{\"refine\": true}' (default {}: the "
                        "add-on's own)")
    p.add_argument("--case-timeout", type=float, default=300.0,
                   help="seconds a case may take before Blender is stopped and the case recorded as failed")
    p.add_argument("--out", default=os.path.join(ROOT, "out", "pinned_unwrap_bench.json"),
                   help="the JSON file of every case (the Markdown summary beside it, .md)")
    p.add_argument("--only", default=None,
                   help="comma-separated case indices of the planned cases to run (to look at one again)")
    p.add_argument("--label", default=None, help="a name for this run in the summary (default: the options)")
    args = p.parse_args()
    try:
        args.options = json.loads(args.texwarp_options)
    except json.JSONDecodeError as e:
        p.error("--texwarp-options is not JSON: %s" % e)
    if not isinstance(args.options, dict):
        p.error("--texwarp-options must be a JSON object, got %s" % args.texwarp_options)
    if args.quick and args.meshes == ",".join(MESHES):
        args.meshes = "grid"
    args.meshes = [m for m in args.meshes.split(",") if m]
    args.families = [f for f in args.families.split(",") if f]
    args.methods = [m for m in args.methods.split(",") if m]
    try:
        args.moves = [float(m) for m in args.moves.split(",") if m]
    except ValueError:
        p.error("--moves: numbers separated by commas, got %s" % args.moves)
    for name, given, known in (("--meshes", args.meshes, MESHES), ("--families", args.families, FAMILIES),
                               ("--methods", args.methods, METHODS)):
        unknown = [g for g in given if g not in known]
        if unknown or not given:
            p.error("%s: %s unknown or none given (known: %s)" % (name, ", ".join(unknown), ", ".join(known)))
    if args.pins < 3:
        p.error("--pins: at least 3")
    python_path = os.path.join(os.path.abspath(args.build), "client", "python")
    if not os.path.isfile(os.path.join(python_path, "texwarp", "__init__.py")):
        p.error("no texwarp Python module in %s: build it (cmake --build %s --target _texwarp)" % (
            python_path, args.build))
    if not any(f.startswith("_texwarp") for f in os.listdir(os.path.join(python_path, "texwarp"))):
        p.error("%s/texwarp has no _texwarp extension: build it (cmake --build %s --target _texwarp)" % (
            python_path, args.build))
    if not os.path.isfile(os.path.join(args.addon, "texwarp_blender", "mesh_job.py")):
        p.error("--addon %s holds no texwarp_blender package" % args.addon)
    args.python_path = python_path
    if args.cases is None:
        args.cases = 30 if args.quick else len(args.meshes) * len(args.families) * len(args.moves) * len(args.methods)
    if args.label is None:
        args.label = "options %s" % json.dumps(args.options, sort_keys=True)
    return args


def plan_cases(args):
    """Case i: combination i mod their number (the family varies fastest, then the move, the method, the mesh),
    seed S·100000 + i."""
    combos = list(itertools.product(args.meshes, args.methods, args.moves, args.families))
    cases = []
    for i in range(args.cases):
        mesh, method, move, family = combos[i % len(combos)]
        cases.append({"index": i, "mesh": mesh, "method": method, "family": family, "move": move,
                      "seed": args.seed * 100000 + i})
    if args.only:
        wanted = {int(i) for i in args.only.split(",") if i}
        if not wanted <= set(range(args.cases)):
            raise RuntimeError("--only: cases %s are not among the %d planned (--cases)" % (
                sorted(wanted - set(range(args.cases))), args.cases))
        cases = [c for c in cases if c["index"] in wanted]
    return cases


def run_blender(args, spec, rows_file, log):
    """Blender over spec["cases"] from spec["start"], restarted after a crash or a case past --case-timeout (that
    case gets a row with bench_error). Returns the rows, in case order."""
    script = os.path.join(HERE, "pinned_unwrap_blender.py")
    env = dict(os.environ)
    env.setdefault("POCL_CACHE_DIR", os.path.join(os.path.abspath(args.build), "pocl-cache"))
    cases = spec["cases"]
    start = 0
    while start < len(cases):
        spec["start"] = start
        spec_file = rows_file + ".spec.json"
        with open(spec_file, "w") as f:
            json.dump(spec, f)
        done_before = count_rows(rows_file)
        cmd = [args.blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python", script, "--",
               spec_file, rows_file]
        proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                                start_new_session=True)
        lines = queue.Queue()

        def read(stream=proc.stdout, into=lines):
            for line in stream:
                into.put(line)
        threading.Thread(target=read, daemon=True).start()
        last_progress, done, tail = time.monotonic(), done_before, []
        timed_out = warmed_up = False
        while True:
            try:
                line = lines.get(timeout=1.0)
                log.write(line)
                tail = (tail + [line])[-40:]
                warmed_up = warmed_up or line.startswith("warm-up")
                if line.startswith(("case ", "warm-up")):
                    print(line.rstrip(), flush=True)
            except queue.Empty:
                pass
            now_done = count_rows(rows_file)
            if now_done != done:
                done, last_progress = now_done, time.monotonic()
            if proc.poll() is not None and lines.empty():
                break
            # The warm-up job gets a case's time too.
            if time.monotonic() - last_progress > args.case_timeout:
                timed_out = True
                os.killpg(proc.pid, signal.SIGKILL)  # Blender's own process group (start_new_session)
                proc.wait()
                break
        finished = start + (done - done_before)
        if finished >= len(cases) and proc.returncode == 0:
            break
        if finished >= len(cases):
            raise RuntimeError("Blender exited with status %s after the last case; its output's end:\n%s" % (
                proc.returncode, "".join(tail)))
        why = ("no result in %.0f s (--case-timeout): Blender stopped" % args.case_timeout if timed_out else
               "Blender exited with status %s" % proc.returncode)
        if finished == start and not warmed_up:  # texwarp or the add-on not loaded, the script broken: say so
            raise RuntimeError("Blender failed before its first case (%s); its output's end:\n%s" % (
                why, "".join(tail)))
        print("case %d: %s" % (cases[finished]["index"], why), flush=True)
        with open(rows_file, "a") as f:
            f.write(json.dumps(dict(cases[finished], bench_error=why, output_tail="".join(tail[-10:]))) + "\n")
        start = finished + 1
    with open(rows_file) as f:
        return [json.loads(line) for line in f if line.strip()]


def count_rows(path):
    if not os.path.exists(path):
        return 0
    with open(path) as f:
        return sum(1 for line in f if line.endswith("\n"))


# --- the summary ------------------------------------------------------------------------------------------------

def _median(xs):
    return statistics.median(xs) if xs else None


def summarise(rows):
    """Figures of a group of cases (see the Markdown table's columns)."""
    n = len(rows)
    blender = [r["blender"] for r in rows if r.get("blender")]
    texwarp = [r["texwarp"] for r in rows if r.get("texwarp")]
    ok = [(r, r["texwarp"]) for r in rows if r.get("texwarp") and r["texwarp"].get("error") is None]
    ratios = [t["l2_stretch"] / r["blender"]["l2_stretch"] for r, t in ok
              if t.get("l2_stretch") and r["blender"].get("l2_stretch")]
    faces = [t["triangles"] / r["triangles_before"] for r, t in ok]
    return {
        "cases": n,
        "bench_errors": sum(1 for r in rows if r.get("bench_error")),
        "blender_flip_free": sum(1 for b in blender if b["flips"] == 0),
        "blender_pins_exact": sum(1 for b in blender if b["pins_exact"]),
        "blender_max_flips": max((b["flips"] for b in blender), default=None),
        "texwarp_errors": sum(1 for t in texwarp if t.get("error") is not None),
        "texwarp_flip_free": sum(1 for _, t in ok if t["flips"] == 0),
        "texwarp_flip_free_pins_exact": sum(1 for _, t in ok if t["flips"] == 0 and t["pins_exact"]),
        "texwarp_max_flips": max((t["flips"] for _, t in ok), default=None),
        "texwarp_max_pin_px": max((t["pin_residual_px"] for _, t in ok), default=None),
        "faces_ratio_max": max(faces, default=None),
        "faces_ratio_median": _median(faces),
        "stretch_ratio_median": _median(ratios),
        "stretch_ratio_worst": max(ratios, default=None),
        "blender_seconds_median": _median([b["seconds"] for b in blender]),
        "texwarp_seconds_median": _median([t["seconds"] for t in texwarp]),
        "texwarp_seconds_max": max((t["seconds"] for t in texwarp), default=None),
    }


def report_agreement(rows):
    """The benchmark's own L² stretch and flips against the job report's, where texwarp ran: (worst relative
    stretch difference, the same over flip-free cases, cases whose negative-area count differs from the report's
    flipped_triangles). Blender keeps UVs in single precision: nearly degenerate triangles move the stretch."""
    worst, worst_flip_free, differ = 0.0, 0.0, 0
    for r in rows:
        t = r.get("texwarp") or {}
        rep = t.get("report") or {}
        if t.get("error") is None and rep.get("l2_stretch") and t.get("l2_stretch"):
            d = abs(t["l2_stretch"] - rep["l2_stretch"]) / rep["l2_stretch"]
            worst = max(worst, d)
            if t["flips"] == 0:
                worst_flip_free = max(worst_flip_free, d)
            differ += t["negative"] != rep.get("flipped_triangles")
    return worst, worst_flip_free, differ


def _f(x, fmt="%.2f"):
    return "–" if x is None else fmt % x


def table(title, groups):
    lines = ["#### " + title, "",
             "| group: cases | Blender flip-free | texwarp flip-free (pins exact) | failures | max flips Blender / "
             "texwarp | faces ratio max / median | stretch ÷ Blender median / worst | seconds Blender / texwarp "
             "(median; texwarp max) |",
             "|---|---|---|---|---|---|---|---|"]
    for name, rows in groups:
        s = summarise(rows)
        lines.append("| %s: %d | %d | %d (%d) | %d | %s / %s | %s / %s | %s / %s | %s / %s (%s) |" % (
            name, s["cases"], s["blender_flip_free"], s["texwarp_flip_free"], s["texwarp_flip_free_pins_exact"],
            s["texwarp_errors"] + s["bench_errors"], _f(s["blender_max_flips"], "%d"), _f(s["texwarp_max_flips"], "%d"),
            _f(s["faces_ratio_max"]), _f(s["faces_ratio_median"]), _f(s["stretch_ratio_median"]),
            _f(s["stretch_ratio_worst"]), _f(s["blender_seconds_median"]), _f(s["texwarp_seconds_median"]),
            _f(s["texwarp_seconds_max"])))
    return "\n".join(lines) + "\n"


def markdown(args, settings, rows):
    def group(key):
        keys = []
        for r in rows:
            if key(r) not in keys:
                keys.append(key(r))
        return [(k, [r for r in rows if key(r) == k]) for k in keys]

    agreement = report_agreement(rows)
    px = args.texture_px
    out = ["### Pinned unwrap benchmark: %s" % args.label, "",
           "%d cases (seed %d; meshes %s; families %s; moves ±%s UV = ±%s px on %d²; %d pins; Blender %s), texwarp "
           "options %s, commit %s, %s." % (
               len(rows), args.seed, ", ".join(args.meshes), ", ".join(args.families),
               ", ±".join("%g" % m for m in args.moves), ", ±".join("%.0f" % (m * px) for m in args.moves), px,
               args.pins, "/".join(args.methods), json.dumps(args.options), settings["commit"], settings["date"]),
           "Flips: loop triangles of the minority UV orientation on the final UV layer; faces ratio: texwarp's loop "
           "triangles after ÷ before; stretch: Sander's L² (area-normalised); pins exact: every loop of a pinned "
           "vertex within 0.05 px; failures: texwarp's errors and cases that crashed Blender or ran past the "
           "timeout. The benchmark's L² stretch against the job report's: worst relative difference %.1e (%.1e "
           "over texwarp's flip-free cases; Blender stores UVs in single precision); cases whose negative-area "
           "triangles differ from the report's flipped_triangles: %d." % agreement, ""]
    out.append(table("By family and move", group(lambda r: "%s ±%g" % (r["family"], r["move"]))))
    out.append(table("By move (all families)", group(lambda r: "±%g" % r["move"])))
    if len(args.meshes) > 1:
        out.append(table("By mesh", group(lambda r: r["mesh"])))
    out.append(table("By Blender's unwrap method", group(lambda r: r["method"])))
    out.append(table("All", [("all", rows)]))
    errors = [r for r in rows if r.get("bench_error") or (r.get("texwarp") or {}).get("error")]
    if errors:
        out += ["#### Failures", ""]
        for r in errors:
            out.append("- case %d (%s, %s, %s ±%g): %s" % (r["index"], r["mesh"], r["method"], r["family"], r["move"],
                                                           r.get("bench_error") or r["texwarp"]["error"]))
        out.append("")
    return "\n".join(out)


def source_commit(build):
    """The commit the build tree was configured from: its source folder's (CMAKE_HOME_DIRECTORY) git HEAD, "+
    uncommitted changes" when tracked files differ; for a `git archive` export, the hash in its HEAD_COMMIT file."""
    source = ROOT
    cache = os.path.join(build, "CMakeCache.txt")
    if os.path.isfile(cache):
        with open(cache) as f:
            for line in f:
                if line.startswith("CMAKE_HOME_DIRECTORY:"):
                    source = line.split("=", 1)[1].strip()
    try:
        head = subprocess.run(["git", "-C", source, "rev-parse", "--show-toplevel", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.split()
        if os.path.realpath(head[0]) == os.path.realpath(source):
            dirty = subprocess.run(["git", "-C", source, "status", "--porcelain", "--untracked-files=no"],
                                   capture_output=True, text=True, check=True).stdout.strip()
            return head[1][:10] + (" (+ uncommitted changes)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        pass
    marker = os.path.join(source, "HEAD_COMMIT")
    if os.path.isfile(marker):
        with open(marker) as f:
            return f.read().strip()[:10] + " (exported)"
    return "unknown (%s is no git checkout)" % source


def main():
    args = parse_args()
    cases = plan_cases(args)
    out_dir = os.path.dirname(os.path.abspath(args.out))
    os.makedirs(out_dir, exist_ok=True)
    settings = {"label": args.label, "cases": args.cases, "only": args.only, "seed": args.seed, "quick": args.quick,
                "meshes": args.meshes, "families": args.families, "moves": args.moves, "methods": args.methods,
                "pins": args.pins, "texture_px": args.texture_px, "texwarp_options": args.options,
                "build": os.path.abspath(args.build), "addon": os.path.abspath(args.addon),
                "commit": source_commit(os.path.abspath(args.build)),
                "date": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())}
    spec = {"addon_path": os.path.abspath(args.addon), "texwarp_python_path": args.python_path,
            "texture_px": args.texture_px, "pins": args.pins, "texwarp_options": args.options, "cases": cases}
    with tempfile.TemporaryDirectory(prefix="pinned-unwrap-bench-") as scratch:
        rows_file = os.path.join(scratch, "rows.jsonl")
        log_path = os.path.splitext(os.path.abspath(args.out))[0] + ".log"
        start = time.monotonic()
        with open(log_path, "w") as log:
            rows = run_blender(args, spec, rows_file, log)
        settings["wall_seconds"] = time.monotonic() - start
    rows.sort(key=lambda r: r["index"])
    summary = {"all": summarise(rows)}
    for move in args.moves:
        summary["move %g" % move] = summarise([r for r in rows if r["move"] == move])
    for family in args.families:
        summary[family] = summarise([r for r in rows if r["family"] == family])
    worst, worst_flip_free, differ = report_agreement(rows)
    summary["report_agreement"] = {"worst_relative_stretch_difference": worst,
                                   "worst_relative_stretch_difference_flip_free": worst_flip_free,
                                   "flip_count_differences": differ}
    with open(args.out, "w") as f:
        json.dump({"settings": settings, "summary": summary, "cases": rows}, f, indent=1)
    md_path = os.path.splitext(os.path.abspath(args.out))[0] + ".md"
    text = markdown(args, settings, rows)
    with open(md_path, "w") as f:
        f.write(text)
    print()
    print(text)
    print("%d cases in %.0f s: %s, %s (Blender's output: %s)" % (len(rows), settings["wall_seconds"], args.out,
                                                                 md_path, log_path))


if __name__ == "__main__":
    try:
        main()
    except RuntimeError as e:
        sys.exit("pinned_unwrap_bench: %s" % e)
