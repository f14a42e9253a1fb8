"""Scene -> core: figure settings to frozen core parameters, keyed settings to schedules, a Bezier
curve to path control points, obstacle objects to ground footprints.  Reads only; writes nothing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import bpy
import numpy as np

from ...core import BodyParams, Figure, Limits, PhaseEllipse, Schedule
from ...core.registry import SPORT_PRESETS, SPORTS
from ...core.sports import sport as sport_record
from ...core.physics.grip import SNOW
from ...core.physics.model import Resistance
from ...core.ranges import RANGES, lean_range
from ...core.physics.skidding import Skidding
from ...core.validate import check
from .. import compat
from ..anim import bake
from ..anim.foot_track import OWNER as FOOT_TRACK_OWNER
from ..props.figure import BODY_FIELDS, LIMIT_FIELDS


class SceneInputError(ValueError):
    """A setting, path or obstacle object that cannot be used (names it)."""


#: Most frames one bake covers.  A skier's bake peaks at about 17.5 kB per frame and computes for
#: 0.1-0.3 ms per frame (scripts/bench_bake_size.py, BENCHMARKS.md); Blender allows ranges of up
#: to 1,048,574 frames, which would need some 18 GB.  72,000 is 50 min at 24 fps (about 1.3 GB).
MAX_FRAMES = 72_000


@dataclass(frozen=True)
class FrameRange:
    """The frames a bake covers: ``start..end`` inclusive at ``fps`` frames per second."""

    start: int
    end: int
    fps: float

    def __post_init__(self):
        if self.end <= self.start:
            raise ValueError(f"frame range {self.start}..{self.end} needs at least two frames")
        if self.end - self.start + 1 > MAX_FRAMES:
            raise ValueError(f"frame range {self.start}..{self.end} has "
                             f"{self.end - self.start + 1} frames; a bake covers at most "
                             f"{MAX_FRAMES}: shorten the range or bake it in parts")
        if not self.fps > 0:
            raise ValueError(f"fps = {self.fps!r} must be positive")

    @classmethod
    def of_scene(cls, scene) -> "FrameRange":
        return cls(scene.frame_start, scene.frame_end, scene.render.fps / scene.render.fps_base)

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame."""
        return (self.end - self.start) / self.fps

    def times(self) -> np.ndarray:
        return (np.arange(self.start, self.end + 1) - self.start) / self.fps


def _describe(prop, value) -> str:
    """``Turn Period (turning.period) = nan``, angles in degrees."""
    angle = prop.unit == "ROTATION"
    vals = [math.degrees(v) if angle else v for v in (value if prop.is_array else [value])]
    shown = ", ".join(f"{v:g}" for v in vals)
    shown = f"({shown})" if prop.is_array else shown + (" deg" if angle else "")
    return f"{prop.name} (turning.{prop.identifier}) = {shown}"


def _allowed(prop) -> str:
    lo, hi = prop.hard_min, prop.hard_max
    if prop.unit == "ROTATION":
        lo, hi = math.degrees(lo), math.degrees(hi)
    if max(abs(lo), abs(hi)) > 1e30:
        return "type a number"
    return f"type a number from {lo:g} to {hi:g}" + (" deg" if prop.unit == "ROTATION" else "")


def check_finite_settings(settings) -> None:
    """Raise :class:`SceneInputError` naming the first of ``obj.turning``'s numbers that is not
    finite (NaN or infinity typed into a field, or set from a script)."""
    for prop in settings.bl_rna.properties:
        if prop.type != "FLOAT":
            continue
        value = getattr(settings, prop.identifier)
        if not np.all(np.isfinite(np.asarray(value, float))):
            raise SceneInputError(f"{_describe(prop, value)} is not a finite number; "
                                  f"{_allowed(prop)}")


def resistance_from_settings(settings) -> Resistance:
    """The core :class:`Resistance` of ``obj.turning.terrain`` (raises naming a field)."""
    t = settings.terrain
    for prop in t.bl_rna.properties:
        if prop.type == "FLOAT" and not math.isfinite(getattr(t, prop.identifier)):
            raise SceneInputError(f"{prop.name} (turning.terrain.{prop.identifier}) = "
                                  f"{getattr(t, prop.identifier)} is not a finite number")
    return Resistance(mu=float(t.friction), CdA=float(t.drag_area), rho=float(t.air_density))


def figure_from_settings(settings) -> Figure:
    """The frozen core :class:`Figure` of ``obj.turning`` (raises ``ValueError`` naming a field)."""
    check_finite_settings(settings)
    body = BodyParams(**{f: float(getattr(settings, s)) for s, f in BODY_FIELDS.items()})
    limits = Limits(**{f: float(getattr(settings, s)) for s, f in LIMIT_FIELDS.items()})
    return Figure(figure_name(settings), body, limits)


def figure_name(settings) -> str:
    """The figure's preset name: its equipment preset (a preset of its sport, which the mapping
    shows: core/equipment.py) or its sport's (raises ``ValueError`` naming the field)."""
    sport, name = settings.sport.lower(), settings.equipment.preset
    if not name:
        return sport
    if name not in SPORT_PRESETS or SPORT_PRESETS[name].sport != sport:
        raise SceneInputError(
            f"Equipment Preset (turning.equipment.preset) = {name!r} is not a preset of the "
            f"{sport} ("
            f"{', '.join(n for n, r in SPORT_PRESETS.items() if r.sport == sport) or 'none'}"
            "; empty: the sport's own)")
    return name


#: Largest |dC_f/dt| the path planner tries per sport, 1/(m s): the sport records'
#: ``plan_curvature_rate`` (core/sports.py), a live view of the sport registry.
PLAN_CURVATURE_RATE = SPORTS.view("plan_curvature_rate")


def settings_from_preset(settings, sport: str) -> None:
    """Fill ``obj.turning`` from the record of ``sport`` ('SKIER', ...) or of a sport's preset
    ('slalom_racer': core/equipment.py, which sets its sport and equipment too): its preset,
    the planner's rate and what slows it on a slope."""
    own = SPORT_PRESETS.get(sport.lower()) if isinstance(sport, str) else None
    record = own if own is not None else sport_record(sport)
    fig, res = record.figure, record.resistance
    settings.sport = sport_record(own.sport).key if own is not None else record.key
    settings.equipment.preset = own.name if own is not None else ""
    settings.plan_curvature_rate = record.plan_curvature_rate
    settings.terrain.friction, settings.terrain.drag_area = res.mu, res.CdA
    settings.terrain.air_density = res.rho
    for s, f in BODY_FIELDS.items():
        setattr(settings, s, getattr(fig.body, f))
    for s, f in LIMIT_FIELDS.items():
        setattr(settings, s, getattr(fig.limits, f))


def sampled_setting(obj, name: str, frames: FrameRange) -> np.ndarray:
    """``obj.turning.<name>`` at every frame: its F-curve where keyed, else the static value
    (``name`` may reach into a nested group: ``"terrain.target_speed"``)."""
    bag = compat.channels(obj)
    if bag is None:                       # the bake pushed down onto an NLA strip keeps the keys
        action, strip = bake.find_bake(obj)
        bag = compat.channelbag(action, compat.strip_slot(strip)) if strip is not None else None
    fc = None
    if bag is not None:
        fc = next((c for c in bag.fcurves if c.data_path == f"turning.{name}"), None)
    n = frames.end - frames.start + 1
    group, _, leaf = ("." + name).rpartition(".")
    owner = obj.turning
    for part in group.split(".")[1:]:
        owner = getattr(owner, part)
    if fc is None or fc.mute:
        return np.full(n, float(getattr(owner, leaf)))
    values = np.array([fc.evaluate(f) for f in range(frames.start, frames.end + 1)], float)
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        prop = owner.bl_rna.properties[leaf]
        raise SceneInputError(f"{prop.name} (turning.{name}) is keyed to {values[bad[0]]:g} at "
                              f"frame {frames.start + bad[0]}, not a finite number; fix that key "
                              "in the Graph Editor")
    return values


def speed_schedule(obj, frames: FrameRange) -> Schedule:
    """The figure's forward speed ``V_cm`` over ``frames`` (keyed ``turning.speed``, or its value),
    as a schedule of the time since the first frame (raises ``ValueError`` naming the frame)."""
    v = sampled_setting(obj, "speed", frames)
    rna = obj.turning.bl_rna.properties["speed"]          # the setting's own range
    bad = np.nonzero(~((v >= rna.hard_min) & (v <= rna.hard_max)))[0]
    if len(bad):
        raise ValueError(f"speed = {v[bad[0]]:g} m/s at frame {frames.start + bad[0]} is outside "
                         f"the allowed range [{rna.hard_min:g}, {rna.hard_max:g}] m/s")
    return Schedule.constant(v[0]) if np.all(v == v[0]) else Schedule.sampled(frames.times(), v)


def target_schedule(obj, frames: FrameRange):
    """The Target Speed (``turning.terrain.target_speed``, keyable) over ``frames`` as a
    schedule of the time since the first frame, or ``None`` when it is 0 throughout; a keyed
    value of 0 or below within a run that brakes is refused, naming the frame."""
    v = sampled_setting(obj, "terrain.target_speed", frames)
    if np.all(v == 0.0):
        return None
    bad = np.flatnonzero(~(v > 0.0) | ~(v <= RANGES["target_speed"].hi))
    if bad.size:
        raise SceneInputError(f"Target Speed (turning.terrain.target_speed) is {v[bad[0]]:g} m/s "
                              f"at frame {frames.start + bad[0]}: a keyed target must stay in "
                              f"(0, {RANGES['target_speed'].hi:g}] m/s")
    return Schedule.constant(v[0]) if np.all(v == v[0]) else Schedule.sampled(frames.times(), v)


def skidding_from_settings(obj, frames: FrameRange):
    """The core :class:`Skidding` of ``turning.skid`` (docs/skidding.md), or ``None`` for
    Carve without a stop; the Stop Frame on the figure's clock (``frames.start`` is 0 s).  A
    style the sport does not have is refused, naming it."""
    s, k = obj.turning, obj.turning.skid
    style = k.style.lower()
    if style == "carve" and not k.use_stop:
        return None
    record = sport_record(s.sport)
    if style not in record.styles:
        raise SceneInputError(f"Style {k.style.title()} (turning.skid.style) is not one the "
                              f"{record.name} has: {', '.join(x.title() for x in record.styles)}")
    grip = record.grip if record.grip is not None else SNOW[k.snow.lower()]
    if k.grip > 0.0:
        grip = replace(grip, mu=float(check("Grip (turning.skid.grip)", k.grip, "grip")))
    stop = None
    if k.use_stop:
        stop = (k.stop_frame - frames.start) / frames.fps
        if not 0.0 <= stop <= frames.duration:
            raise SceneInputError(f"Stop Frame (turning.skid.stop_frame) = {k.stop_frame} lies "
                                  f"outside the frames {frames.start}-{frames.end}")
    side = k.stop_side.lower() if "slip" in record.styles else None
    return Skidding(style, grip, stop, side)


def controller_from_settings(obj, figure: Figure, frames: FrameRange) -> PhaseEllipse:
    """The phase-ellipse controller (Section 5) following the keyed period, lean and heading."""
    t = frames.times()
    values = {name: sampled_setting(obj, name, frames) for name in ("period", "lean", "heading")}
    if np.any(values["period"] <= 0):
        raise ValueError("turn period must stay positive over the frame range")
    leans = lean_range(figure.limits.theta_fall, f"the {figure.name}")
    # Each value checked once (a Lean not keyed: one value at every frame; a drag step checks
    # 1,441 frames of a 60 s range).
    good = [v for v in np.unique(values["lean"]).tolist() if leans.contains(v)]
    for k in np.flatnonzero(~np.isin(values["lean"], good))[:1]:
        raise SceneInputError(f"Lean (turning.lean) = {math.degrees(values['lean'][k]):.6g} deg "
                              f"at frame {frames.start + k} is outside the allowed range "
                              f"{leans.deg()}: {leans.reason}")

    def schedule(v):
        return Schedule.constant(v[0]) if np.all(v == v[0]) else Schedule.sampled(t, v)

    heading = schedule(values["heading"]) if obj.turning.use_heading else None
    return PhaseEllipse(figure.body, schedule(2 * math.pi / values["period"]),
                        schedule(values["lean"]), heading, limits=figure.limits)


def start_state(obj, controller, start=None) -> tuple:
    """The simulation's initial state ``(x, y, theta_dir, theta_v, omega_v)``: upright at
    ``start = (x, y, theta_dir)`` (default: the figure's Start settings), on the target ellipse
    (``omega_v = omega0 theta_max``; First Turn Right, ``turning.crowd.first_turn``: ``-omega0
    theta_max``, the mirror image about the start direction, Section 1's symmetry, exact when
    the Heading is the Start Direction)."""
    s = obj.turning
    if start is None:
        start = (s.start[0], s.start[1], s.start_heading)
    w, tm = controller.target(0.0)
    rate = -w * tm if s.crowd.first_turn == "RIGHT" else w * tm
    return (float(start[0]), float(start[1]), float(start[2]), 0.0, rate)


def start_from_object(obj):
    """``(x, y, theta_dir)`` of where the figure's armature stands now (the built-in rest pose
    faces +Y; a user's rig faces where it was measured to), rounded as the Start settings store
    them (float32), so a re-bake from those is identical."""
    from .retarget_adapter import facing
    x, y, heading = obj.location[0], obj.location[1], obj.rotation_euler[2] + facing(obj)
    if not np.all(np.isfinite([x, y, heading])):
        raise SceneInputError(f"{obj.name!r} stands at location ({x:g}, {y:g}), rotation Z "
                              f"{math.degrees(obj.rotation_euler[2]):g} deg: not finite numbers; "
                              "type numbers in its Transform panel")
    return tuple(float(v) for v in np.float32([x, y, heading]))


# -- Follow Path ----------------------------------------------------------------------------

def bezier_control_points(curve_obj) -> np.ndarray:
    """World-space ground control points ``(3 k + 1, 2)`` of a Bezier curve object's first spline:
    ``P0, P1, P2, P3, P4, ...`` (each cubic segment ``P3i .. P3i+3``); a poly or NURBS spline
    gives its points as a polyline (handles on the chords)."""
    if curve_obj is None:
        raise SceneInputError("no path curve set (Follow Path > Path)")
    if curve_obj.type != "CURVE":
        raise SceneInputError(f"path {curve_obj.name!r} is a {curve_obj.type.lower()} object, not "
                              "a curve: pick a Bezier curve as Path")
    splines = curve_obj.data.splines
    if len(splines) == 0:
        raise SceneInputError(f"path {curve_obj.name!r} has no spline")
    if len(splines) > 1:
        raise SceneInputError(f"path {curve_obj.name!r} has {len(splines)} splines; Follow Path "
                              "follows one: separate them (Edit Mode, Curve > Separate)")
    sp = splines[0]
    if sp.use_cyclic_u:
        # The planner ends a run when the foot crosses the line through the path's end; on a loop
        # that line passes through the start, so it would stop at once.  Refuse, do not cut.
        raise SceneInputError(
            f"path {curve_obj.name!r} is a closed (cyclic) curve; Follow Path runs from the first "
            "point to the last: open it where the run should start (Edit Mode, Curve > Toggle "
            "Cyclic)")
    mw = np.array(curve_obj.matrix_world)

    def world(pts):
        pts = np.asarray(pts, float).reshape(-1, 3)
        return (pts @ mw[:3, :3].T + mw[:3, 3])[:, :2]

    if sp.type == "BEZIER":
        n = len(sp.bezier_points)
        if n < 2:
            raise SceneInputError(f"path {curve_obj.name!r} has {n} point(s); it needs at least 2")
        co, hl, hr = (np.empty(3 * n), np.empty(3 * n), np.empty(3 * n))
        sp.bezier_points.foreach_get("co", co)
        sp.bezier_points.foreach_get("handle_left", hl)
        sp.bezier_points.foreach_get("handle_right", hr)
        co, hl, hr = world(co), world(hl), world(hr)
        ctrl = [co[0]]
        for i in range(len(co) - 1):
            ctrl += [hr[i], hl[i + 1], co[i + 1]]
        out = np.array(ctrl)
    else:
        n = len(sp.points)
        if n < 2:
            raise SceneInputError(f"path {curve_obj.name!r} has {n} point(s); it needs at least 2")
        co = np.empty(4 * n)
        sp.points.foreach_get("co", co)
        p = world(co.reshape(-1, 4)[:, :3])
        ctrl = [p[0]]
        for a, b in zip(p[:-1], p[1:]):
            ctrl += [a + (b - a) / 3, a + 2 * (b - a) / 3, b]
        out = np.array(ctrl)
    bad = np.flatnonzero(~np.all(np.isfinite(out), axis=1))
    if bad.size:
        raise SceneInputError(f"path {curve_obj.name!r} has a point or handle (control point "
                              f"{bad[0]}) that is not a finite number: fix it in Edit Mode")
    seg = np.linalg.norm(np.diff(out[::3], axis=0), axis=1)
    if np.any(seg < 1e-6):
        raise SceneInputError(f"path {curve_obj.name!r} has two points in the same place")
    return out


def obstacle_footprints(collection, depsgraph=None, exclude=()) -> list:
    """Ground footprints of the collection's objects: convex hulls (k, 2) of their world bounding
    boxes projected to z = 0, one per object (its name kept for reports).  Objects in ``exclude``
    (the planning figure's own) and every figure's foot track and path (guides) are skipped."""
    if collection is None:
        return []
    paths = {o.turning.path for o in bpy.data.objects if o.type == "ARMATURE"} - {None}
    out = []
    for obj in collection.all_objects:
        if obj.type in {"EMPTY", "CAMERA", "LIGHT", "ARMATURE"} or obj in exclude:
            continue
        if obj.get(FOOT_TRACK_OWNER) is not None or obj in paths:   # guides, not things
            continue
        ev = obj.evaluated_get(depsgraph) if depsgraph is not None else obj
        bb = np.array([tuple(c) for c in ev.bound_box], float)
        mw = np.array(ev.matrix_world)
        pts = (bb @ mw[:3, :3].T + mw[:3, 3])[:, :2]
        if not np.all(np.isfinite(pts)):
            raise SceneInputError(f"obstacle {obj.name!r} (collection {collection.name!r}) has a "
                                  "location, rotation, scale or size that is not a finite number")
        hull = convex_hull(pts)
        if len(hull) >= 3:
            out.append((obj.name, hull))
    return out


def convex_hull(points) -> np.ndarray:
    """Counter-clockwise convex hull of 2-D points (Andrew's monotone chain)."""
    pts = sorted(set(map(tuple, np.round(np.asarray(points, float), 9))))
    if len(pts) < 3:
        return np.array(pts)

    def half(seq):
        h = []
        for p in seq:
            while len(h) >= 2 and ((h[-1][0] - h[-2][0]) * (p[1] - h[-2][1])
                                   - (h[-1][1] - h[-2][1]) * (p[0] - h[-2][0])) <= 0:
                h.pop()
            h.append(p)
        return h

    lower, upper = half(pts), half(reversed(pts))
    return np.array(lower[:-1] + upper[:-1])
