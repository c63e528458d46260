"""The texwarp_blender add-on in Blender (headless): installed from its zip, run on bent grids with pinned UVs,
checked against `texwarp run` of the same job (UVs), no flipped face, pins met; compared with Blender's own
pinned unwrap (ANGLE_BASED, CONFORMAL) on the same meshes and pins: flipped faces, pin residuals, L² stretch
(a table on stdout). The add-on also runs on a real texwarpd (preferences' server URL) and with a gradient pin.
Environment: TEXWARP_ADDON_ZIP, TEXWARP_PYTHON_PATH, TEXWARP_CLI, TEXWARPD. Exit status 1 on failure."""

import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
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


def cli_uvs(obj, image_path, folder, refine=False, optimize=True):
    """The same job as the add-on sends, run by `texwarp run`: its uvs.json."""
    from texwarp_blender import mesh_job
    edit(obj)
    bm = bmesh.from_edit_mesh(obj.data)
    region = mesh_job.RegionMesh(bm, bm.loops.layers.uv.active)
    job = mesh_job.mesh_job(region, {"path": image_path}, SIZE, SIZE, device="cpu", name="cli", refine=refine,
                            optimize=optimize)
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
    # Two neighbouring pins swapped (each one quad across the other): the edge between them turns over, which no map
    # of the grid's own faces unfolds (two pins further apart swapped now pass wide of each other and fold nothing).
    "saddle, 2 of 4 pins crossed": (16, (0.4, -0.4), {(8, 8): (0.0625, 0.004), (9, 8): (-0.0625, -0.004),
                                                      (8, 3): (0.0, 0.0), (8, 13): (0.0, 0.0)}),
    "bent sheet, 5 pins twisted": (16, (0.8, 0.0), {(4, 4): (0.06, -0.06), (12, 4): (0.06, 0.06),
                                                    (12, 12): (-0.06, 0.06), (4, 12): (-0.06, -0.06),
                                                    (8, 8): (0.0, 0.0)}),
}


def refined(image, image_path, folder):
    """The crossed saddle with Refine: the job splits the faces the warp would flip; the add-on rebuilds those faces
    in the mesh. Checked independently of the add-on: no flipped loop triangle, pins met (by vertex), every loop's
    UV = `texwarp run`'s for the vertex at the same position (its mesh.obj), the mesh still one disk
    (V − E + F = 1, every edge on one or two faces: no crack)."""
    n, bend, pins = SCENES["saddle, 2 of 4 pins crossed"]
    obj = bent_grid("crossed, refined", n, bend, pins)
    pinned = {}
    for loop in obj.data.loops:
        d = obj.data.uv_layers.active.data[loop.index]
        if d.pin_uv:
            pinned[loop.vertex_index] = tuple(d.uv)
    before = (len(obj.data.vertices), len(obj.data.polygons))
    # The warp's own UVs (optimize off): with it, untangling unfolds this scene's flips on its own faces and
    # refinement adds none.
    uvs, report, _, job = cli_uvs(obj, image_path, folder, refine=True, optimize=False)
    check(job["options"].get("refine") is True, "refine: the job asks for it")
    out = os.path.join(folder, "cli-" + obj.name)
    positions = []
    with open(os.path.join(out, "mesh.obj")) as f:
        for line in f:
            if line.startswith("v "):
                positions.append(tuple(float(x) for x in line.split()[1:4]))
    uv_at = {}
    for i, c in enumerate(uvs["vertices"]):
        uv_at[tuple(round(x, 4) for x in positions[c])] = uvs["uv"][i]
    by_position = [(positions[c], uvs["uv"][i]) for i, c in enumerate(uvs["vertices"])]

    def uv_near(co):
        """The job's UV of the vertex at `co`: by rounded position, else the nearest within 1e-5 (a float32
        coordinate can round to the other side of a 4th decimal than the OBJ's)."""
        key = tuple(round(x, 4) for x in co)
        if key in uv_at:
            return uv_at[key]
        best = min(by_position, key=lambda p: sum((a - b) ** 2 for a, b in zip(p[0], co)))
        return best[1] if sum((a - b) ** 2 for a, b in zip(best[0], co)) < 1e-10 else None
    edit(obj)
    result = bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name, refine=True, optimize=False)
    check(result == {"FINISHED"}, "refine: the operator finished (%s)" % result)
    bpy.ops.object.mode_set(mode="OBJECT")
    mesh = obj.data
    added_faces = len(mesh.polygons) - before[1]
    check(len(mesh.vertices) - before[0] == len(uvs["new_vertices"]["source"]) and added_faces > 0,
          "refine: %d vertices and %d faces added (the job added %d vertices)" % (
              len(mesh.vertices) - before[0], added_faces, len(uvs["new_vertices"]["source"])))
    worst, missing = 0.0, 0
    for k, d in enumerate(mesh.uv_layers.active.data):
        expected = uv_near(tuple(mesh.vertices[mesh.loops[k].vertex_index].co))
        if expected is None:
            missing += 1
            continue
        worst = max(worst, abs(d.uv[0] - expected[0]), abs(d.uv[1] - expected[1]))
    check(missing == 0 and worst < 1e-6, "refine: UVs = texwarp run's by position (max difference %.2e, %d loops "
          "without a match)" % (worst, missing))
    residual = 0.0
    for k, d in enumerate(mesh.uv_layers.active.data):
        target = pinned.get(mesh.loops[k].vertex_index)
        if target is not None:
            residual = max(residual, math.hypot((d.uv[0] - target[0]) * SIZE, (d.uv[1] - target[1]) * SIZE))
    check(residual < 0.05, "refine: pins met (%.4f px)" % residual)
    mesh.calc_loop_triangles()
    uv = mesh.uv_layers.active.data
    flipped = 0
    for t in mesh.loop_triangles:
        p = [uv[l].uv for l in t.loops]
        if (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]) < 0.0:
            flipped += 1
    check(flipped == report["flipped_triangles"], "refine: flipped loop triangles %d, the job's report %d" % (
        flipped, report["flipped_triangles"]))
    check(flipped == 0, "refine: no flipped loop triangle (%d; 2 without refine)" % flipped)
    edge_faces = {}
    for poly in mesh.polygons:
        for e in poly.edge_keys:
            edge_faces[e] = edge_faces.get(e, 0) + 1
    euler = len(mesh.vertices) - len(mesh.edges) + len(mesh.polygons)
    check(euler == 1 and max(edge_faces.values()) <= 2 and len(edge_faces) == len(mesh.edges),
          "refine: one disk, no crack (V - E + F = %d, at most %d faces per edge, %d edges without a face)" % (
              euler, max(edge_faces.values()), len(mesh.edges) - len(edge_faces)))


def start_texwarpd(folder):
    """texwarpd on a free loopback port (--port-file): (process, URL)."""
    port_file = os.path.join(folder, "port")
    proc = subprocess.Popen([os.environ["TEXWARPD"], "--listen", "127.0.0.1:0", "--data-dir",
                             os.path.join(folder, "texwarpd"), "--port-file", port_file, "--device", "cpu"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline and proc.poll() is None:
        port = open(port_file).read().strip() if os.path.exists(port_file) else ""
        if port:
            return proc, "http://127.0.0.1:" + port
        time.sleep(0.05)
    proc.kill()
    raise RuntimeError("texwarpd did not come up")


def loop_uvs(obj):
    bpy.ops.object.mode_set(mode="OBJECT")
    return [tuple(d.uv) for d in obj.data.uv_layers.active.data]


def server_and_gradient(image, image_path, folder):
    """The same mesh and pins on a texwarpd (the preferences' URL: the texture is uploaded) as in Blender's
    process; then a gradient pin (attribute texwarp_gradient) becomes a gradient feature that the job honours."""
    pins = {(5, 10): (-0.04, 0.0), (11, 10): (0.04, 0.0), (8, 5): (0.0, 0.03)}
    local = bent_grid("local", 16, (0.4, 0.4), pins)
    remote = bent_grid("remote", 16, (0.4, 0.4), pins)
    edit(local)
    check(bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name) == {"FINISHED"}, "local run finished")
    prefs = bpy.context.preferences.addons["texwarp_blender"].preferences
    proc, url = start_texwarpd(folder)
    try:
        prefs.server_url = url
        edit(remote)
        check(bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name) == {"FINISHED"},
              "the run on texwarpd finished")
    finally:
        prefs.server_url = ""
        proc.kill()
        proc.wait()
    a, b = loop_uvs(local), loop_uvs(remote)
    worst = max(max(abs(p[0] - q[0]), abs(p[1] - q[1])) for p, q in zip(a, b))
    check(worst < 1e-9, "texwarpd's UVs = the local run's (max difference %.2e)" % worst)
    # From Object Mode: the faces selected in the mesh, the result written into the mesh.
    in_object_mode = bent_grid("object mode", 16, (0.4, 0.4), pins)
    edit(in_object_mode)
    bpy.ops.object.mode_set(mode="OBJECT")
    check(bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name) == {"FINISHED"}, "Object Mode run finished")
    c = loop_uvs(in_object_mode)
    worst = max(max(abs(p[0] - q[0]), abs(p[1] - q[1])) for p, q in zip(a, c))
    check(worst < 1e-9, "Object Mode UVs = Edit Mode's (max difference %.2e)" % worst)

    grad = bent_grid("gradient", 16, (0.4, 0.4), pins)
    attr = grad.data.attributes.new("texwarp_gradient", "FLOAT_VECTOR", "POINT")
    v = 10 * 17 + 5  # vertex (5, 10): the image's x axis along +x at 100 texels per unit
    attr.data[v].vector = (100.0, 0.0, 0.0)
    remember_pins(grad)
    _, report, _, job = cli_uvs(grad, image_path, folder)
    gradient = [f for f in job["mesh"]["features"]["features"] if "target_frame" in f]
    check(len(gradient) == 1 and gradient[0]["target_frame"] == {"direction": [1.0, 0.0, 0.0], "texels_per_unit": 100.0}
          and abs(gradient[0]["source"][0] - (5 / 16 - 0.04) * SIZE) < 1e-4
          and abs(gradient[0]["source"][1] - (1 - 10 / 16) * SIZE) < 1e-4,
          "the gradient pin is a gradient feature: %s" % gradient)
    check(report["warp"]["gradient_features"] == 1, "the job has one gradient feature")
    edit(grad)
    check(bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name) == {"FINISHED"}, "gradient run finished")
    m = measure(grad)
    check(m["flipped"] == 0 and m["pin_residual_px"] < 0.05, "gradient run: %s" % m)
    # Around the gradient pin the texture's x axis runs along +x at about 100 texels per unit (central differences
    # over its neighbours (4, 10) and (6, 10), along the surface).
    mesh = grad.data
    uv_of = {mesh.loops[k].vertex_index: d.uv for k, d in enumerate(mesh.uv_layers.active.data)}
    left, right = v - 1, v + 1
    run = (mesh.vertices[right].co - mesh.vertices[left].co).length
    dx = (uv_of[right][0] - uv_of[left][0]) * SIZE / run
    dy = (uv_of[right][1] - uv_of[left][1]) * SIZE / run
    check(abs(dx - 100.0) < 15.0 and abs(dy) < 15.0,
          "gradient pin: %.1f texels per unit along +x (asked 100), %.1f across" % (dx, dy))


def roles(image):
    """The image's role as a material uses it: colour by default, data when Non-Color, normal behind a Normal Map."""
    from texwarp_blender.operator import image_role
    mat = bpy.data.materials.new("roles")
    mat.use_nodes = True
    tex = mat.node_tree.nodes.new("ShaderNodeTexImage")
    tex.image = image
    image.colorspace_settings.name = "sRGB"
    check(image_role(image, mat) == ("color", "sRGB"), "an sRGB image is colour (%s)" % (image_role(image, mat),))
    image.colorspace_settings.name = "Non-Color"
    check(image_role(image, mat) == ("data", None), "a Non-Color image is data (%s)" % (image_role(image, mat),))
    normal_map = mat.node_tree.nodes.new("ShaderNodeNormalMap")
    mat.node_tree.links.new(tex.outputs["Color"], normal_map.inputs["Color"])
    check(image_role(image, mat) == ("normal", None), "an image behind a Normal Map node is a normal map (%s)" %
          (image_role(image, mat),))
    image.colorspace_settings.name = "sRGB"
    bpy.data.materials.remove(mat)


def material_set(image, folder):
    """Every image texture of the active material warped together ("Every map of the material", on by default):
    the pins' image, a Non-Color data map and a normal map (behind a Normal Map node) come back as
    "<image>.texwarp", each equal pixel for pixel to `texwarp run` of that map alone with its role on the same
    region; an image of another size is left out."""
    from texwarp_blender import mesh_job
    data = bpy.data.images.new("rough.png", SIZE, SIZE)
    data.generated_type = "COLOR_GRID"
    data_path = os.path.join(folder, "rough.png")
    data.save_render(data_path, scene=bpy.context.scene)
    data = bpy.data.images.load(data_path)
    data.colorspace_settings.name = "Non-Color"
    normal = bpy.data.images.new("nrm", SIZE, SIZE)
    normal.generated_color = (0.6, 0.45, 0.9, 1.0)
    normal_path = os.path.join(folder, "nrm.png")
    normal.save_render(normal_path, scene=bpy.context.scene)
    normal = bpy.data.images.load(normal_path)
    normal.colorspace_settings.name = "Non-Color"
    small = bpy.data.images.new("small", SIZE // 2, SIZE // 2)
    obj = bent_grid("material set", 12, (0.3, 0.0), {(3, 3): (0.02, 0.01), (9, 3): (-0.02, 0.01),
                                                     (6, 9): (0.0, -0.02)})
    mat = bpy.data.materials.new("set")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    for img in (image, data, normal, small):
        nodes.new("ShaderNodeTexImage").image = img
    normal_node = nodes.new("ShaderNodeNormalMap")
    tex_of = {n.image.name: n for n in nodes if n.type == "TEX_IMAGE"}
    mat.node_tree.links.new(tex_of[normal.name].outputs["Color"], normal_node.inputs["Color"])
    obj.data.materials.append(mat)
    edit(obj)
    before = set(bpy.data.images.keys())
    result = bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name, refine=False)
    check(result == {"FINISHED"}, "material set: the operator finished (%s)" % result)
    # Blender numbers a name already taken (the scenes above brought in features.texwarp): ".NNN" left out.
    added = sorted(re.sub(r"\.\d{3}$", "", n) for n in set(bpy.data.images.keys()) - before)
    expected = sorted(n + ".texwarp" for n in (image.name, data.name, normal.name))
    check(added == expected, "material set: warped images %s (expected %s; %s left out)" % (added, expected, small.name))
    # Each map alone through `texwarp run`, with the role the add-on gave it: the same pixels.
    edit(obj)
    bm = bmesh.from_edit_mesh(obj.data)
    region = mesh_job.RegionMesh(bm, bm.loops.layers.uv.active)
    bpy.ops.object.mode_set(mode="OBJECT")
    for img, path, role in ((data, data_path, "data"), (normal, normal_path, "normal")):
        job = mesh_job.mesh_job(region, {"path": path}, SIZE, SIZE, device="cpu", name="alone", refine=False,
                                role=role)
        job_file = os.path.join(folder, "alone.json")
        with open(job_file, "w") as f:
            json.dump(job, f)
        out = os.path.join(folder, "alone-" + role)
        subprocess.run([os.environ["TEXWARP_CLI"], "run", job_file, "--out", out, "--quiet"], check=True,
                       stdout=subprocess.DEVNULL)
        alone = bpy.data.images.load(os.path.join(out, "warped.png"), check_existing=False)
        alone.colorspace_settings.name = "Non-Color"
        warped = next(i for i in bpy.data.images if i.name not in before and i.name.startswith(img.name + ".texwarp"))
        check(warped.colorspace_settings.name == "Non-Color", "material set: %s keeps its colour space (%s)" % (
            role, warped.colorspace_settings.name))
        a, b = list(alone.pixels), list(warped.pixels)
        worst = max(abs(x - y) for x, y in zip(a, b)) if len(a) == len(b) else float("inf")
        check(worst == 0.0, "material set: the warped %s map = texwarp run's of it alone (max difference %g, %d and "
              "%d values)" % (role, worst, len(a), len(b)))


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
            # As cli_uvs runs it: the input's faces kept (refined(), below, splits them).
            result = bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name, refine=False)
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
        roles(image)
        material_set(image, folder)
        server_and_gradient(image, image_path, folder)
        refined(image, image_path, folder)
        # A region without pins is refused with a message.
        plain = bent_grid("no pins", 4, (0.2, 0.0), {})
        edit(plain)
        try:
            bpy.ops.uv.texwarp_constrained_unwrap(image_name=image.name)
            check(False, "no pins: refused")
        except RuntimeError as e:
            check("no pinned UVs" in str(e), "no pins: refused with '%s'" % str(e).strip())
        print()
        print("| mesh, pins | method | faces | flipped faces | max pin residual (px, %d² texture) | L² stretch |"
              % SIZE)
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


if __name__ == "__main__":
    main()
