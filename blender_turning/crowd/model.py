"""A crowd as data: figures, each with its body, controller, start and time offset.

A :class:`Crowd` is a tuple of :class:`CrowdFigure`; the formations (:mod:`.formations`) build
them from a template and a seed, the reader (:mod:`.reader`) from a crowd scene file, the runner
(:mod:`.runner`) simulates or plans them.  Two controllers:

- :class:`Turns`: the parametric controller of Section 5 (phase ellipse with directional
  control), one turn period, lean and heading per figure.  All such figures of a crowd that share
  a body run as one task (:mod:`.kernels`: each on floats, or one numpy batch when many).
- :class:`FollowPath`: path following (Section 6) of a core :class:`~..core.course.scene.Scene` (its
  path, obstacles, start, speed profile and planner settings); planned one task per figure.

Every figure has its own clock: it starts at ``time_offset`` seconds of the crowd's clock, and
its trajectory is reported on the crowd's clock (``t = time_offset + own t``).

Priority planning: the figures a crowd's ``priority`` names plan in that order, each
path figure around the bodies of those before it (:mod:`..core.course.moving`), keeping
``clearance``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.course.follow_problem import DEFAULT_CLEARANCE
from ..core.physics.params import Figure, check_range
from ..core.ranges import MAX_STEPS
from ..core.validate import check
from ..core.physics.simulate import slalom_start

__all__ = ["Turns", "FollowPath", "CrowdFigure", "Crowd", "FIRST_TURNS", "BODY_CLEARANCE"]

FIRST_TURNS = ("left", "right")

#: Distance kept between two figures' foot-CM segments in priority planning, m: each figure's
#: half width with its equipment (the obstacles'
#: :data:`..core.course.follow_problem.DEFAULT_CLEARANCE`) on either side of the gap.
BODY_CLEARANCE = 2.0 * DEFAULT_CLEARANCE


@dataclass(frozen=True)
class Turns:
    """Parametric turning (Section 5): a slalom of ``period`` and ``lean`` about ``heading``."""

    period: float
    """One left-right cycle, ``2 pi / omega0``, s."""
    lean: float
    """``theta_max``, rad."""
    heading: float | None = 0.0
    """``theta_h``, the mean direction of travel, rad CCW from +x (Section 5.2); ``None``: no
    directional control (the heading drifts as it will)."""

    def __post_init__(self):
        check("period", self.period, "period")
        check("lean", self.lean, "theta_max")
        if self.heading is not None:
            check("heading", self.heading, "heading")

    @property
    def omega0(self) -> float:
        return 2.0 * math.pi / self.period


@dataclass(frozen=True)
class FollowPath:
    """Path following (Section 6): the figure plans its way along ``scene`` (a core
    :class:`~..core.course.scene.Scene`: path, obstacles, start state, speed profile, planner)."""

    scene: object


@dataclass(frozen=True)
class CrowdFigure:
    """One figure of a crowd.

    For :class:`Turns`, ``position`` (m) is the start of the foot and ``first_turn`` says which
    way the first half-turn goes: ``"left"`` starts at phase 0 (upright, leaning left, heading
    half a half-turn's change right of ``controller.heading``: :func:`~..core.slalom_start`),
    ``"right"`` is its mirror image about the heading (phase 180 deg, the antiphase of Fig. 10,
    track 1).  For :class:`FollowPath` the start is the scene's and ``position`` is ignored.
    """

    name: str
    figure: Figure
    controller: Turns | FollowPath
    position: tuple = (0.0, 0.0)
    first_turn: str = "left"
    time_offset: float = 0.0
    """When the figure starts on the crowd's clock, s (>= 0)."""

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name or self.name.startswith(".") \
                or any(c in self.name for c in "/\\\0"):
            raise ValueError(f"figure name = {self.name!r} is not a non-empty string without "
                             f"a path separator (it names the figure's CSV file)")
        if self.first_turn not in FIRST_TURNS:
            raise ValueError(f"first_turn = {self.first_turn!r} is not one of left, right")
        check_range("time_offset", self.time_offset, 0.0, 1e5)
        p = np.asarray(self.position, float)
        if p.shape != (2,) or not np.all(np.isfinite(p)):
            raise ValueError(f"position = {self.position!r} is not a finite (x, y) pair")
        object.__setattr__(self, "position", (float(p[0]), float(p[1])))

    @property
    def is_path(self) -> bool:
        return isinstance(self.controller, FollowPath)

    def state0(self) -> np.ndarray:
        """The start state ``(x, y, theta_dir, theta_v, omega_v)``."""
        if self.is_path:
            return np.asarray(self.controller.scene.state0, float)
        c = self.controller
        mean = 0.0 if c.heading is None else c.heading
        x, y, th_dir, th_v, om = slalom_start(self.figure.body, c.omega0, c.lean, mean,
                                              *self.position)
        if self.first_turn == "right":     # mirror about the mean heading (Section 1 symmetry)
            th_dir, th_v, om = 2.0 * mean - th_dir, -th_v, -om
        return np.array([x, y, th_dir, th_v, om])


@dataclass(frozen=True)
class Crowd:
    """A crowd: figures with unique names, the length of the shot and the integration step.

    ``duration`` (s, on the crowd's clock) ends every :class:`Turns` figure; a path figure ends
    at its path's end (or its scene's ``duration``).  ``dt`` is the RK4 step of the parametric
    figures.  ``seed`` is the one the formations drew from (recorded in the summary).

    ``priority``: names of figures in planning order (``crowd/runner.py``): each path figure
    named plans around the bodies of the figures named before it, keeping ``clearance`` (m)
    from them; the parametric figures cannot steer, so they must come before every path figure
    named.  Figures not named plan alone."""

    name: str
    figures: tuple
    duration: float
    dt: float = 0.02
    seed: int = 0
    priority: tuple = ()
    clearance: float = BODY_CLEARANCE

    def __post_init__(self):
        object.__setattr__(self, "figures", tuple(self.figures))
        if not self.figures:
            raise ValueError("a crowd needs at least one figure")
        check("duration", self.duration, "duration")
        check("dt", self.dt, "dt")
        if self.duration / self.dt > MAX_STEPS:
            raise ValueError(f"duration {self.duration:g} s / dt {self.dt:g} s = "
                             f"{self.duration / self.dt:.3g} steps; at most {MAX_STEPS:,}")
        seen = set()
        for f in self.figures:
            if f.name in seen:
                raise ValueError(f"figure name {f.name!r} is used twice")
            seen.add(f.name)
            if not f.is_path and f.time_offset >= self.duration:
                raise ValueError(f"figure {f.name!r}: time_offset = {f.time_offset:g} s is not "
                                 f"before the crowd's duration ({self.duration:g} s)")
        object.__setattr__(self, "priority", tuple(self.priority))
        check("clearance", self.clearance, "body_clearance")
        path_named = None
        for i, name in enumerate(self.priority):
            if name not in seen:
                raise ValueError(f"priority[{i}] = {name!r} names no figure of the crowd")
            if name in self.priority[:i]:
                raise ValueError(f"priority[{i}] = {name!r} is named twice")
            if self[name].is_path:
                path_named = path_named or name
            elif path_named is not None:
                raise ValueError(f"priority[{i}] = {name!r} follows the parametric controller "
                                 f"and cannot steer around {path_named!r}, named before it: "
                                 f"name the parametric figures first")

    def __getitem__(self, name: str) -> CrowdFigure:
        for f in self.figures:
            if f.name == name:
                return f
        raise KeyError(name)
