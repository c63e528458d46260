"""The operator uv.texwarp_constrained_unwrap: builds the mesh job of the selected faces and their pins
(mesh_job.py), runs it (in-process or on a texwarpd), puts the UVs, the warped image and the report back.
From the UI it is modal (a timer polls the job; progress bar; Esc cancels); from a script it runs to the end."""

import json
import os
import shutil
import sys
import tempfile

import bmesh
import bpy

from . import mesh_job


def _preferences(context):
    addon = context.preferences.addons.get(__package__)
    return addon.preferences if addon else None


def import_texwarp(context):
    """The texwarp module, from the preferences' folder first, then sys.path; None with a message if absent."""
    prefs = _preferences(context)
    folder = bpy.path.abspath(prefs.module_path) if prefs and prefs.module_path else ""
    if folder and folder not in sys.path:
        sys.path.insert(0, folder)
    try:
        import texwarp
        return texwarp, None
    except ImportError as e:
        return None, ("the texwarp Python module is not found (%s): install texwarp (cmake --install) or set its "
                      "folder in the add-on's preferences" % e)


def _image_of(context, name):
    if name:
        return bpy.data.images.get(name)
    space = getattr(context, "space_data", None)
    if space is not None and space.type == "IMAGE_EDITOR" and space.image is not None:
        return space.image
    obj = context.active_object
    mat = obj.active_material if obj else None
    if mat and mat.use_nodes:
        for node in mat.node_tree.nodes:
            if node.type == "TEX_IMAGE" and node.image is not None:
                return node.image
    return None


def _open_bmesh(obj):
    """(bm, owned): the edit-mode BMesh of obj, or a new one from its mesh (owned: to be written back and freed)."""
    if obj.mode == "EDIT":
        return bmesh.from_edit_mesh(obj.data), False
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    return bm, True


def _image_file(image, scratch, scene):
    """A file holding the image's pixels: its own file when it has one, else a PNG written into scratch."""
    path = bpy.path.abspath(image.filepath) if image.filepath else ""
    if path and os.path.isfile(path) and image.packed_file is None and not image.is_dirty:
        return path
    path = os.path.join(scratch, "texture.png")
    image.save_render(path, scene=scene)
    return path


class TEXWARP_OT_constrained_unwrap(bpy.types.Operator):
    """Unwrap the selected faces so that every pinned UV stays where it is on the image, without foldovers
    (texwarp: the image is warped onto the faces' LSCM embedding)"""

    bl_idname = "uv.texwarp_constrained_unwrap"
    bl_label = "Constrained unwrap (texwarp)"
    bl_options = {"REGISTER", "UNDO"}

    image_name: bpy.props.StringProperty(name="Image", default="",
                                         description="The image the pins are on; empty: the UV editor's image, "
                                                     "else the active material's first image texture")
    alpha: bpy.props.FloatProperty(name="Alpha", default=2.0, min=1.01, max=8.0,
                                   description="Weight falloff exponent of the warp (paper default 2)")
    warped_image: bpy.props.BoolProperty(name="Warped image", default=True,
                                         description="Bring in the warped image and its UV map texwarp_warped")
    refine: bpy.props.BoolProperty(name="Refine", default=False,
                                   description="Split the faces where the warp would flip a triangle or a pin lies "
                                               "inside a face (adds vertices; split faces become triangles)")
    # The report, shown in the operator's panel.
    l2_stretch: bpy.props.FloatProperty(name="L² stretch", default=0.0, options={"SKIP_SAVE"})
    l2_shear: bpy.props.FloatProperty(name="L² shear", default=0.0, options={"SKIP_SAVE"})
    flipped: bpy.props.IntProperty(name="Flipped faces", default=0, options={"SKIP_SAVE"})
    max_residual_px: bpy.props.FloatProperty(name="Max pin residual (px)", default=0.0, options={"SKIP_SAVE"})
    pins: bpy.props.IntProperty(name="Pins", default=0, options={"SKIP_SAVE"})
    faces_added: bpy.props.IntProperty(name="Faces added", default=0, options={"SKIP_SAVE"})

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "MESH"

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "image_name")
        layout.prop(self, "alpha")
        layout.prop(self, "warped_image")
        layout.prop(self, "refine")
        box = layout.box()
        box.label(text="Report (%d pins)" % self.pins)
        box.label(text="L² stretch %.4f   L² shear %.4f" % (self.l2_stretch, self.l2_shear))
        box.label(text="Flipped faces %d   max pin residual %.4f px" % (self.flipped, self.max_residual_px))
        if self.refine:
            box.label(text="Faces added by refinement %d" % self.faces_added)

    # --- the job -----------------------------------------------------------------------------------------------

    def _start(self, context):
        """Builds and submits the job; a message (str) when it cannot."""
        texwarp, message = import_texwarp(context)
        if texwarp is None:
            return message
        self._texwarp = texwarp
        obj = context.active_object
        image = _image_of(context, self.image_name)
        if image is None:
            return "no image: open the texture in the UV editor, or give the operator's Image"
        width, height = image.size
        if width == 0 or height == 0:
            return "image %s has no pixels" % image.name
        self._image = image
        self._object = obj
        bm, owned = _open_bmesh(obj)
        try:
            uv_layer = bm.loops.layers.uv.active
            if uv_layer is None:
                return "the mesh has no UV map: add one and pin UVs on it"
            region = mesh_job.RegionMesh(bm, uv_layer)
        finally:
            if owned:
                bm.free()
        if not region.face_indices:
            return "no faces selected: select the faces to texture"
        if not region.pins:
            return "no pinned UVs on the selected faces: pin UVs where image features belong (UV editor, P)"
        self._region = region
        self.pins = len(region.pins)
        self._scratch = tempfile.mkdtemp(prefix="texwarp-blender-")
        prefs = _preferences(context)
        server = prefs.server_url.strip() if prefs else ""
        device = prefs.device.strip() if prefs else ""
        image_file = _image_file(image, self._scratch, context.scene)
        try:
            if server:
                # Upload and submit run on Blender's main thread: give up on an unreachable server in seconds,
                # not after the library's default minute.
                client = texwarp.Client(server, retry_budget=5.0)
                source = {"blob": client.upload_file(image_file)}
            else:
                source = {"path": image_file}
            self.job_dict = mesh_job.mesh_job(region, source, width, height, alpha=self.alpha, device=device or None,
                                              name="blender: %s" % obj.name, refine=self.refine)
            self._job = client.submit(self.job_dict) if server else texwarp.submit_local(self.job_dict)
        except texwarp.Error as e:
            return "texwarp: %s" % e
        return None

    def _finish(self, context):
        """Fetches the result and applies it; a message (str) when it cannot."""
        texwarp = self._texwarp
        out = os.path.join(self._scratch, "out")
        try:
            result = self._job.fetch(out)
        except texwarp.Error as e:
            return "texwarp: %s" % e
        with open(os.path.join(out, "uvs.json")) as f:
            uvs = json.load(f)
        triangles = None
        if "new_vertices" in uvs:  # refined: the region's faces come back in mesh.obj
            with open(os.path.join(out, "mesh.obj")) as f:
                triangles = mesh_job.obj_triangles(f.read())
        # The mesh is opened again: the user may have left or entered Edit Mode while a modal run went on.
        obj = self._object
        bm, owned = _open_bmesh(obj)
        try:
            uv_layer = bm.loops.layers.uv.active
            warped_layer = None
            if self.warped_image:
                warped_layer = bm.loops.layers.uv.get("texwarp_warped") or bm.loops.layers.uv.new("texwarp_warped")
                uv_layer = bm.loops.layers.uv.active  # adding a layer may move the BMesh's layer handles
            if triangles is None:
                mesh_job.apply_uvs(bm, self._region, uvs, uv_layer, warped_layer)
                self.faces_added = 0
            else:
                _, self.faces_added = mesh_job.apply_refined_uvs(bm, self._region, uvs, triangles, uv_layer,
                                                                 warped_layer)
            if owned:
                bm.to_mesh(obj.data)
                obj.data.update()
            else:
                bmesh.update_edit_mesh(obj.data, loop_triangles=True, destructive=triangles is not None)
        except ValueError as e:
            return "texwarp: %s" % e
        finally:
            if owned:
                bm.free()
        report = result["report"]  # a mesh job's report: the mapping's fields at its top level
        self.l2_stretch = report["l2_stretch"]
        self.l2_shear = report["l2_shear"]
        self.flipped = report["flipped_triangles"]
        self.max_residual_px = report["max_residual_px"]
        if self.warped_image:
            warped = [f for f in result["files"] if os.path.basename(f).startswith("warped.")]
            if warped:
                img = bpy.data.images.load(warped[0], check_existing=False)
                img.name = self._image.name + ".texwarp"
                img.pack()
        self.report({"INFO"}, "texwarp: %d pins, L² stretch %.3f, %d flipped, max residual %.3f px" %
                    (self.pins, self.l2_stretch, self.flipped, self.max_residual_px))
        return None

    def _cleanup(self):
        scratch = getattr(self, "_scratch", None)
        if scratch:
            shutil.rmtree(scratch, ignore_errors=True)
        self._job = None

    # --- script: to the end; UI: modal -------------------------------------------------------------------------

    def execute(self, context):
        try:
            message = self._start(context)
            if message is None:
                try:
                    self._job.wait()
                except self._texwarp.Error as e:
                    message = "texwarp: %s" % e
            if message is None:
                message = self._finish(context)
        finally:
            self._cleanup()
        if message is not None:
            self.report({"ERROR"}, message)
            return {"CANCELLED"}
        return {"FINISHED"}

    def invoke(self, context, event):
        if context.window_manager is None or context.window is None:
            return self.execute(context)
        try:
            message = self._start(context)
        except Exception:
            self._cleanup()
            raise
        if message is not None:
            self._cleanup()
            self.report({"ERROR"}, message)
            return {"CANCELLED"}
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 100)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        wm = context.window_manager
        if event.type == "ESC":
            self._job.cancel()
            self._end_modal(context)
            self.report({"WARNING"}, "texwarp: canceled")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        wm.progress_update(int(self._job.progress * 100))
        if not self._job.poll():
            return {"PASS_THROUGH"}
        try:
            message = self._finish(context)
        finally:
            self._end_modal(context)
        if message is not None:
            self.report({"ERROR"}, message)
            return {"CANCELLED"}
        return {"FINISHED"}

    def _end_modal(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        self._cleanup()
