"""The texwarp mesh job of a Blender mesh (no bpy operators here; a BMesh in, a job dict out, UVs back).

Region: the selected faces, triangulated (Blender's loop triangles), sent as the job's inline mesh with their
vertices renumbered 0..n-1 (so a mesh job never sees the rest of the object). Features: the selected faces' pinned
UVs: source = where the pin sits on the image (pixels, top-left origin), target = that vertex. A vertex whose
FLOAT_VECTOR point attribute "texwarp_gradient" is non-zero makes its pin a gradient feature: the image's x axis
goes along that (object-space) direction with length(vector) texels per object unit.
"""

import os
import re

GRADIENT_ATTRIBUTE = "texwarp_gradient"


class RegionMesh:
    """The selected faces of a BMesh as a triangle mesh: vertices (compact ids), triangles, pinned UVs. Holds indices
    only (no BMesh references): the result may be applied to the mesh opened again (apply_uvs)."""

    def __init__(self, bm, uv_layer):
        bm.verts.ensure_lookup_table()
        bm.verts.index_update()
        bm.faces.index_update()
        faces = [f for f in bm.faces if f.select]
        self.face_indices = [f.index for f in faces]
        self.counts = (len(bm.verts), len(bm.faces))  # to tell whether the mesh changed meanwhile
        self.mesh_vertex = []  # compact id -> BMesh vertex index
        compact = {}
        for f in faces:
            for v in f.verts:
                if v.index not in compact:
                    compact[v.index] = len(self.mesh_vertex)
                    self.mesh_vertex.append(v.index)
        self.compact = compact
        self.vertices = [list(bm.verts[i].co) for i in self.mesh_vertex]
        selected = set(self.face_indices)
        loop_triangles = [tri for tri in bm.calc_loop_triangles() if tri[0].face.index in selected]
        self.triangles = [[compact[l.vert.index] for l in tri] for tri in loop_triangles]
        self.triangle_face = [tri[0].face.index for tri in loop_triangles]  # the BMesh face of each triangle
        self.pins = {}  # compact id -> (u, v) of its first pinned loop
        for f in faces:
            for loop in f.loops:
                uv = loop[uv_layer]
                if uv.pin_uv and compact[loop.vert.index] not in self.pins:
                    self.pins[compact[loop.vert.index]] = (uv.uv[0], uv.uv[1])
        self.gradients = {}  # compact id -> (direction xyz, texels per unit)
        layer = bm.verts.layers.float_vector.get(GRADIENT_ATTRIBUTE)
        if layer is not None:
            for c in self.pins:
                g = tuple(bm.verts[self.mesh_vertex[c]][layer])
                length = sum(x * x for x in g) ** 0.5
                if length > 0.0:
                    self.gradients[c] = ([x / length for x in g], length)


def map_names(image_names):
    """Output names for a texture set's maps from Blender image names: the name without an image file extension,
    every other character than A-Z a-z 0-9 . _ - as "_", not starting with ".", at most 100 characters, made unique
    ("-2", "-3", ...)."""
    names = []
    for image_name in image_names:
        stem, ext = os.path.splitext(image_name)
        base = stem if ext.lower() in _IMAGE_EXTENSIONS and stem else image_name
        base = re.sub(r"[^A-Za-z0-9._-]", "_", base).lstrip(".")[:90] or "map"
        name, k = base, 2
        while name in names:
            name, k = "%s-%d" % (base, k), k + 1
        names.append(name)
    return names


_IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr", ".tga", ".bmp", ".hdr", ".tx", ".webp")


def _image_entry(source, role, color_space):
    entry = dict(source)
    if role:
        entry["role"] = role
    if color_space:
        entry["color_space"] = color_space
    return entry


def mesh_job(region, image_source, width, height, alpha=2.0, device=None, margin_px=8.0, name="blender",
             refine=True, optimize=True, role=None, color_space=None, maps=None):
    """The job dict: the region's inline mesh, its pins as surface features, UVs with a bottom-left origin; options
    refine (split faces until no UV triangle flips; the job may add vertices: see apply_refined_uvs) and optimize
    (lower the UVs' stretch from there, pins fixed, never through a flip), both on by default; the image's role and
    colour space (operator.image_role) when given. `maps`: a texture set instead of the one image, a list of
    (source, role, colour space, output name) whose first is the image the pins are on (all of its size): the job's
    "images", every map warped by the one warp of the region."""
    image_source = _image_entry(image_source, role, color_space)
    features = []
    for c in sorted(region.pins):
        u, v = region.pins[c]
        feature = {"id": "pin-v%d" % region.mesh_vertex[c], "source": [u * width, (1.0 - v) * height],
                   "target": {"vertex": c}}
        if c in region.gradients:
            direction, texels = region.gradients[c]
            feature["source_frame"] = {"angle_deg": 0.0, "scale": 1.0}
            feature["target_frame"] = {"direction": direction, "texels_per_unit": texels}
        features.append(feature)
    job = {"name": name, "image": image_source,
           "mesh": {"source": {"inline": {"vertices": region.vertices, "triangles": region.triangles}},
                    "features": {"alpha": alpha, "prealign": "similarity", "features": features},
                    "margin_px": margin_px, "obj_uv": "original"},
           "output": {"width": width, "height": height, "uv_origin": "bottom_left", "file_format": "png"}}
    if maps:
        del job["image"]
        job["images"] = [dict(_image_entry(source, r, c), name=n) for source, r, c, n in maps]
    options = {"refine": bool(refine), "optimize": "stretch" if optimize else "none"}
    if device:
        options["device"] = device
    job["options"] = options
    return job


def _check_unchanged(bm, region):
    if (len(bm.verts), len(bm.faces)) != region.counts:
        raise ValueError("the mesh changed while texwarp ran (vertices, faces %s, now %s)" % (
            region.counts, (len(bm.verts), len(bm.faces))))


def obj_triangles(obj_text):
    """The faces of a mesh.obj the job wrote (1-based "f v/vt ..." lines) as 0-based vertex id triples."""
    triangles = []
    for line in obj_text.splitlines():
        if line.startswith("f "):
            ids = [int(token.split("/")[0]) - 1 for token in line.split()[1:]]
            if len(ids) != 3 or min(ids) < 0:
                raise ValueError("mesh.obj: expected triangles with positive vertex numbers, got '%s'" % line)
            triangles.append(ids)
    return triangles


def apply_uvs(bm, region, uvs_doc, uv_layer, warped_layer=None):
    """uvs.json onto the region's face loops in bm (the mesh the region was made of, opened again): "uv" (into the
    original image) on uv_layer, "warped_uv" (into the warped image) on warped_layer. ValueError when the mesh's
    vertex or face count changed since. Returns the number of loops written."""
    _check_unchanged(bm, region)
    bm.faces.ensure_lookup_table()
    by_vertex = {c: i for i, c in enumerate(uvs_doc["vertices"])}
    written = 0
    for f in (bm.faces[i] for i in region.face_indices):
        for loop in f.loops:
            _set_uvs(loop, by_vertex[region.compact[loop.vert.index]], uvs_doc, uv_layer, warped_layer)
            written += 1
    return written


def _set_uvs(loop, i, uvs_doc, uv_layer, warped_layer):
    """uvs.json's UVs of its vertex i on a loop: "uv" on uv_layer, "warped_uv" on warped_layer (when given)."""
    loop[uv_layer].uv = uvs_doc["uv"][i]
    if warped_layer is not None:
        loop[warped_layer].uv = uvs_doc["warped_uv"][i]


def apply_refined_uvs(bm, region, uvs_doc, triangles, uv_layer, warped_layer=None):
    """A refined job's result onto bm: `triangles` (mesh.obj's faces: the region's triangles after refinement,
    input vertices first, then uvs_doc["new_vertices"]) and uvs.json's UVs. A selected face whose triangles came
    back as they went keeps its topology and gets its UVs; a face that refinement split is replaced by its output
    triangles (material and smoothing kept). A new vertex on a mesh edge splits that edge (bmesh edge_split), so a
    face outside the selection that shares it gains the vertex instead of a crack. ValueError when the mesh changed
    meanwhile or the result does not fit the region. Returns (loops written, faces added)."""
    _check_unchanged(bm, region)
    bm.verts.ensure_lookup_table()
    bm.faces.ensure_lookup_table()
    faces = {i: bm.faces[i] for i in region.face_indices}  # held before edge splits touch the tables
    source_face = uvs_doc["source_face"]
    added = uvs_doc["new_vertices"]
    first = added["first"]
    if len(source_face) != len(triangles) or first != len(region.mesh_vertex):
        raise ValueError("the refined result does not fit the region (%d faces, %d source faces, first new vertex "
                         "%d of %d)" % (len(triangles), len(source_face), first, len(region.mesh_vertex)))
    by_vertex = {c: i for i, c in enumerate(uvs_doc["vertices"])}
    # Output triangles per input triangle; a Blender face is unchanged when each of its triangles came back whole.
    out_of = {}
    for o, s in enumerate(source_face):
        out_of.setdefault(s, []).append(o)
    tris_of_face = {}
    for t, f in enumerate(region.triangle_face):
        tris_of_face.setdefault(f, []).append(t)
    changed = set()
    for f, tris in tris_of_face.items():
        for t in tris:
            outs = out_of.get(t, [])
            if len(outs) != 1 or sorted(triangles[outs[0]]) != sorted(region.triangles[t]):
                changed.add(f)
                break
    # The new vertices, in order (their ids first, first + 1, ...): on a mesh edge by splitting it, else new.
    verts = [bm.verts[i] for i in region.mesh_vertex]
    splits = {}
    for k, point in enumerate(added["source"]):
        corners = [verts[c] for c in region.triangles[point["face"]]]
        bary = point["barycentric"]
        co = sum((v.co * w for v, w in zip(corners, bary)), corners[0].co * 0.0)
        on_edge = [i for i in range(3) if abs(bary[i]) > 1e-9]  # an edge's point may carry a rounding residue
        vert = None
        if len(on_edge) == 2:
            # On the input edge (a, b) at parameter s: split the piece of it (earlier splits) that brackets s.
            i, j = on_edge
            a, b = corners[i], corners[j]
            vert = _split_edge_at(bm, splits, a, b, bary[j] / (bary[i] + bary[j]))
        if vert is None:
            vert = bm.verts.new(co)
        vert.co = co
        verts.append(vert)
    written = 0
    for f in (faces[i] for i in region.face_indices if i not in changed):
        for loop in f.loops:
            _set_uvs(loop, by_vertex[region.compact[loop.vert.index]], uvs_doc, uv_layer, warped_layer)
            written += 1
    style = {f: (faces[f].material_index, faces[f].smooth) for f in changed}
    new_faces = []
    for o, tri in enumerate(triangles):
        f = region.triangle_face[source_face[o]]
        if f in changed:
            new_faces.append((tri, style[f]))
    import bmesh
    old_edges = {e for f in changed for e in faces[f].edges}
    bmesh.ops.delete(bm, geom=[faces[f] for f in changed], context="FACES_ONLY")
    for tri, (material, smooth) in new_faces:
        face = bm.faces.new([verts[c] for c in tri])
        face.material_index = material
        face.smooth = smooth
        for loop, c in zip(face.loops, tri):
            _set_uvs(loop, by_vertex[c], uvs_doc, uv_layer, warped_layer)
            written += 1
    # An input edge that refinement split through its interior is no face's edge any more: not left loose.
    for e in [e for e in old_edges if e.is_valid and not e.link_faces]:
        bm.edges.remove(e)
    bm.verts.index_update()
    bm.faces.index_update()
    return written, len(new_faces) - len(changed)


def _split_edge_at(bm, splits, a, b, s):
    """The vertex splitting the mesh edge a-b at parameter s (0 at a, 1 at b), or None when a and b share no edge
    (a diagonal inside an n-gon). `splits` remembers the splits made per input edge, {(a, b): [(s, vertex)]}, so
    a second point on the same edge splits the right piece (found by parameter, not by geometry)."""
    import bmesh
    if bm.edges.get((a, b)) is None and not splits.get((a, b)) and not splits.get((b, a)):
        return None
    if (b, a) in splits:
        a, b, s = b, a, 1.0 - s
    done = splits.setdefault((a, b), [])
    chain = [(0.0, a)] + sorted(done, key=lambda x: x[0]) + [(1.0, b)]
    for (sp, p), (sq, q) in zip(chain, chain[1:]):
        if sp < s < sq:
            edge = bm.edges.get((p, q))
            if edge is None:
                return None
            _, vert = bmesh.utils.edge_split(edge, p, (s - sp) / (sq - sp))
            done.append((s, vert))
            return vert
    return None
