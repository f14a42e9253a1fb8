"""Sport presets through Blender's preset system.

The four sports ship as preset scripts in ``presets/turning_figure/`` at the extension root
(registered with ``bpy.utils.register_preset_path``); users save their own next to Blender's
other presets with the "+" button.  The shipped files hold the core's ``PRESETS`` numbers (a test
checks they agree).
"""
from __future__ import annotations

import re
from pathlib import Path

import bpy
from bl_operators.presets import AddPresetBase
from bpy.props import StringProperty

from .figure_context import sport_label
from .rig_builder import RIG_TAG

#: The folder that holds ``presets/<PRESET_SUBDIR>`` (the extension root).
PRESET_ROOT = str(Path(__file__).resolve().parents[2])
PRESET_SUBDIR = "turning_figure"
PRESET_VALUES = ["settings.sport", "settings.mass", "settings.com_height", "settings.inertia",
                 "settings.speed", "settings.curvature_max", "settings.curvature_rate_max",
                 "settings.fall_angle", "settings.plan_curvature_rate"]


def _poll_figure_object(cls, context) -> bool:
    obj = context.object
    if obj is None or not getattr(getattr(obj, "turning", None), "is_figure", False):
        cls.poll_message_set("Select a figure's armature")
        return False
    return True


_SPORT_LINE = re.compile(r"""^settings\.sport\s*=\s*['"](\w+)['"]""", re.MULTILINE)


def preset_sport(filepath: str) -> str | None:
    """The sport a preset file sets (``'SKIER'``...), or ``None`` when it sets none."""
    try:
        with open(filepath, encoding="utf-8") as fh:
            found = _SPORT_LINE.search(fh.read())
    except (OSError, UnicodeDecodeError):
        return None
    return found.group(1).upper() if found else None


class TURNING_OT_apply_figure_preset(bpy.types.Operator):
    """Apply a sport preset to the active figure (its body and limits); a preset of another sport
    is refused: the figure's rig is that of its own sport"""

    bl_idname = "turning.apply_figure_preset"
    bl_label = "Apply Figure Preset"
    bl_options = {"REGISTER", "UNDO"}

    filepath: StringProperty(subtype="FILE_PATH", options={"SKIP_SAVE", "HIDDEN"})

    @classmethod
    def poll(cls, context):
        return _poll_figure_object(cls, context)

    def execute(self, context):
        fig = context.object
        sport = preset_sport(self.filepath)
        rig = fig.get(RIG_TAG)
        rig = rig.upper() if isinstance(rig, str) else fig.turning.sport
        if sport is not None and sport != rig:
            self.report({"ERROR"}, f"{fig.name} is a {sport_label(rig)} rig; a "
                                   f"{sport_label(sport)} preset would not change its rig: add a "
                                   f"new figure with Add Figure > {sport_label(sport)}")
            return {"CANCELLED"}
        return bpy.ops.script.execute_preset(filepath=self.filepath,
                                             menu_idname=TURNING_MT_figure_presets.__name__)


class TURNING_MT_figure_presets(bpy.types.Menu):
    bl_label = "Sport Presets"
    preset_subdir = PRESET_SUBDIR
    preset_operator = TURNING_OT_apply_figure_preset.bl_idname
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
        return _poll_figure_object(cls, context)


classes = (TURNING_OT_apply_figure_preset, TURNING_MT_figure_presets,
           TURNING_OT_figure_preset_add)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.utils.register_preset_path(PRESET_ROOT)


def unregister():
    bpy.utils.unregister_preset_path(PRESET_ROOT)
    _unregister()
