"""texwarp for Blender: "Constrained unwrap (texwarp)" in the UV menu (operator uv.texwarp_constrained_unwrap).

Select the faces to texture, pin UVs where image features belong (UV editor, P), run it: the selected faces get new
UVs on the active UV map that meet every pin exactly and never fold over (Seo & Cordier's constrained texture
mapping: the image is warped onto the faces' LSCM embedding), the warped image comes in as a new image with its
own UV map "texwarp_warped", and the report (stretch, shear, flips, residuals) shows in the operator's panel.
It needs the texwarp Python module: installed with texwarp (`cmake --install`: lib/python3.11/dist-packages under
the prefix; /usr/local is on Blender's path), or its folder set in the add-on's preferences.
"""

bl_info = {
    "name": "texwarp: constrained unwrap",
    "author": "texwarp",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "UV Editor > UV > Constrained unwrap (texwarp); 3D View (Edit Mode) > UV",
    "description": "Foldover-free constrained texture mapping: pinned UVs become texture features",
    "category": "UV",
}

import importlib

if "operator" in locals():
    importlib.reload(mesh_job)  # noqa: F821 (add-on reload)
    importlib.reload(operator)  # noqa: F821

import bpy

from . import mesh_job, operator  # noqa: E402


class TexwarpPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    server_url: bpy.props.StringProperty(
        name="texwarpd URL", default="",
        description="Run jobs on this texwarpd (http://host:port); empty: in Blender's process (texwarp.run_local)")
    module_path: bpy.props.StringProperty(
        name="texwarp module folder", subtype="DIR_PATH", default="",
        description="The folder holding the texwarp package (site-packages of texwarp's install prefix); empty: "
                    "Blender's sys.path")
    device: bpy.props.StringProperty(
        name="Device", default="", description="'cpu', 'opencl' or 'opencl:<name>'; empty: texwarp's default")

    def draw(self, context):
        layout = self.layout
        layout.prop(self, "server_url")
        layout.prop(self, "module_path")
        layout.prop(self, "device")


def menu_func(self, context):
    self.layout.separator()
    self.layout.operator(operator.TEXWARP_OT_constrained_unwrap.bl_idname)


classes = (TexwarpPreferences, operator.TEXWARP_OT_constrained_unwrap)


def register():
    for cls in classes:
        bpy.utils.register_class(cls)
    bpy.types.IMAGE_MT_uvs.append(menu_func)
    bpy.types.VIEW3D_MT_uv_map.append(menu_func)


def unregister():
    bpy.types.VIEW3D_MT_uv_map.remove(menu_func)
    bpy.types.IMAGE_MT_uvs.remove(menu_func)
    for cls in reversed(classes):
        bpy.utils.unregister_class(cls)
