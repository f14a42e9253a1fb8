"""The Turning tab's Crowd sub-panel: the figure's start offset, first turn and
planning order, Add Crowd from it, and what Bake Turns / Follow Path will do (the selection, or
the active Crowd collection's figures; for Follow Path, the order the figures plan in when they
avoid each other)."""
from __future__ import annotations

import bpy

from ..jobs.crowd_job import follow_figures, planning_order
from ..scene.figure_context import crowd_collection, selected_figures
from .panel import FigurePanel


class VIEW3D_PT_turning_crowd(FigurePanel, bpy.types.Panel):
    bl_label = "Crowd"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        s = self.settings(context)
        col = self.layout.column()
        col.prop(s.crowd, "time_offset")
        col.prop(s.crowd, "first_turn")
        col.prop(s.crowd, "priority")
        self.layout.operator_menu_enum("turning.add_crowd", "formation", text="Add Crowd",
                                       icon="COMMUNITY")
        coll = crowd_collection(context)
        count = len(selected_figures(context))
        where = f"collection {coll.name!r}" if coll is not None and count else "the selection"
        self.layout.label(text=f"Bake and Follow Path act on {count} figure"
                               f"{'s' if count != 1 else ''} ({where})", icon="INFO")
        paths = follow_figures(context)
        if len(paths) > 1:
            self.layout.label(text="Follow Path plans: " + ", ".join(planning_order(paths)),
                              icon="SORTSIZE")


classes = (VIEW3D_PT_turning_crowd,)
register, unregister = bpy.utils.register_classes_factory(classes)
