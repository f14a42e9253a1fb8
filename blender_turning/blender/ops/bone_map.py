"""The custom bone map: start it from a shipped map, save it as a preset (a JSON file
in the user's presets folder, the format of ``rigs/bone_maps``) and load one back."""
from __future__ import annotations

import json
from pathlib import Path

import bpy
from bpy.props import EnumProperty, StringProperty

from ...mapping.retarget.bone_map import load_bone_map, parse_bone_map
from ..scene import retarget_adapter as ra

PRESET_DIR = "presets/turning_bone_maps"


def preset_dir(create: bool = False) -> Path:
    return Path(bpy.utils.user_resource("SCRIPTS", path=PRESET_DIR, create=create))


def _presets(self, context):
    folder = preset_dir()
    names = sorted(p.stem for p in folder.glob("*.json")) if folder.is_dir() else []
    return [(n, n, f"Bone map preset {n!r}") for n in names] or [("", "(none saved)", "")]


def _armature_poll(cls, context):
    obj = context.active_object
    if obj is None or obj.type != "ARMATURE":
        cls.poll_message_set("Select your armature")
        return False
    return True


class TURNING_OT_custom_map_from(bpy.types.Operator):
    """Fill the custom bone map from a shipped one (then edit the rows)"""

    bl_idname = "turning.custom_map_from"
    bl_label = "Start Custom Map"
    bl_options = {"REGISTER", "UNDO"}

    source: EnumProperty(name="From", items=[(k, k.title(), "") for k in ra.NAMED])

    @classmethod
    def poll(cls, context):
        return _armature_poll(cls, context)

    def execute(self, context):
        obj = context.active_object
        ra.fill_custom_map(obj, load_bone_map(ra.NAMED[self.source]))
        obj.turning.rig.bone_map = "CUSTOM"
        return {"FINISHED"}


class TURNING_OT_custom_map_save(bpy.types.Operator):
    """Save the custom bone map as a preset (our joint -> your bone)"""

    bl_idname = "turning.custom_map_save"
    bl_label = "Save Bone Map Preset"
    bl_options = {"REGISTER"}

    name: StringProperty(name="Name", default="My Rig")

    @classmethod
    def poll(cls, context):
        if not _armature_poll(cls, context):
            return False
        if not len(context.active_object.turning.rig.custom_map):
            cls.poll_message_set("The custom bone map is empty: start it from a shipped one")
            return False
        return True

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        name = self.name.strip()
        if not name or any(c in name for c in '/\\:*?"<>|'):
            self.report({"ERROR"}, f"Save Bone Map Preset: name = {self.name!r} must be a plain "
                                   f"file name")
            return {"CANCELLED"}
        rows = context.active_object.turning.rig.custom_map
        doc = {"name": name, "label": name, "joints": {r.name: r.bone for r in rows if r.bone}}
        try:
            parse_bone_map(doc, "custom map")
        except ValueError as exc:
            self.report({"ERROR"}, f"Save Bone Map Preset: {exc}")
            return {"CANCELLED"}
        path = preset_dir(create=True) / f"{name}.json"
        path.write_text(json.dumps(doc, indent=2) + "\n")
        self.report({"INFO"}, f"Saved the bone map preset {name!r} ({path})")
        return {"FINISHED"}


class TURNING_OT_custom_map_load(bpy.types.Operator):
    """Load a saved bone map preset into the custom bone map"""

    bl_idname = "turning.custom_map_load"
    bl_label = "Load Bone Map Preset"
    bl_options = {"REGISTER", "UNDO"}

    preset: EnumProperty(name="Preset", items=_presets)

    @classmethod
    def poll(cls, context):
        return _armature_poll(cls, context)

    def execute(self, context):
        path = preset_dir() / f"{self.preset}.json"
        try:
            bm = parse_bone_map(json.loads(path.read_text()), path.name)
        except (OSError, ValueError) as exc:
            self.report({"ERROR"}, f"Load Bone Map Preset: {exc}")
            return {"CANCELLED"}
        obj = context.active_object
        ra.fill_custom_map(obj, bm)
        obj.turning.rig.bone_map = "CUSTOM"
        return {"FINISHED"}


classes = (TURNING_OT_custom_map_from, TURNING_OT_custom_map_save, TURNING_OT_custom_map_load)
register, unregister = bpy.utils.register_classes_factory(classes)
