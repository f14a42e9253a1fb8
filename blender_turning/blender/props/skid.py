"""How a figure brakes (``Object.turning.skid``, docs/skidding.md): its style, the snow, the grip,
a stop at a frame.  Read by :func:`.scene_adapters.skidding_from_settings`."""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

from ...core.ranges import RANGES

_STATIC = set()            # options: not animatable (the bake reads these once)

STYLE_ITEMS = [("CARVE", "Carve", "Brake by turning across the hill only (the paper's carved "
                "ski)", 0),
               ("SKID", "Skid", "Skid for what turning across the hill leaves of the Target "
                "Speed", 1),
               ("WEDGE", "Wedge", "Snowplough: both skis edged inward, tips together (skis)", 2),
               ("SLIP", "Side-Slip", "The board across the fall line, sliding down it (board)",
                3)]
SNOW_ITEMS = [("HARD", "Hard Pack", "Groomed snow: the edge holds up to about 1 g", 0),
              ("SOFT", "Soft Snow", "Soft snow gives way earlier: less grip", 1),
              ("RACE", "Race Piste", "Watered, icy race snow: the edge holds a force up to 70 "
               "deg from the snow's normal (a ratio of 2.75)", 2)]
SIDE_ITEMS = [("HEEL", "Heel Side", "The board's heel edge: the rider faces downhill", 0),
              ("TOE", "Toe Side", "The board's toe edge: the rider faces uphill", 1)]


class TurningSkidSettings(bpy.types.PropertyGroup):
    """``Object.turning.skid``: how the figure brakes at the foot (docs/skidding.md)."""

    style: EnumProperty(name="Style", items=STYLE_ITEMS, default="CARVE", options=_STATIC,
                        description="How the figure holds the Target Speed on a Ground mesh")
    snow: EnumProperty(name="Snow", items=SNOW_ITEMS, default="HARD", options=_STATIC,
                       description="How much grip the snow gives the edge (snow sports)")
    grip: FloatProperty(name="Grip", default=0.0, min=0.0, max=RANGES["grip"].hi,
                        precision=2, options=_STATIC,
                        description="The friction circle's mu at the foot (0: the sport's; a "
                                    "tyre on dry asphalt 0.9, wet 0.5, gravel 0.35)")
    use_stop: BoolProperty(name="Stop", default=False, options=_STATIC,
                           description="Skid to rest from the Stop Frame, then stand still "
                                       "across the fall line")
    stop_frame: IntProperty(name="Stop Frame", default=1, options=_STATIC,
                            description="The frame the stop begins at")
    stop_side: EnumProperty(name="Stop Side", items=SIDE_ITEMS, default="HEEL", options=_STATIC,
                            description="The board's edge in a stop or a side-slip")


classes = (TurningSkidSettings,)
register, unregister = bpy.utils.register_classes_factory(classes)
