"""The sidebar tab "Turning" in the 3D viewport: figure, controller, bake and Follow Path."""
from __future__ import annotations

import bpy

from . import bake
from .ops_common import context_figure


class TurningPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Turning"


class VIEW3D_PT_turning(TurningPanel, bpy.types.Panel):
    bl_label = "Turning"

    def draw(self, context):
        layout = self.layout
        layout.operator_menu_enum("turning.add_figure", "sport", text="Add Figure", icon="ADD")
        fig = context_figure(context)
        if fig is None:
            layout.label(text="Select a figure, or add one", icon="INFO")
            return
        row = layout.row(align=True)
        row.menu("TURNING_MT_figure_presets", text=fig.turning.sport.title())
        row.operator("turning.figure_preset_add", text="", icon="ADD")
        row.operator("turning.figure_preset_add", text="", icon="REMOVE").remove_active = True


class _FigurePanel(TurningPanel):
    bl_parent_id = "VIEW3D_PT_turning"

    @classmethod
    def poll(cls, context):
        return context_figure(context) is not None

    def settings(self, context):
        self.layout.use_property_split = True
        self.layout.use_property_decorate = True     # the keyframe dots: these are animatable
        return context_figure(context).turning


class VIEW3D_PT_turning_controller(_FigurePanel, bpy.types.Panel):
    bl_label = "Turns"

    def draw(self, context):
        s = self.settings(context)
        col = self.layout.column()
        col.prop(s, "period")
        col.prop(s, "lean")
        row = col.row(heading="Heading")
        row.prop(s, "use_heading", text="")
        sub = row.row()
        sub.active = s.use_heading
        sub.prop(s, "heading", text="")


class VIEW3D_PT_turning_body(_FigurePanel, bpy.types.Panel):
    bl_label = "Body and Limits"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = self.settings(context)
        col = self.layout.column()
        for name in ("mass", "com_height", "inertia", "speed"):
            col.prop(s, name)
        col.separator()
        for name in ("curvature_max", "curvature_rate_max", "fall_angle"):
            col.prop(s, name)
        col.separator()
        col.prop(s, "start")
        col.prop(s, "start_heading")


class VIEW3D_PT_turning_bake(_FigurePanel, bpy.types.Panel):
    bl_label = "Bake"

    def draw(self, context):
        fig = context_figure(context)
        layout = self.layout
        scene = context.scene
        layout.label(text=f"Frames {scene.frame_start}-{scene.frame_end}", icon="TIME")
        row = layout.row(align=True)
        row.operator("turning.bake_turns", icon="REC")
        row.operator("turning.clear_bake", text="", icon="TRASH")
        layout.prop(fig.turning, "show_foot_track")
        action = bake.figure_action(fig)
        if action is not None:
            layout.label(text=f"Action: {action.name}", icon="ACTION")


class VIEW3D_PT_turning_path(_FigurePanel, bpy.types.Panel):
    bl_label = "Follow Path"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = self.settings(context)
        layout = self.layout
        layout.prop(s, "path")
        layout.prop(s, "obstacles")
        layout.prop(s, "plan_curvature_rate")
        layout.operator("turning.follow_path", icon="CURVE_PATH")


classes = (VIEW3D_PT_turning, VIEW3D_PT_turning_controller, VIEW3D_PT_turning_body,
           VIEW3D_PT_turning_bake, VIEW3D_PT_turning_path)
register, unregister = bpy.utils.register_classes_factory(classes)
