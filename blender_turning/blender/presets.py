"""Sport presets through Blender's preset system.

The four sports ship as preset scripts in ``presets/turning_figure/`` at the extension root
(registered with ``bpy.utils.register_preset_path``); users save their own next to Blender's
other presets with the "+" button.  The shipped files hold the core's ``PRESETS`` numbers (a test
checks they agree).
"""
from __future__ import annotations

from pathlib import Path

import bpy
from bl_operators.presets import AddPresetBase

#: The folder that holds ``presets/<PRESET_SUBDIR>`` (the extension root).
PRESET_ROOT = str(Path(__file__).resolve().parents[2])
PRESET_SUBDIR = "turning_figure"
PRESET_VALUES = ["settings.sport", "settings.mass", "settings.com_height", "settings.inertia",
                 "settings.speed", "settings.curvature_max", "settings.curvature_rate_max",
                 "settings.fall_angle", "settings.plan_curvature_rate"]


class TURNING_MT_figure_presets(bpy.types.Menu):
    bl_label = "Sport Presets"
    preset_subdir = PRESET_SUBDIR
    preset_operator = "script.execute_preset"
    draw = bpy.types.Menu.draw_preset


class TURNING_OT_figure_preset_add(AddPresetBase, bpy.types.Operator):
    """Save or remove a preset of the active figure's sport and body settings"""

    bl_idname = "turning.figure_preset_add"
    bl_label = "Add Figure Preset"
    preset_menu = "TURNING_MT_figure_presets"
    preset_subdir = PRESET_SUBDIR
    preset_defines = ["settings = bpy.context.object.turning"]
    preset_values = PRESET_VALUES

    @classmethod
    def poll(cls, context):
        obj = context.object
        if obj is None or not getattr(getattr(obj, "turning", None), "is_figure", False):
            cls.poll_message_set("Select a figure's armature")
            return False
        return True


classes = (TURNING_MT_figure_presets, TURNING_OT_figure_preset_add)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.utils.register_preset_path(PRESET_ROOT)


def unregister():
    bpy.utils.unregister_preset_path(PRESET_ROOT)
    _unregister()
