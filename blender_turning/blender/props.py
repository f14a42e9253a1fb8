"""Per-figure settings: a property group on the armature object (``Object.turning``).

Body parameters and limits are plain settings; the controller's ``period``, ``lean`` and
``heading`` are animatable: key them in the Graph Editor and the bake follows them over time
(Section 5's parameters "specified over time").  Angles are radians (``subtype='ANGLE'``).
"""
from __future__ import annotations

import math

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty,
                       PointerProperty)

from .props_rig import TurningRigSettings

SPORTS = (
    ("SKIER", "Skier", "Alpine skier on slalom skis"),
    ("SNOWBOARDER", "Snowboarder", "Carving snowboarder"),
    ("TELEMARK", "Telemark", "Telemark skier"),
    ("CYCLIST", "Cyclist", "Cyclist on a road bicycle"),
)
_STATIC = set()            # options: not animatable (the bake reads these once)


def _is_curve(self, obj):
    return obj.type == "CURVE"


class TurningFigureSettings(bpy.types.PropertyGroup):
    is_figure: BoolProperty(name="Is Figure", options=_STATIC,
                            description="This armature is a turning figure")
    sport: EnumProperty(name="Sport", items=SPORTS, default="SKIER", options=_STATIC,
                        description="Which figure and mapping (Section 7) the bake uses")
    # -- body (Fig. 2) ----------------------------------------------------------------------
    mass: FloatProperty(name="Mass", description="Mass of the body, m (kg)", default=75.0,
                        min=1.0, max=1000.0, unit="MASS", options=_STATIC)
    com_height: FloatProperty(name="COM Height", default=1.0, min=0.2, max=3.0, unit="LENGTH",
                              description="Height of the centre of mass above the foot, l (m)",
                              options=_STATIC)
    inertia: FloatProperty(name="Roll Inertia", default=12.0, min=0.0, max=1000.0,
                           description="Roll moment of inertia about the centre of mass, "
                                       "I_v (kg m^2, Eq. 13)", options=_STATIC)
    speed: FloatProperty(name="Speed", default=10.0, min=0.5, max=60.0, unit="VELOCITY",
                         description="Forward speed of the centre of mass, V_cm (m/s)",
                         options=_STATIC)
    # -- limits (Sections 3, 5.1) -----------------------------------------------------------
    curvature_max: FloatProperty(name="Max Curvature", default=1 / 6, min=0.001, max=10.0,
                                 description="Largest |C_f| the foot can steer (1/m)",
                                 options=_STATIC)
    curvature_rate_max: FloatProperty(name="Max Curvature Rate", default=0.67, min=0.001,
                                      max=100.0, options=_STATIC,
                                      description="Largest |dC_f/dt| (1/(m s))")
    fall_angle: FloatProperty(name="Fall Angle", default=math.radians(60), min=math.radians(5),
                              max=math.radians(85), subtype="ANGLE", options=_STATIC,
                              description="Lean beyond which the figure has fallen")
    # -- the parametric controller (Section 5), animatable ----------------------------------
    period: FloatProperty(name="Turn Period", default=2.0, min=0.3, max=20.0, unit="TIME_ABSOLUTE",
                          description="Time of one left-right turn cycle, 2 pi / omega0 (s); "
                                      "animatable")
    lean: FloatProperty(name="Lean", default=math.radians(23), min=math.radians(1),
                        max=math.radians(60), subtype="ANGLE",
                        description="Sharpness of the turns: the peak lean theta_max; animatable")
    use_heading: BoolProperty(name="Hold Heading", default=True, options=_STATIC,
                              description="Steer the mean direction of travel (Section 5.2)")
    heading: FloatProperty(name="Heading", default=math.radians(90), subtype="ANGLE",
                           description="Mean direction of travel, counter-clockwise from +X; "
                                       "animatable")
    # -- placement and Follow Path ----------------------------------------------------------
    start: FloatVectorProperty(name="Start", size=3, subtype="TRANSLATION", unit="LENGTH",
                               options=_STATIC, description="Where the foot starts (world)")
    start_heading: FloatProperty(name="Start Direction", default=math.radians(90),
                                 subtype="ANGLE", options=_STATIC,
                                 description="Direction of travel at the first frame, "
                                             "counter-clockwise from +X")
    path: PointerProperty(name="Path", type=bpy.types.Object, poll=_is_curve, options=_STATIC,
                          description="Bezier curve the figure follows (Follow Path)")
    obstacles: PointerProperty(name="Obstacles", type=bpy.types.Collection, options=_STATIC,
                               description="Objects whose ground footprints are obstacles")
    plan_curvature_rate: FloatProperty(
        name="Planner Curvature Rate", default=0.0, min=0.0, max=100.0, options=_STATIC,
        description="Largest |dC_f/dt| the path planner tries (1/(m s)); 0 uses Max Curvature "
                    "Rate.  The sport presets set a gentler rate than the figure's limit")
    foot_track: PointerProperty(name="Foot Track", type=bpy.types.Object, options=_STATIC,
                                description="Curve object drawn along the foot's path")
    rig: PointerProperty(type=TurningRigSettings, options=_STATIC)   # issue 8: your own rig


#: Settings name -> the ``BodyParams`` / ``Limits`` field it holds.
BODY_FIELDS = {"mass": "m", "com_height": "l", "inertia": "I_v", "speed": "V_cm"}
LIMIT_FIELDS = {"curvature_max": "C_f_max", "curvature_rate_max": "dC_f_max",
                "fall_angle": "theta_fall"}
#: The animatable controller settings (their F-curves are ``turning.<name>``).
ANIMATED = ("period", "lean", "heading")


def figure_settings(obj):
    """``obj.turning`` when ``obj`` is a figure's armature, else ``None``."""
    if obj is None or obj.type != "ARMATURE":
        return None
    settings = getattr(obj, "turning", None)
    return settings if settings is not None and settings.is_figure else None


classes = (TurningFigureSettings,)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.Object.turning = PointerProperty(type=TurningFigureSettings)


def unregister():
    del bpy.types.Object.turning
    _unregister()
