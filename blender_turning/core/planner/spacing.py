"""Two consecutive track samples cannot both be close to the path's samples (Section 6's
``d_i``, the distance to the nearest path sample).

Let ``p, p'`` be the foot at two consecutive samples and ``s, s'`` their nearest path samples.

- If ``s = s'``: ``d + d' = |p - s| + |p' - s| >= |p' - p| >= a``, where ``a`` is the least the
  foot moves in one sample interval: every RK4 stage velocity of the interval has ``V_f >=
  v_min = V_min / (1 + eps)`` (Eq. 21, ``eps = min(0.9, C_f_max l sin_lean)``) and a heading
  within ``w = v_max C_f_max sample_dt`` of the heading at ``p`` (the heading rate is ``V_f C_f``),
  so the displacement's component along that heading is at least
  ``a = sample_dt v_min cos(w)`` (for ``w < pi / 2``).
- If ``s != s'``: ``d + d' >= |s - s'| - |p' - p| >= delta - b``, ``b = v_max sample_dt`` the most
  the foot moves, ``delta`` the least distance between distinct path samples in the region where
  ``s, s'`` must lie if ``d + d' < a``: both within ``a`` of the foot, which at sample ``k`` is
  at most ``k b`` from the node's foot and at least ``near[k]`` ahead of it along the node's
  heading (the sum of each step's least component along it, the heading turning no faster than
  ``v_max C_f_max``).

So each pair costs at least ``c = min(a, delta - b)`` (if it cost less than ``c <= a``, both
nearest samples would be in the region, and either case above gives at least ``c``).  The cost
still to come is then at least the best split of its samples into singles (each at least its
own bound ``t_k``) and consecutive pairs (each at least ``max(t_k + t_k+1, c)``), found by a
dynamic programme; and the first sample pairs with the node's own last one:
``d_1 >= c - d_last``.  Not used with the exact (spline) distance, which lets both be small.
"""
from __future__ import annotations

import math

import numpy as np

from ..physics.dynamics import PHYSICAL_MARGIN, THETA_DIR, X, Y

__all__ = ["PairFloor"]


class PairFloor:
    """For one problem's path samples: ``apart[i]``, the distance from sample ``i`` to the
    nearest distinct other sample, and the interval's least and largest foot travel ``a, b``."""

    def __init__(self, problem):
        st, lim = problem.settings, problem.limits
        slip = min(PHYSICAL_MARGIN, lim.C_f_max * problem.body.l * problem._sin_lean)
        v_min = float(np.min(problem.speed.V)) / (1.0 + slip)
        w = problem.v_max * lim.C_f_max * st.sample_dt
        self.a = st.sample_dt * v_min * math.cos(w) * (1 - 1e-9) if w < math.pi / 2 else 0.0
        self.b = problem.v_max * st.sample_dt * (1 + 1e-9)
        # The least distance from the start after k samples: the sum of each step's least
        # component along the first heading, the headings within v_max C_f_max t of it (a
        # component can be negative once they may have turned through more than pi / 2).
        h, steps = st.dt, st.n_stages * st.steps_per_stage
        turn = np.minimum(problem.v_max * lim.C_f_max * h * np.arange(1, steps + 1), math.pi)
        cos = np.cos(turn)
        along = np.cumsum(h * np.where(cos >= 0.0, v_min, problem.v_max) * cos)
        near = np.concatenate([[0.0], along])[::st.steps_per_sample]
        self.near = near - 1e-9 * (1.0 + np.abs(near))
        S = problem.distance.samples
        self.samples = S
        r = np.hypot(S[:, None, 0] - S[None, :, 0], S[:, None, 1] - S[None, :, 1])
        r[r == 0.0] = np.inf                           # the same point counts as one sample
        self.apart = r.min(axis=1) * (1 - 1e-9) if len(S) > 1 else np.full(len(S), np.inf)

    @staticmethod
    def for_problem(problem) -> "PairFloor | None":
        if problem.distance.exact or not len(problem.distance.samples):
            return None
        return PairFloor(problem)

    def floor(self, state, n):
        """``c`` for the pairs ending at samples ``1..n`` (shape ``(m, n)``; column ``k`` is the
        pair of samples ``k`` and ``k + 1``, sample 0 the node's own) of nodes at ``state``."""
        m = state.shape[1]
        if self.a <= 0.0 or n == 0:
            return np.zeros((m, n))
        dx = self.samples[None, :, 0] - state[X][:, None]
        dy = self.samples[None, :, 1] - state[Y][:, None]
        r = np.hypot(dx, dy)
        ahead = dx * np.cos(state[THETA_DIR])[:, None] + dy * np.sin(state[THETA_DIR])[:, None]
        lo, hi = self._region(n)
        used = np.flatnonzero((r <= hi[-1]).any(axis=0))      # samples in some node's region
        r, ahead, apart = r[:, used], ahead[:, used], self.apart[used]
        inside = (ahead[:, None, :] >= lo[None, :, None]) & (r[:, None, :] <= hi[None, :, None])
        c = np.where(inside, apart, np.inf).min(axis=2, initial=np.inf)         # (m, n)
        return np.clip(c - self.b, 0.0, self.a)

    def _region(self, n):
        """Where the nearest path samples of a pair below ``a`` can be: both within ``a`` of the
        foot, which at sample ``k`` is at most ``k b`` from where it started and at least
        ``near[k]`` ahead of it along its first heading."""
        if n > len(self.near) - 1:
            raise ValueError("more samples than the horizon")
        k = np.arange(n)
        return np.minimum(self.near[k], self.near[k + 1]) - self.a, (k + 1) * self.b + self.a
    @staticmethod
    def total(terms, K, c, d_last):
        """The best split of each row's first ``K`` samples into singles and pairs (see the module
        docstring); ``terms`` (shape ``(m, Kmax)``) are the per-sample bounds, ``c`` the pairs'
        floors from :meth:`floor`."""
        m, n = terms.shape
        if n == 0:
            return np.zeros(m)
        t = terms.T.copy()                      # one row per sample: contiguous
        t[0] = np.maximum(t[0], np.where(K >= 1, c[:, 0] - d_last, 0.0))
        c = np.where(K[None, :] > np.arange(n)[:, None], c.T[:n], 0.0)
        prev2, prev = np.zeros(m), t[0].copy()
        pair, single = np.empty(m), np.empty(m)
        for k in range(1, n):
            np.maximum(np.add(t[k - 1], t[k], out=pair), c[k], out=pair)
            np.add(prev, t[k], out=single)
            np.add(prev2, pair, out=pair)
            prev2, prev = prev, np.maximum(single, pair, out=prev2)
        return prev
