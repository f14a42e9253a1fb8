"""Sport presets: one per registered sport, from its record (core/sports.py), and the user's own
through Blender's preset system.

The Sport Presets menu lists every registered sport first (its record's body, limits and
planner rate: nothing is stored in a file, so a sport registered by a script is there too), then
the sports' own presets with their equipment (the racers, the carver: core/equipment.py; each
applies to a figure of its sport), then the presets users save with the "+" button (preset scripts
in their ``presets/turning_figure/``, next to Blender's other presets).
"""
from __future__ import annotations

import re
from pathlib import Path

import bpy
from bl_operators.presets import AddPresetBase
from bpy.props import StringProperty

from ...core.registry import SPORT_PRESETS, SPORTS
from ...core.controllers.speed_habits import habit_of
from ..registry_items import sport_label
from ..scene.rig_builder import RIG_TAG

PRESET_SUBDIR = "turning_figure"
PRESET_VALUES = ["settings.sport", "settings.mass", "settings.com_height", "settings.inertia",
                 "settings.speed", "settings.curvature_max", "settings.curvature_rate_max",
                 "settings.fall_angle", "settings.plan_curvature_rate",
                 "settings.equipment.preset"]
"""What a saved preset stores: the sport, the body, the limits, the planner's rate and the
equipment (a racer's skis: ``settings.equipment.preset``, '' for the sport's own)."""


def _poll_figure_object(cls, context) -> bool:
    obj = context.object
    if obj is None or not getattr(getattr(obj, "turning", None), "is_figure", False):
        cls.poll_message_set("Select a figure's armature")
        return False
    return True


_SPORT_LINE = re.compile(r"""^settings\.sport\s*=\s*['"](\w+)['"]""", re.MULTILINE)


def sport_preset_values(sport: str) -> dict:
    """``PRESET_VALUES`` (without ``settings.``) of the sport's own preset, from its record, or
    of a sport's preset (``SLALOM_RACER``: core/equipment.py), with its sport and equipment."""
    from ..props.figure import BODY_FIELDS, LIMIT_FIELDS
    own = SPORT_PRESETS.get(sport.lower())
    record = own if own is not None else SPORTS.lookup(sport.lower())
    key = SPORTS[own.sport].key if own is not None else record.key
    values = {"sport": key, "plan_curvature_rate": record.plan_curvature_rate,
              "equipment.preset": own.name if own is not None else ""}
    values.update({s: getattr(record.figure.body, f) for s, f in BODY_FIELDS.items()})
    values.update({s: getattr(record.figure.limits, f) for s, f in LIMIT_FIELDS.items()})
    return {v.split(".", 1)[1]: values[v.split(".", 1)[1]] for v in PRESET_VALUES}


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
    sport: StringProperty(name="Sport", options={"SKIP_SAVE", "HIDDEN"},
                          description="A registered sport's own preset, or a sport's preset "
                                      "with its equipment (instead of a file)")

    @classmethod
    def poll(cls, context):
        return _poll_figure_object(cls, context)

    def execute(self, context):
        fig = context.object
        if self.sport:
            try:
                values = sport_preset_values(self.sport)
            except ValueError as exc:
                self.report({"ERROR"}, f"Apply Figure Preset: {exc}")
                return {"CANCELLED"}
            sport = values["sport"]
        else:
            values, sport = None, preset_sport(self.filepath)
        rig = fig.get(RIG_TAG)
        rig = rig.upper() if isinstance(rig, str) else fig.turning.sport
        if sport is not None and sport != rig:
            self.report({"ERROR"}, f"{fig.name} is a {sport_label(rig)} rig; a "
                                   f"{sport_label(sport)} preset would not change its rig: add a "
                                   f"new figure with Add Figure > {sport_label(sport)}")
            return {"CANCELLED"}
        if values is None:
            # A file saved before presets stored the equipment sets none: the sport's own.
            before = fig.turning.equipment.preset
            fig.turning.equipment.preset = ""
            done = set()
            try:
                done = bpy.ops.script.execute_preset(
                    filepath=self.filepath, menu_idname=TURNING_MT_figure_presets.__name__)
            finally:
                if done != {"FINISHED"}:
                    fig.turning.equipment.preset = before
            return done
        for name, value in values.items():
            owner, _, attr = name.rpartition(".")
            setattr(getattr(fig.turning, owner) if owner else fig.turning, attr, value)
        habit = habit_of(self.sport.lower())        # the beginner's wedge at 4.5 m/s ...
        if habit is not None:
            fig.turning.skid.style = habit.style.upper()
            fig.turning.terrain.target_speed = habit.target_speed
        return {"FINISHED"}


class TURNING_MT_figure_presets(bpy.types.Menu):
    """Every registered sport's preset, then the user's saved presets."""

    bl_label = "Sport Presets"
    preset_subdir = PRESET_SUBDIR
    preset_operator = TURNING_OT_apply_figure_preset.bl_idname

    def draw(self, context):
        layout = self.layout
        for record in SPORTS.values():
            layout.operator(self.preset_operator, text=record.label,
                            icon=record.icon).sport = record.key
        if SPORT_PRESETS:
            layout.separator()
            for record in SPORT_PRESETS.values():
                layout.operator(self.preset_operator, text=record.label,
                                icon=SPORTS[record.sport].icon).sport = record.name.upper()
        if any(Path(p).is_dir() and any(Path(p).glob("*.py"))
               for p in bpy.utils.preset_paths(PRESET_SUBDIR)):
            layout.separator()
            bpy.types.Menu.draw_preset(self, context)


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
register, unregister = bpy.utils.register_classes_factory(classes)
