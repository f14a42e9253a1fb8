"""``turning.make_figure`` and ``turning.remove_figure``: the user's own armature as a figure,
and back."""
from __future__ import annotations

import math

import bpy
from bpy.props import EnumProperty

from ...core.physics.params import PRESETS
from ...core.errors import TurningError
from ...mapping.retarget.stance import STANCES as RIG_STANCES
from ...mapping.retarget.user_rig import fit_rig
from ..anim import bake, bake_layers, export_ready, export_state, foot_track
from ..scene import retarget_adapter as ra
from ..registry_items import retargeted_sport_items
from ..props.rig import BONE_MAPS, STANCES
from ..scene.scene_adapters import settings_from_preset


def _active_armature(cls, context):
    if context.mode != "OBJECT":
        cls.poll_message_set("Switch to Object Mode first")
        return None
    obj = getattr(context, "active_object", None)
    if obj is None or obj.type != "ARMATURE":
        cls.poll_message_set("Select your armature (make it the active object)")
        return None
    return obj


class TURNING_OT_make_figure(bpy.types.Operator):
    """Make the active armature (your own rig) a turning figure of a sport: its bones play our
    joints through a bone map, and the sport's equipment is added, tied to it"""

    bl_idname = "turning.make_figure"
    bl_label = "Make Figure"
    bl_options = {"REGISTER", "UNDO"}

    sport: EnumProperty(name="Sport", items=retargeted_sport_items, default=0)
    bone_map: EnumProperty(name="Bone Map", items=BONE_MAPS, default="AUTO",
                           description="Which bone of your rig plays each of our joints")
    stance: EnumProperty(name="Stance", items=STANCES, default="REGULAR",
                         description="Snowboarder: which foot is forward")

    @classmethod
    def poll(cls, context):
        obj = _active_armature(cls, context)
        if obj is None:
            return False
        if ra.is_figure(obj):
            cls.poll_message_set("The active armature is already a figure")
            return False
        return True

    def execute(self, context):
        obj = context.active_object
        try:
            ra.check_transform(obj)
            bm = ra.resolve_bone_map(obj, self.bone_map)
            sport = self.sport.lower()
            mirror = self.stance == "GOOFY" and sport in RIG_STANCES
            fit = fit_rig(ra.user_rig(obj), bm, sport, mirror)
        except (ValueError, TurningError) as exc:
            self.report({"ERROR"}, f"Make Figure: {exc}")
            return {"CANCELLED"}
        s = obj.turning
        had_state_props = [p for p in obj.keys() if p.startswith("turn_")]
        if had_state_props:
            self.report({"ERROR"}, f"Make Figure: {obj.name} already has the add-on's state "
                                   f"properties {', '.join(had_state_props)}")
            return {"CANCELLED"}
        rig = s.rig
        rig.bone_map = "CUSTOM" if bm.name == "custom" else bm.name.upper()
        rig.stance = "GOOFY" if mirror else "REGULAR"
        ra.save_state(obj, bm)
        s.is_figure = True
        rig.is_user_rig = True
        settings_from_preset(s, self.sport)
        # Body from the rig's proportions: the centre of mass scales with the legs (k, the size
        # the retargeting measures); mass with height squared (a constant body-mass index).
        body = PRESETS[sport].body
        s.com_height = body.l * fit.k
        s.mass = body.m * fit.k ** 2
        heading = obj.rotation_euler[2] + fit.travel
        s.start = obj.location
        s.start_heading = heading
        s.heading = heading
        ra.apply_rig_settings(obj, bm)
        ra.build_equipment(context, obj, bm)
        chosen = f"the {bm.label!r} bone map" + (" (chosen by AUTO)" if self.bone_map == "AUTO"
                                                  else "")
        self.report({"INFO"}, f"{obj.name} is a {self.sport.lower()} figure with {chosen}; it "
                              f"faces {math.degrees(fit.facing):.0f} deg, {fit.k:.2f}x the "
                              f"built-in figure")
        return {"FINISHED"}


class TURNING_OT_remove_figure(bpy.types.Operator):
    """Give your armature back exactly as it was: remove the bake, the equipment and the figure
    settings"""

    bl_idname = "turning.remove_figure"
    bl_label = "Remove Figure"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = _active_armature(cls, context)
        if obj is None:
            return False
        if not ra.is_user_rig(obj):
            cls.poll_message_set("The active armature is not a figure made from your rig")
            return False
        return True

    def execute(self, context):
        obj = context.active_object
        tweaks = remove_user_figure(obj)
        kept = (f"; your tweaks are kept in the action {tweaks!r} (fake user)" if tweaks
                else "")
        self.report({"INFO"}, f"{obj.name} is your rig again{kept}")
        return {"FINISHED"}


def remove_user_figure(obj) -> str | None:
    """Clear the bake and the foot track, remove the equipment, restore the rig and drop the
    figure settings.  Returns the name of the action a tweak layer with keys is kept in (off
    the rig, :func:`.bake_layers.keep_in_file`), or ``None``."""
    export_ready.clear_equipment(obj)
    export_state.clear_state(obj)
    bake.clear_bake(obj)
    tweaks = bake_layers.keep_in_file(obj)
    foot_track.remove_foot_track(obj)
    ra.remove_equipment(obj)
    ra.restore_state(obj)
    for prop in [p for p in obj.keys() if p.startswith("turn_")]:    # ours (Make Figure
        del obj[prop]                                                 # refuses a rig with any)
    obj.property_unset("turning")
    return tweaks


classes = (TURNING_OT_make_figure, TURNING_OT_remove_figure)
register, unregister = bpy.utils.register_classes_factory(classes)
