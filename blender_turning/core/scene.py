"""Path-following scenes (Section 6, Fig. 11) as JSON files: load, validate, run.

A scene holds the path, the obstacles, the start state, the figure preset and the planner settings
(the format is documented in README.md, "Path following").  Every problem with a file is one
``ValueError`` naming the field: ``scene field obstacles[2].radius = -1 is outside the allowed
range (0, inf)``.  Lengths are metres, times seconds, angles degrees (``*_deg``) at this edge and
radians inside.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, replace

import numpy as np

from .obstacles import Obstacles
from .params import Figure, check_range, preset
from .follow_problem import DEFAULT_CLEARANCE, FollowSetup, start_state
from .path import HermitePath
from .planner import FollowResult, PlannerSettings, Problem, SpeedProfile

__all__ = ["Scene", "load_scene", "scene_from_dict"]

_TOP = {"name", "description", "figure", "path", "obstacles", "clearance", "start", "speed",
        "planner", "duration", "run_out"}


class _Field:
    """Reads fields of a JSON object, naming them fully in every error."""

    def __init__(self, doc, where=""):
        self.doc = doc
        self.where = where

    def name(self, key):
        return f"{self.where}.{key}" if self.where else str(key)

    def fail(self, key, msg):
        raise ValueError(f"scene field {self.name(key)} {msg}")

    def obj(self, key, required=False, allowed=None):
        v = self.doc.get(key) if isinstance(self.doc, dict) else None
        if v is None:
            if required:
                self.fail(key, "is missing")
            v = {}
        if not isinstance(v, dict):
            self.fail(key, f"= {v!r} is not an object")
        f = _Field(v, self.name(key))
        if allowed is not None:
            f.only(allowed)
        return f

    def only(self, allowed):
        for k in self.doc:
            if k not in allowed:
                raise ValueError(f"scene field {self.name(k)} is not known "
                                 f"(expected one of: {', '.join(sorted(allowed))})")

    def has(self, key):
        return key in self.doc

    def number(self, key, default=None, lo=-math.inf, hi=math.inf, lo_open=False, hi_open=False):
        v = self.doc.get(key, default)
        if v is None:
            self.fail(key, "is missing")
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(key, f"= {v!r} is not a number")
        try:
            return check_range(f"scene field {self.name(key)}", v, lo, hi,
                               lo_open=lo_open or lo == -math.inf,
                               hi_open=hi_open or hi == math.inf)
        except ValueError as exc:
            raise ValueError(str(exc)) from None

    def integer(self, key, default, lo, hi):
        v = self.number(key, default, lo, hi)
        if v != int(v):
            self.fail(key, f"= {self.doc.get(key)!r} is not a whole number")
        return int(v)

    def boolean(self, key, default):
        v = self.doc.get(key, default)
        if not isinstance(v, bool):
            self.fail(key, f"= {v!r} is not true or false")
        return v

    def string(self, key, default=None):
        v = self.doc.get(key, default)
        if v is None:
            self.fail(key, "is missing")
        if not isinstance(v, str):
            self.fail(key, f"= {v!r} is not a string")
        return v

    def points(self, key, min_rows=1, default=None):
        v = self.doc.get(key, default)
        if v is None:
            self.fail(key, "is missing")
        try:
            a = np.array(v, float)
        except (TypeError, ValueError):
            self.fail(key, "is not a list of [x, y] pairs of numbers")
        if a.ndim != 2 or a.shape[1] != 2:
            self.fail(key, "is not a list of [x, y] pairs of numbers")
        if len(a) < min_rows:
            self.fail(key, f"has {len(a)} points; at least {min_rows} are needed")
        if not np.all(np.isfinite(a)):
            self.fail(key, "has a value that is not a finite number")
        return a

    def xy(self, key, default):
        v = self.doc.get(key, default)
        if v is None:
            self.fail(key, "is missing")
        try:
            a = np.array(v, float)
        except (TypeError, ValueError):
            a = None
        if a is None or a.shape != (2,) or not np.all(np.isfinite(a)):
            self.fail(key, f"= {v!r} is not an [x, y] pair of numbers")
        return a


@dataclass(frozen=True)
class Scene:
    """A validated scene.  ``state0`` is ``(x, y, theta_dir, theta_v, omega_v)`` in SI units."""

    name: str
    figure: Figure
    path: HermitePath
    obstacles: Obstacles
    state0: np.ndarray
    C_f0: float
    speed: SpeedProfile
    settings: PlannerSettings
    samples_per_segment: int = 12
    exact_distance: bool = False
    duration: float | None = None
    run_out: float | None = None
    description: str = ""

    def with_settings(self, **changes) -> "Scene":
        return replace(self, settings=replace(self.settings, **changes))

    def setup(self) -> FollowSetup:
        """The shared path-following builder (:mod:`.follow_problem`) for this scene."""
        return FollowSetup(self.figure, self.path, self.obstacles, self.settings, self.speed,
                           self.samples_per_segment, self.exact_distance, self.run_out)

    def problem(self) -> Problem:
        """The planning problem (the path with its run-out: :mod:`.follow_problem`)."""
        return self.setup().problem()

    def run(self) -> FollowResult:
        """Follow the path to its end (raises ``PathNotFinished`` at the time limit), or for
        ``duration`` seconds."""
        return self.setup().run(self.state0, self.C_f0, self.duration, meta={"scene": self.name})


def load_scene(path) -> Scene:
    """Read and validate a scene file."""
    try:
        with open(path) as fh:
            doc = json.load(fh)
    except OSError as exc:
        raise ValueError(f"scene file {str(path)!r} cannot be read: {exc.strerror}") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"scene file {str(path)!r} is not valid JSON ({exc})") from None
    return scene_from_dict(doc)


def scene_from_dict(doc) -> Scene:
    if not isinstance(doc, dict):
        raise ValueError("scene must be a JSON object")
    top = _Field(doc)
    top.only(_TOP)
    name = top.string("name", "scene")

    # Figure: a preset, with optional body and limit overrides.
    fig_f = top.obj("figure", required=True, allowed={"preset", "body", "limits"})
    try:
        fig = preset(fig_f.string("preset"))
    except ValueError as exc:
        raise ValueError(f"scene field figure.{exc}") from None
    body_f = fig_f.obj("body", allowed={"m", "l", "I_v", "V_cm", "g"})
    lim_f = fig_f.obj("limits", allowed={"C_f_max", "dC_f_max", "theta_fall_deg"})
    body = {k: body_f.number(k, lo=0.0, hi=1e5, lo_open=True) for k in body_f.doc}
    lims = {k: lim_f.number(k, lo=0.0, hi=1e3, lo_open=True) for k in ("C_f_max", "dC_f_max")
            if lim_f.has(k)}
    if lim_f.has("theta_fall_deg"):
        lims["theta_fall"] = math.radians(lim_f.number("theta_fall_deg", lo=0, hi=90,
                                                       lo_open=True, hi_open=True))
    try:
        fig = replace(fig, body=replace(fig.body, **body), limits=replace(fig.limits, **lims))
    except ValueError as exc:
        raise ValueError(f"scene field figure.{exc}") from None

    # Path: points + tangents, Bezier control points, or a polyline.
    pf = top.obj("path", required=True, allowed={"points", "tangents", "bezier", "polyline",
                                                   "samples_per_segment", "exact_distance"})
    kinds = [k for k in ("points", "bezier", "polyline") if pf.has(k)]
    if len(kinds) != 1:
        pf.fail("points", "or path.bezier or path.polyline: exactly one is needed")
    if kinds[0] == "points":
        pts = pf.points("points", 2)
        tan = pf.points("tangents", len(pts))
        if len(tan) != len(pts):
            pf.fail("tangents", f"has {len(tan)} entries; path.points has {len(pts)}")
        path = HermitePath.from_points(pts, tan)
    elif kinds[0] == "bezier":
        ctrl = pf.points("bezier", 4)
        if (len(ctrl) - 1) % 3:
            pf.fail("bezier", f"has {len(ctrl)} points; 3 n + 1 are needed")
        path = HermitePath.from_bezier(ctrl)
    else:
        path = HermitePath.from_polyline(pf.points("polyline", 2))
    per = pf.integer("samples_per_segment", 12, 1, 10000)
    exact = pf.boolean("exact_distance", False)

    # Obstacles.
    clearance = top.number("clearance", DEFAULT_CLEARANCE, 0.0, 1e3)
    obs = doc.get("obstacles", [])
    if not isinstance(obs, list):
        top.fail("obstacles", "is not a list")
    segs, circles, polys = [], [], []
    for i, o in enumerate(obs):
        of = _Field(o, f"obstacles[{i}]")
        if not isinstance(o, dict):
            raise ValueError(f"scene field obstacles[{i}] is not an object")
        kind = of.string("type")
        if kind == "circle":
            of.only({"type", "center", "radius"})
            c = of.xy("center", None)
            circles.append([c[0], c[1], of.number("radius", lo=0.0, lo_open=True)])
        elif kind == "segment":
            of.only({"type", "from", "to"})
            segs.append([of.xy("from", None), of.xy("to", None)])
        elif kind == "polygon":
            of.only({"type", "points"})
            polys.append(of.points("points", 3))
        else:
            of.fail("type", f"= {kind!r} is not one of circle, segment, polygon")
    obstacles = Obstacles(np.array(segs).reshape(-1, 2, 2), np.array(circles).reshape(-1, 3),
                          polys, clearance)

    # Start state.
    sf = top.obj("start", allowed={"position", "heading_deg", "lean_deg", "lean_rate_deg",
                                   "speed", "C_f"})
    pos = sf.xy("position", list(path.knots[0]))
    heading = math.radians(sf.number("heading_deg")) if sf.has("heading_deg") else None
    lean = math.radians(sf.number("lean_deg", 0.0, -89.0, 89.0))
    rate = math.radians(sf.number("lean_rate_deg", 0.0, -3600.0, 3600.0))
    if sf.has("speed"):
        fig = replace(fig, body=replace(fig.body, V_cm=sf.number("speed", lo=0, hi=100,
                                                                 lo_open=True)))
    cf0 = sf.number("C_f", 0.0, -fig.limits.C_f_max, fig.limits.C_f_max)
    try:
        state0 = start_state(path, pos, heading, lean, rate)
    except ValueError as exc:
        raise ValueError(f"scene field path: {exc}") from None

    # Speed profile (Section 6: "a function of the terrain").
    spf = top.obj("speed", allowed={"by", "at", "V_cm"})
    if spf.doc:
        by = spf.string("by")
        if by not in ("time", "distance"):
            spf.fail("by", f"= {by!r} is not one of time, distance")
        at, vs = spf.doc.get("at"), spf.doc.get("V_cm")
        if not (isinstance(at, list) and isinstance(vs, list) and len(at) == len(vs) and at):
            spf.fail("at", "and speed.V_cm must be lists of numbers of the same, non-zero length")
        for key, values in (("at", at), ("V_cm", vs)):
            for i, v in enumerate(values):
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                    raise ValueError(f"scene field speed.{key}[{i}] = {v!r} is not a number")
        try:
            speed = SpeedProfile(by, at, vs)
        except ValueError as exc:
            raise ValueError(f"scene field {exc}") from None
    else:
        speed = SpeedProfile.constant(fig.body.V_cm)

    # Planner settings (Section 6.1).
    pl = top.obj("planner", allowed={"stages", "choices", "stage_time", "lean_bound_deg",
                                     "sample_dt", "dt", "warm_start", "lower_bound", "fall_table",
                                     "batch"})
    kw = dict(n_stages=pl.integer("stages", 10, 1, 64), q=pl.integer("choices", 5, 2, 64),
              t_stage=pl.number("stage_time", 0.3, 0.0, 60.0, lo_open=True),
              theta_bound=math.radians(pl.number("lean_bound_deg", 30.0, 0.0, 90.0, lo_open=True,
                                                 hi_open=True)),
              sample_dt=pl.number("sample_dt", 0.1, 0.0, 60.0, lo_open=True),
              dt=pl.number("dt", 0.05, 1e-4, 1.0),
              warm_start=pl.boolean("warm_start", True),
              lower_bound=pl.boolean("lower_bound", True),
              fall_table=pl.boolean("fall_table", True),
              batch=pl.integer("batch", 128, 1, 4096))
    try:
        settings = PlannerSettings(**kw)
    except ValueError as exc:
        raise ValueError(f"scene field planner: {exc}") from None

    duration = top.number("duration", lo=0.0, hi=1e5, lo_open=True) if top.has("duration") \
        else None
    run_out = top.number("run_out", lo=0.0, hi=1e5) if top.has("run_out") else None
    if not math.isfinite(fig.limits.dC_f_max) or not math.isfinite(fig.limits.C_f_max):
        raise ValueError("scene field figure.limits: the planner needs finite C_f_max and "
                         "dC_f_max")
    return Scene(name, fig, path, obstacles, state0, cf0, speed, settings, per, exact, duration,
                 run_out, doc.get("description", "") if isinstance(doc.get("description", ""),
                                                                  str) else "")
