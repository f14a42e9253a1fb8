"""One builder of the path-following problem (Section 6) for every caller: the CLI's scene files
(:mod:`.scene`) and Blender's Follow Path (``blender/jobs/follow_job.py``) build the same problem
from the same inputs, with the same run-out, time limit, start state and end test.

- Run-out: the planner sees the path extended by a straight run-out along its end direction,
  by default one horizon's reach (:meth:`.planner.Problem.reach`), so it does not turn back
  toward the end of the path while the end is within its horizon.
- Time limit: :data:`TIME_LIMIT_FACTOR` times the time to ride the path at the slowest speed of
  the profile; reaching it before the end of the path is a failure
  (:class:`.errors.PathNotFinished`).
- End: progress along the path by arc length (:class:`.path.PathProgress`), counted while the
  foot is within one horizon's reach of the path (what the planner can see).
- Start: the path's first point, heading along its first non-degenerate tangent
  (:meth:`.path.HermitePath.start_direction`), upright, at rest in lean.
- Terrain: given a ``ground`` (:mod:`.terrain`), the problem is the
  :class:`.planner.Problem` on it, with the speed a state where it is not held (start: the body's
  ``V_cm``, the sixth entry of the start state) and the time limit counts at the start speed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from .obstacles import Obstacles
from ..physics.params import Figure
from .path import HermitePath, PathDistance, PathProgress
from ..planner import FollowResult, PlannerSettings, Problem, SpeedProfile, follow
from ..planner.speed_cap import path_curvature_max

__all__ = ["FollowSetup", "DEFAULT_CLEARANCE", "TIME_LIMIT_FACTOR", "start_state"]

#: Distance kept from every obstacle by the foot and the body's ground point when none is given,
#: m: about half the width of a figure with its equipment (poles, handlebars), so its sides clear
#: as well as its centre line.  (Blender's Follow Path keeps the same.)
DEFAULT_CLEARANCE = 0.5

#: The time limit is this many times the time to ride the path at the slowest speed.
TIME_LIMIT_FACTOR = 3.0


def start_state(path: HermitePath, position=None, heading=None, lean=0.0,
                lean_rate=0.0) -> np.ndarray:
    """``(x, y, theta_dir, theta_v, omega_v)``: by default at the path's first point, heading
    along its first non-degenerate tangent, upright and at rest in lean."""
    pos = path.knots[0] if position is None else np.asarray(position, float)
    if heading is None:
        d = path.start_direction()
        heading = math.atan2(d[1], d[0])
    return np.array([pos[0], pos[1], heading, lean, lean_rate], float)


@dataclass(frozen=True)
class FollowSetup:
    """Everything one path-following run needs; :meth:`problem` and :meth:`run`."""

    figure: Figure
    path: HermitePath
    obstacles: Obstacles
    settings: PlannerSettings = field(default_factory=PlannerSettings)
    speed: SpeedProfile | None = None
    samples_per_segment: int = 12
    exact_distance: bool = False
    run_out: float | None = None
    """Straight run-out beyond the path's end, m; ``None``: one horizon's reach."""
    ground: object = None
    """The terrain (:class:`.terrain.Plane`, :class:`.terrain.HeightField`); ``None``: flat
    ground at the speed profile, the paper's problem."""
    resistance: object = None
    """Friction and drag on terrain (:class:`.model.Resistance`; ``None``: none)."""
    speed_cap: object = None
    """Brake to a target speed within the grip (:class:`.planner.speed_cap.SpeedCap`; its
    ``curvature`` is taken from the path); ``None``: no braking."""

    @property
    def speed_profile(self) -> SpeedProfile:
        return self.speed or SpeedProfile.constant(self.figure.body.V_cm)

    def problem(self, cls=Problem) -> Problem:
        """The planning problem on the path with its run-out (``cls``: a :class:`Problem`
        subclass, if the caller needs one)."""
        speed = self.speed_profile
        run_out = self.run_out
        cap = self.speed_cap
        if cap is not None:
            # The racer's line is not held to the drawn path, so its bends set no cap: the
            # gates are the constraints (docs/racing.md, "The least-time line").
            race = self.settings.line == "race"
            cap = replace(cap, curvature=0.0 if race else path_curvature_max(self.path),
                          lean_bound=self.settings.theta_bound)
        if self.ground is not None or cap is not None:
            def make(dist, obstacles):
                return cls(self.figure, dist, obstacles, self.settings, ground=self.ground,
                           resistance=self.resistance, speed_cap=cap)
        else:
            def make(dist, obstacles):
                return cls(self.figure, dist, obstacles, self.settings, speed)
        if run_out is None:
            run_out = make(PathDistance(self.path, 1), Obstacles()).reach()
        dist = PathDistance(self.path.extended(run_out), self.samples_per_segment,
                            self.exact_distance)
        return make(dist, self.obstacles)

    def time_limit(self) -> float:
        """:data:`TIME_LIMIT_FACTOR` times the path's length over the slowest speed, s."""
        v = min(float(self.speed_profile.V.min()), self.figure.body.V_cm)
        return TIME_LIMIT_FACTOR * self.path.length() / v

    def progress(self, problem: Problem | None = None) -> PathProgress:
        """The end test: progress along the path, counted within one horizon's reach of it."""
        return PathProgress(self.path, (problem or self.problem()).reach())

    def run(self, state0=None, C_f0: float = 0.0, duration: float | None = None,
            problem: Problem | None = None, meta: dict | None = None,
            on_replan=None) -> FollowResult:
        """Follow the path from ``state0`` (default :func:`start_state`) to its end, within
        :meth:`time_limit` (raises :class:`.errors.PathNotFinished` otherwise); or, given a
        ``duration``, for that long wherever it gets."""
        problem = problem or self.problem()
        state0 = start_state(self.path) if state0 is None else np.asarray(state0, float)
        if (self.ground is not None or self.speed_cap is not None) and len(state0) == 5:
            state0 = np.append(state0, self.figure.body.V_cm)
        if duration is not None:
            return follow(problem, state0, C_f0, duration, meta=meta, on_replan=on_replan)
        return follow(problem, state0, C_f0, self.time_limit(), self.progress(problem),
                      meta={"path_length": self.path.length(), **(meta or {})},
                      on_replan=on_replan)
