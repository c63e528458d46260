"""The texwarp mesh job of a Blender mesh (no bpy operators here; a BMesh in, a job dict out, UVs back).

Region: the selected faces, triangulated (Blender's loop triangles), sent as the job's inline mesh with their
vertices renumbered 0..n-1 (so a mesh job never sees the rest of the object). Features: the selected faces' pinned
UVs: source = where the pin sits on the image (pixels, top-left origin), target = that vertex. A vertex whose
FLOAT_VECTOR point attribute "texwarp_gradient" is non-zero makes its pin a gradient feature: the image's x axis
goes along that (object-space) direction with length(vector) texels per object unit.
"""

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
        self.triangles = [[compact[l.vert.index] for l in tri] for tri in bm.calc_loop_triangles()
                          if tri[0].face.index in selected]
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


def mesh_job(region, image_source, width, height, alpha=2.0, device=None, margin_px=8.0, name="blender"):
    """The job dict: the region's inline mesh, its pins as surface features, UVs with a bottom-left origin."""
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
    if device:
        job["options"] = {"device": device}
    return job


def apply_uvs(bm, region, uvs_doc, uv_layer, warped_layer=None):
    """uvs.json onto the region's face loops in bm (the mesh the region was made of, opened again): "uv" (into the
    original image) on uv_layer, "warped_uv" (into the warped image) on warped_layer. ValueError when the mesh's
    vertex or face count changed since. Returns the number of loops written."""
    if (len(bm.verts), len(bm.faces)) != region.counts:
        raise ValueError("the mesh changed while texwarp ran (vertices, faces %s, now %s)" % (
            region.counts, (len(bm.verts), len(bm.faces))))
    bm.faces.ensure_lookup_table()
    by_vertex = {c: i for i, c in enumerate(uvs_doc["vertices"])}
    written = 0
    for f in (bm.faces[i] for i in region.face_indices):
        for loop in f.loops:
            i = by_vertex[region.compact[loop.vert.index]]
            loop[uv_layer].uv = uvs_doc["uv"][i]
            if warped_layer is not None:
                loop[warped_layer].uv = uvs_doc["warped_uv"][i]
            written += 1
    return written
