"""Blender side of the pinned unwrap benchmark (bench/pinned_unwrap_bench.py runs it in `blender -b`; issue 28).

Per case: a mesh of its own (an open disk), unwrapped by Blender (CONFORMAL or ANGLE_BASED), a seeded pin set
(families random, crossing, cluster, boundary; moves up to ±move UV), then on the same pins (a) Blender's own pinned
unwrap and (b) texwarp through the add-on's own code path (mesh_job.RegionMesh → mesh_job.mesh_job → the operator's
_JobRun.run(), i.e. texwarp.submit_local → mesh_job.apply_uvs / apply_refined_uvs), the job's options updated with
the spec's texwarp_options. Each method's result is measured on the object's final UV layer, independently of
texwarp: flips (triangles of the minority orientation), pin residuals (px), triangles, Sander's L² stretch (the
formula of core/mesh/src/uv_metrics.cpp). One JSON line per case is appended to the output file.

Usage: blender -b --factory-startup --python-exit-code 1 --python pinned_unwrap_blender.py -- SPEC.json OUT.jsonl
SPEC.json (written by the driver): {"addon_path", "texwarp_python_path", "texture_px", "pins", "texwarp_options",
"start", "cases": [{"index", "mesh", "method", "family", "move", "seed"}, ...]}.
"""

import json
import math
import os
import random
import shutil
import sys
import tempfile
import time
import traceback

import bmesh
import bpy

# Below this share of its longest squared edge (or of the mean |area|), a UV triangle is degenerate: as
# kDegenerateUvFraction in core/mesh/include/texwarp/mesh/uv_metrics.hpp.
DEGENERATE_UV_FRACTION = 1e-12
PIN_EXACT_PX = 0.05  # a pin is met when its every loop is within this many pixels of the pinned UV


# --- meshes: open disks, made with bmesh ---------------------------------------------------------------------------

def grid_mesh(bm):
    """A bent 30×30 quad grid over [-1, 1]², z = 0.5·x² + 0.2·y² (1 800 triangles)."""
    n = 30
    verts = {}
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = -1.0 + 2.0 * i / n, -1.0 + 2.0 * j / n
            verts[i, j] = bm.verts.new((x, y, 0.5 * x * x + 0.2 * y * y))
    for j in range(n):
        for i in range(n):
            bm.faces.new((verts[i, j], verts[i + 1, j], verts[i + 1, j + 1], verts[i, j + 1]))


def cylinder_mesh(bm):
    """A 200° patch of a cylinder (radius 1, height 2.4), 36 × 20 quads (1 440 triangles)."""
    nu, nv = 36, 20
    verts = {}
    for j in range(nv + 1):
        for i in range(nu + 1):
            a = math.radians(-100.0 + 200.0 * i / nu)
            verts[i, j] = bm.verts.new((math.sin(a), -math.cos(a), -1.2 + 2.4 * j / nv))
    for j in range(nv):
        for i in range(nu):
            bm.faces.new((verts[i, j], verts[i + 1, j], verts[i + 1, j + 1], verts[i, j + 1]))


def cap_mesh(bm):
    """A hemisphere (radius 1): the upper half of a UV sphere of 40 segments and 32 rings, a triangle fan at the pole
    (1 240 triangles)."""
    bmesh.ops.create_uvsphere(bm, u_segments=40, v_segments=32, radius=1.0)
    bmesh.ops.delete(bm, geom=[v for v in bm.verts if v.co.z < -1e-6], context="VERTS")


MESHES = {"grid": grid_mesh, "cylinder": cylinder_mesh, "cap": cap_mesh}


def make_object(kind, name):
    if kind not in MESHES:
        raise ValueError("unknown mesh '%s' (known: %s)" % (kind, ", ".join(MESHES)))
    bm = bmesh.new()
    MESHES[kind](bm)
    # The faces in one order from run to run: bmesh.ops.delete (the cap) leaves them in an order that varies between
    # Blender runs, and a job's result may depend on the order its faces come in (case 58 was flip-free in 2 of 3
    # runs). Sorted by their vertices' indices, which do not vary.
    bm.verts.index_update()
    bm.faces.index_update()
    order = sorted(bm.faces, key=lambda f: sorted(v.index for v in f.verts))
    rank = {f.index: r for r, f in enumerate(order)}
    bm.faces.sort(key=lambda f: rank[f.index])
    bm.loops.layers.uv.new("UVMap")
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def copy_object(obj, name):
    twin = bpy.data.objects.new(name, obj.data.copy())
    bpy.context.scene.collection.objects.link(twin)
    return twin


def remove_object(obj):
    mesh = obj.data
    bpy.data.objects.remove(obj, do_unlink=True)
    bpy.data.meshes.remove(mesh)


def edit(obj):
    """obj active, alone selected, in Edit Mode with every face selected."""
    object_mode()
    for o in bpy.context.scene.objects:
        o.select_set(o == obj)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")


def object_mode():
    if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")


# --- the starting unwrap and the pin sets -------------------------------------------------------------------------

def initial_unwrap(obj, method):
    """Blender's unwrap without pins, then the island scaled uniformly into [0.1, 0.9]² (centred), so that the pins'
    moves mostly stay on the texture. Returns {vertex: (u, v)}."""
    edit(obj)
    bpy.ops.uv.unwrap(method=method, margin=0.0)
    object_mode()
    mesh = obj.data
    uvs = mesh.uv_layers.active.data
    lo_u = min(d.uv[0] for d in uvs)
    hi_u = max(d.uv[0] for d in uvs)
    lo_v = min(d.uv[1] for d in uvs)
    hi_v = max(d.uv[1] for d in uvs)
    scale = 0.8 / max(hi_u - lo_u, hi_v - lo_v)
    cu, cv = (lo_u + hi_u) / 2.0, (lo_v + hi_v) / 2.0
    at = {}
    for loop in mesh.loops:
        d = uvs[loop.index]
        d.uv = (0.5 + (d.uv[0] - cu) * scale, 0.5 + (d.uv[1] - cv) * scale)
        at.setdefault(loop.vertex_index, (d.uv[0], d.uv[1]))
    return at


def boundary_distance(obj):
    """{vertex: edges to the nearest boundary vertex} (breadth first from the boundary)."""
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    dist = {v.index: 0 for v in bm.verts if v.is_boundary}
    front = list(dist)
    while front:
        nxt = []
        for i in front:
            for e in bm.verts[i].link_edges:
                j = e.other_vert(bm.verts[i]).index
                if j not in dist:
                    dist[j] = dist[i] + 1
                    nxt.append(j)
        front = nxt
    bm.free()
    return dist


def _spread(rng, candidates, uv, k, gap, taken=()):
    """Up to k vertices of `candidates` in random order, each at least `gap` (UV) from the others and from `taken`;
    the gap shrinks until k are found."""
    chosen = []
    while gap > 1e-4:
        order = list(candidates)
        rng.shuffle(order)
        chosen = []
        for v in order:
            if all(math.dist(uv[v], uv[w]) >= gap for w in chosen + list(taken)):
                chosen.append(v)
                if len(chosen) == k:
                    return chosen
        gap *= 0.8
    raise ValueError("only %d of %d pins could be placed" % (len(chosen), k))


def _clamped(p):
    return (min(0.99, max(0.01, p[0])), min(0.99, max(0.01, p[1])))


def _jitter(rng, m):
    return (rng.uniform(-m, m), rng.uniform(-m, m))


def pin_set(rng, family, move, k, uv, dist):
    """{vertex: pinned UV} of one family, every pinned UV in [0.01, 0.99]² and at least 2 texels (512²) from the
    others: random (k interior vertices spread out, each moved by up to ±move in u and v), crossing (k/3 pairs of
    vertices about 0.8·move apart that swap places, ±0.15·move, the rest moved as random), cluster (the k vertices
    nearest a random interior vertex, moved together by up to ±move, each by up to ±move/4 more), boundary (k
    vertices on the boundary or one edge in, moved as random)."""
    interior = [v for v, d in dist.items() if d >= 2]
    pins = {}
    if family == "random":
        for v in _spread(rng, interior, uv, k, 0.08):
            pins[v] = (uv[v], _jitter(rng, move))
    elif family == "boundary":
        near = [v for v, d in dist.items() if d <= 1]
        for v in _spread(rng, near, uv, k, 0.08):
            pins[v] = (uv[v], _jitter(rng, move))
    elif family == "crossing":
        pairs = k // 3
        firsts = _spread(rng, interior, uv, pairs, max(0.12, 2.0 * move))
        used = list(firsts)
        for a in firsts:
            others = [b for b in interior if b not in used
                      and all(math.dist(uv[b], uv[w]) >= 0.03 for w in used if w != a)]
            b = min(others, key=lambda b: abs(math.dist(uv[a], uv[b]) - 0.8 * move))
            used.append(b)
            pins[a] = (uv[b], _jitter(rng, 0.15 * move))
            pins[b] = (uv[a], _jitter(rng, 0.15 * move))
        for v in _spread(rng, interior, uv, k - 2 * pairs, 0.08, taken=used):
            pins[v] = (uv[v], _jitter(rng, move))
    elif family == "cluster":
        deep = [v for v, d in dist.items() if d >= 3]
        centre = deep[rng.randrange(len(deep))]
        nearest = sorted(interior, key=lambda v: math.dist(uv[v], uv[centre]))[:k]
        shift = _jitter(rng, move)
        for v in nearest:
            j = _jitter(rng, move / 4.0)
            pins[v] = (uv[v], (shift[0] + j[0], shift[1] + j[1]))
    else:
        raise ValueError("unknown pin family '%s' (random, crossing, cluster, boundary)" % family)
    # Place them, moving again (up to 100 times) a pin that lands within 2 texels of another.
    placed = {}
    for v, (base, d) in pins.items():
        p = _clamped((base[0] + d[0], base[1] + d[1]))
        tries = 0
        while any(math.dist(p, q) < 2.0 / 512.0 for q in placed.values()):
            tries += 1
            if tries > 100:
                raise ValueError("pin of vertex %d: no place 2 texels from the others" % v)
            j = _jitter(rng, 4.0 / 512.0)
            p = _clamped((base[0] + d[0] + j[0], base[1] + d[1] + j[1]))
        placed[v] = p
    return placed


def set_pins(obj, pins):
    """Every loop of a pinned vertex: its pinned UV, pin_uv on; other loops unpinned."""
    object_mode()
    mesh = obj.data
    uvs = mesh.uv_layers.active.data
    for loop in mesh.loops:
        p = pins.get(loop.vertex_index)
        uvs[loop.index].pin_uv = p is not None
        if p is not None:
            uvs[loop.index].uv = p


# --- measurement: on the object's final UV layer, independent of texwarp ------------------------------------------

def measure(obj, pins, texture_px):
    """Flips (loop triangles of the minority orientation), triangles with negative UV area, degenerate ones, Sander's
    L² stretch (area normalised; uv_metrics.cpp's formula and degeneracy rule), the worst pin residual (px) over every
    loop of a pinned vertex, faces and loop triangles."""
    object_mode()
    mesh = obj.data
    mesh.calc_loop_triangles()
    uvs = mesh.uv_layers.active.data
    co = [v.co.copy() for v in mesh.vertices]
    tris = []
    for t in mesh.loop_triangles:
        q = [co[i] for i in t.vertices]
        p = [tuple(uvs[i].uv) for i in t.loops]
        area3 = (q[1] - q[0]).cross(q[2] - q[0]).length / 2.0
        area2 = ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])) / 2.0
        longest = max((p[1][0] - p[0][0]) ** 2 + (p[1][1] - p[0][1]) ** 2,
                      (p[2][0] - p[1][0]) ** 2 + (p[2][1] - p[1][1]) ** 2,
                      (p[0][0] - p[2][0]) ** 2 + (p[0][1] - p[2][1]) ** 2)
        degenerate = area2 == 0.0 or abs(2.0 * area2) <= DEGENERATE_UV_FRACTION * longest
        tris.append([q, p, area3, area2, degenerate])
    mean_abs = sum(abs(t[3]) for t in tris) / max(1, len(tris))
    for t in tris:
        if abs(t[3]) <= DEGENERATE_UV_FRACTION * mean_abs:
            t[4] = True
    kept = [t for t in tris if not t[4]]
    uv_area = sum(abs(t[3]) for t in kept)
    surface = sum(t[2] for t in kept)
    scale = math.sqrt(surface / uv_area) if uv_area > 0.0 else 1.0
    stretch2 = 0.0
    for q, p, area3, area2, _ in kept:
        (s0, t0), (s1, t1), (s2, t2) = [(scale * u, scale * v) for u, v in p]
        a2 = 2.0 * area2 * scale * scale
        ss = (q[0] * (t1 - t2) + q[1] * (t2 - t0) + q[2] * (t0 - t1)) / a2
        st = (q[0] * (s2 - s1) + q[1] * (s0 - s2) + q[2] * (s1 - s0)) / a2
        stretch2 += 0.5 * (ss.dot(ss) + st.dot(st)) * area3
    positive = sum(1 for t in kept if t[3] > 0.0)
    negative = len(kept) - positive
    residual = 0.0
    for loop in mesh.loops:
        p = pins.get(loop.vertex_index)
        if p is not None:
            uv = uvs[loop.index].uv
            residual = max(residual, math.hypot((uv[0] - p[0]) * texture_px, (uv[1] - p[1]) * texture_px))
    return {"flips": min(positive, negative), "negative": negative, "degenerate": len(tris) - len(kept),
            "triangles": len(tris), "faces": len(mesh.polygons), "vertices": len(mesh.vertices),
            "l2_stretch": math.sqrt(stretch2 / surface) if surface > 0.0 else None, "pin_residual_px": residual,
            "pins_exact": residual <= PIN_EXACT_PX}


# --- the two methods ----------------------------------------------------------------------------------------------

def blender_pinned_unwrap(obj, method):
    """Blender's own unwrap with the pinned loops held (pin_uv): seconds."""
    edit(obj)
    start = time.perf_counter()
    bpy.ops.uv.unwrap(method=method, margin=0.0)
    seconds = time.perf_counter() - start
    object_mode()
    return seconds


class Texwarp:
    """texwarp through the add-on's code path, as its operator runs from a script (execute): RegionMesh of the
    selected faces, mesh_job(), _JobRun.run() (texwarp.submit_local without a server), then apply_uvs or
    apply_refined_uvs on the Edit Mode BMesh; the job's options updated with `options`."""

    def __init__(self, spec, image, image_file):
        sys.path.insert(0, spec["texwarp_python_path"])
        sys.path.insert(0, spec["addon_path"])
        import texwarp
        from texwarp_blender import mesh_job, operator
        self.texwarp, self.mesh_job, self.operator = texwarp, mesh_job, operator
        self.options = dict(spec["texwarp_options"])
        self.image, self.image_file = image, image_file
        self.role, self.color_space = operator.image_role(image, None)

    def make_job(self, region, name):
        width, height = self.image.size
        mesh_job, options = self.mesh_job, self.options

        def make(sources):
            job = mesh_job.mesh_job(region, sources[0], width, height, name=name, role=self.role,
                                    color_space=self.color_space)
            if options:
                job["options"] = dict(job.get("options", {}), **options)
            if os.environ.get("TEXWARP_BENCH_JOBS"):  # each case's job as the add-on made it, to run it again alone
                with open(os.path.join(os.environ["TEXWARP_BENCH_JOBS"], name + ".json"), "w") as f:
                    json.dump(job, f)
            return job
        return make

    def run(self, obj, name):
        """(seconds, the job's report or None, message or None, refined)."""
        mesh_job = self.mesh_job
        scratch = tempfile.mkdtemp(prefix="texwarp-bench-")
        start = time.perf_counter()
        try:
            edit(obj)
            bm = bmesh.from_edit_mesh(obj.data)
            region = mesh_job.RegionMesh(bm, bm.loops.layers.uv.active)
            run = self.operator._JobRun(self.texwarp, "", scratch, [self.image_file], self.make_job(region, name))
            run.run()
            if run.message is not None:
                return time.perf_counter() - start, None, run.message, False
            bm = bmesh.from_edit_mesh(obj.data)
            uv_layer = bm.loops.layers.uv.active
            try:
                if run.triangles is None:
                    mesh_job.apply_uvs(bm, region, run.uvs, uv_layer)
                else:
                    mesh_job.apply_refined_uvs(bm, region, run.uvs, run.triangles, uv_layer)
            except ValueError as e:
                return time.perf_counter() - start, run.result["report"], "applying: %s" % e, False
            bmesh.update_edit_mesh(obj.data, loop_triangles=True, destructive=run.triangles is not None)
            object_mode()
            return time.perf_counter() - start, run.result["report"], None, run.triangles is not None
        finally:
            shutil.rmtree(scratch, ignore_errors=True)


def texture(folder, size):
    image = bpy.data.images.new("bench-texture", size, size)
    image.generated_type = "UV_GRID"
    path = os.path.join(folder, "texture.png")
    image.save_render(path, scene=bpy.context.scene)
    return image, path


def report_summary(report):
    """The figures of a mesh job's report the benchmark keeps."""
    if report is None:
        return None
    keep = {k: report.get(k) for k in ("l2_stretch", "l2_shear", "linf_stretch", "flipped_triangles",
                                       "degenerate_triangles", "max_residual_px")}
    keep["refinement"] = report.get("refinement")
    keep["untangling"] = report.get("untangling")
    keep["optimization"] = {k: v for k, v in (report.get("optimization") or {}).items() if k != "before"} or None
    keep["seconds"] = report.get("seconds")
    keep["embedding"] = report.get("embedding")
    return keep


def run_case(case, spec, tw, out):
    k, px = spec["pins"], spec["texture_px"]
    rng = random.Random("pinned-unwrap-%s" % case["seed"])
    base = make_object(case["mesh"], "case%d" % case["index"])
    row = dict(case)
    try:
        uv = initial_unwrap(base, case["method"])
        pins = pin_set(rng, case["family"], case["move"], k, uv, boundary_distance(base))
        row["pins"] = [[v, list(uv[v]), list(p)] for v, p in sorted(pins.items())]
        row["pin_move_px"] = max(math.dist(uv[v], p) for v, p in pins.items()) * px
        before = measure(base, {}, px)
        row["triangles_before"] = before["triangles"]
        row["faces_before"] = before["faces"]
        set_pins(base, pins)
        ours = copy_object(base, "case%d blender" % case["index"])
        theirs = copy_object(base, "case%d texwarp" % case["index"])
        seconds = blender_pinned_unwrap(ours, case["method"])
        row["blender"] = dict(measure(ours, pins, px), seconds=seconds)
        seconds, report, message, refined = tw.run(theirs, "bench case %d" % case["index"])
        result = {"seconds": seconds, "error": message, "refined": refined, "report": report_summary(report)}
        if message is None:
            result.update(measure(theirs, pins, px))
        row["texwarp"] = result
        for o in (ours, theirs):
            remove_object(o)
    except Exception as e:  # a benchmark's own failure on one case: said in its row, the others go on
        row["bench_error"] = "%s: %s" % (type(e).__name__, e)
        traceback.print_exc()
    finally:
        remove_object(base)
    out.write(json.dumps(row) + "\n")
    out.flush()
    return row


def main():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if len(argv) != 2:
        raise SystemExit("usage: blender -b --python pinned_unwrap_blender.py -- SPEC.json OUT.jsonl")
    with open(argv[0]) as f:
        spec = json.load(f)
    folder = tempfile.mkdtemp(prefix="texwarp-bench-texture-")
    try:
        image, image_file = texture(folder, spec["texture_px"])
        tw = Texwarp(spec, image, image_file)
        if spec.get("warm_up", True):
            # Not timed: the first job compiles (or loads) the OpenCL kernels.
            warm = make_object("grid", "warm-up")
            uv = initial_unwrap(warm, "CONFORMAL")
            set_pins(warm, pin_set(random.Random(0), "random", 0.02, 4, uv, boundary_distance(warm)))
            seconds, _, message, _ = tw.run(warm, "bench warm-up")
            print("warm-up job: %.2f s%s" % (seconds, "" if message is None else " (%s)" % message), flush=True)
            remove_object(warm)
        with open(argv[1], "a") as out:
            for case in spec["cases"][spec.get("start", 0):]:
                row = run_case(case, spec, tw, out)
                b, t = row.get("blender") or {}, row.get("texwarp") or {}
                print("case %d %s %s %s ±%.2f: blender %s flips %.2fs, texwarp %s flips %.2fs%s" % (
                    case["index"], case["mesh"], case["method"], case["family"], case["move"], b.get("flips"),
                    b.get("seconds", 0.0), t.get("flips"), t.get("seconds", 0.0),
                    "" if not t.get("error") else " (%s)" % t["error"]), flush=True)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


if __name__ == "__main__":
    main()
