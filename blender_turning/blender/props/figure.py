"""Per-figure settings: a property group on the armature object (``Object.turning``).

Body parameters and limits are plain settings; the controller's ``period``, ``lean`` and
``heading`` and the body's ``speed`` are animatable: key them in the Graph Editor and the bake
follows them over time (Section 5's parameters "specified over time"; the speed as Section 6's
speed profile).  Angles are radians (``subtype='ANGLE'``).  Tooltips say what a setting does,
then the paper's symbol and the unit; settings without a Blender unit carry theirs in the label.
"""
from __future__ import annotations

import math

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, FloatVectorProperty,
                       PointerProperty, StringProperty)

from ...core.ranges import RANGES
from .. import compat
from .crowd import TurningCrowdSettings
from .rig import TurningRigSettings
from .skid import TurningSkidSettings
from ..registry_items import sport_items

_STATIC = set()            # options: not animatable (the bake reads these once)


def _show_foot_track(settings, context):
    from ..anim.foot_track import update_visibility   # a sibling module, imported when used
    update_visibility(settings, context)


#: What switching a figure's Live Preview calls, with the figure: set by ``live.register()``
#: (props is read by live, so it takes the call from there instead of importing it).
on_live_switched = None


def _live_changed(settings, context):
    if on_live_switched is not None:
        on_live_switched(settings.id_data)


def _range(key: str) -> dict:
    """``min``/``max`` of a setting: the core's table of ranges (core/ranges.py), so a value
    typed here is held to the same bounds as a flag, a scene file or a render-job key."""
    r = RANGES[key]
    return {"min": r.lo, "max": r.hi}


def _is_curve(self, obj):
    return obj.type == "CURVE"


def _is_mesh(self, obj):
    return obj.type == "MESH"


class TurningTerrainSettings(bpy.types.PropertyGroup):
    """``Object.turning.terrain``: what slows the figure on a Ground mesh (docs/TERRAIN.md
    Section 3) and the speed it brakes to.  Read once per bake (the core's ``Resistance`` and
    ``TargetSpeed`` are constant over a run), so not animatable.  Used only with a Ground mesh:
    on flat ground the figure keeps its (keyed) Speed, the paper's model."""

    friction: FloatProperty(name="Slope Friction", default=0.05, min=RANGES["mu"].lo,
                            max=RANGES["mu"].hi, soft_max=0.2, precision=3, options=_STATIC,
                            description="Snow or rolling friction against the ground's normal "
                                        "force (mu; ski on snow 0.05, bicycle tyre 0.004)")
    drag_area: FloatProperty(name="Drag Area (m^2)", default=0.5, min=RANGES["CdA"].lo,
                             max=RANGES["CdA"].hi, soft_max=1.5, options=_STATIC,
                             description="Air drag coefficient times frontal area (C_d A, m^2; "
                                         "skier 0.5, cyclist on the hoods 0.32)")
    air_density: FloatProperty(name="Air Density (kg/m^3)", default=1.007, min=0.01,
                               max=RANGES["rho"].hi, options=_STATIC,
                               description="Density of the air (rho, kg/m^3; 1.225 at sea level, "
                                           "1.007 at 2000 m)")
    target_speed: FloatProperty(name="Target Speed", default=0.0, min=RANGES["target_speed"].lo,
                                max=RANGES["target_speed"].hi, soft_max=30.0, unit="VELOCITY",
                                description="Brake when faster than this (m/s; needs Hold "
                                            "Heading, the course down the hill), by turning "
                                            "across the hill and as the Style says; animatable; "
                                            "0 lets the speed run.  On Follow Path: the speed "
                                            "the planned figure brakes to")


class TurningEquipmentSettings(bpy.types.PropertyGroup):
    """``Object.turning.equipment``: the sport's preset whose equipment the figure shows (the
    racers, the carver: core/equipment.py), set by the Sport Presets menu."""

    preset: StringProperty(name="Equipment Preset", default="", options=_STATIC,
                           description="A preset of the figure's sport with carving equipment "
                                       "(slalom_racer, gs_racer, carver): the bake shows its "
                                       "skis or board on the edge angle that carves the "
                                       "figure's curvature (docs/racing.md).  Empty: the "
                                       "sport's own, Section 7's linear tilt")


class TurningFigureSettings(bpy.types.PropertyGroup):
    """``Object.turning``.  The Python names below are API (scripts and users' F-curves on
    ``turning.<name>`` use them): never rename or move one.  New concepts go into nested groups
    of their own (``turning.<group>.<name>``, a ``PointerProperty`` line at the end of this class,
    the group registered before this class), drawn in their own sub-panel of ``panel.py``."""

    is_figure: BoolProperty(name="Is Figure", options=_STATIC,
                            description="This armature is a turning figure")
    # The registered sports (core/sports.py), listed when drawn; default 0: the skier.
    sport: EnumProperty(name="Sport", items=sport_items, default=0, options=_STATIC,
                        description="Which figure and mapping (Section 7) the bake uses")
    # -- body (Fig. 2) ----------------------------------------------------------------------
    mass: FloatProperty(name="Mass", default=75.0, **_range("m"), soft_min=20.0,
                        soft_max=150.0, unit="MASS", options=_STATIC,
                        description="How heavy the body is, with its equipment (m, kg)")
    com_height: FloatProperty(name="COM Height", default=1.0, **_range("l"), soft_min=0.4,
                              soft_max=1.5, unit="LENGTH", options=_STATIC,
                              description="How high the body's centre of mass is above the "
                                          "foot (l, m)")
    inertia: FloatProperty(name="Roll Inertia (kg m^2)", default=12.0, **_range("I_v"),
                           soft_min=1.0, soft_max=40.0, options=_STATIC,
                           description="How hard the body is to tip sideways about its centre "
                                       "of mass (I_v, kg m^2, Eq. 13)")
    speed: FloatProperty(name="Speed", default=10.0, **_range("V_cm"), soft_min=2.0,
                         soft_max=30.0, unit="VELOCITY",
                         description="How fast the body moves forward (V_cm, m/s); animatable: "
                                     "key it to speed up or brake")
    # -- limits (Sections 3, 5.1) -----------------------------------------------------------
    curvature_max: FloatProperty(name="Max Curvature (1/m)", default=1 / 6,
                                 **_range("C_f_max"), soft_min=0.02, soft_max=1.0, options=_STATIC,
                                 description="How sharply the foot can steer: one over the "
                                             "tightest turn radius (C_f max, 1/m)")
    curvature_rate_max: FloatProperty(name="Max Curvature Rate (1/(m s))", default=0.67,
                                      **_range("dC_f_max"), soft_min=0.05, soft_max=5.0,
                                      options=_STATIC,
                                      description="How fast the steering can change, e.g. edge "
                                                  "to edge (dC_f/dt max, 1/(m s))")
    fall_angle: FloatProperty(name="Fall Angle", default=math.radians(60),
                              **_range("theta_fall"), soft_min=math.radians(30),
                              soft_max=math.radians(85), subtype="ANGLE", options=_STATIC,
                              description="How far the body can lean before it falls over "
                                          "(theta_fall)")
    # -- the parametric controller (Section 5), animatable ----------------------------------
    period: FloatProperty(name="Turn Period", default=2.0, **_range("period"), soft_min=0.6,
                          soft_max=8.0, unit="TIME_ABSOLUTE",
                          description="How long one left-right pair of turns takes "
                                      "(2 pi / omega0, s); animatable")
    lean: FloatProperty(name="Lean", default=math.radians(23), **_range("theta_max"),
                        soft_min=math.radians(3),
                        soft_max=math.radians(45), subtype="ANGLE",
                        description="How far the body leans at the apex of a turn (theta_max), "
                                    "below the Fall Angle; animatable")
    use_heading: BoolProperty(name="Hold Heading", default=True, options=_STATIC,
                              description="Steer so the turns keep to the Heading on average "
                                          "(directional control, Section 5.2)")
    heading: FloatProperty(name="Heading", default=math.radians(90), subtype="ANGLE",
                           **_range("heading"), soft_min=-2 * math.pi, soft_max=2 * math.pi,
                           description="Which way the turns go on average, counter-clockwise "
                                       "from +X (theta_h); animatable")
    # -- placement and Follow Path ----------------------------------------------------------
    start: FloatVectorProperty(name="Start", size=3, subtype="TRANSLATION", unit="LENGTH",
                               options=_STATIC,
                               description="Where the foot is at the first frame (world)")
    start_heading: FloatProperty(name="Start Direction", default=math.radians(90),
                                 subtype="ANGLE", options=_STATIC,
                                 description="Which way the figure moves at the first frame, "
                                             "counter-clockwise from +X (theta_dir)")
    path: PointerProperty(name="Path", type=bpy.types.Object, poll=_is_curve, options=_STATIC,
                          description="Bezier curve the figure follows (Follow Path)")
    obstacles: PointerProperty(name="Obstacles", type=bpy.types.Collection, options=_STATIC,
                               description="Objects whose ground footprints the figure steers "
                                           "around (Follow Path)")
    plan_curvature_rate: FloatProperty(
        name="Planner Curvature Rate (1/(m s))", default=0.0, **_range("plan_curvature_rate"),
        soft_min=0.0, soft_max=2.0, options=_STATIC,
        description="How fast the path planner may change the steering (dC_f/dt, 1/(m s)); 0 "
                    "uses Max Curvature Rate.  The sport presets set a gentler rate than the "
                    "figure's limit")
    foot_track: PointerProperty(name="Foot Track", type=bpy.types.Object, options=_STATIC,
                                description="Curve object drawn along the foot's path")
    show_foot_track: BoolProperty(name="Show Foot Track", default=False, options=_STATIC,
                                  update=_show_foot_track,
                                  description="Draw the foot's path in the viewport (a guide: it "
                                              "never renders; hidden, it is out of the view "
                                              "layer and no exporter writes it)")
    rig: PointerProperty(type=TurningRigSettings, options=_STATIC,
                         description="Your own rig as a figure: its bone map, stance and "
                                     "equipment")
    ground: PointerProperty(name="Ground", type=bpy.types.Object, poll=_is_mesh,
                            options=_STATIC,
                            description="Mesh the figure rides on: its speed then follows the "
                                        "slope, friction and drag (docs/TERRAIN.md).  Empty: a "
                                        "flat plane at the Start height")
    terrain: PointerProperty(type=TurningTerrainSettings, options=_STATIC,
                             description="Friction, drag and target speed on the Ground mesh")
    crowd: PointerProperty(type=TurningCrowdSettings, options=_STATIC,
                           description="The figure's start offset and first turn in a crowd")
    live: BoolProperty(name="Live Preview", default=False, options=_STATIC, update=_live_changed,
                       description="Re-bake the figure whenever one of its settings, keys, its "
                                   "Path, obstacles or Ground change (docs/live-preview.md)")
    equipment: PointerProperty(type=TurningEquipmentSettings, options=_STATIC,
                               description="The sport's preset whose equipment the figure "
                                           "shows")
    skid: PointerProperty(type=TurningSkidSettings, options=_STATIC,
                          description="How the figure brakes: style, snow, grip, a stop "
                                      "(docs/skidding.md)")


#: Settings name -> the ``BodyParams`` / ``Limits`` field it holds.
BODY_FIELDS = {"mass": "m", "com_height": "l", "inertia": "I_v", "speed": "V_cm"}
LIMIT_FIELDS = {"curvature_max": "C_f_max", "curvature_rate_max": "dC_f_max",
                "fall_angle": "theta_fall"}


def figure_settings(obj):
    """``obj.turning`` when ``obj`` is a figure's armature, else ``None``."""
    if obj is None or obj.type != "ARMATURE":
        return None
    if compat.SETTINGS_IN_IDPROPS and "turning" not in obj.keys():
        return None                       # never a figure; reading would add the group
    settings = getattr(obj, "turning", None)
    return settings if settings is not None and settings.is_figure else None


classes = (TurningTerrainSettings, TurningEquipmentSettings, TurningFigureSettings)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.Object.turning = PointerProperty(type=TurningFigureSettings)


def unregister():
    del bpy.types.Object.turning
    _unregister()
