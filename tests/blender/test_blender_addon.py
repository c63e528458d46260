"""The texwarp_blender add-on in Blender (headless): installed from its zip, run on bent grids with pinned UVs,
checked against `texwarp run` of the same job (UVs), no flipped face, pins met; compared with Blender's own
pinned unwrap (ANGLE_BASED, CONFORMAL) on the same meshes and pins: flipped faces, pin residuals, L² stretch
(a table on stdout). Environment: TEXWARP_ADDON_ZIP, TEXWARP_PYTHON_PATH, TEXWARP_CLI. Exit status 1 on failure."""

import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import traceback

import bmesh
import bpy

SIZE = 256  # the texture, pixels
FAILURES = []


def check(condition, what):
    print(("ok   " if condition else "FAIL ") + what)
    if not condition:
        FAILURES.append(what)


def install_addon():
    bpy.ops.preferences.addon_install(filepath=os.environ["TEXWARP_ADDON_ZIP"], overwrite=True)
    bpy.ops.preferences.addon_enable(module="texwarp_blender")
    prefs = bpy.context.preferences.addons["texwarp_blender"].preferences
    prefs.module_path = os.environ["TEXWARP_PYTHON_PATH"]  # the module is found through the preferences
    prefs.device = "cpu"


def texture(folder):
    image = bpy.data.images.new("features", SIZE, SIZE)
    image.generated_type = "UV_GRID"
    path = os.path.join(folder, "features.png")
    image.save_render(path, scene=bpy.context.scene)
    return image, path


def bent_grid(name, n, bend, pins):
    """An n×n-quad grid over [-1, 1]², bent into z = bx·x² + by·y² (bend = (bx, by)), UVs of the flat grid;
    `pins` {(i, j): (du, dv)} pins vertex (i, j) at its flat UV moved by (du, dv)."""
    bm = bmesh.new()
    verts = {}
    for j in range(n + 1):
        for i in range(n + 1):
            x, y = -1.0 + 2.0 * i / n, -1.0 + 2.0 * j / n
            verts[i, j] = bm.verts.new((x, y, bend[0] * x * x + bend[1] * y * y))
    for j in range(n):
        for i in range(n):
            bm.faces.new((verts[i, j], verts[i + 1, j], verts[i + 1, j + 1], verts[i, j + 1]))
    uv = bm.loops.layers.uv.new("UVMap")
    pinned = {id(verts[k]): d for k, d in pins.items()}
    for f in bm.faces:
        for loop in f.loops:
            x, y = loop.vert.co.x, loop.vert.co.y
            u, v = (x + 1.0) / 2.0, (y + 1.0) / 2.0
            d = pinned.get(id(loop.vert))
            if d is not None:
                loop[uv].uv = (u + d[0], v + d[1])
                loop[uv].pin_uv = True
            else:
                loop[uv].uv = (u, v)
    mesh = bpy.data.meshes.new(name)
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def edit(obj):
    if bpy.context.object is not None and bpy.context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    for o in bpy.context.scene.objects:
        o.select_set(o == obj)
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    bpy.ops.mesh.select_all(action="SELECT")


def measure(obj):
    """Independent of texwarp: per triangle (Blender's loop triangles) the UV signed area (flipped when < 0, the
    face's own winding), Sander's L² stretch over the UV domain scaled to the surface's area, and the pins' residual
    (texture pixels) between each pinned loop's UV now and where it was pinned (obj["pins"])."""
    bpy.ops.object.mode_set(mode="OBJECT")
    mesh = obj.data
    mesh.calc_loop_triangles()
    uvs = mesh.uv_layers.active.data
    tris = []
    for t in mesh.loop_triangles:
        q = [mesh.vertices[v].co.copy() for v in t.vertices]
        p = [tuple(uvs[l].uv) for l in t.loops]
        area3 = (q[1] - q[0]).cross(q[2] - q[0]).length / 2.0
        area2 = ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1])) / 2.0
        tris.append((q, p, area3, area2))
    scale = math.sqrt(sum(t[2] for t in tris) / sum(abs(t[3]) for t in tris))
    flipped = sum(1 for t in tris if t[3] < 0.0)
    s2 = a3 = 0.0
    for q, p, area3, area2 in tris:
        (s0, t0), (s1, t1), (s2_, t2) = [(scale * u, scale * v) for u, v in p]
        a = 2.0 * area2 * scale * scale
        if a == 0.0:
            continue
        ss = (q[0] * (t1 - t2) + q[1] * (t2 - t0) + q[2] * (t0 - t1)) / a
        st = (q[0] * (s2_ - s1) + q[1] * (s0 - s2_) + q[2] * (s1 - s0)) / a
        s2 += 0.5 * (ss.dot(ss) + st.dot(st)) * area3
        a3 += area3
    residual = 0.0
    for loop_index, (u, v) in json.loads(obj["pins"]).items():
        uv = uvs[int(loop_index)].uv
        residual = max(residual, math.hypot((uv[0] - u) * SIZE, (uv[1] - v) * SIZE))
    return {"flipped": flipped, "faces": len(tris), "l2_stretch": math.sqrt(s2 / a3), "pin_residual_px": residual}


def remember_pins(obj):
    uvs = obj.data.uv_layers.active.data
    obj["pins"] = json.dumps({str(i): list(d.uv) for i, d in enumerate(uvs) if d.pin_uv})


def cli_uvs(obj, image_path, folder):
    """The same job as the add-on sends, run by `texwarp run`: its uvs.json."""
    from texwarp_blender import mesh_job
    edit(obj)
    bm = bmesh.from_edit_mesh(obj.data)
    region = mesh_job.RegionMesh(bm, bm.loops.layers.uv.active)
    job = mesh_job.mesh_job(region, {"path": image_path}, SIZE, SIZE, device="cpu", name="cli")
    bpy.ops.object.mode_set(mode="OBJECT")
    job_file = os.path.join(folder, "job.json")
    with open(job_file, "w") as f:
        json.dump(job, f)
    out = os.path.join(folder, "cli-" + obj.name)
    subprocess.run([os.environ["TEXWARP_CLI"], "run", job_file, "--out", out, "--quiet"], check=True,
                   stdout=subprocess.DEVNULL)
    with open(os.path.join(out, "uvs.json")) as f:
        uvs = json.load(f)
    with open(os.path.join(out, "report.json")) as f:
        return uvs, json.load(f), region, job


SCENES = {
    # name: (quads per side, bend (bx, by), pins {(i, j): (du, dv)})
    "bent sheet, 4 pins": (12, (0.35, 0.0), {(3, 3): (0.02, 0.01), (9, 3): (-0.02, 0.01), (3, 9): (0.01, -0.02),
                                              (9, 9): (-0.01, -0.02)}),
    "dome, 6 pins apart": (16, (0.4, 0.4), {(5, 10): (-0.09, 0.0), (11, 10): (0.09, 0.0), (8, 5): (0.0, 0.06),
                                             (8, 12): (0.0, -0.05), (3, 3): (0.03, 0.03), (13, 3): (-0.03, 0.03)}),
    "saddle, 4 pins": (16, (0.4, -0.4), {(6, 8): (0.08, 0.04), (10, 8): (-0.08, -0.04), (8, 3): (0.0, 0.0),
                                         (8, 13): (0.0, 0.0)}),
    # The two middle pins swapped (each 0.16 across the other): no unwrap without folds meets them on this grid.
    "saddle, 2 of 4 pins crossed": (16, (0.4, -0.4), {(6, 8): (0.16, 0.04), (10, 8): (-0.16, -0.04),
                                                      (8, 3): (0.0, 0.0), (8, 13): (0.0, 0.0)}),
    "bent sheet, 5 pins twisted": (16, (0.8, 0.0), {(4, 4): (0.06, -0.06), (12, 4): (0.06, 0.06),
                                                    (12, 12): (-0.06, 0.06), (4, 12): (-0.06, -0.06), (8, 8): (0.0, 0.0)}),
}


def main():
    folder = tempfile.mkdtemp(prefix="texwarp-blender-test-")
    try:
        install_addon()
        check(hasattr(bpy.types, "UV_OT_texwarp_constrained_unwrap") or "texwarp_constrained_unwrap" in dir(bpy.ops.uv),
              "the add-on registers uv.texwarp_constrained_unwrap")
        image, image_path = texture(folder)
        rows = []
        for scene, (n, bend, pins) in SCENES.items():
            crossed = "crossed" in scene  # pins in the opposite order of their vertices: see the closing note
            objs = {m: bent_grid("%s %s" % (scene, m), n, bend, pins) for m in ("texwarp", "ANGLE_BASED", "CONFORMAL")}
            for obj in objs.values():
                remember_pins(obj)
            expected, report, region, job = cli_uvs(objs["texwarp"], image_path, folder)
            check(len(job["mesh"]["features"]["features"]) == len(pins), "%s: one feature per pinned vertex" % scene)
            edit(objs["texwarp"])
            result = bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name)
            check(result == {"FINISHED"}, "%s: the operator finished (%s)" % (scene, result))
            # The UVs on every loop are the CLI's UVs of its vertex.
            bpy.ops.object.mode_set(mode="OBJECT")
            mesh = objs["texwarp"].data
            by_vertex = {region.mesh_vertex[c]: expected["uv"][i] for i, c in enumerate(expected["vertices"])}
            worst = max(max(abs(d.uv[0] - by_vertex[mesh.loops[k].vertex_index][0]),
                            abs(d.uv[1] - by_vertex[mesh.loops[k].vertex_index][1]))
                        for k, d in enumerate(mesh.uv_layers.active.data))
            check(worst < 1e-6, "%s: UVs = texwarp run's within 1e-6 (max difference %.2e)" % (scene, worst))
            check("texwarp_warped" in mesh.uv_layers, "%s: UV map texwarp_warped added" % scene)
            check(any(i.name.startswith("features.texwarp") for i in bpy.data.images),
                  "%s: the warped image is an image datablock" % scene)
            for method in ("ANGLE_BASED", "CONFORMAL"):
                edit(objs[method])
                bpy.ops.uv.unwrap(method=method, margin=0.0)
            for method, obj in objs.items():
                m = measure(obj)
                rows.append((scene, method, m))
            tw = rows[-3][2]
            # The report's own figures agree with the measurement here (same triangles, same definitions).
            check(tw["flipped"] == report["flipped_triangles"], "%s: flipped faces %d, report %d" % (
                scene, tw["flipped"], report["flipped_triangles"]))
            check(abs(tw["l2_stretch"] - report["l2_stretch"]) < 1e-3 * report["l2_stretch"],
                  "%s: L² stretch %.5f, report %.5f" % (scene, tw["l2_stretch"], report["l2_stretch"]))
            if not crossed:
                check(tw["flipped"] == 0, "%s: texwarp flips no face" % scene)
            check(tw["pin_residual_px"] < 0.05, "%s: texwarp meets the pins (%.4f px)" % (scene, tw["pin_residual_px"]))
        # A region without pins is refused with a message.
        plain = bent_grid("no pins", 4, (0.2, 0.0), {})
        edit(plain)
        try:
            bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name)
            check(False, "no pins: refused")
        except RuntimeError as e:
            check("no pinned UVs" in str(e), "no pins: refused with '%s'" % str(e).strip())
        print()
        print("| mesh, pins | method | faces | flipped faces | max pin residual (px, %d² texture) | L² stretch |" % SIZE)
        print("|---|---|---|---|---|---|")
        for scene, method, m in rows:
            print("| %s | %s | %d | %d | %.4f | %.4f |" % (scene, method, m["faces"], m["flipped"],
                                                         m["pin_residual_px"], m["l2_stretch"]))
    except Exception:
        traceback.print_exc()
        FAILURES.append("exception")
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    print("blender add-on test: %d failure(s)" % len(FAILURES))
    sys.exit(1 if FAILURES else 0)


main()
