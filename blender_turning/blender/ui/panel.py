"""The sidebar tab "Turning" in the 3D viewport.

``VIEW3D_PT_turning`` (Add Figure, the sport presets) holds one sub-panel per group of settings,
each a :class:`FigurePanel` (``bl_parent_id`` the root, ``use_property_split``): Turns, Bake,
Body, Limits, Ground, Follow Path, and Rig.  Rig (``VIEW3D_PT_turning_rig``) also shows for an
armature that is not a figure yet; modules of their own hang their panels under it
(``bl_parent_id = RIG_PANEL``) and register after this one.
"""
from __future__ import annotations

import bpy

from ...core.sports import sport as sport_record
from ..anim import bake, bake_layers
from ..jobs import live, model_notes
from ..scene.figure_context import context_figure, selected_figures
from ..registry_items import sport_label

ROOT_PANEL = "VIEW3D_PT_turning"
RIG_PANEL = "VIEW3D_PT_turning_rig"


class TurningPanel:
    """Where every Turning panel lives."""

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
        row.menu("TURNING_MT_figure_presets", text=sport_label(fig.turning.sport))
        row.operator("turning.figure_preset_add", text="", icon="ADD")
        row.operator("turning.figure_preset_add", text="", icon="REMOVE").remove_active = True


class FigurePanel(TurningPanel):
    """A sub-panel of the root showing settings of the active figure (``obj.turning``)."""

    bl_parent_id = ROOT_PANEL

    @classmethod
    def poll(cls, context):
        return context_figure(context) is not None

    def settings(self, context):
        self.layout.use_property_split = True
        self.layout.use_property_decorate = True     # the keyframe dots of animatable settings
        return context_figure(context).turning

    def draw_props(self, context, names):
        s = self.settings(context)
        col = self.layout.column()
        for name in names:
            col.prop(s, name)
        return s, col


class VIEW3D_PT_turning_controller(FigurePanel, bpy.types.Panel):
    bl_label = "Turns"

    def draw(self, context):
        s, col = self.draw_props(context, ("period", "lean"))
        turn = model_notes.panel_turn(context_figure(context), context.scene)
        if turn is not None and turn.limited:      # what a bake will lean to, and why
            for line, icon in zip(model_notes.panel_text(turn), ("ERROR", "NONE")):
                col.label(text=line, icon=icon)
        row = col.row(heading="Heading")
        row.prop(s, "use_heading", text="")
        sub = row.row()
        sub.active = s.use_heading
        sub.prop(s, "heading", text="")
        col.prop(s, "speed")


class VIEW3D_PT_turning_bake(FigurePanel, bpy.types.Panel):
    bl_label = "Bake"

    def draw(self, context):
        layout = self.layout
        scene = context.scene
        text = f"Scene frames {scene.frame_start}-{scene.frame_end}"
        if scene.use_preview_range:
            text += f", preview {scene.frame_preview_start}-{scene.frame_preview_end}"
        layout.label(text=text, icon="TIME")
        count = len(selected_figures(context))
        row = layout.row(align=True)
        row.operator("turning.bake_turns", icon="REC",
                     text="Bake Turns" if count < 2 else f"Bake {count} Figures")
        row.operator_menu_enum("turning.bake_turns", "frame_range", text="", icon="PREVIEW_RANGE")
        row.operator("turning.clear_bake", text="", icon="TRASH")
        fig = context_figure(context)
        draw_live(layout, fig, count)
        layout.prop(fig.turning, "show_foot_track")
        draw_layers(layout, fig)


#: Icon per layer kind (:func:`.bake.layers`).
LAYER_ICONS = {"TWEAKS": "GREASEPENCIL", "BAKE": "NLA", "USER": "ACTION"}


def draw_layers(layout, fig) -> None:
    """The figure's animation layers, top first, and Start Tweak Layer when it has none playing."""
    rows = bake.layers(fig)
    if not rows:
        return
    box = layout.box()
    box.label(text="Layers (top first)")
    for kind, name, state in rows:
        box.label(text=f"{kind.title()}: {name} ({state})", icon=LAYER_ICONS[kind])
    tweaks = bake_layers.tweak_layer(fig)[0]
    if bake.figure_action(fig) is not None and not bake_layers.playing(fig, tweaks):
        box.operator("turning.start_tweaks", icon="ADD")


def draw_live(layout, fig, count: int) -> None:
    """Live Preview's switch (for the selection when several figures are selected) and, when the
    figure's settings make it fail, why and where it falls."""
    row = layout.row(align=True)
    row.prop(fig.turning, "live", toggle=True, icon="PLAY" if fig.turning.live else "PAUSE")
    if count > 1:
        row.operator("turning.live_preview", text=f"All {count}", icon="GROUP")
    failure = live.FAILURES.get(fig.name) if fig.turning.live else None
    if failure is not None:
        col = layout.column(align=True)
        col.alert = True
        if failure.frame is not None:
            col.label(text=f"Falls at frame {failure.frame}: the last good bake stays",
                      icon="ERROR")
        else:
            col.label(text="Cannot bake these settings: the last good bake stays", icon="ERROR")
        col.label(text=failure.message)


class VIEW3D_PT_turning_body(FigurePanel, bpy.types.Panel):
    bl_label = "Body"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        self.draw_props(context, ("mass", "com_height", "inertia"))


class VIEW3D_PT_turning_limits(FigurePanel, bpy.types.Panel):
    bl_label = "Limits"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        self.draw_props(context, ("curvature_max", "curvature_rate_max", "fall_angle"))


class VIEW3D_PT_turning_ground(FigurePanel, bpy.types.Panel):
    bl_label = "Ground"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s, col = self.draw_props(context, ("start", "start_heading", "ground"))
        sub = col.column()
        sub.active = s.ground is not None          # they act on a Ground mesh only
        for name in ("friction", "drag_area", "air_density"):
            sub.prop(s.terrain, name)


class VIEW3D_PT_turning_speed(FigurePanel, bpy.types.Panel):
    """Speed control (docs/skidding.md): the Target Speed, how the figure brakes, a stop."""

    bl_label = "Speed Control"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = self.settings(context)
        col = self.layout.column()
        row = col.row()
        row.active = s.ground is not None         # a target needs a Ground mesh
        row.prop(s.terrain, "target_speed")
        k = s.skid
        record = sport_record(s.sport)
        col.prop(k, "style")
        snow = col.row()
        snow.active = record.grip is None          # a tyre has no snow
        snow.prop(k, "snow")
        col.prop(k, "grip")
        col.prop(k, "use_stop")
        sub = col.column()
        sub.active = k.use_stop
        sub.prop(k, "stop_frame")
        if "slip" in record.styles:
            col.prop(k, "stop_side")


class VIEW3D_PT_turning_path(FigurePanel, bpy.types.Panel):
    bl_label = "Follow Path"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        self.draw_props(context, ("path", "obstacles", "plan_curvature_rate"))
        self.layout.operator("turning.follow_path", icon="CURVE_PATH")


class VIEW3D_PT_turning_rig(FigurePanel, bpy.types.Panel):
    """The figure's armature; also shown for an armature that is not a figure yet."""

    bl_label = "Rig"
    bl_options = {"DEFAULT_CLOSED"}

    @classmethod
    def poll(cls, context):
        obj = getattr(context, "active_object", None)
        return context_figure(context) is not None or (obj is not None and obj.type == "ARMATURE")

    def draw(self, context):
        fig = context_figure(context)
        obj = fig or context.active_object
        text = (f"{obj.name}: {fig.turning.sport.title()} figure, {len(obj.data.bones)} bones"
                if fig is not None else f"{obj.name} is not a turning figure")
        self.layout.label(text=text, icon="ARMATURE_DATA")


classes = (VIEW3D_PT_turning, VIEW3D_PT_turning_controller, VIEW3D_PT_turning_bake,
           VIEW3D_PT_turning_body, VIEW3D_PT_turning_limits, VIEW3D_PT_turning_ground,
           VIEW3D_PT_turning_speed, VIEW3D_PT_turning_path, VIEW3D_PT_turning_rig)
register, unregister = bpy.utils.register_classes_factory(classes)
