"""The operator uv.texwarp_constrained_unwrap: builds the mesh job of the selected faces and their pins
(mesh_job.py), runs it (in-process or on a texwarpd), puts the UVs, the warped image and the report back.
From the UI it is modal: upload and submit, then fetch, run on worker threads (_JobRun, no bpy there), a timer shows
progress (progress bar, status bar) and applies the result on the main thread; Esc cancels. From a script it runs to
the end."""

import json
import os
import shutil
import sys
import tempfile
import threading

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


# Blender's colour spaces that hold linear light (its 3.4 OCIO config); sRGB is "sRGB"; "Non-Color" and "Raw" are data.
_LINEAR_SPACES = ("Linear", "Linear Rec.709", "scene_linear")


def image_role(image, material):
    """(role, colour space) of `image` as the material uses it: the input of a Normal Map node is "normal"; an image
    whose colour space is Non-Color (or Raw) is "data"; any other is "color", in "sRGB" or "linear" when Blender says
    so, else the file's own (None)."""
    if material is not None and material.use_nodes:
        for link in material.node_tree.links:
            if (link.to_node.type == "NORMAL_MAP" and link.from_node.type == "TEX_IMAGE"
                    and link.from_node.image == image):
                return "normal", None
    settings = image.colorspace_settings
    if settings.is_data or settings.name in ("Non-Color", "Raw"):
        return "data", None
    if settings.name == "sRGB":
        return "color", "sRGB"
    if settings.name in _LINEAR_SPACES:
        return "color", "linear"
    return "color", None


def material_maps(material, image):
    """The texture set of `material` around `image` (the one the pins are on): `image` first, then every other image
    of the material's Image Texture nodes, each once, in node order, as (image, role, colour space) (image_role).
    Images of another size than `image`'s cannot share its warp: returned apart as `skipped` (their names)."""
    maps = [(image,) + image_role(image, material)]
    skipped = []
    if material is None or not material.use_nodes:
        return maps, skipped
    seen = {image.name}
    for node in material.node_tree.nodes:
        other = node.image if node.type == "TEX_IMAGE" else None
        if other is None or other.name in seen:
            continue
        seen.add(other.name)
        if tuple(other.size) != tuple(image.size):
            skipped.append(other.name)
            continue
        maps.append((other,) + image_role(other, material))
    return maps, skipped


def _open_bmesh(obj):
    """(bm, owned): the edit-mode BMesh of obj, or a new one from its mesh (owned: to be written back and freed)."""
    if obj.mode == "EDIT":
        return bmesh.from_edit_mesh(obj.data), False
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    return bm, True


def _image_file(image, scratch, scene, index=0):
    """A file holding the image's pixels: its own file when it has one, else a PNG written into scratch (the
    index-th image of the job)."""
    path = bpy.path.abspath(image.filepath) if image.filepath else ""
    if path and os.path.isfile(path) and image.packed_file is None and not image.is_dirty:
        return path
    path = os.path.join(scratch, "texture-%d.png" % index)
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
    refine: bpy.props.BoolProperty(name="Refine", default=True,
                                   description="Split the faces whose UVs would flip until none does, and faces a "
                                               "pin lies inside (adds vertices; split faces become triangles)")
    optimize: bpy.props.BoolProperty(name="Optimize stretch", default=True,
                                     description="Lower the UVs' stretch from the flip-free result, pins fixed, "
                                                 "never through a flip")
    all_maps: bpy.props.BoolProperty(name="Every map of the material", default=True,
                                     description="Warp every image texture of the active material with the same "
                                                 "warp (base colour, roughness, normal…; roles from their colour "
                                                 "space and Normal Map nodes); off: only the image the pins are on")
    # The report, shown in the operator's panel.
    l2_stretch: bpy.props.FloatProperty(name="L² stretch", default=0.0, options={"SKIP_SAVE"})
    l2_shear: bpy.props.FloatProperty(name="L² shear", default=0.0, options={"SKIP_SAVE"})
    flipped: bpy.props.IntProperty(name="Flipped faces", default=0, options={"SKIP_SAVE"})
    max_residual_px: bpy.props.FloatProperty(name="Max pin residual (px)", default=0.0, options={"SKIP_SAVE"})
    pins: bpy.props.IntProperty(name="Pins", default=0, options={"SKIP_SAVE"})
    faces_added: bpy.props.IntProperty(name="Faces added", default=0, options={"SKIP_SAVE"})
    stretch_before: bpy.props.FloatProperty(name="L² stretch before optimisation", default=0.0,
                                            options={"SKIP_SAVE"})
    max_aspect: bpy.props.FloatProperty(name="Max σ1/σ2", default=0.0, options={"SKIP_SAVE"})
    refine_note: bpy.props.StringProperty(name="Refinement", default="", options={"SKIP_SAVE"})
    texture_role: bpy.props.StringProperty(name="Texture role", default="", options={"SKIP_SAVE"})
    footprint_pixels: bpy.props.IntProperty(name="Pixels averaged over their footprint", default=0,
                                            options={"SKIP_SAVE"})
    maps_note: bpy.props.StringProperty(name="Maps", default="", options={"SKIP_SAVE"})

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
        layout.prop(self, "optimize")
        layout.prop(self, "all_maps")
        box = layout.box()
        box.label(text="Report (%d pins)" % self.pins)
        if self.stretch_before > 0.0:
            box.label(text="L² stretch %.4f (%.4f before optimising)" % (self.l2_stretch, self.stretch_before))
        else:
            box.label(text="L² stretch %.4f" % self.l2_stretch)
        box.label(text="L² shear %.4f   max σ1/σ2 %.3g" % (self.l2_shear, self.max_aspect))
        box.label(text="Flipped faces %d   max pin residual %.4f px" % (self.flipped, self.max_residual_px))
        box.label(text="Faces added by refinement %d" % self.faces_added)
        if self.refine_note:
            box.label(text=self.refine_note)
        if self.texture_role:
            box.label(text="Texture: %s, %d px footprint-filtered" % (self.texture_role, self.footprint_pixels))
        if self.maps_note:
            box.label(text=self.maps_note)

    # --- the job: prepared on the main thread (bpy), sent, watched and fetched by _JobRun (no bpy), applied on the
    # main thread ------------------------------------------------------------------------------------------------

    def _prepare(self, context):
        """Reads the selection, pins and image (bpy: main thread) into a _JobRun; a message (str) when it cannot."""
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
        self._image_name = image.name
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
        # Plain values only: the job is made on a worker thread, where neither the object (the user may delete it
        # meanwhile) nor this operator (freed on Esc) may be touched.
        self._object_name = obj.name
        if self.all_maps:
            maps, skipped = material_maps(obj.active_material, image)
        else:
            maps, skipped = [(image,) + image_role(image, obj.active_material)], []
        _, role, color_space = maps[0]
        self.texture_role = role if color_space is None else "%s (%s)" % (role, color_space)
        self.maps_note = ""
        if len(maps) > 1:
            self.maps_note = "%d maps warped together" % len(maps)
        if skipped:
            self.maps_note += "%s%s left out (not %d×%d)" % ("; " if self.maps_note else "", ", ".join(skipped),
                                                             width, height)
        image_files = [_image_file(m[0], self._scratch, context.scene, i) for i, m in enumerate(maps)]
        names = mesh_job.map_names([m[0].name for m in maps]) if len(maps) > 1 else ["warped"]
        # The warped image of each output name: the Blender image it comes from.
        self._warped_of = {name: m[0].name for name, m in zip(names, maps)}
        job_values = dict(width=width, height=height, alpha=float(self.alpha), device=device or None,
                          name="blender: %s" % obj.name, refine=bool(self.refine),
                          optimize=bool(self.optimize), role=role,
                          color_space=color_space)

        def make_job(sources):
            if len(maps) == 1:
                return mesh_job.mesh_job(region, sources[0], **job_values)
            set_maps = [(source, r, c, n) for source, (_, r, c), n in zip(sources, maps, names)]
            return mesh_job.mesh_job(region, sources[0], maps=set_maps, **job_values)
        self._run = _JobRun(texwarp, server, self._scratch, image_files, make_job)
        return None

    def _apply(self, context):
        """Puts the fetched result on the mesh (main thread); a message (str) when it cannot."""
        run = self._run
        if run.message is not None:
            return run.message
        uvs, triangles, result = run.uvs, run.triangles, run.result
        # The mesh is opened again: the user may have left or entered Edit Mode (or deleted the object) meanwhile.
        obj = self._object
        try:
            obj.name
        except ReferenceError:
            return "texwarp: the object %s was deleted while texwarp ran: nothing to apply" % self._object_name
        if obj.type != "MESH" or obj.data is None:
            return "texwarp: the object %s is no mesh any more: nothing to apply" % self._object_name
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
        self.max_aspect = report.get("max_aspect", 0.0)
        optimization = report.get("optimization") or {}
        self.stretch_before = optimization["before"]["l2_stretch"] if optimization.get("applied") else 0.0
        refinement = report.get("refinement") or {}
        untangling = report.get("untangling") or {}
        self.refine_note = ""
        if self.flipped and refinement.get("stop") not in (None, "flip_free", "untangled"):
            self.refine_note = "Refinement stopped (%s): %d faces still flip" % (refinement["stop"], self.flipped)
        elif self.flipped:
            self.refine_note = "%d faces still flip" % self.flipped
        elif untangling.get("applied"):
            self.refine_note = "Untangled: %d flipped faces unfolded" % untangling["flipped_before"]
        sampling = report.get("texture_sampling") or {}
        self.footprint_pixels = sampling.get("footprint_pixels", 0)
        if self.warped_image:
            # Each warped image (one, or every map of the set) as "<its image's name>.texwarp", packed.
            for f in result["files"]:
                stem, ext = os.path.splitext(os.path.basename(f))
                if stem in self._warped_of and ext.lower() not in (".obj", ".json", ".gltf", ".glb"):
                    img = bpy.data.images.load(f, check_existing=False)
                    img.name = self._warped_of[stem] + ".texwarp"
                    source = bpy.data.images.get(self._warped_of[stem])
                    if source is not None:  # the warped file holds its source's encoding (sRGB, linear, data)
                        img.colorspace_settings.name = source.colorspace_settings.name
                    img.pack()
        self.report({"INFO"}, "texwarp: %d pins, L² stretch %.3f, %d flipped, max residual %.3f px" %
                    (self.pins, self.l2_stretch, self.flipped, self.max_residual_px))
        return None

    def _cleanup(self):
        scratch = getattr(self, "_scratch", None)
        if scratch:
            shutil.rmtree(scratch, ignore_errors=True)
        self._scratch = None
        self._run = None

    # --- script: to the end; UI: modal, the network on a thread -----------------------------------------------

    def execute(self, context):
        try:
            message = self._prepare(context)
            if message is None:
                self._run.run()  # a script waits for its result: on this thread
                message = self._apply(context)
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
            message = self._prepare(context)
        except Exception:
            self._cleanup()
            raise
        if message is not None:
            self._cleanup()
            self.report({"ERROR"}, message)
            return {"CANCELLED"}
        self._run.start()  # upload and submit on a thread, later fetch on another: Blender's UI keeps running
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 100)
        self._status(context, "texwarp: starting (Esc cancels)")
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        run = self._run
        if event.type == "ESC":
            self._stop(context)
            self.report({"WARNING"}, "texwarp: canceled")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if not run.step():
            progress = run.progress()
            context.window_manager.progress_update(int(progress * 100))
            self._status(context, "texwarp: %s %d%% (Esc cancels)" % (run.phase, int(progress * 10) * 10))
            return {"PASS_THROUGH"}
        try:
            message = self._apply(context)
        finally:
            self._end_modal(context)
        if message is not None:
            self.report({"ERROR"}, message)
            return {"CANCELLED"}
        return {"FINISHED"}

    def cancel(self, context):
        """Blender drops the modal operator (a file loaded, the window closed): stop the job as Esc does."""
        if getattr(self, "_run", None) is not None:
            self._stop(context)

    def _stop(self, context):
        self._run.cancel()  # a thread cancels the job (a request to the server) and removes the scratch folder
        self._scratch = None
        self._end_modal(context)

    def _status(self, context, text):
        """The status bar's text (redrawn only when it changes)."""
        workspace = getattr(context, "workspace", None)
        if workspace is not None and text != getattr(self, "_status_text", None):
            workspace.status_text_set(text)
            self._status_text = text

    def _end_modal(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        self._status(context, None)
        self._cleanup()


class _JobRun:
    """The network side of one run, without bpy: upload the textures (texwarpd) and submit; once the job has ended,
    fetch into the scratch folder and read uvs.json (and mesh.obj when refined). From the UI each network step runs on
    a short-lived thread (none while the job runs: the main thread's step() reads its state without blocking);
    run() does it all on the caller's thread (a script). cancel() returns at once: a thread asks the server to stop
    and removes the scratch folder."""

    def __init__(self, texwarp, server, scratch, image_files, make_job):
        self._texwarp = texwarp
        self._server = server
        self._scratch = scratch
        self._image_files = image_files
        self._make_job = make_job
        self._job = None
        self._threads = []  # the submit thread, then the fetch thread
        self.phase = "uploading" if server else "starting"
        self.message = None  # why it failed (str), once finished
        self.uvs = self.triangles = self.result = None

    def _guarded(self, work):
        """work(), its failure kept as the message the user sees (any exception: a thread must not die silently)."""
        try:
            work()
        except self._texwarp.Error as e:
            self.message = "texwarp: %s" % e
        except (OSError, ValueError) as e:
            self.message = "texwarp: reading the result: %s" % e
        except Exception as e:  # a bug: said, not left to end the thread with the operator waiting forever
            self.message = "texwarp: unexpected error (%s: %s)" % (type(e).__name__, e)

    def _submit(self):
        texwarp = self._texwarp
        if self._server:
            # From the UI on a thread: an unreachable server is retried for a while (Esc ends the operator at once).
            client = texwarp.Client(self._server, retry_budget=30.0 if self._threads else 5.0)
            sources = [{"blob": client.upload_file(f)} for f in self._image_files]
        else:
            sources = [{"path": f} for f in self._image_files]
        self.phase = "submitting"
        job_dict = self._make_job(sources)
        self._job = client.submit(job_dict) if self._server else texwarp.submit_local(job_dict)
        self.phase = "running"

    def _fetch(self):
        out = os.path.join(self._scratch, "out")
        self.result = self._job.fetch(out)
        with open(os.path.join(out, "uvs.json")) as f:
            self.uvs = json.load(f)
        if "new_vertices" in self.uvs:  # refined: the region's faces come back in mesh.obj
            with open(os.path.join(out, "mesh.obj")) as f:
                self.triangles = mesh_job.obj_triangles(f.read())

    def _thread(self, work):
        thread = threading.Thread(target=self._guarded, args=(work,), name="texwarp job", daemon=True)
        self._threads.append(thread)
        thread.start()

    def run(self):
        """All of it on this thread (a script): submit, wait, fetch."""
        def everything():
            self._submit()
            self._job.wait()
            self._fetch()
        self._guarded(everything)

    def start(self):
        self._thread(self._submit)

    def step(self):
        """True once finished (message, or the result read); never blocks (the main thread's timer)."""
        if self.message is not None:
            return True
        if any(t.is_alive() for t in self._threads):
            return False
        if self._job is None:
            if not self._threads:
                return False  # not started
            # Every thread has ended without a job and without a message: finished, never waiting forever.
            self.message = "texwarp: the job was not submitted (no reason given)"
            return True
        if len(self._threads) == 1:
            if not self._job.poll():
                return False
            self.phase = "fetching"
            self._thread(self._fetch)
            return False
        return True

    def progress(self):
        job = self._job
        return job.progress if job is not None else 0.0

    def cancel(self):
        def stop():
            for t in list(self._threads):
                t.join()
            if self._job is not None and not self._job.poll():
                try:
                    self._job.cancel()
                except self._texwarp.Error:
                    pass  # it ended meanwhile, or the server is gone: nothing left to stop
            shutil.rmtree(self._scratch, ignore_errors=True)
        threading.Thread(target=stop, name="texwarp cancel", daemon=True).start()
