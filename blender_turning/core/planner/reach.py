"""A lower bound on the distance to the path at later samples, from where the foot can get
(Section 6.1's bounds on C_f and dC_f/dt, Eq. 21's foot speed).

From a node with heading ``psi0`` and curvature ``C0`` (constant speed ``V_cm``), at every RK4
stage of integration step ``n`` after it (``h = dt``):

1. ``C_f`` lies in ``[c_lo(n), c_hi(n)] = C0 -+ dC_f_max (n + 1) h``, clipped to ``+-C_f_max``:
   each step's first stage is bounded relative to the previous step's, the later stages relative
   to the first (``dynamics.bound_cf``), and the stage boundary keeps the chain; the physical
   limit never binds here (the bound is only used when ``C_f_max l <= 0.9``).
2. The heading rate ``V_f C_f = V_cm C_f / (1 - C_f l sin theta_v)`` increases with ``C_f``; over
   ``|sin theta_v| <= sin_lean`` (the lean bound with ``Problem``'s margin) it lies in
   ``[rho_lo(c_lo), rho_hi(c_hi)]`` with ``rho_hi(c) = V c / (1 - c l sin_lean)`` and
   ``rho_lo(c) = V c / (1 + c l sin_lean)``.
3. Summing (RK4's weights are positive and sum to one), the heading at the start of step ``n`` is
   within ``psi0 + [Lo_n, Hi_n]``, and every stage of step ``n`` within ``psi0 + I_n``,
   ``I_n = [Lo_n + h min(0, rho_lo), Hi_n + h max(0, rho_hi)]``.
4. The foot's displacement over step ``n`` is ``h`` times a weighted mean of stage velocities
   ``V_f (cos psi, sin psi)`` with ``psi`` in ``I_n`` and ``V_f`` in ``[v_min, v_max]``, so it
   lies in ``h`` times the convex hull ``A_n`` of that set, whose support function in direction
   ``phi`` is ``v_max c+ + v_min c-`` with ``c = max cos(phi - psi)`` over ``psi`` in ``I_n``.
5. After ``k`` steps the displacement lies in the Minkowski sum of those hulls, whose support
   function ``H_k(phi)`` is the sum.  For any path sample ``s`` and unit vector ``u(phi)``,
   ``|s - p_k| >= u.(s - p0) - H_k(phi)``; so the nearest-sample distance ``d`` (Section 6) at
   step ``k`` is at least ``min_s max_phi (u(phi).(s - p0) - H_k(phi))`` over any set of
   directions.

The intervals are tabulated once per figure and settings on a grid of ``C0``; a node takes the
hull of its grid cell's ends (both ends of ``I_n`` grow with ``C0``), an over-estimate of ``H``.
Not used with the exact (spline) path distance, which can be below the nearest-sample distance.
"""
from __future__ import annotations

import numpy as np

from ..physics.dynamics import THETA_DIR, X, Y

__all__ = ["ReachBound"]

_CACHE: dict = {}


class ReachBound:
    """``H[cell, k, j]``: support of the foot's displacement after sample ``k + 1``, direction
    ``phi[j]`` relative to the node's heading, for ``C0`` in grid cell ``cell``; ``L[k]``: the
    farthest the foot can be then; ``samples``: how many samples the bound is used for."""

    def __init__(self, problem, directions=16, cells=64):
        st, lim, b = problem.settings, problem.limits, problem.body
        V = float(problem.speed.V[0])
        h, sl = st.dt, problem._sin_lean
        n = np.arange(st.n_stages * st.steps_per_stage)
        self.grid = np.linspace(-lim.C_f_max, lim.C_f_max, cells + 1)
        c0 = self.grid[:, None]
        c_hi = np.minimum(lim.C_f_max, c0 + lim.dC_f_max * (n + 1) * h)
        c_lo = np.maximum(-lim.C_f_max, c0 - lim.dC_f_max * (n + 1) * h)
        r_hi = V * c_hi / (1.0 - c_hi * b.l * sl)
        r_lo = V * c_lo / (1.0 + c_lo * b.l * sl)
        hi = np.cumsum(h * r_hi, axis=1) - h * r_hi + h * np.maximum(r_hi, 0.0)
        lo = np.cumsum(h * r_lo, axis=1) - h * r_lo + h * np.minimum(r_lo, 0.0)
        lo, hi = lo[:-1], hi[1:]                       # a cell's hull: its lower and upper end
        #: ``I_n`` of every grid cell (heading relative to the node's, rad), shape (cells, steps).
        self.lo, self.hi = lo, hi
        per = st.steps_per_sample
        # Samples while every heading interval is narrower than pi: later the hull of where the
        # foot can be is (nearly) a disc, and the cheap Lipschitz bound says as much.
        narrow = np.all(hi - lo < np.pi, axis=0)[per - 1::per]
        self.samples = int(np.argmin(narrow)) if not narrow.all() else len(narrow)
        self.phi = np.linspace(-np.pi, np.pi, directions, endpoint=False)
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
        gap = np.abs((self.phi - mid[..., None] + np.pi) % (2 * np.pi) - np.pi) - half[..., None]
        c = np.where(gap <= 0.0, 1.0, np.cos(np.minimum(gap, np.pi)))
        v_min = V / (1.0 + lim.C_f_max * b.l * sl)
        sup = h * np.where(c >= 0.0, problem.v_max * c, v_min * c)
        H = np.cumsum(sup, axis=1)[:, per - 1::per]
        self.H = H * (1 + 1e-9) + 1e-9                 # rounding of the sums
        self.L = problem.v_max * st.sample_dt * np.arange(1, H.shape[1] + 1) * (1 + 1e-9) + 1e-9

    @staticmethod
    def for_problem(problem, headings_only: bool = False) -> "ReachBound | None":
        """The bound, if it applies: constant speed, the physical limit cannot bind, and the
        paper's nearest-sample distance.  ``headings_only``: the tables of the heading intervals
        ``I_n`` (``lo``, ``hi``), which any path distance may use (the
        racer's line, ``race.py``)."""
        if not problem.speed.is_constant or problem._physical_binds:
            return None
        st = problem.settings
        directions = max(st.reach_directions, 1) if headings_only else st.reach_directions
        if not headings_only and (problem.distance.exact or directions == 0):
            return None
        key = (problem.body, problem.limits, st.dt, st.t_stage, st.n_stages, st.sample_dt,
               st.theta_bound, float(problem.speed.V[0]), directions)
        if key not in _CACHE:
            _CACHE[key] = ReachBound(problem, directions)
            if len(_CACHE) > 64:
                _CACHE.pop(next(iter(_CACHE)))
        return _CACHE[key]

    def sample_bounds(self, samples, state, C0, k, nearest=24):
        """Lower bounds on ``d`` at samples ``k`` (1-based, shape ``(n,)``) after nodes
        ``state`` (shape ``(5, m)``) with curvature ``C0``: shape ``(m, n)``.

        Only each node's ``nearest`` path samples are tested against the reachable set; any other
        is at least its distance from the node less the farthest the foot can go."""
        cells = len(self.grid) - 1
        cell = np.clip(np.searchsorted(self.grid, C0, side="right") - 1, 0, cells - 1)
        rel = samples[None, :, :] - np.stack([state[X], state[Y]], -1)[:, None, :]   # (m, P, 2)
        far = np.inf
        if rel.shape[1] > nearest:
            r2 = rel[..., 0] ** 2 + rel[..., 1] ** 2
            part = np.argpartition(r2, nearest, axis=1)
            far = np.sqrt(np.take_along_axis(r2, part[:, nearest:], 1).min(axis=1))
            rel = np.take_along_axis(rel, part[:, :nearest, None], 1)
        ang = state[THETA_DIR][None, :] + self.phi[:, None]                         # (D, m)
        rel = rel.transpose(2, 1, 0)                                                # (2, W, m)
        proj = rel[0] * np.cos(ang)[:, None] + rel[1] * np.sin(ang)[:, None]        # (D, W, m)
        kk = np.asarray(k) - 1
        H = self.H[cell[None, :], kk[:, None]]                                      # (n, m, D)
        # max over the directions, min over the path samples: elementwise along leading axes.
        best = proj[0][None] - H[:, None, :, 0]                                     # (n, W, m)
        for j in range(1, proj.shape[0]):
            np.maximum(best, proj[j][None] - H[:, None, :, j], out=best)
        out = np.minimum(best.min(axis=1), np.asarray(far) - self.L[kk][:, None]).T  # (m, n)
        return np.maximum(out, 0.0)
