"""File › Export › myriad scene: the scene as F12 would render it, written to a folder
(scene.ron and scene.glb) for `myriad render`, `myriad compare` or a cluster."""

import os

import bpy
from bpy_extras.io_utils import ExportHelper

from .export import ExportError, export_scene


class EXPORT_SCENE_OT_myriad(bpy.types.Operator, ExportHelper):
    """Write the scene for myriad: a .ron scene and the .glb it places, beside each other"""

    bl_idname = "export_scene.myriad"
    bl_label = "Export myriad Scene"
    filename_ext = ".ron"
    filter_glob: bpy.props.StringProperty(default="*.ron", options={"HIDDEN"})

    def execute(self, context):
        folder = os.path.dirname(os.path.abspath(self.filepath))
        depsgraph = context.evaluated_depsgraph_get()
        try:
            export = export_scene(depsgraph, folder, context.scene.myriad)
        except (ExportError, OSError) as e:
            self.report({"ERROR"}, f"myriad: {e}")
            return {"CANCELLED"}
        target = os.path.abspath(self.filepath)
        if os.path.abspath(export.ron) != target:
            os.replace(export.ron, target)
        for w in export.warnings:
            self.report({"WARNING"}, f"myriad: {w}")
        self.report(
            {"INFO"},
            f"myriad: wrote {target} ({export.triangles} triangles, {export.lights} lights) in {export.seconds:.2f} s",
        )
        return {"FINISHED"}


def menu(self, context):
    self.layout.operator(EXPORT_SCENE_OT_myriad.bl_idname, text="myriad scene (.ron)")


def register():
    bpy.utils.register_class(EXPORT_SCENE_OT_myriad)
    bpy.types.TOPBAR_MT_file_export.append(menu)


def unregister():
    bpy.types.TOPBAR_MT_file_export.remove(menu)
    bpy.utils.unregister_class(EXPORT_SCENE_OT_myriad)
