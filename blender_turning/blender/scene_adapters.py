"""Scene -> core: figure settings to frozen core parameters, keyed settings to schedules, a Bezier
curve to path control points, obstacle objects to ground footprints.  Reads only; writes nothing.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core import BodyParams, Figure, Limits, PhaseEllipse, Schedule
from ..core.params import PRESETS
from . import compat
from .props import ANIMATED, BODY_FIELDS, LIMIT_FIELDS


@dataclass(frozen=True)
class FrameRange:
    """The frames a bake covers: ``start..end`` inclusive at ``fps`` frames per second."""

    start: int
    end: int
    fps: float

    def __post_init__(self):
        if self.end <= self.start:
            raise ValueError(f"frame range {self.start}..{self.end} needs at least two frames")
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


def figure_from_settings(settings) -> Figure:
    """The frozen core :class:`Figure` of ``obj.turning`` (raises ``ValueError`` naming a field)."""
    body = BodyParams(**{f: float(getattr(settings, s)) for s, f in BODY_FIELDS.items()})
    limits = Limits(**{f: float(getattr(settings, s)) for s, f in LIMIT_FIELDS.items()})
    return Figure(settings.sport.lower(), body, limits)


#: Largest |dC_f/dt| the path planner tries per sport, 1/(m s).  Gentler than the figures' own
#: limits: with the full rate every branch of the first searches from an upright start leans past
#: the planner's 30 deg bound and the figure runs straight (measured on a 6 m slalom, 12 m gates:
#: these rates follow it to within about 3 m).
PLAN_CURVATURE_RATE = {"skier": 0.2, "snowboarder": 0.3, "telemark": 0.3, "cyclist": 0.5}


def settings_from_preset(settings, sport: str) -> None:
    """Fill ``obj.turning`` from the core preset of ``sport`` ('SKIER', ...)."""
    fig = PRESETS[sport.lower()]
    settings.sport = sport.upper()
    settings.plan_curvature_rate = PLAN_CURVATURE_RATE[sport.lower()]
    for s, f in BODY_FIELDS.items():
        setattr(settings, s, getattr(fig.body, f))
    for s, f in LIMIT_FIELDS.items():
        setattr(settings, s, getattr(fig.limits, f))


def sampled_setting(obj, name: str, frames: FrameRange) -> np.ndarray:
    """``obj.turning.<name>`` at every frame: its F-curve where keyed, else the static value."""
    bag = compat.channels(obj)
    fc = None
    if bag is not None:
        fc = next((c for c in bag.fcurves if c.data_path == f"turning.{name}"), None)
    n = frames.end - frames.start + 1
    if fc is None or fc.mute:
        return np.full(n, float(getattr(obj.turning, name)))
    return np.array([fc.evaluate(f) for f in range(frames.start, frames.end + 1)], float)


def controller_from_settings(obj, figure: Figure, frames: FrameRange) -> PhaseEllipse:
    """The phase-ellipse controller (Section 5) following the keyed period, lean and heading."""
    t = frames.times()
    values = {name: sampled_setting(obj, name, frames) for name in ANIMATED}
    if np.any(values["period"] <= 0):
        raise ValueError("turn period must stay positive over the frame range")
    if np.any(values["lean"] <= 0) or np.any(values["lean"] >= figure.limits.theta_fall):
        raise ValueError(f"lean must stay in (0, {math.degrees(figure.limits.theta_fall):.0f}) deg"
                         " (the fall angle) over the frame range")

    def schedule(v):
        return Schedule.constant(v[0]) if np.all(v == v[0]) else Schedule.sampled(t, v)

    heading = schedule(values["heading"]) if obj.turning.use_heading else None
    return PhaseEllipse(figure.body, schedule(2 * math.pi / values["period"]),
                        schedule(values["lean"]), heading)


def start_state(obj, controller, start=None) -> tuple:
    """The simulation's initial state ``(x, y, theta_dir, theta_v, omega_v)``: upright at
    ``start = (x, y, theta_dir)`` (default: the figure's Start settings), on the target ellipse
    (``omega_v = omega0 theta_max``)."""
    s = obj.turning
    if start is None:
        start = (s.start[0], s.start[1], s.start_heading)
    w, tm = controller.target(0.0)
    return (float(start[0]), float(start[1]), float(start[2]), 0.0, w * tm)


def start_from_object(obj):
    """``(x, y, theta_dir)`` of where the figure's armature stands now (the built-in rest pose
    faces +Y; a user's rig faces where it was measured to), rounded as the Start settings store
    them (float32), so a re-bake from those is identical."""
    from .retarget_adapter import facing
    x, y, heading = obj.location[0], obj.location[1], obj.rotation_euler[2] + facing(obj)
    return tuple(float(v) for v in np.float32([x, y, heading]))


# -- Follow Path ----------------------------------------------------------------------------

class SceneInputError(ValueError):
    """A path or obstacle object that cannot be used (names it)."""


def bezier_control_points(curve_obj) -> np.ndarray:
    """World-space ground control points ``(3 k + 1, 2)`` of a Bezier curve object's first spline:
    ``P0, P1, P2, P3, P4, ...`` (each cubic segment ``P3i .. P3i+3``); a poly or NURBS spline
    gives its points as a polyline (handles on the chords)."""
    if curve_obj is None or curve_obj.type != "CURVE":
        raise SceneInputError("the path must be a curve object")
    splines = curve_obj.data.splines
    if len(splines) == 0:
        raise SceneInputError(f"path {curve_obj.name!r} has no spline")
    sp = splines[0]
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
        if sp.use_cyclic_u:
            co, hl, hr = np.vstack([co, co[:1]]), np.vstack([hl, hl[:1]]), np.vstack([hr, hr[:1]])
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
    seg = np.linalg.norm(np.diff(out[::3], axis=0), axis=1)
    if np.any(seg < 1e-6):
        raise SceneInputError(f"path {curve_obj.name!r} has two points in the same place")
    return out


def obstacle_footprints(collection, depsgraph=None) -> list:
    """Ground footprints of the collection's objects: convex hulls (k, 2) of their world bounding
    boxes projected to z = 0, one per object (its name kept for reports)."""
    if collection is None:
        return []
    out = []
    for obj in collection.all_objects:
        if obj.type in {"EMPTY", "CAMERA", "LIGHT", "ARMATURE"}:
            continue
        ev = obj.evaluated_get(depsgraph) if depsgraph is not None else obj
        bb = np.array([tuple(c) for c in ev.bound_box], float)
        mw = np.array(ev.matrix_world)
        pts = (bb @ mw[:3, :3].T + mw[:3, 3])[:, :2]
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
