"""Clip nodes that will fall over whatever they do (an exact addition to Fig. 14's fall clip).

The lean (theta_v, omega_v) and the curvature evolve independently of position at constant
speed.  Steering into a leftward fall as hard as allowed (``dC_f/dt = +dC_f_max`` at every stage)
gives the largest ``C_f`` at every instant of any plan, and (Eq. 2) ``alpha_v`` decreases with
``C_f``.  Where ``alpha_v`` also increases with ``theta_v`` (checked on the whole range, else the
table is not used), the lean system is cooperative, and so is each RK4 step (all its stages are
monotone), so that plan's lean is the smallest of all plans at every step: if even it passes the
bound, every plan does, no later.  The right side is the mirror image (docs/ARCHITECTURE.md
Section 4).

The table covers ``max(n_stages, viable_stages)`` stages: the search asks it about nodes within
the horizon and, for a plan's last node, the ``viable_stages`` after it (``search.py``).

``T[i, j, k]`` is the first step at which the hardest-steering plan from grid state
``(theta[i], omega[j], C_f[k])`` passes ``theta_bound + 1e-9``.  A node is looked up at the grid
corner that is no worse (lean and lean rate no larger, curvature no smaller), whose fall comes no
sooner, so a node is only clipped when it provably falls within its remaining stages.
"""
from __future__ import annotations

import math

import numpy as np

from ..physics.dynamics import THETA_V
from . import flat_stage

__all__ = ["FallTable"]

_NEVER = np.iinfo(np.int64).max // 2
_CACHE: dict = {}


class FallTable:
    """Built once per (body, limits, settings); ``doomed(state, C_f, steps_left)``."""

    def __init__(self, problem, n_theta=41, n_omega=41, n_cf=25, omega_max=2.0):
        st, lim = problem.settings, problem.limits
        V = float(problem.speed.V[0])
        self.bound = st.theta_bound + 1e-9
        self.theta = np.linspace(-st.theta_bound, st.theta_bound, n_theta)
        self.omega = np.linspace(-omega_max, omega_max, n_omega)
        self.cf = np.linspace(-lim.C_f_max, lim.C_f_max, n_cf)
        th, om, cf = np.meshgrid(self.theta, self.omega, self.cf, indexing="ij")
        m = th.size
        x = np.zeros((5, m))
        x[THETA_V], x[4] = th.ravel(), om.ravel()
        c0 = cf.ravel()
        u = np.full(m, lim.dC_f_max)
        T = np.full(m, _NEVER, np.int64)
        h, steps = st.dt, st.steps_per_stage
        end = (steps - 1) * h + h
        live = np.arange(m)            # columns neither fallen yet nor out of the checked range
        for stage in range(max(st.n_stages, st.viable_stages)):
            # Each stage starts from the curvature reached (flat_stage.py: the search's RK4).
            CF, c0 = flat_stage.curvatures(c0, u[:len(live)], h, steps, lim.C_f_max,
                                           lim.dC_f_max, end)
            P = flat_stage.integrate(x, CF, h, V, problem.body)
            going = np.ones(len(live), bool)
            for k, lean in enumerate(P[1:, THETA_V], stage * steps + 1):
                hit = going & (lean > self.bound) & (lean >= -problem._lean_checked)
                T[live[hit]] = k
                going &= ~hit & (lean >= -problem._lean_checked)   # lost: claim nothing
            live, x, c0 = live[going], P[-1][:, going], c0[going]
        self.T = T.reshape(th.shape)

    @staticmethod
    def for_problem(problem) -> "FallTable | None":
        """The table, if the monotonicity it rests on holds for this problem (else ``None``)."""
        st, lim, b = problem.settings, problem.limits, problem.body
        if not problem._fused:          # a varying speed, the physical limit binding, terrain
            return None
        key = (b, lim, st.dt, st.t_stage, max(st.n_stages, st.viable_stages), st.theta_bound,
               float(problem.speed.V[0]))
        if key not in _CACHE:
            _CACHE[key] = FallTable(problem) if _cooperative(problem) else None
            if len(_CACHE) > 64:
                _CACHE.pop(next(iter(_CACHE)))
        return _CACHE[key]

    def doomed(self, state, C_f, steps_left) -> np.ndarray:
        """Nodes whose every continuation passes the lean bound within ``steps_left`` steps."""
        th, om = state[THETA_V], state[4]
        C_f = np.asarray(C_f, float)
        return self._side(th, om, C_f, steps_left) | self._side(-th, -om, -C_f, steps_left)

    def _side(self, th, om, cf, steps_left):
        i = np.searchsorted(self.theta, th, side="right") - 1      # theta[i] <= th
        j = np.searchsorted(self.omega, om, side="right") - 1      # omega[j] <= om
        k = np.searchsorted(self.cf, cf, side="left")              # cf[k] >= C_f
        ok = (i >= 0) & (j >= 0) & (k < len(self.cf))
        i, j, k = (np.clip(a, 0, n - 1) for a, n in ((i, len(self.theta)),
                                                      (j, len(self.omega)), (k, len(self.cf))))
        return ok & (self.T[i, j, k] <= steps_left)


def _cooperative(problem) -> bool:
    """Does ``alpha_v`` (Eq. 2) increase with ``theta_v`` for every ``|C_f| <= C_f_max`` and
    lean in the checked range?  d alpha / d theta =
    ``(g cos th - C V^2 (C l - sin th) / (1 - C l sin th)^2) / J``."""
    b, lim = problem.body, problem.limits
    V = float(problem.speed.V[0])
    th = np.linspace(-problem._lean_checked, problem._lean_checked, 721)[:, None]
    C = np.linspace(-lim.C_f_max, lim.C_f_max, 401)[None, :]
    s, c = np.sin(th), np.cos(th)
    d = b.g * c - C * V * V * (C * b.l - s) / (1.0 - C * b.l * s) ** 2
    return bool(np.all(d > 1e-6)) and problem._lean_checked < math.pi / 2
