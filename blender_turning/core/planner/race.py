"""The racer's line: the least time through the course, as the branch-and-bound's cost
(``PlannerSettings.line = "race"``; docs/racing.md, "The racer's line").

A racer does not follow a drawn line: the racer's objective is the time from the start to the
finish through the gates (Hirano, "Quickest descent line during alpine ski racing", Sports
Engineering 9, 2006: the quickest line by optimal control, the edging angle the control), and
racers' lines tend to "go straight, turn short" (Reinisch, Gautier & Monjo, "The optimal
trajectory in top-level alpine skiing", 1994).  On flat ground at a constant speed the least time
is the shortest path around the turning poles.  Over the receding horizon's fixed time that is
the plan which gets furthest down the course: the cost replaces Section 6's ``sum d_i`` (the
distance to the drawn path) by the distance *not* made good along the course's direction ``e``
(the path's start to its end, a unit vector), with the gates the hard constraints they are (the
obstacles and their clearance, as in Section 6).

Progress is the centre of mass's: it moves forward at ``V_cm`` along the heading (Eq. 21, ``V_f
(1 - C_f l sin theta_v) = V_cm``), so over the stage's integration steps (``h = dt``, headings
``psi_j`` at the steps' ends, ``psi_0`` the node's) it makes good ``V_cm`` times the trapezoidal
sum of ``cos(psi_j - phi_e)`` along ``e``, and the stage costs what it does not::

    cost = V_cm h sum_j (1 - (cos(psi_j - phi_e) + cos(psi_j+1 - phi_e)) / 2)      >= 0

A plan's cost is ``N t_stage V_cm`` less the distance its centre of mass's forward velocity makes
good down the course: the least is the plan that gets furthest in the horizon's fixed time, the
problem stated.  (The foot's progress would reward a foot swinging wide of the centre of mass,
``V_f = V_cm + l sin(theta_v) dpsi/dt``, and the ground point under the centre of mass sways
sideways with the lean; neither is time gained, and a branch could buy either with a wiggle.)
Each stage's cost is non-negative, so ``f`` never decreases along a branch and the search
(``search.py``) stays exact with any admissible bound on the cost still to come.

The bound (:meth:`RaceCost.bound`): from a node with heading ``psi0`` and curvature ``C0``, the
heading at the end of its ``k``-th integration step lies in ``psi0 + I_k`` (``reach.py``: the
curvature within ``C0 -+ dC_f_max (k + 1) h``, clipped to ``C_f_max``, and the heading rate
``V_f C_f`` within its range over the lean bound).  So each step makes good at most ``V_cm h
(c_k-1 + c_k) / 2`` with ``c_k = max cos(phi_e - psi)`` over ``psi`` in ``psi0 + I_k`` (``c_-1``
the node's own ``cos(phi_e - psi0)``), and the cost still to come, over the node's remaining
``n = K t_stage / dt`` steps, is at least ``V_cm h sum (1 - (c_k-1 + c_k) / 2)``: 0 for a node
running straight down the course, more for one heading across it that must first turn at the
rates Section 6.1 allows.  Where the tables do not apply (a varying speed, or the physical limit
binds: ``ReachBound.for_problem``) the bound is 0, which every non-negative cost admits.

The proof reuse of ``proof.py`` stays valid: a stage's cost depends on the node and its choice
only (``e`` and ``V_cm`` are fixed for the problem), as ``sum d_i`` does.
"""
from __future__ import annotations

import numpy as np

from ..physics.dynamics import THETA_DIR

__all__ = ["LINES", "RaceCost"]

#: ``PlannerSettings.line``: the paper's cost (distance to the drawn path) or the racer's.
LINES = ("path", "race")


class RaceCost:
    """The racer's stage cost and its bound for one :class:`.problem.Problem`."""

    def __init__(self, problem):
        path = problem.distance.path
        a = path.evaluate(0, 0.0)
        b = path.evaluate(path.n_segments - 1, 1.0)
        e = np.asarray(b, float) - np.asarray(a, float)
        if not np.hypot(*e) > 0.0:
            raise ValueError("line = 'race' needs a path whose end is not its start (the "
                             "course's direction runs from one to the other)")
        #: The course's direction ``e`` (a unit vector) and its angle ``phi_e``, rad.
        self.e = e / np.hypot(*e)
        self.angle = float(np.arctan2(self.e[1], self.e[0]))
        st = problem.settings
        self.n_stages, self.steps = st.n_stages, st.steps_per_stage
        #: ``V_cm h``, m: what one integration step makes good at most (the speed held; with a
        #: speed profile, its largest).
        self.step = problem.speed.max * st.dt
        from .reach import ReachBound
        self.tables = ReachBound.for_problem(problem, headings_only=True)

    def stage_cost(self, P) -> np.ndarray:
        """The cost of stages whose states at the integration steps' ends are ``P`` (shape
        ``(steps + 1, rows, m)``, the stage's start first)."""
        c = np.cos(P[:, THETA_DIR] - self.angle)                   # (steps + 1, m)
        return self.step * (len(c) - 1 - 0.5 * (c[:-1] + c[1:]).sum(axis=0))

    def bound(self, state, C0, depth) -> np.ndarray:
        """Admissible lower bound on the cost still to come after nodes at ``depth`` (module
        docstring)."""
        C0 = np.atleast_1d(np.asarray(C0, float))
        K = np.broadcast_to(self.n_stages - np.asarray(depth), C0.shape)
        t = self.tables
        top = int(np.max(K, initial=0)) * self.steps
        if t is None or not top:
            return np.zeros(C0.shape)
        cells = len(t.grid) - 1
        cell = np.clip(np.searchsorted(t.grid, C0, side="right") - 1, 0, cells - 1)
        lo, hi = t.lo[cell, :top], t.hi[cell, :top]                  # (m, top)
        phi = (self.angle - np.asarray(state[THETA_DIR]))[:, None]
        gap = np.abs((phi - 0.5 * (lo + hi) + np.pi) % (2 * np.pi) - np.pi) - 0.5 * (hi - lo)
        c = np.where(gap <= 0.0, 1.0, np.cos(np.minimum(gap, np.pi)))
        c = np.concatenate([np.cos(phi), c], axis=1)                 # c_-1, c_0, ...
        term = 1.0 - 0.5 * (c[:, :-1] + c[:, 1:])
        term = np.where(np.arange(top)[None, :] < (K * self.steps)[:, None], term, 0.0)
        # The sums' rounding (about 1e-15 m a term) stays inside the search's 1e-9 tolerance.
        return np.maximum(self.step * term.sum(axis=1) * (1 - 1e-9) - 1e-12, 0.0)
