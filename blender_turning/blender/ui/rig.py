"""The Turning tab's "Your Rig" sub-panel, under Rig: make the active armature a figure, its bone
map (a custom one edited as a list: our joint -> your bone, with a bone picker, saved and loaded
as presets), remove it."""
from __future__ import annotations

import bpy

from ...mapping.retarget.stance import STANCES
from ..scene import retarget_adapter as ra
from .panel import RIG_PANEL, TurningPanel


class TURNING_UL_bone_map(bpy.types.UIList):
    """Rows of the custom bone map: our joint, and a picker among the armature's bones."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_prop, index=0):
        arm = data.id_data.data if data.id_data.type == "ARMATURE" else None
        row = layout.row(align=True)
        row.label(text=item.name)
        if arm is not None:
            row.prop_search(item, "bone", arm, "bones", text="")
        else:
            row.prop(item, "bone", text="")


class VIEW3D_PT_turning_your_rig(TurningPanel, bpy.types.Panel):
    bl_label = "Your Rig"
    bl_parent_id = RIG_PANEL
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return obj is not None and obj.type == "ARMATURE" and (
            not ra.is_figure(obj) or ra.is_user_rig(obj))

    def draw(self, context):
        layout = self.layout
        obj = context.active_object
        rig = obj.turning.rig
        if not ra.is_figure(obj):
            layout.label(text=f"Make {obj.name} a figure:", icon="ARMATURE_DATA")
            row = layout.row(align=True)
            row.operator_menu_enum("turning.make_figure", "sport", text="Make Figure",
                                        icon="ADD")
            layout.separator()
            layout.label(text="Custom bone map (optional):")
            row = layout.row(align=True)
            row.operator_menu_enum("turning.custom_map_from", "source",
                                   text="Start From a Shipped Map")
            row.operator_menu_enum("turning.custom_map_load", "preset", text="", icon="PRESET")
            if len(rig.custom_map):
                layout.template_list("TURNING_UL_bone_map", "", rig, "custom_map", rig,
                                     "custom_index", rows=6)
                row = layout.row(align=True)
                row.operator("turning.make_figure", text="Make Figure (Custom Map)").bone_map = (
                    "CUSTOM")
                row.operator("turning.custom_map_save", text="", icon="FILE_TICK")
            return
        col = layout.column()
        col.label(text=f"Bone map: {rig.bone_map.title()}", icon="BONE_DATA")
        if ra.mirrored(obj) or obj.turning.sport.lower() in STANCES:
            col.label(text=f"Stance: {rig.stance.title()}")
        if rig.equipment is not None:
            col.label(text=f"Equipment: {rig.equipment.name}", icon="OUTLINER_COLLECTION")
        layout.operator("turning.remove_figure", icon="X")


class VIEW3D_PT_turning_stance(TurningPanel, bpy.types.Panel):
    """The stance of a built-in figure of a sport ridden either way round (the snowboarder; a
    figure made from your rig shows it under Your Rig)."""

    bl_label = "Stance"
    bl_parent_id = RIG_PANEL

    @classmethod
    def poll(cls, context):
        obj = context.active_object
        return (ra.is_figure(obj) and not ra.is_user_rig(obj)
                and obj.turning.sport.lower() in STANCES)

    def draw(self, context):
        self.layout.use_property_split = True
        self.layout.prop(context.active_object.turning.rig, "stance")


classes = (TURNING_UL_bone_map, VIEW3D_PT_turning_your_rig, VIEW3D_PT_turning_stance)
register, unregister = bpy.utils.register_classes_factory(classes)
