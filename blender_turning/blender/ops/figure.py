"""``turning.add_figure``: a sport preset's figure at the 3D cursor; also in the Add menu
(Shift+A > Turning Figure > sport)."""
from __future__ import annotations

import math

import bpy
from bpy.props import EnumProperty

from ..scene import rig_builder
from ...core.registry import SPORTS
from ..registry_items import sport_items, sport_label
from ..scene.scene_adapters import settings_from_preset


class TURNING_OT_add_figure(bpy.types.Operator):
    """Add a turning figure (a sport preset) at the 3D cursor and make it active"""

    bl_idname = "turning.add_figure"
    bl_label = "Add Figure"
    bl_options = {"REGISTER", "UNDO"}

    sport: EnumProperty(name="Sport", items=sport_items, default=0)

    @classmethod
    def poll(cls, context):
        if context.mode != "OBJECT":
            cls.poll_message_set("Switch to Object Mode to add a figure")
            return False
        if context.scene is None or context.view_layer is None:
            cls.poll_message_set("No scene to add the figure to")
            return False
        return True

    def execute(self, context):
        try:
            spec = rig_builder.load_spec(self.sport.lower())
        except (OSError, ValueError) as exc:
            self.report({"ERROR"}, f"Add Figure: {exc}")
            return {"CANCELLED"}
        cursor = context.scene.cursor
        # Facing: the cursor's rotation about Z turns the figure's +Y (its rest facing).
        yaw = cursor.rotation_euler.to_matrix().to_euler("XYZ").z
        collection = context.collection or context.scene.collection
        name = sport_label(self.sport)
        try:
            obj = rig_builder.build_figure(context, spec, name, cursor.location.copy(), collection)
        except ValueError as exc:
            self.report({"ERROR"}, f"Add Figure: {exc}")
            return {"CANCELLED"}
        obj.rotation_euler = (0.0, 0.0, yaw)
        s = obj.turning
        s.is_figure = True
        settings_from_preset(s, self.sport)
        s.start = cursor.location
        s.start_heading = yaw + math.pi / 2
        s.heading = s.start_heading
        for o in context.selected_objects:
            o.select_set(False)
        obj.select_set(True)
        context.view_layer.objects.active = obj
        self.report({"INFO"}, f"Added {obj.name} at the 3D cursor")
        return {"FINISHED"}


class VIEW3D_MT_turning_figure_add(bpy.types.Menu):
    """Shift+A > Turning Figure: one entry per registered sport."""

    bl_idname = "VIEW3D_MT_turning_figure_add"
    bl_label = "Turning Figure"

    def draw(self, context):
        for sport in SPORTS.values():
            self.layout.operator(TURNING_OT_add_figure.bl_idname, text=sport.label,
                                 icon=sport.icon).sport = sport.key


def draw_add_menu(self, context):
    """The entry in the 3D viewport's Add menu (``VIEW3D_MT_add``)."""
    self.layout.menu(VIEW3D_MT_turning_figure_add.bl_idname, icon="OUTLINER_OB_ARMATURE")


classes = (TURNING_OT_add_figure, VIEW3D_MT_turning_figure_add)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.VIEW3D_MT_add.append(draw_add_menu)


def unregister():
    bpy.types.VIEW3D_MT_add.remove(draw_add_menu)
    _unregister()
