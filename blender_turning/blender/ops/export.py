"""Export FBX with Tweaks (File > Export): Blender's FBX exporter at its defaults, with each
figure's tweak layer flattened into the take an importer plays (:mod:`..anim.export_fbx`,
docs/export.md)."""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, FloatProperty, StringProperty
from bpy_extras.io_utils import ExportHelper

from ..anim import export_fbx, export_gltf, export_shared


def _fbx_exporter() -> bool:
    return hasattr(bpy.types, "EXPORT_SCENE_OT_fbx")


class TURNING_OT_export_fbx(bpy.types.Operator, ExportHelper):
    """Export FBX at the exporter's defaults, each baked figure's first take playing its bake with
    the tweak layer above it (the scene is given back as it was)"""

    bl_idname = "turning.export_fbx"
    bl_label = "Export FBX with Tweaks"
    bl_options = {"PRESET"}

    filename_ext = ".fbx"
    filter_glob: StringProperty(default="*.fbx", options={"HIDDEN"})
    use_selection: BoolProperty(name="Selected Objects", default=False,
                                description="Export the selected objects only (as the FBX "
                                            "exporter's option of that name)")
    bake_anim_simplify_factor: FloatProperty(
        name="Simplify", default=1.0, min=0.0, max=100.0, soft_max=10.0,
        description="How much to simplify the baked values, as the FBX exporter's option of that "
                    "name (0: off, every frame's value exactly)")

    @classmethod
    def poll(cls, context):
        if not _fbx_exporter():
            cls.poll_message_set("Enable the FBX add-on (io_scene_fbx) first")
            return False
        return True

    def execute(self, context):
        objs = context.selected_objects if self.use_selection else context.scene.objects
        try:
            with export_shared.unshared(list(objs)), export_fbx.flattened(list(objs)) as n:
                result = bpy.ops.export_scene.fbx(
                    filepath=self.filepath, use_selection=self.use_selection,
                    bake_anim_simplify_factor=self.bake_anim_simplify_factor)
        except RuntimeError as exc:           # the exporter's error: its last line says what
            lines = [ln for ln in str(exc).splitlines() if ln.strip()
                     and not ln.startswith("Location:")]
            self.report({"ERROR"}, f"Export FBX with Tweaks: {lines[-1] if lines else exc}; "
                                   "nothing was changed")
            return {"CANCELLED"}
        if result != {"FINISHED"}:
            return {"CANCELLED"}
        self.report({"INFO"}, f"Exported {self.filepath} ({n} figures with their tweaks)")
        return {"FINISHED"}


def menu_entry(self, context):
    self.layout.operator(TURNING_OT_export_fbx.bl_idname, text="FBX with Turning Tweaks (.fbx)")


classes = (TURNING_OT_export_fbx,)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.TOPBAR_MT_file_export.append(menu_entry)
    bpy.app.handlers.save_pre.append(export_gltf.restore_before_save)


def unregister():
    while export_gltf.restore_before_save in bpy.app.handlers.save_pre:
        bpy.app.handlers.save_pre.remove(export_gltf.restore_before_save)
    if bpy.app.timers.is_registered(export_gltf.restore_after_export):
        bpy.app.timers.unregister(export_gltf.restore_after_export)
    bpy.types.TOPBAR_MT_file_export.remove(menu_entry)
    _unregister()
