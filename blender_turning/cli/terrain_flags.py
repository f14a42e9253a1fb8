"""The terrain flags of ``simulate``: a ground (a plane or a file), friction, drag, target speed.

``--slope-deg S --downhill-deg D`` is the plane (``D`` the direction of steepest descent, deg
CCW from +x); ``--ground FILE`` any ground from a file instead (docs/TERRAIN.md, "The ground
from a file"): a scene's ``terrain`` table as JSON (:mod:`..core.ground.scene_terrain`; a whole
scene file gives its ``terrain``) or a ``.npy`` height grid with ``--ground-cell`` and
``--ground-origin``; ``--start X Y`` where the foot starts.
``--friction MU --drag-area CDA --air-density RHO`` what slows the figure;
``--target-speed V`` brakes by turning across the hill (docs/TERRAIN.md Section 6) and, on
snow, by skidding for what turning leaves; ``--style``, ``--snow``, ``--grip``, ``--stop-at`` and
``--stop-side`` say how the figure brakes (docs/skidding.md).  With none
of them the run is today's flat one.  On a slope (``S > 0``) a resistance flag that is not given
takes the sport's default (its record's ``resistance``, sources there): a skier on a
slope slides on snow and through air unless told otherwise; on flat ground (``S = 0``) the
defaults are none, so today's runs are unchanged.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

from ..core.equipment import sport_of
from ..core.physics.grip import SNOW, snow
from ..core.physics.params import check_range
from ..core.registry import SPORTS
from ..core.physics.skidding import STOP_SIDES, Skidding
from ..core.controllers.speed_habits import habit_of
from ..core.ground.scene_terrain import read_terrain
from ..core.ground.terrain import Plane
from ..core.physics.model import RESISTANCE, Resistance
from ..core.validate import FieldError, Fields, check, read_json

SNOW_HELP = ("hard|soft|race: the snow's grip (default hard; race: a race piste, "
             "docs/skidding.md)")

# flag -> (Resistance field, allowed range)
RESISTANCE_FLAGS = {"friction": ("mu", 0.0, 1.0), "drag_area": ("CdA", 0.0, 10.0),
                    "air_density": ("rho", 0.0, 2.0)}


def add_terrain_flags(p) -> None:
    g = p.add_argument_group("terrain (docs/TERRAIN.md)")
    g.add_argument("--slope-deg", type=float,
                   help="slope of the ground plane, deg (0-60; default 0: flat)")
    g.add_argument("--downhill-deg", type=float,
                   help="direction of steepest descent, deg CCW from +x (default -90)")
    g.add_argument("--friction", type=float,
                   help="snow friction or rolling resistance mu (0-1; default on a slope: the "
                        "sport's)")
    g.add_argument("--drag-area", type=float,
                   help="drag area C_d A, m^2 (0-10; default on a slope: the sport's)")
    g.add_argument("--air-density", type=float,
                   help="air density, kg/m^3 (0-2; default on a slope: the sport's)")
    g.add_argument("--ground", metavar="FILE",
                   help="the ground from a file instead of a plane: a scene's terrain table as "
                        ".json, or a .npy grid of heights (with --ground-cell)")
    g.add_argument("--ground-cell", type=float, metavar="M",
                   help="grid spacing of a .npy --ground, m")
    g.add_argument("--ground-origin", type=float, nargs=2, metavar=("X", "Y"),
                   help="position of a .npy --ground's first height [0][0], m (default 0 0)")
    g.add_argument("--start", type=float, nargs=2, metavar=("X", "Y"),
                   help="where the foot starts, m (default 0 0)")
    g.add_argument("--target-speed", type=float,
                   help="m/s: turn across the hill when faster, and skid for the rest on snow "
                        "(phase-ellipse controller)")
    k = p.add_argument_group("grip and skidding (docs/skidding.md)")
    k.add_argument("--style", help="how the figure brakes: carve|skid|wedge|slip (skis: "
                                   "wedge, board: slip; default with --target-speed: skid)")
    k.add_argument("--snow", help=SNOW_HELP)
    k.add_argument("--grip", type=float, metavar="MU",
                   help="the friction circle's mu at the foot, overriding the sport's (tyre: "
                        "dry asphalt 0.9, wet 0.5, gravel 0.35; snow: its largest ratio)")
    k.add_argument("--stop-at", type=float, metavar="SECONDS",
                   help="a stop commanded at this time: skid to rest, then stand across the "
                        "fall line")
    k.add_argument("--stop-side", help="heel|toe: the snowboarder's edge in a stop or slip")


def terrain_options(args, sport: str) -> dict:
    """``simulate``'s ``ground``, ``resistance`` and ``target_speed`` from the flags (an empty
    dict: today's flat run)."""
    given = {field: check_range(f"--{flag.replace('_', '-')}", getattr(args, flag), lo, hi)
             for flag, (field, lo, hi) in RESISTANCE_FLAGS.items()
             if getattr(args, flag) is not None}
    out = {}
    if args.ground is not None:
        for flag in ("slope_deg", "downhill_deg"):
            if getattr(args, flag) is not None:
                raise ValueError(f"--ground replaces --{flag.replace('_', '-')}; give one or "
                                 "the other")
        out["ground"], base = read_ground(args, sport)
        out["resistance"] = replace(base, **given)
    else:
        for flag in ("ground_cell", "ground_origin"):
            if getattr(args, flag) is not None:
                raise ValueError(f"--{flag.replace('_', '-')} needs --ground (a .npy grid)")
        slope = math.radians(check_range("--slope-deg", 0.0 if args.slope_deg is None
                                         else args.slope_deg, 0.0, 60.0))
        down = math.radians(check_range("--downhill-deg", -90.0 if args.downhill_deg is None
                                        else args.downhill_deg, -3600.0, 3600.0))
        base = (RESISTANCE.get(sport, Resistance()) if slope > 0.0
                else Resistance(mu=0.0, CdA=0.0))
        if slope > 0.0:
            out["ground"] = Plane(slope, down)
        if slope > 0.0 or given:
            out["resistance"] = replace(base, **given)
    habit = habit_of(sport) if "ground" in out else None    # a preset's speed on a slope
    if args.target_speed is not None:
        out["target_speed"] = check_range("--target-speed", args.target_speed, 0.0, 100.0,
                                          lo_open=True)
    elif habit is not None:
        out["target_speed"] = habit.target_speed
    skidding = skid_options(args, sport, "target_speed" in out, habit)
    if skidding is not None:
        out["skidding"] = skidding
    return out


def _choice(flag: str, value, allowed) -> str:
    if value not in allowed:
        raise ValueError(f"--{flag} = {value!r} is not one of {'|'.join(allowed)}")
    return value


def skid_options(args, sport: str, target: bool, habit=None):
    """The :class:`..core.physics.skidding.Skidding` of ``--style``, ``--snow``, ``--grip``,
    ``--stop-at`` and ``--stop-side`` (``None``: the carved run).  With ``--target-speed`` and
    no ``--style`` the figure skids (``skid``), or brakes in its preset's style (``habit``, a
    :class:`..core.controllers.speed_habits.SpeedHabit`: the beginner's wedge)."""
    record = SPORTS[sport_of(sport)]          # a preset (slalom_racer) has its sport's grip
    grip = grip_of(args, sport)
    if args.stop_side is not None:
        if "slip" not in record.styles:
            raise ValueError(f"--stop-side is for a board; the {sport} has none")
        _choice("stop-side", args.stop_side, STOP_SIDES)
    style = args.style
    if style is not None:
        _choice("style", style, record.styles)
    stop = None if args.stop_at is None else check("--stop-at", args.stop_at, "stop_at")
    if style is None and stop is None and args.grip is None and args.snow is None \
            and args.stop_side is None and not target:
        return None
    if style is None:
        style = habit.style if habit is not None else "skid" if target else "carve"
    return Skidding(style, grip, stop, args.stop_side)


def grip_of(args, sport: str):
    """The :class:`..core.physics.grip.Grip` of ``--snow`` and ``--grip`` for ``sport``: its
    own (a tyre) or the snow named (default hard pack), ``--grip`` overriding its ratio."""
    record = SPORTS[sport_of(sport)]          # a preset (slalom_racer) has its sport's grip
    if args.snow is not None:
        if record.grip is not None:
            raise ValueError(f"--snow is for a sport on snow; the {sport} rides on "
                             f"{record.grip.kind}s (give --grip MU)")
        _choice("snow", args.snow, tuple(SNOW))
    grip = record.grip if record.grip is not None else snow(args.snow or "hard")
    if args.grip is not None:
        mu = check("--grip", args.grip, "grip")
        grip = replace(grip, mu=mu, name=f"{mu:g}")
    return grip


def start_point(args, ground) -> tuple:
    """``--start X Y`` (default the origin), checked to lie on a height field."""
    x, y = (0.0, 0.0) if args.start is None else (check("--start X", args.start[0], "coordinate"),
                                                  check("--start Y", args.start[1], "coordinate"))
    contains = getattr(ground, "contains", None)
    if contains is not None and not contains(x, y):
        x_lo, x_hi, y_lo, y_hi = ground.extent
        raise ValueError(f"--start ({x:g}, {y:g}) m lies off the --ground terrain, which covers "
                         f"x in [{x_lo:g}, {x_hi:g}] and y in [{y_lo:g}, {y_hi:g}] m")
    return x, y


def read_ground(args, sport: str):
    """``(ground, resistance)`` of ``--ground FILE``: a ``.json`` file holding a ``terrain``
    table (or a scene with one), read as a scene's
    (:func:`..core.ground.scene_terrain.read_terrain`:
    the same fields, ranges and messages; a ``file`` is relative to the JSON file), or a
    ``.npy`` grid of heights at ``--ground-cell`` spacing from ``--ground-origin``.  Every
    problem is a one-line ``ValueError`` naming ``--ground`` (or the flag at fault)."""
    path = Path(args.ground)
    kind = path.suffix.lower()
    if kind == ".npy":
        if args.ground_cell is None:
            raise ValueError(f"--ground {args.ground} is a .npy grid: give its spacing with "
                             "--ground-cell M")
        cell = check("--ground-cell", args.ground_cell, "cell")
        x0, y0 = (0.0, 0.0) if args.ground_origin is None else (
            check("--ground-origin X", args.ground_origin[0], "coordinate"),
            check("--ground-origin Y", args.ground_origin[1], "coordinate"))
        doc = {"type": "height_field", "file": str(path.resolve()), "cell": cell,
               "origin": [x0, y0]}
        tf = Fields(doc, args.ground)
    elif kind == ".json":
        for flag in ("ground_cell", "ground_origin"):
            if getattr(args, flag) is not None:
                raise ValueError(f"--{flag.replace('_', '-')} is for a .npy --ground; the JSON "
                                 f"terrain {args.ground} gives its own cell and origin")
        doc = read_json(path, "--ground file")
        if not isinstance(doc, dict):
            raise ValueError(f"--ground file {args.ground!r} holds a JSON "
                             f"{type(doc).__name__}, not a terrain table")
        tf = Fields(doc, args.ground)               # a terrain.file is relative to it
    else:
        raise ValueError(f"--ground {args.ground!r} is neither a .json terrain table nor a .npy "
                         "height grid")
    try:
        if "terrain" in tf.doc and "type" not in tf.doc:        # a whole scene file
            tf = tf.table("terrain")
        return read_terrain(tf, sport)
    except FieldError as exc:
        raise ValueError(f"--ground {exc}") from None
