"""Start Tweak Layer: the figure's active action becomes its tweak layer, above the bake
(:mod:`.bake_layers`, docs/layers.md)."""
from __future__ import annotations

import bpy

from ..anim import bake, bake_layers
from ..scene.figure_context import context_figure, poll_figure


class TURNING_OT_start_tweaks(bpy.types.Operator):
    """Key tweaks on a layer above the bake (its active action, blended in Combine mode): the
    keys are offsets on the baked motion and survive every rebake and Clear Bake"""

    bl_idname = "turning.start_tweaks"
    bl_label = "Start Tweak Layer"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not poll_figure(cls, context):
            return False
        fig = context_figure(context)
        if fig is None or bake.figure_action(fig) is None:
            cls.poll_message_set("Bake the figure first: the tweak layer sits above its bake")
            return False
        if bake_layers.playing(fig, bake_layers.tweak_layer(fig)[0]):
            cls.poll_message_set("The tweak layer is already the figure's active action")
            return False
        return True

    def execute(self, context):
        fig = context_figure(context)
        try:
            action = bake_layers.start_tweaks(fig)
        except ValueError as exc:
            self.report({"ERROR"}, f"Start Tweak Layer: {exc}; unassign it in the Action "
                                   "Editor (or push it down onto the NLA) first")
            return {"CANCELLED"}
        self.report({"INFO"}, f"{fig.name}: keys now go to {action.name!r}, above the bake")
        return {"FINISHED"}


classes = (TURNING_OT_start_tweaks,)
register, unregister = bpy.utils.register_classes_factory(classes)
