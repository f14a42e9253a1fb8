"""One planning problem (Section 6): a figure, a path, obstacles, a speed profile and the
settings; and the simulation of one stage for a batch of nodes (Section 6.1).

Within a stage the control ``u = dC_f/dt`` is constant: the demanded curvature is
``C0 + u (t - t_stage_start)``, clipped to ``|C_f| <= C_f_max`` (Section 6.1), and bounded by
:func:`..dynamics.bound_cf` at every RK4 stage relative to the curvature at the step's start.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..dynamics import (PHYSICAL_MARGIN, THETA_DIR, THETA_V, OMEGA_V, X, Y, bound_cf,
                        forward_alpha, foot_speed, rk4_step)
from ..obstacles import Obstacles
from ..params import Figure
from ..path import PathDistance
from .settings import PlannerSettings, SpeedProfile

__all__ = ["Problem", "StageResult"]

#: Lean margin (rad) over the fall bound used for the largest foot speed: RK4's inner stages of a
#: step whose ends are within the bound can poke slightly beyond it.
_LEAN_MARGIN = 0.1


@dataclass(frozen=True)
class _BatchBody:
    """A :class:`..params.BodyParams` look-alike whose ``V_cm`` may be one value per column."""

    m: float
    l: float
    I_v: float
    V_cm: object
    g: float
    J: float


@dataclass(frozen=True)
class StageResult:
    """Nodes after one stage; every array has one entry per column (child)."""

    state: np.ndarray        # (5, m)
    C_f: np.ndarray          # curvature at the end of the stage
    s: np.ndarray            # foot distance travelled (sum of chord lengths), m
    cost: np.ndarray         # sum of d_i over the stage's samples
    d_last: np.ndarray       # d_i at the stage's last sample (for the lower bound)
    collided: np.ndarray     # bool
    fell: np.ndarray         # bool
    record: dict | None = None   # per-step columns when asked for


def start_derivative(body, x, cf, sin_t, cos_t):
    """The state's time derivative under curvature ``cf`` (Eqs. 2 and 21), with alpha_v, V_f."""
    V_f = foot_speed(body, x[THETA_V], cf, sin_t)
    alpha = forward_alpha(body, x[THETA_V], cf, sin_t, cos_t)
    d = x[THETA_DIR]
    k1 = np.stack([V_f * np.cos(d), V_f * np.sin(d), V_f * cf, x[OMEGA_V], alpha])
    return k1, alpha, V_f


class Problem:
    """Everything a search needs, as plain arrays (the Blender side builds one from a curve and
    objects).  ``distance`` is a :class:`PathDistance`, ``obstacles`` an :class:`Obstacles`."""

    def __init__(self, figure: Figure, distance: PathDistance, obstacles: Obstacles,
                 settings: PlannerSettings, speed: SpeedProfile | None = None):
        self.figure = figure
        self.body = figure.body
        self.limits = figure.limits
        if not math.isfinite(self.limits.dC_f_max) or not math.isfinite(self.limits.C_f_max):
            raise ValueError(f"the planner needs finite C_f_max and dC_f_max; preset "
                             f"{figure.name!r} has {self.limits.C_f_max!r}, {self.limits.dC_f_max!r}")
        self.distance = distance
        self.obstacles = obstacles
        self.settings = settings
        self.speed = speed or SpeedProfile.constant(self.body.V_cm)
        #: The q values of dC_f/dt, spread evenly within their bound (Section 6.1).
        self.u_values = self.limits.dC_f_max * np.linspace(-1.0, 1.0, settings.q)
        # Largest foot speed on any branch that is not clipped (Eq. 21 at the largest |C_f| and
        # lean), for the admissible lower bound.
        lean = min(settings.theta_bound + _LEAN_MARGIN, math.pi / 2)
        slip = min(PHYSICAL_MARGIN, self.limits.C_f_max * self.body.l * math.sin(lean))
        self.v_max = self.speed.max / (1.0 - slip)

    def reach(self) -> float:
        """How far the foot can get within one horizon, m."""
        return self.v_max * self.settings.horizon * 1.001 + 1e-6

    def local(self, center) -> "Problem":
        """The same problem with the path samples and obstacles that cannot matter within one
        horizon of ``center`` dropped (exact: see :meth:`PathDistance.near`, :meth:`Obstacles.near`)."""
        r = self.reach()
        p = Problem.__new__(Problem)
        p.__dict__.update(self.__dict__)
        p.distance = self.distance.near(center, r)
        p.obstacles = self.obstacles.near(center, r)
        return p

    def lower_bound(self, d_last, depth):
        """Admissible bound on the cost still to come after a node at ``depth`` whose last sample
        was ``d_last`` from the path: d can shrink by at most ``v_max sample_dt`` per sample
        (d is 1-Lipschitz), so ``sum_k max(0, d_last - k v_max sample_dt)``."""
        st = self.settings
        K = (st.n_stages - np.asarray(depth)) * st.samples_per_stage
        b = self.v_max * st.sample_dt
        M = np.minimum(K, np.floor(np.asarray(d_last) / b))
        return np.maximum(M * d_last - b * M * (M + 1) * 0.5, 0.0)

    def _body_at(self, t, s):
        if self.speed.is_constant and self.speed.V[0] == self.body.V_cm:
            return self.body
        b = self.body
        return _BatchBody(b.m, b.l, b.I_v, self.speed(t, s), b.g, b.J)

    def simulate_stage(self, state, C_f0, u, t0, s0, record: bool = False) -> StageResult:
        """Simulate every column of ``state`` (shape ``(5, m)``) for one stage with
        ``dC_f/dt = u``; ``t0``, ``s0`` are the columns' start time and distance travelled."""
        st = self.settings
        body0, lim = self.body, self.limits
        cmax = lim.C_f_max
        u = np.asarray(u, float)
        C_f0 = np.asarray(C_f0, float)

        def desired(tau, _state):
            return np.clip(C_f0 + u * tau, -cmax, cmax)

        x = np.array(state, float)
        s = np.array(s0, float)
        m = x.shape[1]
        anchor = C_f0
        cost = np.zeros(m)
        d = np.zeros(m)
        fell = np.zeros(m, bool)
        seg_a, seg_b = [], []
        rec = {k: [] for k in ("state", "C_f", "alpha_v", "V_f", "t")} if record else None
        h = st.dt
        for k in range(st.steps_per_stage):
            tau = k * h
            body = self._body_at(t0 + tau, s)
            sin_t, cos_t = np.sin(x[THETA_V]), np.cos(x[THETA_V])
            cf = bound_cf(body, lim, desired(tau, x), sin_t, anchor, h)
            k1, alpha, V_f = start_derivative(body, x, cf, sin_t, cos_t)
            if record:
                rec["state"].append(x.copy())
                rec["C_f"].append(cf)
                rec["alpha_v"].append(alpha)
                rec["V_f"].append(V_f)
                rec["t"].append(np.asarray(t0, float) + tau)
            new = rk4_step(body, lim, x, tau, h, desired, cf, k1)
            seg_a.append(x[:2].T)
            seg_b.append(new[:2].T)
            s = s + np.hypot(new[X] - x[X], new[Y] - x[Y])
            x, anchor = new, cf
            fell |= ~(np.abs(x[THETA_V]) <= st.theta_bound)       # NaN counts as fallen
            if (k + 1) % st.steps_per_sample == 0:
                d = self.distance(x[:2].T)
                cost = cost + d
        # The curvature in force at the end of the stage (the next stage's C0).
        cf_end = bound_cf(self._body_at(t0 + st.t_stage, s), lim, desired(st.t_stage, x),
                          np.sin(x[THETA_V]), anchor, h)
        collided = self.obstacles.collides(np.concatenate(seg_a), np.concatenate(seg_b))
        collided = collided.reshape(st.steps_per_stage, m).any(axis=0) if len(self.obstacles) \
            else np.zeros(m, bool)
        return StageResult(x, np.asarray(cf_end, float) * np.ones(m), s, cost, d, collided,
                           fell, rec)
