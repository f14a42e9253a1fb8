"""``turning.add_crowd``: a formation of figures from the active one as template; also
in the Add menu (Shift+A > Turning Figure > Add Crowd) and the Crowd panel.

The formation is the core's, by its record (:data:`..crowd.registry.FORMATIONS`: follow the
leader, synchronised, peloton, and any registered later), computed before anything is made, so
bad input is reported and the scene stays as it was.  The figures are linked duplicates of the
template (:mod:`.crowd_scene`) in a new "Crowd"
collection, selected, so Bake Turns (or Follow Path) then does the whole crowd.
"""
from __future__ import annotations

import math
import types

import bpy
import numpy as np
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

from ...core.errors import TurningError
from ...core.validate import check
from ...crowd.formations import FORMATIONS
from ...crowd import shot_length, stage
from ...core.ranges import CROWD_RANGES
from ..scene import crowd_scene
from ..scene.figure_context import context_figure, poll_figure, report_error
from ..registry_items import formation_items

STAGING = (
    ("ALONG_TRACK", "Along the Track",
     "Every figure moves from the first frame; a follower due later starts that far behind on "
     "the leader's line (a path follower on a straight lead-in to its path) and ends as far "
     "behind the leader's end"),
    ("WAIT", "Wait at the Start",
     "Each follower stands at the leader's start until its start offset (a path follower ends "
     "its gap behind the leader's end)"),
)
GAP_BY = (("TIME", "Time", "Each follower starts Gap seconds after the one before"),
          ("DISTANCE", "Distance", "Each follower starts Gap metres (at the leader's speed) "
                                   "behind the one before"))


def _r(key: str, **ui) -> dict:
    """The UI limits of a property from the crowd file's table of ranges (soft ones, so that a
    value a script passes outside them reaches :meth:`TURNING_OT_add_crowd._values` and is
    refused by name rather than clamped in silence); ``ui``: tighter soft limits for the
    slider."""
    r = CROWD_RANGES[key]
    return {"soft_min": r.lo, "soft_max": r.hi, **ui}


class TURNING_OT_add_crowd(bpy.types.Operator):
    """Add a crowd made from the active figure: followers of a leader, a synchronised pair or
    line, or a peloton, in a new Crowd collection"""

    bl_idname = "turning.add_crowd"
    bl_label = "Add Crowd"
    bl_options = {"REGISTER", "UNDO"}

    # The registered formations (crowd/registry.py), listed when drawn; default 0: follow the
    # leader.
    formation: EnumProperty(name="Formation", items=formation_items, default=0)
    count: IntProperty(name="Count", default=4, soft_min=1, soft_max=50,
                       description="How many figures the formation adds")
    gap_by: EnumProperty(name="Gap By", items=GAP_BY, default="TIME")
    gap_time: FloatProperty(name="Gap", default=1.5, **_r("gap_s", soft_max=10.0),
                            unit="TIME_ABSOLUTE",
                            description="Time between successive followers (s)")
    gap_distance: FloatProperty(name="Gap", default=6.0, **_r("gap_m", soft_max=50.0),
                                unit="LENGTH",
                                description="Distance between successive followers (m)")
    lateral: FloatProperty(name="Lateral Offset", default=0.0,
                           **_r("lateral_m", soft_min=-10.0, soft_max=10.0), unit="LENGTH",
                           description="How far to the left of the leader's track the "
                                       "followers go (m; negative: right)")
    alternate: BoolProperty(name="Alternate Sides", default=False,
                            description="Followers alternate right and left of the track by "
                                        "the Lateral Offset")
    seed: IntProperty(name="Seed", default=0, soft_min=0, max=2**31 - 1,
                      description="Draws the small random differences; the same seed makes "
                                  "the same crowd")
    body_jitter: FloatProperty(name="Body Differences", default=0.0, **_r("jitter"),
                               subtype="FACTOR",
                               description="Mass, centre-of-mass height and roll inertia each "
                                           "up to this fraction larger or smaller")
    timing_jitter: FloatProperty(name="Timing Differences", default=0.0,
                                 **_r("timing_jitter_s", soft_max=1.0), unit="TIME_ABSOLUTE",
                                 description="Start times up to this much earlier or later "
                                             "(s; at most half the gap)")
    period_jitter: FloatProperty(name="Period Differences", default=0.0, **_r("jitter"),
                                 subtype="FACTOR",
                                 description="Turn periods up to this fraction longer or "
                                             "shorter")
    spacing: FloatProperty(name="Spacing", default=3.0, **_r("spacing_m", soft_max=20.0),
                           unit="LENGTH", description="Distance between figures side by side")
    antiphase: BoolProperty(name="Antiphase", default=True,
                            description="Every other figure starts with the opposite turn")
    sync_gap: FloatProperty(name="Start Gap", default=0.0, **_r("sync_gap_s", soft_max=10.0),
                            unit="TIME_ABSOLUTE",
                            description="Each figure starts this long after the one before")
    abreast: IntProperty(name="Abreast", default=2, soft_min=1,
                         soft_max=int(CROWD_RANGES["abreast"].hi),
                         description="Riders in a row")
    row_spacing: FloatProperty(name="Row Spacing", default=0.8, **_r("spacing_m", soft_max=3.0),
                               unit="LENGTH",
                               description="Distance between riders of a row, centre to centre")
    row_gap: FloatProperty(name="Row Gap", default=2.0, **_r("gap_m", soft_max=20.0),
                           unit="LENGTH",
                           description="Distance between rows along the road, centre to centre "
                                       "(2 m: half a wheel between one bicycle and the next)")
    staging: EnumProperty(name="Staging", items=STAGING, default="ALONG_TRACK",
                          description="Where the followers are at the first frame")
    fit_range: BoolProperty(name="Fit Scene Range", default=True,
                            description="Lengthen the scene's frame range so that the last "
                                        "follower to start runs as long as the leader")

    @classmethod
    def poll(cls, context):
        return poll_figure(cls, context)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "formation")
        layout.prop(self, "count")
        record = FORMATIONS.get(self.formation.lower())
        for name in record.fields(self) if record is not None else ():
            layout.prop(self, name)
        layout.prop(self, "staging")
        row = layout.row()
        row.active = self.staging == "WAIT"
        row.prop(self, "fit_range")

    def _values(self) -> types.SimpleNamespace:
        """The settings as typed (a float property keeps float32: 0.05 is read back as
        0.0500000007; the shortest decimal that float32 holds is what was typed), each checked
        against the crowd's table of ranges (a script may pass any value)."""
        out = {}
        for name, key in (("count", "count"), ("gap_time", "gap_s"), ("gap_distance", "gap_m"),
                          ("lateral", "lateral_m"), ("seed", "seed"), ("body_jitter", "jitter"),
                          ("timing_jitter", "timing_jitter_s"), ("period_jitter", "jitter"),
                          ("spacing", "spacing_m"), ("sync_gap", "sync_gap_s"),
                          ("abreast", "abreast"), ("row_spacing", "spacing_m"),
                          ("row_gap", "gap_m")):
            v = getattr(self, name)
            if isinstance(v, float):
                v = float(np.format_float_positional(np.float32(v), unique=True, trim="0"))
            out[name] = check(name, v, CROWD_RANGES[key])
        for name in ("formation", "gap_by", "alternate", "antiphase", "staging", "fit_range"):
            out[name] = getattr(self, name)
        return types.SimpleNamespace(**out)

    @staticmethod
    def members(context, template, v) -> tuple:
        """``(template's member, the formation's members)``, the core's (nothing is made), for
        the settings ``v`` (:meth:`_values`), by the formation's record."""
        record = FORMATIONS.lookup(v.formation.lower())
        if record.template == "path" and template.turning.path is None:
            raise ValueError(f"{record.label}: the template has no path curve: set its Path "
                             "(Follow Path > Path) to the road")
        path = {"turns": False, "path": True}.get(record.template,
                                                 template.turning.path is not None)
        lead = crowd_scene.template_member(context, template, path=path)
        return lead, tuple(record.build(lead, v, "m"))

    @staticmethod
    def _path_object(template, lead, member, k, collection, v):
        """The member's path curve: the template's when it is the same path, else a new one."""
        path = member.controller.scene.path
        s_along = FORMATIONS.lookup(v.formation.lower()).start_along(k, v)
        if path is lead.controller.scene.path and s_along == 0.0:
            return template.turning.path
        return crowd_scene.curve_object(crowd_scene.path_from(path, s_along),
                                        f"{template.name} {k} Path",
                                        float(template.turning.start[2]), collection)

    @staticmethod
    def staged(template, lead, members, v) -> tuple:
        """``members`` staged as the render job stages them (:func:`..crowd.stage`)."""
        s = template.turning
        heading = float(s.heading) if s.use_heading else float(s.start_heading)
        return stage(lead, members, heading, v.staging.lower())

    @staticmethod
    def fitted_end(scene, lead, members, v):
        """The last frame the crowd needs (``None``: the scene's range already fits)."""
        if v.staging != "WAIT" or not v.fit_range:
            return None
        fps = scene.render.fps / scene.render.fps_base
        length = (scene.frame_end - scene.frame_start) / fps
        end = scene.frame_start + math.ceil(shot_length(lead, members, length) * fps - 1e-9)
        return end if end > scene.frame_end else None

    def execute(self, context):
        template = context_figure(context)
        try:
            v = self._values()
            lead, members = self.members(context, template, v)
            members = self.staged(template, lead, members, v)
            end = self.fitted_end(context.scene, lead, members, v)
        except (ValueError, TurningError) as exc:
            return report_error(self, "Add Crowd", template.name, exc)
        coll = crowd_scene.new_crowd_collection(context)
        figs = []
        led = FORMATIONS.lookup(v.formation.lower()).template == "leader"
        try:
            if led:
                coll.objects.link(template)          # the leader is one of the crowd
                figs.append(template)
            children = template.children_recursive
            for k, member in enumerate(members, start=1):
                path_obj = self._path_object(template, lead, member, k, coll, v) \
                    if member.is_path else None
                new = crowd_scene.duplicate_figure(template, f"{template.name} {k}", coll,
                                                   children)
                crowd_scene.place(new, member, template.turning.start, path_obj)
                figs.append(new)
        except Exception as exc:                     # a bug: take back what was made
            crowd_scene.remove_crowd(coll, keep=template)
            return report_error(self, "Add Crowd", template.name, exc)
        for obj in context.selected_objects:
            obj.select_set(False)
        if not led:                                  # a pattern, not one of the crowd
            crowd_scene.set_aside(template)
        for fig in figs:
            fig.select_set(True)
        context.view_layer.objects.active = figs[0]
        staged = "strung out along the track" if v.staging == "ALONG_TRACK" \
            else "waiting at the start"
        if not led:
            staged += f"; the template {template.name!r} is hidden, Alt+H shows it"
        if end is not None:
            context.scene.frame_end = end
            staged += f", the scene's range now ends at frame {end} to fit them"
        self.report({"INFO"}, f"Add Crowd: {len(figs)} figures in {coll.name!r} "
                              f"({FORMATIONS[v.formation.lower()].label.lower()}, {staged}); Bake "
                              "Turns or Follow Path now does them all")
        return {"FINISHED"}


def draw_add_menu(self, context):
    """Shift+A > Turning Figure > Add Crowd (from the active figure)."""
    self.layout.separator()
    self.layout.operator_menu_enum(TURNING_OT_add_crowd.bl_idname, "formation",
                                   text="Add Crowd", icon="COMMUNITY")


classes = (TURNING_OT_add_crowd,)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.VIEW3D_MT_turning_figure_add.append(draw_add_menu)


def unregister():
    bpy.types.VIEW3D_MT_turning_figure_add.remove(draw_add_menu)
    _unregister()
