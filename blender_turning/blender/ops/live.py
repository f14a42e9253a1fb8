"""``turning.refresh_preview`` and ``turning.live_preview``: run every pending Live Preview
re-bake now, and switch Live Preview for every selected figure (:mod:`.live`)."""
from __future__ import annotations

import bpy
from bpy.props import EnumProperty

from ..jobs import live
from ..scene.figure_context import poll_figure, selected_figures


class TURNING_OT_refresh_preview(bpy.types.Operator):
    """Re-bake every figure whose Live Preview waits for a re-bake, now (the interface's timer
    does the same by itself)"""

    bl_idname = "turning.refresh_preview"
    bl_label = "Refresh Live Preview"
    # No undo step: as the interface's timer, a re-bake follows the change that made it pending
    # (whose undo step gives back the bake before it).
    bl_options = {"REGISTER"}

    def execute(self, context):
        pending = len(live.pending_figures(context.scene))
        try:
            results = live.refresh(context.scene)
        except ValueError as exc:            # the scene's frame range
            self.report({"ERROR"}, f"Refresh Live Preview: {exc}")
            return {"CANCELLED"}
        failed = {name: f for name, f in results.items() if f is not None}
        for name, f in failed.items():
            where = f" (falls at frame {f.frame})" if f.frame is not None else ""
            self.report({"WARNING"}, f"Live Preview: {name}{where}: {f.message}; the last good "
                                     "bake stays")
        if not failed:
            self.report({"INFO"}, f"Live Preview: re-baked {len(results)} of {pending} pending "
                                  "figure(s)")
        return {"FINISHED"}


class TURNING_OT_live_preview(bpy.types.Operator):
    """Switch Live Preview for every selected figure: on, each is re-baked whenever one of its
    settings, keys, its Path, obstacles or Ground change"""

    bl_idname = "turning.live_preview"
    bl_label = "Live Preview"
    bl_options = {"REGISTER", "UNDO"}

    action: EnumProperty(name="Action", default="TOGGLE", options={"SKIP_SAVE"},
                         items=(("TOGGLE", "Toggle", "The opposite of the active figure's"),
                                ("ON", "On", "Switch it on"), ("OFF", "Off", "Switch it off")),
                         description="What to do with the selected figures' Live Preview")

    @classmethod
    def poll(cls, context):
        return poll_figure(cls, context)

    def execute(self, context):
        figs = selected_figures(context)
        on = {"ON": True, "OFF": False}.get(self.action, not figs[0].turning.live)
        for fig in figs:
            fig.turning.live = on
        self.report({"INFO"}, f"Live Preview {'on' if on else 'off'} for "
                              f"{', '.join(f.name for f in figs)}")
        return {"FINISHED"}


classes = (TURNING_OT_refresh_preview, TURNING_OT_live_preview)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    live.register()


def unregister():
    live.unregister()
    _unregister()
