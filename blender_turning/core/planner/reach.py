"""A lower bound on the distance to the path at later samples, from where the foot can get
(Section 6.1's bounds on C_f and dC_f/dt, Eq. 21's foot speed); and the racer's cost, whose
bound comes from the same headings (:class:`RaceCost`).

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

import math

import numpy as np

from ..ground.terrain import Plane
from ..physics.dynamics import OMEGA_V, THETA_DIR, THETA_V, X, Y
from ..physics.model import V_CM
from ..physics.terrain_sim import MIN_SPEED

__all__ = ["ReachBound", "LINES", "RaceCost"]

_CACHE: dict = {}


class ReachBound:
    """``H[cell, k, j]``: support of the foot's displacement after sample ``k + 1``, direction
    ``phi[j]`` relative to the node's heading, for ``C0`` in grid cell ``cell``; ``L[k]``: the
    farthest the foot can be then; ``samples``: how many samples the bound is used for."""

    def __init__(self, problem, directions=16, cells=64, speeds=None, gains=(1.0, 1.0)):
        st, lim, b = problem.settings, problem.limits, problem.body
        V = float(problem.speed.V[0])
        # The speed's and the heading gain's ranges (held speed, flat: one value each; a
        # varying speed: RaceCost.at_root): the rate V_cm gain C_f / (1 - C_f l sin theta_v)
        # is largest at the fast end for C_f > 0 and at the slow end for C_f < 0.
        v_lo, v_hi = (V, V) if speeds is None else speeds
        k_lo, k_hi = v_lo * gains[0], v_hi * gains[1]
        h, sl = st.dt, problem._sin_lean
        n = np.arange(st.n_stages * st.steps_per_stage)
        self.grid = np.linspace(-lim.C_f_max, lim.C_f_max, cells + 1)
        c0 = self.grid[:, None]
        c_hi = np.minimum(lim.C_f_max, c0 + lim.dC_f_max * (n + 1) * h)
        c_lo = np.maximum(-lim.C_f_max, c0 - lim.dC_f_max * (n + 1) * h)
        r_hi = np.where(c_hi > 0.0, k_hi, k_lo) * c_hi / (1.0 - c_hi * b.l * sl)
        r_lo = np.where(c_lo > 0.0, k_lo, k_hi) * c_lo / (1.0 + c_lo * b.l * sl)
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
        v_min = v_lo / (1.0 + lim.C_f_max * b.l * sl)
        sup = h * np.where(c >= 0.0, problem.v_max * c, v_min * c)
        H = np.cumsum(sup, axis=1)[:, per - 1::per]
        self.H = H * (1 + 1e-9) + 1e-9                 # rounding of the sums
        self.L = problem.v_max * st.sample_dt * np.arange(1, H.shape[1] + 1) * (1 + 1e-9) + 1e-9

    @staticmethod
    def for_problem(problem, headings_only: bool = False) -> "ReachBound | None":
        """The bound, if it applies: constant speed, the physical limit cannot bind, and the
        paper's nearest-sample distance.  ``headings_only``: the tables of the heading intervals
        ``I_n`` (``lo``, ``hi``), which any path distance may use (the
        racer's line, :class:`RaceCost`)."""
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


#: ``PlannerSettings.line``: the paper's cost (distance to the drawn path) or the racer's.
LINES = ("path", "race")


class RaceCost:
    """The racer's stage cost and its bound for one :class:`.problem.Problem`.

    The racer's line: the least time through the course, as the branch-and-bound's cost
    (``PlannerSettings.line = "race"``; docs/racing.md, "The racer's line").

    A racer does not follow a drawn line: the racer's objective is the time from the start to the
    finish through the gates (Hirano, "Quickest descent line during alpine ski racing", Sports
    Engineering 9, 2006: the quickest line by optimal control, the edging angle the control), and
    racers' lines tend to "go straight, turn short" (Reinisch, Gautier & Monjo, "The optimal
    trajectory in top-level alpine skiing", 1994).  On flat ground at a constant speed the least
    time is the shortest path around the turning poles.  Over the receding horizon's fixed time that
    is the plan which gets furthest down the course: the cost replaces Section 6's ``sum d_i`` (the
    distance to the drawn path) by the distance *not* made good along the course's direction ``e``
    (the path's start to its end, a unit vector), with the gates the hard constraints they are (the
    obstacles and their clearance, as in Section 6).

    Progress is the centre of mass's: it moves forward at ``V_cm`` along the heading (Eq. 21, ``V_f
    (1 - C_f l sin theta_v) = V_cm``), so over the stage's integration steps (``h = dt``, headings
    ``psi_j`` at the steps' ends, ``psi_0`` the node's) it makes good ``V_cm`` times the trapezoidal
    sum of ``cos(psi_j - phi_e)`` along ``e``, and the stage costs what it does not::

        cost = V_cm h sum_j (1 - (cos(psi_j - phi_e) + cos(psi_j+1 - phi_e)) / 2)      >= 0

    A plan's cost is ``N t_stage V_cm`` less the distance its centre of mass's forward velocity
    makes good down the course: the least is the plan that gets furthest in the horizon's fixed
    time, the problem stated.  (The foot's progress would reward a foot swinging wide of the centre
    of mass, ``V_f = V_cm + l sin(theta_v) dpsi/dt``, and the ground point under the centre of mass
    sways sideways with the lean; neither is time gained, and a branch could buy either with a
    wiggle.) Each stage's cost is non-negative, so ``f`` never decreases along a branch and the
    search (``search.py``) stays exact with any admissible bound on the cost still to come.

    The bound (:meth:`RaceCost.bound`): from a node with heading ``psi0`` and curvature ``C0``, the
    heading at the end of its ``k``-th integration step lies in ``psi0 + I_k`` (:class:`ReachBound`:
    the curvature within ``C0 -+ dC_f_max (k + 1) h``, clipped to ``C_f_max``, and the heading rate
    ``V_f C_f`` within its range over the lean bound).  So each step makes good at most ``V_cm h
    (c_k-1 + c_k) / 2`` with ``c_k = max cos(phi_e - psi)`` over ``psi`` in ``psi0 + I_k`` (``c_-1``
    the node's own ``cos(phi_e - psi0)``), and the cost still to come, over the node's remaining ``n
    = K t_stage / dt`` steps, is at least ``V_cm h sum (1 - (c_k-1 + c_k) / 2)``: 0 for a node
    running straight down the course, more for one heading across it that must first turn at the
    rates Section 6.1 allows.  Where the tables do not apply (a varying speed, or the physical limit
    binds: ``ReachBound.for_problem``) the bound is 0, which every non-negative cost admits.

    The proof reuse of ``proof.py`` stays valid: a stage's cost depends on the node and its choice
    only (``e`` and ``V_cm`` are fixed for the problem), as ``sum d_i`` does.

    **A free speed** (terrain, resistance, braking: ``Problem.free``).  The plans still all last
    ``N t_stage``, so the least time is still the plan whose centre of mass makes good the most
    along ``e``, now at its own speed: ``V_cm(t) cos(psi - phi_e)``.  For a non-negative stage
    cost the distance not made good is counted against an envelope of the speed,

        E(t)^2 = (V_r + a (t - t_r))^2 + 2 (g l (cos theta_r - cos theta_bound)
                                            + (l^2 + I_v / m) omega_r^2 / 2)

    ``V_r``, ``theta_r``, ``omega_r`` the search's root's speed, lean and lean rate at ``t_r``:
    ``a = g sin sigma_max`` is the most gravity adds along the track (friction, drag and braking
    only slow: docs/TERRAIN.md Section 4), and the lean trades its energy with the speed (on flat
    ground without resistance the model keeps ``V^2 / 2 + g l cos theta_v + (l^2 + I_v / m)
    omega_v^2 / 2``, to 1e-10 of it over 3 s of RK4 at 1 ms), so the speed gains at most the
    lean's energy above its least, the lean at its bound and still::

        cost = h sum_j ((E_j - V_j cos(psi_j - phi_e)) + (E_j+1 - V_j+1 cos(psi_j+1 - phi_e))) / 2

    ``sum E`` is the same for every plan of a search, so the least cost is the furthest plan.  The
    envelope rests on that balance, which a slope's lean dynamics only approach; as the run-away
    foot speed (:mod:`.terrain_problem`), it is made a rule of the problem: a branch whose
    ``V_cm`` passes ``E`` at a step's end is clipped and counted as a run-away
    (:meth:`runaway`).  The bound: step
    ``k`` makes good at most ``E_k max(c_k, 0)`` (``c_k`` over the heading interval of the tables
    built with the speed in ``[MIN_SPEED, E]`` and, on a plane of slope ``sigma``, the heading
    gain ``dpsi/dt / (V_f C_f)`` of :func:`..terrain.surface_frame`, ``cos sigma (1 + p^2)`` with
    the slope along the track ``|p| <= tan sigma``, in ``[cos sigma, 1 / cos sigma]``).  The costs
    refer to the search's root, so a search hands no proof on (``receding.py``).
    """

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
        self.n_stages, self.steps, self.h, self.t_stage = (st.n_stages, st.steps_per_stage,
                                                           st.dt, st.t_stage)
        #: ``V_cm h``, m: what one integration step makes good at most (the speed held; with a
        #: speed profile, its largest).
        self.step = problem.speed.max * st.dt
        #: A free speed: the envelope's slope ``a`` (m/s^2) and its root ``(t_r, V_r)``.
        self.free = problem.free
        self.accel = problem.body.g * problem._sin_max if self.free else 0.0
        self.root = (0.0, float(problem.speed.V[0]), 0.0)
        self._lean = (problem.body.g * problem.body.l, math.cos(st.theta_bound),
                      0.5 * (problem.body.l ** 2 + problem.body.I_v / problem.body.m))
        self.tables = (None if self.free else
                       ReachBound.for_problem(problem, headings_only=True))

    def at_root(self, problem, t: float, state) -> "RaceCost":
        """This cost for a search from a root ``state`` at time ``t`` (a free speed: the
        envelope and the tables over its speed range; class docstring)."""
        out = RaceCost.__new__(RaceCost)
        out.__dict__.update(self.__dict__)
        gl, cos_bound, j = self._lean
        lean = gl * (math.cos(float(state[THETA_V])) - cos_bound) + j * float(state[OMEGA_V]) ** 2
        out.root = (float(t), float(state[V_CM]), 2.0 * max(lean, 0.0))
        out.tables = None
        if isinstance(problem.ground, Plane):     # a height field: no tables, the bound 0
            cos = math.cos(problem.ground.slope)
            top = self.envelope(out.root, t + (self.n_stages + 1) * self.t_stage)
            out.tables = ReachBound(problem, max(problem.settings.reach_directions, 1),
                                    speeds=(MIN_SPEED, top), gains=(cos, 1.0 / cos))
        return out

    def envelope(self, root, t):
        """``E(t)``, m/s (class docstring)."""
        return np.sqrt((root[1] + self.accel * (np.asarray(t, float) - root[0])) ** 2 + root[2])

    def runaway(self, P, t0) -> np.ndarray:
        """Columns of ``P`` (shape ``(steps + 1, rows, m)``, from times ``t0``) whose speed
        passes the envelope at a step's end (a free speed only)."""
        if not self.free:
            return np.zeros(P.shape[2], bool)
        t = np.asarray(t0, float)[None, :] + self.h * np.arange(1, len(P))[:, None]
        return ~(P[1:, V_CM] <= self.envelope(self.root, t) * (1 + 1e-9) + 1e-9).all(axis=0)

    def stage_cost(self, P, t0=None) -> np.ndarray:
        """The cost of stages whose states at the integration steps' ends are ``P`` (shape
        ``(steps + 1, rows, m)``, the stage's start first), from times ``t0`` (a free speed)."""
        c = np.cos(P[:, THETA_DIR] - self.angle)                   # (steps + 1, m)
        if not self.free:
            return self.step * (len(c) - 1 - 0.5 * (c[:-1] + c[1:]).sum(axis=0))
        t = np.asarray(t0, float)[None, :] + self.h * np.arange(len(P))[:, None]
        short = np.maximum(self.envelope(self.root, t) - P[:, V_CM] * c, 0.0)
        return self.h * 0.5 * (short[:-1] + short[1:]).sum(axis=0)

    def bound(self, state, C0, depth) -> np.ndarray:
        """Admissible lower bound on the cost still to come after nodes at ``depth`` (the class
        docstring)."""
        C0 = np.atleast_1d(np.asarray(C0, float))
        depth = np.broadcast_to(np.asarray(depth), C0.shape)
        K = self.n_stages - depth
        t = self.tables
        top = int(np.max(K, initial=0)) * self.steps
        if not top or (t is None and not self.free):
            return np.zeros(C0.shape)
        phi = (self.angle - np.asarray(state[THETA_DIR]))[:, None]
        if t is None:
            c = np.ones((len(C0), top))
        else:
            cells = len(t.grid) - 1
            cell = np.clip(np.searchsorted(t.grid, C0, side="right") - 1, 0, cells - 1)
            lo, hi = t.lo[cell, :top], t.hi[cell, :top]                  # (m, top)
            gap = np.abs((phi - 0.5 * (lo + hi) + np.pi) % (2 * np.pi) - np.pi) - 0.5 * (hi - lo)
            c = np.where(gap <= 0.0, 1.0, np.cos(np.minimum(gap, np.pi)))
        mask = np.arange(top)[None, :] < (K * self.steps)[:, None]
        if self.free:            # the envelope E at the steps' ends; step k makes good <= E c+
            tj = (self.root[0] + depth * self.t_stage)[:, None] + self.h * np.arange(top + 1)
            E = self.envelope(self.root, tj)
            made = np.concatenate([np.asarray(state[V_CM])[:, None] * np.cos(phi),
                                   E[:, 1:] * np.maximum(c, 0.0)], axis=1)
            short = E - made
            term = np.where(mask, 0.5 * (short[:, :-1] + short[:, 1:]), 0.0)
            return np.maximum(self.h * term.sum(axis=1) * (1 - 1e-9) - 1e-12, 0.0)
        c = np.concatenate([np.cos(phi), c], axis=1)                 # c_-1, c_0, ...
        term = 1.0 - 0.5 * (c[:, :-1] + c[:, 1:])
        term = np.where(mask, term, 0.0)
        # The sums' rounding (about 1e-15 m a term) stays inside the search's 1e-9 tolerance.
        return np.maximum(self.step * term.sum(axis=1) * (1 - 1e-9) - 1e-12, 0.0)
