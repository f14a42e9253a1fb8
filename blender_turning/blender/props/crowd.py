"""A figure's place in a crowd: ``Object.turning.crowd``.

A nested group of the figure's settings (one ``PointerProperty`` in :mod:`.props`), set by Add
Crowd (:mod:`.ops_crowd`) and editable by hand: when the figure starts on the scene's clock and
which way its first turn goes (the bake, :mod:`.pipeline`, and Follow Path read both), and its
place in Follow Path's planning order when figures avoid each other (:mod:`.crowd_job`).  Ranges
are the crowd scene file's (``core.ranges.CROWD_RANGES``), so a value typed here is held to the
bounds a crowd file is (the planning order's: ``core.ranges``' ``crowd_priority``).
"""
from __future__ import annotations

import bpy
from bpy.props import EnumProperty, FloatProperty, IntProperty

from ...core.ranges import RANGES
from ...core.ranges import CROWD_RANGES

FIRST_TURNS = (
    ("LEFT", "Left", "The first turn goes left (phase 0: the lean rate starts positive)"),
    ("RIGHT", "Right", "The first turn goes right: the mirror image about the Start Direction "
                       "(phase 180 deg, the antiphase of a synchronised pair)"),
)
_STATIC = set()


class TurningCrowdSettings(bpy.types.PropertyGroup):
    time_offset: FloatProperty(
        name="Start Offset", default=0.0, min=CROWD_RANGES["time_offset"].lo,
        max=CROWD_RANGES["time_offset"].hi, soft_max=60.0, unit="TIME_ABSOLUTE",
        options=_STATIC,
        description="When the figure starts, in seconds after the first frame of the bake: it "
                    "stands at its Start until then, then runs its turns (keyed settings "
                    "are read on its own clock, so a follower replays its leader's keys)")
    first_turn: EnumProperty(name="First Turn", items=FIRST_TURNS, default="LEFT",
                             options=_STATIC,
                             description="Which way the first turn goes (Bake Turns)")
    priority: IntProperty(
        name="Planning Order", default=0, min=int(RANGES["crowd_priority"].lo),
        max=int(RANGES["crowd_priority"].hi), soft_min=0, soft_max=100, options=_STATIC,
        description="Follow Path on several figures that avoid each other plans them in "
                    "this order (lower first, equal numbers by name): each plans around the "
                    "figures before it, so the first goes its way as if alone and the later "
                    "ones give way")


classes = (TurningCrowdSettings,)
register, unregister = bpy.utils.register_classes_factory(classes)
