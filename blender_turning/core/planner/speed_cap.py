"""The planner brakes (docs/skidding.md Section 6): a speed cap the figure holds by braking at the
foot, within the grip, while the search steers.

A :class:`SpeedCap` makes the braking force a law of the state, part of the problem's model: above
the cap ``V_c`` the braking force is the one that makes the speed decay to ``V_c`` with the time
constant ``tau``, ``F_brake / m = max(0, dV_free / dt + (V - V_c) / tau) V_cm / V_f`` for
``V > V_c`` (``dV_free`` the rate without it: gravity, friction, drag, the lean's share; the
force works at the foot's speed, :func:`..model.rhs`), bounded by the friction circle it shares with
the turn
(:func:`..grip.brake_limit`, the skid at most :data:`..grip.SKID_MAX_TURNING`).  Below the cap it
is 0, the carved model.  The cap is the speed the grip, the lean and the path allow:
``V_c = min(V_target, sqrt(a_max / kappa_max))``, ``kappa_max`` the path's largest curvature and
``a_max = g min(mu_grip, tan theta_bound)`` the largest lateral acceleration (the grip's circle,
or the search's lean bound ``theta_bound``: a steady turn leans ``atan(a / g)``), so that the
tightest bend is within both.

The search stays exact for the problem it states: braking only slows the figure, so the run-away
speed limit and every lower bound of :mod:`.terrain_problem` still hold.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..physics.grip import SKID_MAX_TURNING, Grip, brake_limit, foot_lateral
from ..validate import check

__all__ = ["SpeedCap", "path_curvature_max"]


@dataclass(frozen=True)
class SpeedCap:
    """Brake to ``speed`` within ``grip`` (module docstring)."""

    speed: float
    """The target speed, m/s."""
    grip: Grip
    tau: float = 0.3
    """The time constant the speed decays to the cap with, s."""
    curvature: float = 0.0
    """The path's largest curvature, 1/m (0: the path sets no cap)."""
    lean_bound: float = 0.5 * math.pi
    """The search's lean bound, rad (:class:`.settings.PlannerSettings` ``theta_bound``)."""

    def __post_init__(self):
        check("target_speed", self.speed, "brake_speed")
        check("tau", self.tau, "brake_tau")

    def cap(self, g: float) -> float:
        """``V_c``, m/s."""
        if self.curvature <= 0.0:
            return self.speed
        lateral = min(self.grip.mu, math.tan(min(self.lean_bound, 1.5)))
        return min(self.speed, math.sqrt(lateral * g / self.curvature))

    def brake(self, body, d, cf, V, V_f, N, frame, theta_v):
        """The braking force over the mass, m/s^2, of states at speed ``V`` whose unbraked rates
        are ``d`` (:func:`..model.rhs`)."""
        ratio = V_f / V
        over = V - self.cap(body.g)
        want = np.where(over > 0.0, np.maximum(d[5] + over / self.tau, 0.0), 0.0) / ratio
        mu = self.grip.mu_at(theta_v)
        F_lat = foot_lateral(body.l, frame, V, V_f, cf, theta_v, d[3], d[4])
        room = brake_limit(mu, N / body.m, F_lat, SKID_MAX_TURNING)
        return np.minimum(want, room)


def path_curvature_max(path, per_segment: int = 32) -> float:
    """The largest curvature of a :class:`..path.HermitePath`, 1/m, sampled ``per_segment``
    times a segment: ``|x' y'' - y' x''| / |x'|^3``."""
    best = 0.0
    for seg in range(path.n_segments):
        u = np.linspace(0.0, 1.0, per_segment)
        d1 = np.asarray(path.evaluate(seg, u, 1), float)
        d2 = np.asarray(path.evaluate(seg, u, 2), float)
        cross = np.abs(d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0])
        speed = np.hypot(d1[..., 0], d1[..., 1])
        best = max(best, float(np.max(cross / np.maximum(speed, 1e-12) ** 3)))
    return best
