"""One planning problem (Section 6): a figure, a path, obstacles, a speed profile and the
settings; and the simulation of one stage for a batch of nodes (Section 6.1).

Within a stage the control ``u = dC_f/dt`` is constant: the demanded curvature is
``C0 + u (t - t_stage_start)``, clipped to ``|C_f| <= C_f_max`` (Section 6.1), and bounded by
the same rule as :func:`..dynamics.bound_cf` at every RK4 stage, relative to the curvature at the
step's start (fused into :meth:`Problem._rhs`; tests hold it to the core's RK4).

On a preset's carving skis a branch also falls when, at the start of an integration step or at
the stage's end, its curvature needs a larger edge angle than its lean and the body's angulation
give (:class:`..equipment.EdgeLimit`: ``R_sc |C_f| cos(min(edge_max, max(0, theta_v sgn(C_f) +
A))) <= 1``): the racer cannot hold that edge, so the line is not skiable (docs/racing.md, "The
racer's line"; ``PlannerSettings.edge_limit``).

With ``PlannerSettings.leg_force_max`` a branch also falls when, at the start of an integration
step or at the stage's end, the leg force (Appendix A) passes that many body weights: the legs
cannot hold it.

A node collides when, over any integration step, the foot's straight move or that of the ground
point under the centre of mass (:meth:`Problem.body_point`) comes within the clearance of an
obstacle (Section 6 checks the foot; the body sways up to ``l sin(theta_bound)`` to the side of
it, 0.86 m for the skier at 30 deg, enough to pass over a gate panel the foot clears).  Adding a
clip only removes branches, so every lower bound on the cost of a branch stays admissible.

Figures planned before this one (a crowd's priority planning) are moving obstacles:
:attr:`Problem.movers`, a :class:`..moving.MovingBodies` on this figure's clock, checked on the
same steps with each step's time (:meth:`..moving.MovingBodies.collides`); a node's time is
part of its identity, so every reuse across searches (proof, warm start: ``proof.py``) sees the
same collisions for the same node.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..physics.dynamics import (PHYSICAL_MARGIN, OMEGA_V, THETA_DIR, THETA_V, X, Y, leg_force,
                                 steer)
from ..physics.model import V_CM, speed_held
from ..ground.terrain import FLAT
from ..course.obstacles import Obstacles
from ..physics.params import Figure
from ..course.path import PathDistance
from ..equipment import edge_limit_of
from . import flat_stage, terrain_problem as free_speed
from .settings import PlannerSettings, SpeedProfile

__all__ = ["Problem", "StageResult"]

#: Lean margin (rad) over the fall bound used for the largest foot speed: RK4's inner stages of a
#: step whose ends are within the bound can poke slightly beyond it.
_LEAN_MARGIN = 0.1


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


class Problem:
    """Everything a search needs, as plain arrays (the Blender side builds one from a curve and
    objects).  ``distance`` is a :class:`PathDistance`, ``obstacles`` an :class:`Obstacles`.

    On any ``ground`` (:mod:`..model`; flat by default) with ``resistance``: where the speed is
    held (:func:`..model.speed_held`, the paper's case) nodes have the 5 rows of
    :data:`..dynamics.STATE` and the speed follows ``speed``; otherwise (:attr:`free`) the speed
    is a sixth row starting at ``V0`` (default the body's) and the search clips what
    :mod:`.terrain_problem` says; ``speed_cap`` (:class:`.speed_cap.SpeedCap`) brakes it to a
    cap within the grip (docs/skidding.md Section 6)."""

    #: Other figures' bodies as moving obstacles (:class:`..moving.MovingBodies`), or ``None``
    #: (set with :func:`..moving.around`).
    movers = None

    def __init__(self, figure: Figure, distance: PathDistance, obstacles: Obstacles,
                 settings: PlannerSettings, speed: SpeedProfile | None = None, ground=FLAT,
                 resistance=None, V0: float | None = None, speed_cap=None):
        from ..physics.model import NO_RESISTANCE
        self.ground = FLAT if ground is None else ground
        self.resistance = NO_RESISTANCE if resistance is None else resistance
        #: The speed is a state (a sixth row), not held.
        self.free = not speed_held(self.ground, self.resistance) or speed_cap is not None
        #: The braking law that caps the speed (:class:`.speed_cap.SpeedCap`) or ``None``.
        self.speed_cap = speed_cap
        if self.free:
            if speed is not None and not speed.is_constant:
                raise ValueError("the speed is a state on this ground (it follows the slope): "
                                 "give a speed profile or a ground, not both")
            V0 = figure.body.V_cm if V0 is None else float(V0)
            speed = SpeedProfile.constant(V0)
            self.V0 = V0
        self.figure = figure
        self.body = figure.body
        self.limits = figure.limits
        if not math.isfinite(self.limits.dC_f_max) or not math.isfinite(self.limits.C_f_max):
            raise ValueError(f"the planner needs finite C_f_max and dC_f_max; preset "
                             f"{figure.name!r} has {self.limits.C_f_max!r}, "
                             f"{self.limits.dC_f_max!r}")
        self.distance = distance
        self.obstacles = obstacles
        self.settings = settings
        self.speed = speed or SpeedProfile.constant(self.body.V_cm)
        #: The edge a lean can hold (:class:`..equipment.EdgeLimit`), or ``None``.
        self.edge_limit = edge_limit_of(figure.name) if settings.edge_limit else None
        #: The q values of dC_f/dt, spread evenly within their bound (Section 6.1); with
        #: ``spread = "range"`` each node's own are :meth:`rates`.
        self.u_values = self.limits.dC_f_max * np.linspace(-1.0, 1.0, settings.q)
        # Largest foot speed on any branch that is not clipped (Eq. 21 at the largest |C_f| and
        # lean), for the admissible lower bound.
        lean = min(settings.theta_bound + _LEAN_MARGIN, math.pi / 2)
        slip = min(PHYSICAL_MARGIN, self.limits.C_f_max * self.body.l * math.sin(lean))
        self.v_max = self.speed.max / (1.0 - slip)
        self._sin_lean = math.sin(lean)
        # The arc bound of lower_bound: for a constant speed, over the next `lookahead` samples.
        self._lookahead = None
        if settings.lookahead and self.speed.is_constant:
            per = 16
            ds = settings.sample_dt / per
            self._lookahead = ds * np.arange(1, settings.lookahead * per + 1).reshape(
                settings.lookahead, per)
            self._lookahead_ds = ds
            grid = np.linspace(0.0, self.limits.C_f_max, 257)
            self._radius_table = self._radius(grid, settings.lookahead)
        #: Lean range (rad) on which the fall table's monotonicity is checked.
        self._lean_checked = min(settings.theta_bound + 0.1, 1.5)
        # Section 3's physical limit 0.9 / (l |sin theta_v|) can only bind when C_f_max l > 0.9.
        self._physical_binds = self.limits.C_f_max * self.body.l > PHYSICAL_MARGIN
        self._fall_table = False                  # built on first use (fall_table.py)
        self._reach = False                       # built on first use (reach.py)
        self._pairs = False                       # built on first use (spacing.py)
        #: The stage's RK4 fused on flat ground at a constant speed (flat_stage.py).
        self._fused = not self.free and flat_stage.applies(self)
        if self.free:
            free_speed.setup(self, lean)
        if settings.leg_force_max and not (self.free or self.speed.is_constant):
            raise ValueError("leg_force_max needs a constant speed held or a free one (terrain): "
                             "the leg force is checked at the state's speed")
        #: The racer's cost (:class:`.reach.RaceCost`) for ``settings.line == "race"``, or
        #: ``None``: Section 6's distance to the path.
        self.race = None
        if settings.line == "race":
            from .reach import RaceCost
            self.race = RaceCost(self)

    @property
    def flat_rhs(self) -> bool:
        """Is this problem's right-hand side :meth:`_rhs` itself (flat ground), not a subclass's?"""
        return type(self)._rhs is Problem._rhs

    def fall_table(self):
        """The :class:`.fall_table.FallTable` of this problem, or ``None`` where it does not
        apply (varying speed, or a figure for which the lean is not monotone)."""
        if self._fall_table is False:
            from .fall_table import FallTable
            st = self.settings
            self._fall_table = FallTable.for_problem(self) if (st.fall_table or
                                                               st.viable_stages) else None
        return self._fall_table

    def reach(self) -> float:
        """How far the foot can get within one horizon, m."""
        return self.v_max * self.settings.horizon * 1.001 + 1e-6

    def local(self, center, state=None, t=None) -> "Problem":
        """The same problem with the path samples and obstacles that cannot matter within one
        horizon of ``center`` dropped (exact: see :meth:`PathDistance.near` and
        :meth:`Obstacles.near`); with ``q_near`` choices where any is left
        (:class:`.settings.PlannerSettings`).  ``state``: the root's (used on terrain only);
        ``t``: its time (the moving bodies kept are those that can come near from then to the
        end of the horizon and one stage more; ``None``: at any time)."""
        r = self.reach()
        self.fall_table()                       # built once, shared by the local copies
        p = type(self).__new__(type(self))
        p.__dict__.update(self.__dict__)
        if self.free:
            if state is not None:
                p.v_max = free_speed.speed_limit(self, float(state[V_CM]))
            p._runaways = np.zeros(1, np.int64)
            r = p.reach()
            if p.race is not None and state is not None:    # the speed's envelope (RaceCost)
                p.race = p.race.at_root(p, 0.0 if t is None else t, state)
        p.distance = self.distance.near(center, r)
        # One stage more for the dead-end test (search.py), and the body's ground point.
        far = r + p.v_max * self.settings.t_stage * 1.001 + self.body.l
        p.obstacles = self.obstacles.near(center, far)
        if self.movers is not None:
            st = self.settings
            p.movers = self.movers.near(center, far, t, None if t is None else
                                        t + (st.n_stages + 1) * st.t_stage * 1.001 + st.dt)
        p._pairs = False if not self.free else None     # its own path samples
        st = self.settings
        if st.q_near and st.q_near != st.q and (len(p.obstacles) or p.movers is not None):
            # An obstacle within reach: the finer choices (PlannerSettings.q_near).
            p.settings = replace(st, q=st.q_near)
            p.u_values = self.limits.dC_f_max * np.linspace(-1.0, 1.0, st.q_near)
        return p

    def rates(self, C_f, ch) -> np.ndarray:
        """``dC_f/dt`` of choices ``ch`` (indices, broadcast with ``C_f``) at stage-start
        curvatures ``C_f`` (``PlannerSettings.spread``): ``u_values[ch]``, or with ``"range"``
        the fraction ``linspace(-1, 1, q)[ch]`` of ``min(dC_f_max, (C_f_max -+ C_f) /
        t_stage)``, the rate that brings ``C_f`` to its bound on that side by the stage's end
        (never above ``dC_f_max``, never past the bound: Section 6.1's limits)."""
        if self.settings.spread == "rate":
            return self.u_values[ch]
        lim = self.limits
        frac = self.u_values[ch] / lim.dC_f_max
        room = lim.C_f_max - np.copysign(1.0, frac) * np.asarray(C_f, float)
        return frac * np.clip(room / self.settings.t_stage, 0.0, lim.dC_f_max)

    @property
    def runaways(self) -> int:
        """Branches this search clipped as run-aways (free speed only; :mod:`.terrain_problem`):
        the receding horizon hands no proof on from a search that clipped any."""
        return int(self._runaways[0]) if self.free else 0

    def lower_bound(self, d_last, depth, state=None, C_f=None, reach: bool = False):
        """Admissible bound on the cost still to come after nodes at ``depth`` whose last sample
        was ``d_last`` from the path: the sum of :meth:`sample_bounds` (the racer's line: its
        own, :class:`.reach.RaceCost`, given the nodes' ``state`` and ``C_f``)."""
        d_last = np.asarray(d_last, float)
        if self.race is not None:
            if state is None:
                return np.zeros(d_last.shape)
            return self.race.bound(state, C_f, depth).reshape(d_last.shape)
        terms = self.sample_bounds(d_last, depth, state, C_f, reach)
        return self.total_bound(terms, d_last, depth, state).reshape(d_last.shape)

    def total_bound(self, terms, d_last, depth, state=None, pairs=None):
        """The cost still to come from the per-sample bounds ``terms`` (:meth:`sample_bounds`):
        their sum, or with the nodes' ``state``, at least as much from pairs of consecutive
        samples (``spacing.py``; ``pairs``: :meth:`pair_floors`, when already known)."""
        if state is None or not terms.shape[1]:
            return terms.sum(axis=-1)
        st = self.settings
        d_last = np.atleast_1d(np.asarray(d_last, float))
        K = np.broadcast_to((st.n_stages - np.asarray(depth)) * st.samples_per_stage,
                            d_last.shape)
        if pairs is None:
            pairs = self.pair_floors(state, K)
        if pairs is None:
            return terms.sum(axis=-1)
        return self._pairs.total(terms, K, pairs[:, :terms.shape[1]], d_last)

    def pair_floors(self, state, K):
        """:meth:`.spacing.PairFloor.floor` for nodes at ``state`` with ``K`` samples to come,
        or ``None`` where the pair floor does not apply."""
        if self._pairs is False:
            from .spacing import PairFloor
            self._pairs = PairFloor.for_problem(self) if self.settings.pair_floor else None
        if self._pairs is None:
            return None
        return self._pairs.floor(state, int(np.max(K, initial=0)))

    def sample_bounds(self, d_last, depth, state=None, C_f=None, reach: bool = False,
                      direct=None):
        """Lower bounds on ``d`` at each sample still to come after nodes at ``depth`` whose last
        sample was ``d_last`` from the path, shape ``(m, K)`` (0 past a node's horizon).

        Everywhere: d is 1-Lipschitz and the foot moves at most ``b = v_max sample_dt`` per
        sample, so a sample at least ``x`` from the path makes the next at least ``x - b``, and
        the one before at least ``x - b``.  Given the nodes' ``state`` and ``C_f`` (and a constant
        speed), the first ``lookahead`` samples are bounded more tightly: the foot stays within
        ``r(tau)`` of the arc of curvature ``C_f`` through its position and heading, because
        ``C_f`` changes no faster than ``dC_f_max`` and ``V_f`` (Eq. 21) stays within the lean
        bound's range; so the sample is at least ``d(arc point) - r(tau)``.  With ``reach``, the
        samples are also bounded by the distance from the path samples to where the foot can be
        then (``reach.py``; while the heading can still turn through less than pi).
        ``direct``: these nodes' :meth:`direct_bounds`, when already known (the search adds the
        reach bound to the nodes that pass the cheaper bounds).
        """
        st = self.settings
        d_last = np.atleast_1d(np.asarray(d_last, float))
        K = np.broadcast_to((st.n_stages - np.asarray(depth)) * st.samples_per_stage,
                            d_last.shape)
        b = self.v_max * st.sample_dt
        k = np.arange(1, int(np.max(K, initial=0)) + 1)
        if state is None or not len(k) or not len(d_last):
            return np.where(k[None, :] <= K[:, None],
                            np.maximum(d_last[:, None] - b * k[None, :], 0.0), 0.0)
        C_f = np.asarray(C_f, float)
        terms = self.direct_bounds(d_last, state, C_f, len(k)) if direct is None else \
            direct[:, :len(k)].copy()
        rb = self.reach_bound() if reach else None
        if rb is not None:
            j = k[k <= rb.samples]
            if len(j):
                terms[:, j - 1] = np.maximum(terms[:, j - 1], rb.sample_bounds(
                    self.distance.samples, state, C_f, j))
        # Each bound also holds, less b per sample, for the samples after and before it:
        # sample j is at least max over i of (bound_i - |j - i| b), first over i <= j (running
        # maxima of bound_i + i b, less j b), then, past the horizon cut, over i >= j.  (The
        # sums round to ~1e-15 m, far inside the search's relative tolerance of 1e-9.)
        kb = b * k
        terms = np.maximum.accumulate(terms + kb, axis=1) - kb
        terms = np.where(k[None, :] <= K[:, None], terms, 0.0)
        return np.maximum.accumulate((terms - kb)[:, ::-1], axis=1)[:, ::-1] + kb

    def direct_bounds(self, d_last, state, C_f, n):
        """The Lipschitz and arc bounds of :meth:`sample_bounds` on the next ``n`` samples, shape
        ``(m, n)``, before they are carried to the samples around them."""
        b = self.v_max * self.settings.sample_dt
        terms = np.maximum(d_last[:, None] - b * np.arange(1, n + 1)[None, :], 0.0)
        a = min(self._lookahead.shape[0], n) if self._lookahead is not None else 0
        if a:
            terms[:, :a] = np.maximum(terms[:, :a], self._arc_bound(state, C_f, a))
        return terms

    def reach_bound(self):
        """The :class:`.reach.ReachBound` of this problem, or ``None`` where it does not apply."""
        if self._reach is False:
            from .reach import ReachBound
            self._reach = ReachBound.for_problem(self)
        return self._reach

    def _arc_bound(self, state, C0, n):
        """``d(arc point) - r(tau)`` for the next ``n`` samples, shape ``(m, n)``."""
        st = self.settings
        V = float(self.speed.V[0])
        tau = st.sample_dt * np.arange(1, n + 1)
        x, y, th = state[X], state[Y], state[THETA_DIR]
        turn = V * C0[:, None] * tau[None, :]
        chord = V * tau[None, :] * np.sinc(turn / (2 * np.pi))       # sin(turn/2) / (turn/2)
        ang = th[:, None] + 0.5 * turn
        pts = np.stack([x[:, None] + chord * np.cos(ang), y[:, None] + chord * np.sin(ang)], -1)
        # r grows with |C0|: take the tabulated value at the next grid point up (an over-estimate).
        cells = self._radius_table.shape[0] - 1
        i = np.minimum(np.ceil(np.abs(C0) / self.limits.C_f_max * cells), cells).astype(np.intp)
        return self.distance(pts) - self._radius_table[i, :n]

    def _radius(self, absC0, n):
        """``r(tau_k)``, k = 1..n: how far the foot can be from the nominal arc (Section 6.1's
        bounds on C_f and dC_f/dt, Eq. 21's speed), by right Riemann sums of non-decreasing
        integrands (over-estimates), evaluated one integration step late for RK4's inner stages."""
        st, lim, b = self.settings, self.limits, self.body
        V = float(self.speed.V[0])
        G = self._lookahead                      # (n_total, G) fine time grid per sample
        ds = self._lookahead_ds
        s = G[:n].reshape(-1)[None, :] + st.dt   # one step late
        cb = np.minimum(lim.C_f_max, absC0[:, None] + lim.dC_f_max * s)
        eps = np.minimum(cb * b.l * self._sin_lean, PHYSICAL_MARGIN)
        dv = V / (1.0 - eps) - V                                  # >= V - V / (1 + eps)
        vhi = V + dv
        eta = np.cumsum((dv * cb + V * lim.dC_f_max * s) * ds, axis=1)   # heading deviation
        r = np.cumsum((dv + vhi * eta) * ds, axis=1)
        per = G.shape[1]
        return r[:, per - 1::per] * (1 + 1e-6) + 1e-9

    def leg_force_bw(self, P, C) -> np.ndarray:
        """Appendix A's leg force in body weights at states ``P`` (shape ``(steps + 1, rows,
        m)``) with curvatures ``C`` (shape ``(steps + 1, m)``): ``alpha_v`` from Eq. (12) at each
        state (:func:`..dynamics.steer`, the curvature already within its bounds), as the
        trajectory's ``F_leg`` has it at its samples."""
        n, rows, m = P.shape
        S = P.transpose(1, 0, 2).reshape(rows, n * m)
        c = np.asarray(C, float).reshape(n * m)
        if self.free:                     # on the ground, at the state's speed (model.leg_force)
            return free_speed.leg_force_bw(self, S, c).reshape(n, m)
        V = float(self.speed.V[0])
        _, cf, alpha, _ = steer(self.body, self.limits, c, S, None, 0.0, V)
        F = leg_force(self.body, S[THETA_V], S[OMEGA_V], alpha, cf, V)[0]
        return F.reshape(n, m) / (self.body.m * self.body.g)

    def body_point(self, state) -> np.ndarray:
        """The ground point under the centre of mass, shape ``(2, ...)`` for ``state`` of shape
        ``(>= 4, ...)``: the foot plus ``l sin(theta_v)`` across the direction of travel, to the
        left for a lean to the left (docs/ARCHITECTURE.md Section 4), i.e.
        ``foot + l sin(theta_v) (-sin theta_dir, cos theta_dir)``."""
        off = self.body.l * np.sin(state[THETA_V])
        th = state[THETA_DIR]
        return np.stack([state[X] - off * np.sin(th), state[Y] + off * np.cos(th)])

    def _speed_at(self, t, s):
        if self.speed.is_constant:
            return float(self.speed.V[0])
        return self.speed(t, s)

    def _rhs(self, x, V, tau, C0, u, anchor, rate_step, out, bad=None):
        """:func:`..dynamics.steer` under the stage's law ``C_f = C0 + u tau`` (Section 6.1),
        written into ``out`` (shape (5, m)).  Returns ``(C_f, alpha_v, V_f)``.  ``bad``: columns
        the problem clips besides a fall (none at a held speed; free: :mod:`.terrain_problem`)."""
        if self.free:
            return free_speed.rhs(self, x, tau, C0, u, anchor, rate_step, out, bad)
        d, cf, alpha, V_f = steer(self.body, self.limits, C0 + u * tau, x, anchor, rate_step, V)
        for row, v in enumerate(d):
            out[row] = v
        return cf, alpha, V_f

    def simulate_stage(self, state, C_f0, u, t0, s0, record: bool = False) -> StageResult:
        """Simulate every column of ``state`` (shape ``(5, m)``) for one stage with
        ``dC_f/dt = u``; ``t0``, ``s0`` are the columns' start time and distance travelled.

        Classical RK4 with step ``dt``; at the start of each step the curvature is bounded
        relative to the previous step's (the rate bound), and inside the step relative to the
        step's start, exactly as :func:`..dynamics.rk4_step` does (:meth:`_integrate`; on flat
        ground at a constant speed the same numbers from the fused :mod:`.flat_stage`)."""
        st = self.settings
        u = np.asarray(u, float)
        C_f0 = np.asarray(C_f0, float)
        x = np.array(state, float)
        m = x.shape[1]
        rec = None
        if self._fused and not record:
            CF, cf_end = flat_stage.curvatures(
                np.broadcast_to(C_f0, (m,)), np.broadcast_to(u, (m,)), st.dt,
                st.steps_per_stage, self.limits.C_f_max, self.limits.dC_f_max, st.t_stage)
            P = flat_stage.integrate(x, CF, st.dt, float(self.speed.V[0]), self.body)
            fell = np.zeros(m, bool)
            C = np.concatenate([CF[:, 0], cf_end[None]]) \
                if self.edge_limit or st.leg_force_max else None
        else:
            P, cf_end, fell, rec, C = self._integrate(x, C_f0, u, t0, s0, record)
        # P: the state at every step's end, shape (steps + 1, rows, m).  The distance travelled
        # (the steps' chords), the cost (the path distance at every sample, Section 6) and a
        # fall (the lean past its bound at a step's end; NaN counts).
        s = np.array(s0, float)
        for ds in np.hypot(P[1:, X] - P[:-1, X], P[1:, Y] - P[:-1, Y]):
            s = s + ds
        fell |= ~(np.abs(P[1:, THETA_V]) <= st.theta_bound).all(axis=0)
        if self.edge_limit is not None:      # an edge the lean cannot hold (module docstring)
            fell |= ~self.edge_limit.holds(P[:, THETA_V], C).all(axis=0)
        if st.leg_force_max:                 # a leg force the legs cannot hold (module docstring)
            fell |= ~(self.leg_force_bw(P, C) <= st.leg_force_max).all(axis=0)
        per = st.steps_per_sample
        if self.race is not None:         # the racer's cost (RaceCost): the distance not made good
            cost = self.race.stage_cost(P, t0)
            if self.free:                 # past the speed's envelope: a run-away (RaceCost)
                runaway = self.race.runaway(P, t0) & ~fell
                self._runaways[0] += int(np.count_nonzero(runaway))
                fell |= runaway
            D = np.zeros((1, m))
        else:
            D = self.distance(P[per::per, :2].transpose(0, 2, 1))      # (samples, m)
            cost = np.zeros(m)
            for d in D:
                cost = cost + d
        collided = np.zeros(m, bool)
        if len(self.obstacles) or self.movers is not None:
            # The foot's and the body's ground point's moves, step by step.
            track = P[:, :THETA_V + 1].transpose(1, 0, 2)           # (4, steps + 1, m)
            foot, body = track[:2], self.body_point(track)
            if len(self.obstacles):
                # Step k's segments (foot's, then body's) run from t0 + k dt to t0 + (k + 1) dt.
                a = np.concatenate([foot[:, :-1], body[:, :-1]], axis=1)
                b = np.concatenate([foot[:, 1:], body[:, 1:]], axis=1)
                hit = self.obstacles.collides(a.reshape(2, -1).T, b.reshape(2, -1).T)
                collided = hit.reshape(-1, m).any(axis=0)
            if self.movers is not None:   # the same steps, at their times (core/course/moving.py)
                collided |= self.movers.collides(foot, body, t0, st.dt)
        return StageResult(P[-1].copy(), np.asarray(cf_end, float) * np.ones(m), s, cost, D[-1],
                           collided, fell, rec)

    def _integrate(self, x, C_f0, u, t0, s0, record):
        """The stage's RK4 through :meth:`_rhs` (any problem).  Returns ``(P, cf_end, bad,
        record, C)``: the states at every step boundary (shape ``(steps + 1, rows, m)``), the
        curvature at the end, the columns ``_rhs`` clipped, with ``record`` the per-step
        columns, and the curvature at every step boundary (shape ``(steps + 1, m)``)."""
        st = self.settings
        s = np.array(s0, float)
        anchor = C_f0
        bad = np.zeros(x.shape[1], bool)
        P = [x]
        C = []
        rec = {k: [] for k in ("state", "C_f", "alpha_v", "V_f", "t")} if record else None
        h = st.dt
        half = 0.5 * h
        k1, k2, k3, k4 = (np.empty_like(x) for _ in range(4))
        for k in range(st.steps_per_stage):
            tau = k * h
            V = self._speed_at(t0 + tau, s)
            cf, alpha, V_f = self._rhs(x, V, tau, C_f0, u, anchor, h, k1, bad)
            C.append(np.broadcast_to(cf, x.shape[1:]))
            if record:
                rec["state"].append(x.copy())
                rec["C_f"].append(cf)
                rec["alpha_v"].append(alpha)
                rec["V_f"].append(V_f)
                rec["t"].append(np.asarray(t0, float) + tau)
            self._rhs(x + half * k1, V, tau + half, C_f0, u, cf, half, k2, bad)
            self._rhs(x + half * k2, V, tau + half, C_f0, u, cf, half, k3, bad)
            self._rhs(x + h * k3, V, tau + h, C_f0, u, cf, h, k4, bad)
            new = x + (h / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
            s = s + np.hypot(new[X] - x[X], new[Y] - x[Y])
            x, anchor = new, cf
            P.append(x)
        # The curvature in force at the end of the stage (the next stage's C0).
        cf_end = self._rhs(x, self._speed_at(t0 + st.t_stage, s), st.t_stage, C_f0, u, anchor,
                           h, k1, bad)[0]
        C.append(np.broadcast_to(cf_end, x.shape[1:]))
        return np.stack(P), cf_end, bad, rec, np.stack(C)

    def end_rates(self, x, cf, t, s):
        """``(alpha_v, V_f)`` of the state ``x`` (shape ``(5, 1)``) at curvature ``cf``."""
        if self.free:
            return free_speed.end_rates(self, x, cf)
        V = self._speed_at(np.array([t]), np.array([s]))
        _, _, a, v = steer(self.body, self.limits, np.array([cf]), x, None, 0.0, V)
        return a, v

    def columns(self, S, A, C, V) -> dict:
        """Trajectory columns beyond the state: ``F_leg`` (Appendix A) and ``V_cm``, recovered
        from ``V_f`` by Eq. (21) so that a varying speed profile is honoured (``z``: flat, 0)."""
        if self.free:
            return free_speed.columns(self, S, A, C, V)
        v_cm = V * (1.0 - C * self.body.l * np.sin(S[3]))
        return {"V_cm": v_cm, "F_leg": leg_force(self.body, S[3], S[4], A, C, v_cm)[0]}

    def meta(self) -> dict:
        """What the trajectory's meta records of the problem beyond the body (flat: nothing)."""
        return free_speed.meta(self) if self.free else {}
