"""Speed control by turning on terrain (issue 10; docs/TERRAIN.md Section 6): skiers brake by
turning across the hill.  :class:`TargetSpeed` is the setting, :class:`_Braking` the rule at run
time: the heading schedule :func:`.terrain_sim.simulate_terrain` gives the phase-ellipse
controller (``brake.update(t, state)`` once per step, ``brake(t)`` the commanded heading)."""
from __future__ import annotations

import math
from dataclasses import dataclass

from .params import check_range
from .schedule import Schedule

__all__ = ["TargetSpeed"]


@dataclass(frozen=True)
class TargetSpeed:
    """Speed control by turning (docs/TERRAIN.md Section 6): skiers brake by turning across the
    hill.  The phase-ellipse controller's heading command (the *course*, e.g. the fall line)
    becomes ``course + side * offset`` with

        offset = max_offset * clip(e + I, 0, 1),   e = (V_cm - speed) / band,
    dI/dt = e / reset_time,  I held in [0, 1] (anti-windup),

    so at or below the target speed the slalom runs along the course, and the faster the figure
    is than the target the further across the hill its turns go (up to ``max_offset``); the
    integral term takes out most of a proportional rule's steady excess.  The side
    flips when the figure has drifted ``corridor`` metres to that side of the course line through
    its start: a run of wide turns zig-zagging down inside a corridor.  Each change of side swings
    the heading through the fall line, where the figure speeds up; on an 18 deg slope the mean
    speed stays ~2 m/s above the target (``tests/test_terrain_sim.py`` measures it; a fall-line
    slalom runs away to its terminal speed, ~27 m/s for the skier)."""

    speed: float
    """The target speed, m/s."""
    band: float = 2.0
    """Speed excess at which the offset is full, m/s."""
    max_offset: float = math.radians(85.0)
    """Largest heading offset from the course, rad."""
    corridor: float = 60.0
    """Half-width of the corridor about the course line, m."""
    reset_time: float = 10.0
    """Integral time of the rule, s (``inf``: proportional only)."""

    def __post_init__(self):
        check_range("target_speed", self.speed, 0.0, 100.0, lo_open=True)
        check_range("band", self.band, 0.0, 100.0, lo_open=True)
        check_range("max_offset", self.max_offset, 0.0, math.pi / 2)
        check_range("corridor", self.corridor, 0.0, 1e5, lo_open=True)
        check_range("reset_time", self.reset_time, 0.0, math.inf, lo_open=True)


class _Braking:
    """:class:`TargetSpeed` at run time: the heading schedule it gives the controller."""

    def __init__(self, rule: TargetSpeed, course: Schedule, x0: float, y0: float):
        self.rule, self.course, self.x0, self.y0 = rule, course, x0, y0
        self.side, self.offset, self.integral, self.t = 1.0, 0.0, 0.0, None

    def update(self, t: float, state) -> None:
        r = self.rule
        e = (float(state[5]) - r.speed) / r.band
        if self.t is not None:                  # anti-windup: the integral stays in [0, 1]
            self.integral = min(max(self.integral + e * (t - self.t) / r.reset_time, 0.0), 1.0)
        self.t = t
        self.offset = r.max_offset * min(max(e + self.integral, 0.0), 1.0)
        c = self.course(t)
        lateral = -(state[0] - self.x0) * math.sin(c) + (state[1] - self.y0) * math.cos(c)
        if self.side * lateral > r.corridor:
            self.side = -self.side

    def __call__(self, t: float) -> float:
        return self.course(t) + self.side * self.offset
