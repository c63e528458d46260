#!/usr/bin/python3
"""Refined glTF outputs checked by the tool glTF users run: the Khronos glTF-Validator (npm gltf-validator, pinned in
gltf-tools/package-lock.json, `npm ci` into BUILD_DIR/npm-gltf-tools once per lock).

examples/mesh/spot.obj is written as a .glb and a .gltf (vertex and face order kept, so the example's region and
vertex features apply) with the attributes a DCC exports: NORMAL, TANGENT, TEXCOORD_0/1, COLOR_0 (normalized bytes),
JOINTS_0 (unsigned shorts) and WEIGHTS_0. `texwarp map-mesh` runs on it with the example's features moved by up to
±60 px (a fixed draw whose warp flips UV triangles, so that refinement splits edges), writing the same container.
Checked: the validator finds no error in the inputs or the outputs; the report says edges were split and no triangle
flips; read back here, every region triangle is front-facing in its float32 TEXCOORD_0 (clockwise with glTF's v
down), NORMAL has unit length, TANGENT's w is ±1 and JOINTS_0 stays unsigned shorts.
Exit 77 (skipped) without Node.js and npm. Usage: validate_gltf_outputs.py SOURCE_DIR BUILD_DIR TEXWARP
"""
import base64
import json
import os
import random
import shutil
import struct
import subprocess
import sys
import tempfile

import numpy as np

GLB_MAGIC, JSON_CHUNK, BIN_CHUNK = 0x46546C67, 0x4E4F534A, 0x004E4942
FLOAT, UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT = 5126, 5121, 5123, 5125
COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}
DTYPES = {FLOAT: np.float32, UNSIGNED_BYTE: np.uint8, UNSIGNED_SHORT: np.uint16, UNSIGNED_INT: np.uint32}


def fail(message):
    print("FAIL: " + message, file=sys.stderr)
    sys.exit(1)


def install_validator(source_dir, build_dir):
    if shutil.which("node") is None or shutil.which("npm") is None:
        print("Node.js and npm are not installed: skipped")
        sys.exit(77)
    manifest = os.path.join(source_dir, "tests", "mesh", "gltf-tools")
    tools = os.path.join(os.path.abspath(build_dir), "npm-gltf-tools")
    lock = os.path.join(manifest, "package-lock.json")
    stamp = os.path.join(tools, "installed-package-lock.json")
    module = os.path.join(tools, "node_modules", "gltf-validator")
    if not (os.path.exists(stamp) and open(stamp, "rb").read() == open(lock, "rb").read() and os.path.isdir(module)):
        shutil.rmtree(tools, ignore_errors=True)
        os.makedirs(tools)
        for name in ("package.json", "package-lock.json"):
            shutil.copy(os.path.join(manifest, name), tools)
        r = subprocess.run(["npm", "ci", "--prefix", tools, "--no-audit", "--no-fund", "--fetch-retries=1",
                            "--fetch-timeout=60000"], capture_output=True, text=True)
        if r.returncode != 0:
            print(r.stdout[-2000:] + r.stderr[-2000:], file=sys.stderr)
            fail("could not install gltf-validator from the npm registry: is it reachable from here?")
        shutil.copy(lock, stamp)
    return module


def validate(module, path):
    """The validator's report on one file: (errors, the error messages)."""
    script = ("const v = require(process.argv[1]); const fs = require('fs');"
              "v.validateBytes(new Uint8Array(fs.readFileSync(process.argv[2])))"
              ".then(r => console.log(JSON.stringify(r.issues)))"
              ".catch(e => { console.error(String(e)); process.exit(1); });")
    r = subprocess.run(["node", "-e", script, module, path], capture_output=True, text=True)
    if r.returncode != 0:
        fail(f"gltf-validator could not run on {path}: {r.stderr.strip()}")
    issues = json.loads(r.stdout)
    return issues["numErrors"], [m for m in issues["messages"] if m["severity"] == 0]


def read_obj(path):
    vertices, faces = [], []
    for line in open(path):
        if line.startswith("v "):
            vertices.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            corners = [int(t.split("/")[0]) - 1 for t in line.split()[1:]]
            faces += [[corners[0], corners[k], corners[k + 1]] for k in range(1, len(corners) - 1)]
    return np.array(vertices, np.float32), np.array(faces, np.uint32)


def gltf_document(vertices, faces):
    """The mesh as a glTF document and its one buffer, with the attributes a DCC exports."""
    n = len(vertices)
    normals = np.zeros((n, 3))
    doubled = np.cross(vertices[faces[:, 1]] - vertices[faces[:, 0]], vertices[faces[:, 2]] - vertices[faces[:, 0]])
    for k in range(3):
        np.add.at(normals, faces[:, k], doubled)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    tangents = np.cross(normals, [0.0, 0.0, 1.0])
    tangents /= np.maximum(np.linalg.norm(tangents, axis=1, keepdims=True), 1e-9)
    tangents = np.hstack([tangents, np.where(vertices[:, :1] > 0, 1.0, -1.0)])
    uv = vertices[:, :2] * 0.5 + 0.5
    colour = np.clip((vertices[:, [0, 1, 2, 0]] * 0.5 + 0.5) * 255, 0, 255)
    joints = np.arange(n)[:, None] % 7 + np.arange(4)[None, :]
    weights = np.tile([0.7, 0.2, 0.1, 0.0], (n, 1))
    attributes = [("POSITION", vertices, FLOAT, "VEC3", False), ("NORMAL", normals, FLOAT, "VEC3", False),
                  ("TANGENT", tangents, FLOAT, "VEC4", False), ("TEXCOORD_0", uv, FLOAT, "VEC2", False),
                  ("TEXCOORD_1", 0.5 * uv, FLOAT, "VEC2", False), ("COLOR_0", colour, UNSIGNED_BYTE, "VEC4", True),
                  ("JOINTS_0", joints, UNSIGNED_SHORT, "VEC4", False), ("WEIGHTS_0", weights, FLOAT, "VEC4", False),
                  (None, faces.reshape(-1), UNSIGNED_INT, "SCALAR", False)]
    data, views, accessors = b"", [], []
    for name, values, component_type, element, normalized in attributes:
        data += b"\0" * (-len(data) % 4)
        block = np.ascontiguousarray(values, DTYPES[component_type]).tobytes()
        views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(block),
                      "target": 34963 if name is None else 34962})
        data += block
        accessor = {"bufferView": len(views) - 1, "componentType": component_type, "count": len(values),
                    "type": element}
        if normalized:
            accessor["normalized"] = True
        if name == "POSITION":
            accessor["min"] = values.min(0).tolist()
            accessor["max"] = values.max(0).tolist()
        accessors.append(accessor)
    data += b"\0" * (-len(data) % 4)
    primitive = {"attributes": {a[0]: i for i, a in enumerate(attributes) if a[0]}, "indices": len(attributes) - 1,
                 "mode": 4}
    document = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
                "nodes": [{"mesh": 0, "skin": 0, "name": "spot"}, {"name": "root"}],
                "skins": [{"joints": [1] + list(range(2, 12))}],
                "meshes": [{"name": "spot", "primitives": [primitive]}],
                "buffers": [{"byteLength": len(data)}], "bufferViews": views, "accessors": accessors}
    document["nodes"] += [{"name": f"bone {k}"} for k in range(10)]
    document["nodes"][1]["children"] = list(range(2, 12))
    return document, data


def write_gltf(path, document, data):
    if path.endswith(".glb"):
        text = json.dumps(document).encode()
        text += b" " * (-len(text) % 4)
        total = 12 + 8 + len(text) + 8 + len(data)
        with open(path, "wb") as f:
            f.write(struct.pack("<III", GLB_MAGIC, 2, total) + struct.pack("<II", len(text), JSON_CHUNK) + text +
                    struct.pack("<II", len(data), BIN_CHUNK) + data)
    else:
        document = dict(document)
        document["buffers"] = [{"byteLength": len(data),
                                "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}]
        with open(path, "w") as f:
            json.dump(document, f)


def read_gltf(path):
    """(document, buffers' bytes) of a .glb or a .gltf with data: URIs."""
    raw = open(path, "rb").read()
    if path.endswith(".glb"):
        length = struct.unpack_from("<I", raw, 12)[0]
        document = json.loads(raw[20:20 + length])
        chunk = 20 + length
        binary = raw[chunk + 8:chunk + 8 + struct.unpack_from("<I", raw, chunk)[0]] if chunk < len(raw) else b""
    else:
        document, binary = json.loads(raw), b""
    buffers = [base64.b64decode(b["uri"].split(",", 1)[1]) if "uri" in b else binary for b in document["buffers"]]
    return document, buffers


def accessor(document, buffers, index):
    a = document["accessors"][index]
    view = document["bufferViews"][a["bufferView"]]
    dtype = np.dtype(DTYPES[a["componentType"]])
    components = COMPONENTS[a["type"]]
    element = dtype.itemsize * components
    stride = view.get("byteStride", element)
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    raw = buffers[view["buffer"]]
    rows = [np.frombuffer(raw, dtype, components, start + i * stride) for i in range(a["count"])]
    return np.array(rows), a["componentType"]


def main():
    source_dir, build_dir, texwarp = sys.argv[1:4]
    module = install_validator(source_dir, build_dir)
    examples = os.path.join(source_dir, "examples")
    vertices, faces = read_obj(os.path.join(examples, "mesh", "spot.obj"))
    document, data = gltf_document(vertices, faces)
    features = json.load(open(os.path.join(examples, "mesh", "spot_head_features.json")))
    rng = random.Random(1)
    for f in features["features"]:
        f["source"] = [f["source"][0] + rng.uniform(-60, 60), f["source"][1] + rng.uniform(-60, 60)]
    with tempfile.TemporaryDirectory(prefix="texwarp-gltf.") as work:
        with open(os.path.join(work, "features.json"), "w") as f:
            json.dump(features, f)
        for ext in (".glb", ".gltf"):
            source = os.path.join(work, "spot" + ext)
            write_gltf(source, document, data)
            errors, messages = validate(module, source)
            if errors:
                fail(f"the test's own input {source} has {errors} validator errors: {messages[:3]}")
            out = os.path.join(work, "textured" + ext)
            report_path = os.path.join(work, "report.json")
            r = subprocess.run([texwarp, "map-mesh", "--backend", "cpu", "--mesh", source, "--texture",
                                os.path.join(examples, "astronaut.png"), "--features",
                                os.path.join(work, "features.json"), "--region",
                                os.path.join(examples, "mesh", "spot_head_region.json"), "--out-gltf", out,
                                "--report", report_path, "--per-triangle"], capture_output=True, text=True)
            if r.returncode != 0:
                fail(f"map-mesh on {source} exited {r.returncode}: {r.stderr.strip()}")
            report = json.load(open(report_path))
            refinement = report["refinement"]
            if refinement["split_edges"] == 0 or report["flipped_triangles"] != 0:
                fail(f"{ext}: expected a refinement that splits edges and leaves no flip, the report says "
                     f"{refinement['split_edges']} edges split, {report['flipped_triangles']} flipped")
            errors, messages = validate(module, out)
            if errors:
                fail(f"{ext}: gltf-validator finds {errors} errors in the refined output: {messages[:5]}")
            out_doc, buffers = read_gltf(out)
            primitive = out_doc["meshes"][0]["primitives"][0]
            indices = accessor(out_doc, buffers, primitive["indices"])[0].reshape(-1, 3)
            if len(indices) != refinement["output_faces"]:
                fail(f"{ext}: {len(indices)} triangles written, the report says {refinement['output_faces']}")
            uv = accessor(out_doc, buffers, primitive["attributes"]["TEXCOORD_0"])[0].astype(np.float64)
            region = [t["face"] for t in report["triangles"]]
            a, b, c = uv[indices[region, 0]], uv[indices[region, 1]], uv[indices[region, 2]]
            cross = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
            if (cross >= 0).any():
                fail(f"{ext}: {(cross >= 0).sum()} of {len(region)} region triangles are not front-facing as written")
            normals = accessor(out_doc, buffers, primitive["attributes"]["NORMAL"])[0]
            length = np.linalg.norm(normals.astype(np.float64), axis=1)
            tangents = accessor(out_doc, buffers, primitive["attributes"]["TANGENT"])[0]
            joints, joint_type = accessor(out_doc, buffers, primitive["attributes"]["JOINTS_0"])
            if np.abs(length - 1).max() > 1e-6 or not set(tangents[:, 3].tolist()) <= {-1.0, 1.0} or \
                    joint_type != UNSIGNED_SHORT or joints.max() > 9:
                fail(f"{ext}: attributes of the new vertices: |NORMAL| {length.min()}–{length.max()}, TANGENT w "
                     f"{sorted(set(tangents[:, 3].tolist()))}, JOINTS_0 type {joint_type} max {joints.max()}")
            print(f"{ext}: {len(vertices)} → {len(uv)} glTF vertices, {len(faces)} → {len(indices)} triangles "
                  f"({refinement['split_edges']} edges split), {len(region)} region triangles front-facing, "
                  f"gltf-validator: 0 errors")
    print("ok")


if __name__ == "__main__":
    main()
