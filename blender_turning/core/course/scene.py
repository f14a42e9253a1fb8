"""Path-following scenes (Section 6, Fig. 11) as JSON files: load, validate, run.

A scene holds the path, the obstacles, the start state, the figure preset and the planner settings
(the format is documented in docs/cli.md, "Scene files").  Every problem with a file is one
``ValueError`` naming the file and the field, with the ranges of :mod:`.ranges`:
``slalom.json: obstacles[2].radius = -1 is outside the allowed range (0, 10000] m``.
Lengths are metres, times seconds, angles degrees (``*_deg``) at this edge and radians inside.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .moving import around
from .obstacles import Obstacles
from .follow_problem import DEFAULT_CLEARANCE, FollowSetup, start_state
from ..physics.params import PRESETS, Figure, preset
from .path import HermitePath
from ..planner import FollowResult, PlannerSettings, Problem, SpeedProfile
from ..planner.reach import LINES
from ..planner.settings import SPREADS
from ..ranges import RANGES
from ..ground.scene_terrain import read_terrain
from ..validate import FieldError, Fields, read_json

__all__ = ["Scene", "load_scene", "scene_from_dict"]

_TOP = {"name", "description", "figure", "path", "obstacles", "clearance", "start", "speed",
        "planner", "duration", "run_out", "terrain"}
# planner key -> (PlannerSettings field, key of RANGES or None for a switch, default)
_PLANNER = {"stages": ("n_stages", "n_stages", 10), "choices": ("q", "q", 5),
            "choices_near": ("q_near", "q_near", 0),
            "stage_time": ("t_stage", "t_stage", 0.3),
            "lean_bound_deg": ("theta_bound", "theta_bound", 30.0),
            "sample_dt": ("sample_dt", "sample_dt", 0.1), "dt": ("dt", "planner_dt", 0.05),
            "batch": ("batch", "batch", 128),
            "leg_force_max_bw": ("leg_force_max", "leg_force_max", 0.0),
            "warm_start": ("warm_start", None, True),
            "lower_bound": ("lower_bound", None, True), "fall_table": ("fall_table", None, True)}


@dataclass(frozen=True)
class Scene:
    """A validated scene.  ``state0`` is ``(x, y, theta_dir, theta_v, omega_v)`` in SI units
    (and ``V_cm`` on terrain, where ``ground`` is set: :mod:`.scene_terrain`)."""

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
    ground: object = None
    resistance: object = None
    speed_cap: object = None
    """Brake to a target speed within the grip (:class:`.planner.speed_cap.SpeedCap`)."""

    def with_settings(self, **changes) -> "Scene":
        return replace(self, settings=replace(self.settings, **changes))

    def setup(self) -> FollowSetup:
        """The shared path-following builder (:mod:`.follow_problem`) for this scene."""
        return FollowSetup(self.figure, self.path, self.obstacles, self.settings, self.speed,
                           self.samples_per_segment, self.exact_distance, self.run_out,
                           self.ground, self.resistance, self.speed_cap)

    def problem(self) -> Problem:
        """The planning problem (the path with its run-out: :mod:`.follow_problem`)."""
        return self.setup().problem()

    def run(self, movers=None, on_replan=None) -> FollowResult:
        """Follow the path to its end (raises ``PathNotFinished`` at the time limit), or for
        ``duration`` seconds; around ``movers`` too (other figures' bodies, a
        :class:`.moving.MovingBodies` on this figure's clock), if given.  ``on_replan(t, xy,
        fraction)``: called before every replanning (:func:`.planner.receding.follow`), e.g. for
        a progress bar."""
        setup = self.setup()
        problem = None if movers is None else around(setup.problem(), movers)
        return setup.run(self.state0, self.C_f0, self.duration, problem=problem,
                         meta={"scene": self.name}, on_replan=on_replan)


def check_horizon(settings: PlannerSettings, where: str = "") -> None:
    """One planning search must stay a bounded amount of work (``RANGES['search_size']``,
    ``RANGES['horizon_*']``)."""
    q = max(settings.q, settings.q_near)
    size = float(q) ** settings.n_stages
    if not RANGES["search_size"].contains(size):
        raise FieldError(f"{where}the search q^N = {q}^{settings.n_stages} = "
                         f"{size:.3g} leaves is outside the allowed range [1, 7^16 = "
                         f"{7.0 ** 16:.3g}]: lower the stages or the choices")
    horizon = settings.n_stages * settings.t_stage
    for key, step, name in (("horizon_steps", settings.dt, "dt"),
                            ("horizon_samples", settings.sample_dt, "sample_dt")):
        n = horizon / step
        if not RANGES[key].contains(round(n)):
            raise FieldError(f"{where}the horizon N t_stage / {name} = {settings.n_stages} x "
                             f"{settings.t_stage:g} s / {step:g} s = {n:.0f} is outside the "
                             f"allowed range {RANGES[key]}")


def load_scene(path) -> Scene:
    """Read and validate a scene file; every error names the file and the field."""
    return scene_from_dict(read_json(path, "scene file"), str(path))


def _path(pf: Fields) -> HermitePath:
    """Section 6's path: points + tangents, Bezier control points, or a polyline."""
    kinds = [k for k in ("points", "bezier", "polyline") if pf.has(k)]
    if len(kinds) != 1:
        pf.fail("points", "or path.bezier or path.polyline: exactly one is needed")
    kind = kinds[0]
    if kind == "points":
        pts = pf.points("points", 2)
        tan = pf.points("tangents", len(pts))
        if len(tan) != len(pts):
            pf.fail("tangents", f"has {len(tan)} entries; path.points has {len(pts)}")
        knots, step = pts, 1
    elif kind == "bezier":
        ctrl = pf.points("bezier", 4)
        if (len(ctrl) - 1) % 3:
            pf.fail("bezier", f"has {len(ctrl)} points; 3 n + 1 are needed")
        knots, step = ctrl[0::3], 3
    else:
        knots, step = pf.points("polyline", 2), 1
    # A segment of zero length has no direction (the run-out and the end test need one).
    for i in range(1, len(knots)):
        if np.array_equal(knots[i], knots[i - 1]):
            Fields(pf.doc[kind], pf.source, pf.name(kind)).fail(
                i * step, f"= {knots[i].tolist()} is the same point as path.{kind}"
                          f"[{(i - 1) * step}]; a path needs distinct consecutive points")
    if kind == "points":
        return HermitePath.from_points(pts, tan)
    if kind == "bezier":
        return HermitePath.from_bezier(ctrl)
    return HermitePath.from_polyline(knots)


def _obstacles(top: Fields) -> Obstacles:
    clearance = top.number("clearance", "clearance", DEFAULT_CLEARANCE)
    segs, circles, polys = [], [], []
    for of in top.tables("obstacles"):
        kind = of.string("type", choices=("circle", "segment", "polygon"))
        if kind == "circle":
            of.only({"type", "center", "radius"})
            c = of.xy("center")
            circles.append([c[0], c[1], of.number("radius", "radius")])
        elif kind == "segment":
            of.only({"type", "from", "to"})
            segs.append([of.xy("from"), of.xy("to")])
        else:
            of.only({"type", "points"})
            polys.append(of.points("points", 3))
    return Obstacles(np.array(segs).reshape(-1, 2, 2), np.array(circles).reshape(-1, 3),
                     polys, clearance)


def read_figure(f) -> Figure:
    """A figure's ``preset`` with its optional ``body`` and ``limits`` overrides, read from the
    fields ``f`` (:class:`.validate.Fields`; ranges: core/ranges.py).  Scene and crowd files."""
    fig = preset(f.string("preset", choices=tuple(PRESETS)))
    body_f = f.table("body", {"m", "l", "I_v", "V_cm", "g"})
    lim_f = f.table("limits", {"C_f_max", "dC_f_max", "theta_fall_deg"})
    body = {k: body_f.number(k, k) for k in body_f.keys()}
    lims = {k: lim_f.number(k, k) for k in ("C_f_max", "dC_f_max") if lim_f.has(k)}
    if lim_f.has("theta_fall_deg"):
        lims["theta_fall"] = math.radians(lim_f.number("theta_fall_deg",
                                                       RANGES["theta_fall"].deg()))
    return replace(fig, body=replace(fig.body, **body), limits=replace(fig.limits, **lims))


def scene_from_dict(doc, source: str = "scene") -> Scene:
    """Validate a parsed scene document; errors name ``source`` and the field."""
    if not isinstance(doc, dict):
        raise FieldError(f"{source}: the scene must be a JSON object, not {type(doc).__name__}")
    top = Fields(doc, source).only(_TOP)
    name = top.string("name", "scene")
    description = top.string("description", "")

    # Figure: a preset, with optional body and limit overrides (ranges: core/ranges.py).
    fig = read_figure(top.table("figure", {"preset", "body", "limits"}, required=True))

    pf = top.table("path", {"points", "tangents", "bezier", "polyline", "samples_per_segment",
                            "exact_distance"}, required=True)
    path = _path(pf)
    per = pf.number("samples_per_segment", "samples_per_segment", 12)
    exact = pf.boolean("exact_distance", False)
    obstacles = _obstacles(top)

    # Start state.
    sf = top.table("start", {"position", "heading_deg", "lean_deg", "lean_rate_deg", "speed",
                             "C_f"})
    pos = sf.xy("position", path.knots[0].tolist())
    heading = None              # default: along the path's first non-degenerate tangent
    if sf.has("heading_deg"):
        heading = math.radians(sf.number("heading_deg", RANGES["heading"].deg()))
    lean = math.radians(sf.number("lean_deg", RANGES["theta_v0"].deg(), 0.0))
    rate = math.radians(sf.number("lean_rate_deg", RANGES["omega_v0"].deg(), 0.0))
    if sf.has("speed"):
        fig = replace(fig, body=replace(fig.body, V_cm=sf.number("speed", "V_cm")))
    c_max = fig.limits.C_f_max
    cf0 = sf.number("C_f", replace(RANGES["C_f0"], lo=-c_max, hi=c_max), 0.0)
    state0 = start_state(path, pos, heading, lean, rate)
    ground = resistance = None
    if top.has("terrain"):      # the ground; the speed becomes a state
        ground, resistance = read_terrain(top.table("terrain"), fig.name)
        if top.has("speed"):
            top.fail("speed", "is computed along the way on terrain; give start.speed instead")
        state0 = np.append(state0, fig.body.V_cm)

    # Speed profile (Section 6: "a function of the terrain").
    spf = top.table("speed", {"by", "at", "V_cm"})
    if spf.keys():
        by = spf.string("by", choices=("time", "distance"))
        at = spf.numbers("at", "schedule_t" if by == "time" else "distance")
        vs = spf.numbers("V_cm", "V_cm")
        if len(at) != len(vs):
            spf.fail("V_cm", f"has {len(vs)} values; speed.at has {len(at)}")
        for i in range(1, len(at)):
            if at[i] <= at[i - 1]:
                spf.fail("at", f"[{i}] = {at[i]!r} does not come after speed.at[{i - 1}] = "
                               f"{at[i - 1]!r}")
        speed = SpeedProfile(by, at, vs)
    else:
        speed = SpeedProfile.constant(fig.body.V_cm)

    # Planner settings (Section 6.1).
    pl = top.table("planner", set(_PLANNER) | {"line", "spread"})
    kw = {"line": pl.string("line", "path", choices=LINES),    # the cost (planner/reach.py)
          "spread": pl.string("spread", "rate", choices=SPREADS)}    # PlannerSettings.spread
    for key, (field, rng, default) in _PLANNER.items():
        if rng is None:
            kw[field] = pl.boolean(key, default)
        elif key.endswith("_deg"):
            kw[field] = math.radians(pl.number(key, RANGES[rng].deg(), default))
        else:
            kw[field] = pl.number(key, rng, default)
    try:
        settings = PlannerSettings(**kw)
    except ValueError as exc:
        raise FieldError(f"{source}: planner: {exc}") from None
    check_horizon(settings, f"{source}: planner: ")

    duration = top.number("duration", "plan_duration", None)
    run_out = top.number("run_out", "run_out", None)
    if duration is None:         # Scene.run's safety net (3 L / V) must be a bounded run too
        longest = 3.0 * path.length() / min(speed.V.min(), fig.body.V_cm)
        if not RANGES["plan_duration"].contains(longest):
            top.fail("duration", f"is missing and the path ({path.length():.0f} m) could take "
                                 f"up to {longest:.0f} s to follow; give a duration in "
                                 f"{RANGES['plan_duration']} or a shorter path")
    if not math.isfinite(fig.limits.dC_f_max) or not math.isfinite(fig.limits.C_f_max):
        top.fail("figure", "limits: the planner needs finite C_f_max and dC_f_max")
    return Scene(name, fig, path, obstacles, state0, cf0, speed, settings, per, exact, duration,
                 run_out, description, ground, resistance)
