"""The parameterized controller of Section 5: phase-ellipse control (5.1) with directional
control (5.2).  Works on one figure (floats) or a batch (arrays).

**The law (default, ``law="smooth"``).**  In the normalised phase plane of Section 4,
``y = theta_v / theta_max``, ``x = omega_v / (omega0 theta_max)`` (the target ellipse of Eq. 3 is
``r = hypot(x, y) = 1``), the lean obeys ``dy/dt = omega0 x`` and
``dx/dt = alpha_v / (omega0 theta_max)``.  Write the demand as the on-ellipse law of Eq. (5) plus a
correction, ``alpha_v = -omega0^2 theta_v + u``.  Then ``dy/dt = omega0 x``,
``dx/dt = -omega0 y + u / (omega0 theta_max)`` and

    d(r^2)/dt = 2 x u / (omega0 theta_max):

only ``u`` changes the ellipse's "radius" (its energy), and only through ``x``.  Energy shaping
with ``u = K omega0^2 theta_max (1 - r) x / max(r, 1)`` (``K = GAIN = 3``) gives

    dr/dt = K omega0 (1 - r) cos^2(phi) * min(r, 1),    phi = atan2(y, x) (Section 4's phase),

so ``r`` moves monotonically toward 1 from any state: outside the ellipse ``1 - r`` decays by
``exp(-K omega0 t / 2)`` on average (e^-3pi per period), inside ``r`` grows logistically at the
same rate.  ``u = 0`` on the ellipse: there the demand is exactly Eq. (5), the open-loop law of
the same ellipse.  The demand is a smooth function of the state (C1 across the ellipse, where
both forms of ``u`` have slope ``-K omega0^2 theta_max x`` in ``r``): nothing switches at the
apex (``phi = 90, 270 deg``, where the correction passes through zero with ``cos phi``) or at the
axes.  The paper's geometric law (Fig. 7, :mod:`.ellipse_paper`) switches between two families
of controlling ellipses whose ``omega0'^2 = omega_v^2 / (theta_max^2 - theta_v^2)`` is 0/0 at
the apex; tiny state errors there flip it between branches, and C_f and F_leg twitch twice per
turn.

Inside the ellipse the correction is a negative damping ``K omega0 (1 - r) omega_v`` (``x / r``
would be a direction undefined at ``r = 0``, and its large gain near the origin asked for faster
C_f changes than the bounds allow: a snowboarder at 20 m/s fell from the origin).  The origin
itself is an equilibrium of both terms; Section 5.1: "a fixed arbitrary value is assigned to
alpha_v for a small region around the origin"; here it fades in smoothly,
``+ 0.5 alpha_max (1 - r / origin_radius)^2`` inside ``origin_radius``.

The demand is clipped to ``|alpha_v| <= alpha_max`` (a continuous clip), and Section 3's bounds
on C_f then act on it (in the integrator).  Convergence onto the target from the origin, from half
and 1.5 times the rate, and from 40 deg of lean is measured in ``tests/test_ellipse_law.py``.

**The ellipse followed.**  The commanded ``(omega0, theta_max)`` is made feasible for the body's
bounds (:mod:`.feasible`: same period, lean lowered when the bounds cannot hold it), then
modified per half-turn by directional control's beta (Section 5.2, Eqs. 6-8, exact half-turn
change from :mod:`..heading_table`), with beta bounded so that the modified half-turn stays
feasible.  At a zero crossing the old and the modified ellipse share the rate intercept
``omega0 theta_max`` (Fig. 9), so a state on one is on the other and the demand stays continuous.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..physics.dynamics import OMEGA_V, THETA_DIR, THETA_V
from .heading_table import BETA_MAX, BETA_MIN, heading_table, linear_beta
from ..physics.params import BodyParams, Limits
from .schedule import Schedule
from ..physics.xp import Scalar, backend
from .base import Controller
from .registry import ControllerType, register_controller
from .ellipse_paper import paper_alpha, paper_alpha_one
from .feasible import STEER_BETAS, FeasibleTurn, TurnsFollowed, feasible_turns

GAIN = 3.0
SPEED_GRID = 0.5
"""m/s: a speed that varies is followed by feasibility tables at multiples of this (rounded
down)."""


def _table_speed(V_cm: float) -> float:
    """The speed whose feasibility table serves ``V_cm``: rounded down to :data:`SPEED_GRID`."""
    return max(SPEED_GRID, math.floor(V_cm / SPEED_GRID) * SPEED_GRID)


def ellipse_alpha(theta_v, omega_v, theta_max, omega0, alpha_max, origin_radius=0.05):
    """The smooth law of the module docstring (arrays; floats go to :func:`ellipse_alpha_one`)."""
    if backend(theta_v, omega_v, theta_max, omega0, alpha_max) is Scalar:
        return ellipse_alpha_one(theta_v, omega_v, theta_max, omega0, alpha_max, origin_radius)
    w2 = omega0 * omega0
    x = omega_v / (omega0 * theta_max)
    r = np.hypot(x, theta_v / theta_max)
    a = -w2 * theta_v + (GAIN * w2 * theta_max) * (1.0 - r) * x / np.maximum(r, 1.0)
    a = a + 0.5 * alpha_max * np.square(np.maximum(1.0 - r / origin_radius, 0.0))
    return np.minimum(np.maximum(a, -alpha_max), alpha_max)


def ellipse_alpha_one(th, om, theta_max, omega0, alpha_max, origin_radius=0.05):
    """:func:`ellipse_alpha` on Python floats (one figure is stepped ~12,000 times a minute; a
    keyed Lean or Turn Period asks it at every stage).  :func:`ellipse_law_one` makes the same
    floats with each ellipse's products made once (tests/test_one_figure.py holds them equal)."""
    w2 = omega0 * omega0
    x = om / (omega0 * theta_max)
    y = th / theta_max
    r = math.sqrt(x * x + y * y)
    a = -w2 * th + GAIN * w2 * theta_max * (1.0 - r) * x / (r if r > 1.0 else 1.0)
    if r < origin_radius:
        f = 1.0 - r / origin_radius
        a += 0.5 * alpha_max * f * f
    return -alpha_max if a < -alpha_max else (alpha_max if a > alpha_max else a)


def ellipse_law_one(pos, neg, origin_radius=0.05):
    """:func:`ellipse_alpha_one` of a turn's two half-turns: ``(t, th, om) -> alpha_v`` about
    the ellipse ``pos = (theta_max, omega0, alpha_max)`` where ``th >= 0`` and ``neg`` where
    not (:meth:`PhaseEllipse.step_law`), each ellipse's products (``omega0 theta_max``,
    ``-omega0^2``, ``K omega0^2 theta_max``) made once: the same floats."""
    def made(theta_max, omega0, alpha_max):
        w2 = omega0 * omega0
        return (theta_max, omega0 * theta_max, -w2, GAIN * w2 * theta_max, -alpha_max,
                alpha_max, 0.5 * alpha_max)
    P, N, sqrt = made(*pos), made(*neg), math.sqrt

    def alpha(t, th, om):
        theta_max, wt, neg_w2, gain, lo, hi, half = P if th >= 0.0 else N
        x = om / wt
        y = th / theta_max
        r = sqrt(x * x + y * y)
        a = neg_w2 * th + gain * (1.0 - r) * x / (r if r > 1.0 else 1.0)
        if r < origin_radius:
            f = 1.0 - r / origin_radius
            a += half * f * f
        return lo if a < lo else (hi if a > hi else a)
    return alpha


def _law_of(alpha_one):
    """``alpha_one(th, om, theta_max, omega0, alpha_max, origin_radius)`` as a law of two
    half-turns (:func:`ellipse_law_one`'s signature)."""
    def law_one(pos, neg, origin_radius=0.05):
        def alpha(t, th, om):
            return alpha_one(th, om, *(pos if th >= 0.0 else neg), origin_radius)
        return alpha
    return law_one


LAWS = {"smooth": (ellipse_alpha, ellipse_alpha_one), "paper": (paper_alpha, paper_alpha_one)}
#: Each law of a turn's two half-turns on floats, as :func:`ellipse_law_one` makes it.
LAWS_ONE = {"smooth": ellipse_law_one, "paper": _law_of(paper_alpha_one)}


class PhaseEllipse(Controller):
    """Turn frequency ``omega0(t)``, sharpness ``theta_max(t)`` and optionally heading
    ``theta_h(t)``, each a number, a callable of time or a :class:`Schedule`.

    ``alpha_max`` (rad/s^2) defaults to ``2 omega0^2 theta_max`` of the ellipse followed (after
    beta): twice the peak of its own ``alpha_v``.  ``law``: ``"smooth"`` (the module docstring)
    or ``"paper"`` (Section 5.1 as written, :mod:`.ellipse_paper`).  ``directional``: how beta is
    found, ``"exact"`` (the closed form of :mod:`..heading_table`) or ``"linear"`` (the paper's
    Eqs. 11/12).  ``limits``: the figure's bounds; the ellipse followed is kept feasible for them
    (:mod:`.feasible`).  ``None``
    takes them from the run (:meth:`begin_run`).  :attr:`achieved` reports the turn followed.
    """

    def __init__(self, body: BodyParams, omega0, theta_max, heading=None, alpha_max=None,
                 origin_radius: float = 0.05, directional: str = "exact", law: str = "smooth",
                 limits: Limits | None = None):
        super().__init__(body)
        if directional not in ("exact", "linear"):
            raise ValueError(f"directional = {directional!r} is not one of exact, linear")
        if law not in LAWS:
            raise ValueError(f"law = {law!r} is not one of {', '.join(LAWS)}")
        self._omega0 = Schedule.of(omega0)
        self._theta_max = Schedule.of(theta_max)
        self.heading = None if heading is None else Schedule.of(heading)
        self.alpha_max = alpha_max
        self.origin_radius = origin_radius
        self.directional = directional
        self.law = law
        self._alpha, self._alpha_one = LAWS[law]
        self._law_one = LAWS_ONE[law]
        self._limits_given = limits is not None
        self._limits = limits
        self._feasible = None if limits is None else feasible_turns(body, limits)
        self._table_speed = None    # the speed follow_speed took _feasible at (None: not yet)
        self._cell = None           # and the cell of the grid it followed last (its floor)
        self._tables = {}           # a run's tables by speed, and their leans (_table_at)
        self._bp = self._bn = None  # beta of the left (theta_v >= 0) and right half-turns
        self._side = None           # +1 during a left half-turn, -1 right, per figure
        self._planned = False       # the coming half-turn's beta was set in this step
        self._t_prev = None
        self._forget()
        self._rates = {}            # mean_heading_rate at the nominal speed, per table and turn
        self.achieved: FeasibleTurn | None = None
        """The most limited turn followed so far (the first one if none was limited)."""
        self.followed: list[FeasibleTurn] = []
        """The turns followed so far, each when it began (:attr:`report`)."""
        self._batch_turns = None        # a batch's per-figure turns (:meth:`_note_batch`)
        self._steer_betas = STEER_BETAS

    @property
    def omega0(self) -> Schedule:
        """The commanded turn frequency over time, rad/s."""
        return self._omega0

    @omega0.setter
    def omega0(self, schedule: Schedule) -> None:
        self._omega0 = schedule
        self._forget()

    @property
    def theta_max(self) -> Schedule:
        """The commanded sharpness (the ellipse's lean) over time, rad."""
        return self._theta_max

    @theta_max.setter
    def theta_max(self, schedule: Schedule) -> None:
        self._theta_max = schedule
        self._forget()

    def _forget(self) -> None:
        """Forget the ellipses made feasible (:meth:`_ellipse`) with every table: the room or a
        schedule changed."""
        self._by_table = {}         # (_memo, _fixed) of a table not followed now, by its speed
        self._ellipses(None)

    def _ellipses(self, kept) -> None:
        """Take the ellipses ``kept`` (``(_memo, _fixed)`` made with the table followed now),
        or none (``None``).  With both schedules constant (and floats) the ellipse depends on
        beta alone and :meth:`lean_law` keeps it per beta (``_fixed``)."""
        if kept is None:
            const = (self._omega0.constant_value, self._theta_max.constant_value)
            kept = {}, {} if all(type(v) is float for v in const) else None
        self._memo, self._fixed = kept
        self._batch = None          # a batch's per-figure ellipses (:meth:`_batch_lean`)
        self._step = None           # the law of the betas and the table now (step_law)

    @property
    def steer_betas(self) -> tuple:
        """The modified half-turns directional control keeps feasible (:meth:`feasible_lean`);
        the braking rule widens them (:data:`.feasible.BRAKE_BETAS`).  Setting it forgets the
        ellipses and heading rates made feasible with the old room."""
        return self._steer_betas

    @steer_betas.setter
    def steer_betas(self, betas) -> None:
        self._steer_betas = tuple(betas)
        self._forget()
        self._rates = {}
        self._tables = {}

    def begin_run(self, limits: Limits) -> None:
        """A new run: forget the last run's half-turns; take the figure's limits unless given."""
        if not self._limits_given:
            self._limits = limits
            self._feasible = feasible_turns(self.body, limits)
            self._table_speed = self._cell = None
        self._bp = self._bn = self._side = self._t_prev = self._step = None
        self._planned = False
        self._forget()
        self._tables = {}
        self.achieved = None
        self.followed = []
        self._batch_turns = None

    @property
    def report(self) -> TurnsFollowed | None:
        """What the run's report says of the turns it followed (:class:`.TurnsFollowed`)."""
        return TurnsFollowed.of(self.followed)

    def batch_report(self, k: int) -> TurnsFollowed | None:
        """:attr:`report` of figure ``k`` of a batch run (per-figure ellipses): from its first
        turn followed, its most limited and the last it changed to (:meth:`_note_batch`), with
        the leans it followed over the run."""
        rec = self._batch_turns
        if rec is None:
            return None
        followed = []
        for key in ("first", "worst", "last"):
            turn = self._turn(*(float(v) for v in rec[key][:, k]))
            if turn not in followed:
                followed.append(turn)
        report = TurnsFollowed.of(sorted(followed, key=lambda f: f.t))
        return replace(report, lo=float(rec["lo"][k]), hi=float(rec["hi"][k]))

    def follow_speed(self, V_cm: float) -> None:
        """Steer at ``V_cm`` (:meth:`.Controller.follow_speed`) and keep the turn feasible at it.

        What is feasible depends on the speed (a slower figure needs more ``C_f`` for the same
        lean), so the table follows it, taken at the speed rounded *down* to ``SPEED_GRID``
        (never promising more than the current speed allows; a few tables, not one a step)."""
        super().follow_speed(V_cm)
        cell = math.floor(V_cm / SPEED_GRID)    # on terrain the speed changes every step
        if self._limits is not None and cell != self._cell:
            self._cell = cell
            grid = _table_speed(V_cm)
            if grid != self._table_speed:
                self._take_table(grid)

    def _take_table(self, grid: float) -> None:
        """Follow the feasibility table of the grid speed ``grid`` (:meth:`_table_at`) with the
        ellipses made feasible with it before in the run: on terrain the speed crosses a grid
        line back and forth, and each ellipse made anew asks the table again."""
        kept = self._by_table
        kept[self._table_speed] = (self._memo, self._fixed)
        self._feasible = self._table_at(grid)[0]
        self._table_speed = grid
        self._ellipses(kept.get(grid))          # not those made feasible by the old table

    def changes_between(self, V_a: float, V_b: float) -> bool:
        """The feasibility table changes between the two speeds (:meth:`follow_speed`) and with
        it the ellipse the law follows.  Between the lean's zero crossings the table acts only
        through :meth:`feasible_lean` (the betas are planned at the crossings): with both
        schedules constant, two tables that leave the commanded turn the same lean change
        nothing the law does (the commanded lean below both tables' bounds, the usual case)."""
        if self._limits is None:
            return False
        if math.floor(V_a / SPEED_GRID) == math.floor(V_b / SPEED_GRID):
            return False                        # one cell of the grid: one table
        a, b = _table_speed(V_a), _table_speed(V_b)
        if a == b:
            return False
        w, tm = self._omega0.constant_value, self._theta_max.constant_value
        if type(w) is not float or type(tm) is not float:
            return True
        return min(tm, self._table_at(a, w)[1]) != min(tm, self._table_at(b, w)[1])

    def _table_at(self, speed: float, omega0: float | None = None):
        """``(table, the largest lean it lets the law follow at omega0)`` of the body at the
        grid speed ``speed`` (:func:`.feasible.feasible_turns`, :meth:`_top`; the lean ``None``
        without ``omega0``), kept for the run: on terrain the speed crosses a grid line back
        and forth (a preview's coarse steps ask at every one, :meth:`changes_between`), and a
        table found again is the one found first (the same numbers)."""
        kept = self._tables.get((speed, omega0))
        if kept is None:
            table = feasible_turns(self.nominal_body.at_speed(speed), self._limits)
            kept = (table, None if omega0 is None else self._top(table, omega0))
            self._tables[(speed, omega0)] = kept
        return kept

    # -- the feasible ellipse -------------------------------------------------------------------
    def feasible_lean(self, omega0: float, theta_max: float) -> float:
        """The lean followed for a commanded ``(omega0, theta_max)``: at most the largest the
        body's bounds allow at that period (:mod:`.feasible`), and with directional control at
        most what leaves it a half-turn to steer with (:meth:`.FeasibleTurns.steerable_lean`):
        the commanded lean is skied whenever directional control can still flatten and sharpen
        its half-turns by ``steer_betas``, and only the turns at the bounds give up some."""
        if self._feasible is None:
            return theta_max
        if np.ndim(omega0) or np.ndim(theta_max):                 # per-figure ellipses
            top = (self._feasible.max_leans(omega0) if self.heading is None else
                   self._feasible.steerable_leans(omega0, self.steer_betas))
            return np.minimum(theta_max, top)
        return min(theta_max, self._top(self._feasible, omega0))

    def _top(self, table, omega0: float) -> float:
        """The largest lean ``table`` lets the law follow at ``omega0`` (one figure)."""
        return (table.max_lean(omega0) if self.heading is None else
                table.steerable_lean(omega0, self.steer_betas))

    def commanded_turn(self, t: float = 0.0) -> FeasibleTurn:
        """The turn followed for the ellipse commanded at ``t`` (one figure), before any run:
        its lean made feasible (:meth:`feasible_lean`) and the bound that limits it, as a run's
        :attr:`achieved` reports it."""
        w, tm = float(self.omega0(t)), float(self.theta_max(t))
        return self._turn(t, w, tm, self.feasible_lean(w, tm))

    def _turn(self, t, w, tm, tmf) -> FeasibleTurn:
        if self._feasible is None or tmf >= tm:
            return FeasibleTurn(tm, tmf, 2 * math.pi / w, None, t)
        # The turn's own bound (beta 1) or, when the steering room limits it, that of the
        # modified half-turn at its bound (:meth:`.FeasibleTurns.steerable_lean`).
        f = self._feasible
        steer = [b for b in self.steer_betas if self.heading is not None and
                 tmf >= f.max_lean(w / b) / b * (1 - 1e-12)]
        beta = steer[0] if steer and tmf < f.max_lean(w) * (1 - 1e-12) else 1.0
        return FeasibleTurn(tm, tmf, 2 * math.pi / w, f.bound(w / beta), t, beta)

    def _note(self, t, w, tm, tmf):
        if np.ndim(tmf):           # a batch of per-figure ellipses
            self._note_batch(t, w, tm, tmf)
            return
        turn = self._turn(t, w, tm, tmf)
        a = self.achieved
        if a is None or (turn.limited and tmf / tm < a.lean / a.commanded_lean):
            self.achieved = turn
        last = self.followed[-1] if self.followed else None
        if last is None or replace(last, t=t) != turn:
            self.followed.append(turn)

    def _note_batch(self, t, w, tm, tmf):
        """:meth:`_note` for every figure of a batch at once, in arrays (k,): the turn each
        followed first, its most limited (the least share of the lean asked) and the last it
        changed to, each ``(t, omega0, theta_max asked, lean followed)``, and the least and
        largest lean followed; :meth:`batch_report` makes a figure's report of them.  With both
        schedules constant the arrays are the same objects at every crossing (:meth:`_batch_lean`
        keeps the leans), and nothing is done: a crowd's batch pays an identity check a step."""
        rec = self._batch_turns
        if rec is not None:
            seen = rec["seen"]
            if seen[0] is w and seen[1] is tm and seen[2] is tmf:
                return
        now = np.stack(np.broadcast_arrays(float(t), w, tm, tmf)).astype(float)
        if rec is None:
            self._batch_turns = {"first": now, "worst": now.copy(), "last": now.copy(),
                                 "lo": now[3].copy(), "hi": now[3].copy(), "seen": (w, tm, tmf)}
            return
        rec["seen"] = (w, tm, tmf)
        worse = now[3] * rec["worst"][2] < rec["worst"][3] * now[2]
        rec["worst"][:, worse] = now[:, worse]
        changed = np.any(now[1:] != rec["last"][1:], axis=0)
        rec["last"][:, changed] = now[:, changed]
        np.minimum(rec["lo"], now[3], out=rec["lo"])
        np.maximum(rec["hi"], now[3], out=rec["hi"])

    # -- Section 5.2 -------------------------------------------------------------------------
    def half_turn_change(self, theta_max, omega0):
        """``dtheta_dir(theta_max, omega0)`` of Eq. (6), rad, at the current speed."""
        table = heading_table(self.nominal_body)
        if np.ndim(theta_max) or np.ndim(omega0):                 # per-figure ellipses
            return table(theta_max, omega0) * self._speed_scale()
        return table.value_one(float(theta_max), float(omega0)) * self._speed_scale()

    def _speed_scale(self):
        """``dtheta_dir(V) / dtheta_dir(V_nominal) = V_nominal / V``: the closed form of
        :mod:`..heading_table` is ``1 / V`` times a function of the ellipse alone, so one table
        per body serves every speed (exactly 1.0 at the nominal speed)."""
        return self.nominal_body.V_cm / self.body.V_cm

    def mean_heading_rate(self, t: float) -> float:
        """The fastest the *mean* heading can turn at the current speed, rad/s (one figure):
        directional control (Section 5.2) sharpens the half-turns to one side to the largest
        feasible beta and flattens those to the other to the smallest, so one full turn moves
        the mean heading by ``dtheta(hi) - dtheta(lo)`` (Eq. 6 at ``(beta theta_max, omega0 /
        beta)``) in ``pi (hi + lo) / omega0`` seconds.  A commanded heading that moves faster
        leaves the figure behind (the braking rule, :mod:`..braking`, stays below it)."""
        w, tm0 = float(self.omega0(t)), float(self.theta_max(t))
        key = (self._feasible, w, tm0)          # the feasible table moves in 0.5 m/s steps
        per_turn = self._rates.get(key)
        if per_turn is None:
            tm = float(self.feasible_lean(w, tm0))
            lo, hi = ((BETA_MIN, BETA_MAX) if self._feasible is None
                      else self._feasible.beta_range(tm, w))
            table = heading_table(self.nominal_body)
            change = table.value_one(hi * tm, w / hi) - table.value_one(lo * tm, w / lo)
            per_turn = float(change) * w / (math.pi * (hi + lo))
            if len(self._rates) > 64:
                self._rates.clear()
            self._rates[key] = per_turn
        return per_turn * self._speed_scale()

    def _solve_beta(self, theta_max, omega0, wanted, lo, hi):
        if self.directional == "linear":
            extra = wanted - self.half_turn_change(theta_max, omega0)
            return np.clip(linear_beta(self.body, theta_max, omega0, extra), lo, hi)
        return heading_table(self.nominal_body).solve_beta(theta_max, omega0,
                                                           wanted / self._speed_scale(), lo, hi)

    def begin_step(self, t, state):
        """Directional control at the zero crossings of the lean (Section 5.2).  The next
        half-turn's beta is planned in the step *before* its crossing (from the heading predicted
        at the crossing), and the law picks beta by the side of the lean at every stage, so the
        modified ellipse starts exactly at the crossing, not at the next step's start (which left a
        kink in C_f inside that step)."""
        th, om = state[THETA_V], state[OMEGA_V]
        dt = 0.0 if self._t_prev is None else t - self._t_prev
        self._t_prev = t
        first = self._bp is None
        if type(th) is float:
            side = 1.0 if th > 0 else -1.0 if th < 0 else 1.0 if om >= 0 else -1.0
            soon = (th + om * dt) * side < 0.0           # a crossing within this step
            if first:
                self._bp = self._bn = 1.0
                self._step = None
                self._side = -side if abs(th) < 0.05 * self.theta_max(t) else side
            elif side == self._side and not soon:        # most steps of one figure
                self._planned = False
                return
            any_crossed = side != self._side
        else:
            side = np.where(th > 0, 1.0, np.where(th < 0, -1.0, np.where(om >= 0, 1.0, -1.0)))
            soon = (th + om * dt) * side < 0.0
            if first:
                self._bp, self._bn = np.ones_like(th), np.ones_like(th)
                self._side = np.where(np.abs(th) < 0.05 * self.theta_max(t), -side, side)
                self._planned = np.zeros(th.shape, bool)
            any_crossed = bool(np.any(side != self._side))
        crossed = side != self._side
        self._side = side
        w, tm = self.omega0(t), self.theta_max(t)
        tmf = self.feasible_lean(w, tm) if type(th) is float else self._batch_lean(w, tm)
        if self._feasible is not None and (any_crossed or first):
            self._note(t, w, tm, tmf)
        if self.heading is None:
            return
        # A crossing not planned in the step before (a start on the axis, a lean that turned
        # faster than predicted): the half-turn on ``side`` starts now.  (One figure: plain
        # bools, a numpy reduction of one costs ~5 us.)
        if type(th) is float:
            late = any_crossed and not self._planned
            some_late, some_soon = late, soon
        else:
            late = crossed & ~np.asarray(self._planned) if any_crossed else False
            some_late, some_soon = np.any(late), np.any(soon)
        self._planned = soon
        if some_late:
            self._plan(t, state[THETA_DIR], side, late, w, tmf)
        if some_soon:
            # Heading at the crossing, tau = -th/om ahead: on the ellipse near th = 0,
            # V_f C_f = k / (V cos th) ~ (g + omega0'^2 J) th / V (module heading_table).
            w_now = w / self._b(th)
            k = (self.body.g + w_now * w_now * self.body.J) * th * th / (2.0 * self.body.V_cm)
            if type(th) is float:
                swing = -k / om if om != 0.0 else 0.0
            else:
                swing = np.where(om != 0, -k / np.where(om != 0, om, 1.0), 0.0)
            self._plan(t, state[THETA_DIR] + swing, -side, soon, w, tmf)

    def _plan(self, t, theta_dir, side, which, w, tmf):
        """Set beta of the half-turn on ``side`` for the figures ``which`` (Eqs. 7-8), bounded so
        that the modified half-turn stays feasible (:mod:`.feasible`)."""
        if type(side) is not float:
            idx = np.nonzero(which)[0]
            every = tmf, w
            tmf, w = (np.asarray(v)[idx] if np.ndim(v) else v for v in (tmf, w))
        change = self.half_turn_change(tmf, w)
        if self._feasible is None:
            lo, hi = BETA_MIN, BETA_MAX
        elif np.ndim(tmf) or np.ndim(w):                          # per-figure ellipses
            lo, hi = self._beta_ranges(*every, idx)
        else:
            lo, hi = self._feasible.beta_range(tmf, w)
        if type(side) is float:
            beta = float(self._modifier(theta_dir, side, t, tmf, w, change, lo, hi))
            if side > 0:
                self._bp = beta
            else:
                self._bn = beta
            self._step = None
            return
        goal = self.heading(t)                                    # per-figure headings too
        beta = self._modifier(np.asarray(theta_dir)[idx], side[idx], t, tmf, w, change, lo, hi,
                              np.asarray(goal)[idx] if np.ndim(goal) else goal)
        left = side[idx] > 0
        self._bp[idx[left]] = beta[left]
        self._bn[idx[~left]] = beta[~left]

    def _modifier(self, theta_dir, side, t, tm, w, change, lo, hi, goal=None):
        """beta of the half-turn starting on ``side`` with heading ``theta_dir`` (Eqs. 7-8),
        within ``[lo, hi]``.

        A half-turn that should turn *more* is made sharper (beta > 1, more lean) only by the part
        of the error beyond ``spare``; the following half-turns, turning the other way, take the
        rest by being shallower (beta < 1, less lean).  The paper allows either (Section 5.2,
        Fig. 8).  So a start off the ellipse, whose transient leaves a heading error of at most
        about one half-turn's change, does not lean past the target; a commanded change of
        heading larger than that still sharpens the turn."""
        # Mean heading: the heading is at an extreme at a crossing (C_f is in phase with theta_v).
        mean = theta_dir + side * 0.5 * change
        goal = self.heading(t) if goal is None else goal         # the figures planned now
        err = (goal - mean + math.pi) % (2 * math.pi) - math.pi
        more = side * err
        # Left to shallow half-turns: what one of them can take, and at least one half-turn's
        # change (the most a start off the ellipse leaves, its first half-turn being partial).
        spare = np.maximum(change - self.half_turn_change(lo * tm, w / lo), change)
        if type(more) is float:
            extra = more - spare if more > spare else min(more, 0.0)
        else:
            extra = np.where(more > spare, more - spare, np.minimum(more, 0.0))
        wanted = change + extra                                     # Eq. (7), in the turn's sense
        return self._solve_beta(tm, w, wanted, lo, hi)

    # -- Section 5.1 -------------------------------------------------------------------------
    def _ellipse(self, w0, tm0, b):
        """``(theta_max, omega0, alpha_max)`` of the half-turn's ellipse: the commanded one made
        feasible, then modified by its beta ``b`` (Section 5.2)."""
        key = (w0, tm0, b) if type(b) is float and type(w0) is float else None
        if key is not None:
            out = self._memo.get(key)
            if out is not None:
                return out
        tmf = self.feasible_lean(w0, tm0) if key is not None else self._batch_lean(w0, tm0)
        w = w0 / b
        amax = self.alpha_max if self.alpha_max is not None else 2.0 * w * w * (b * tmf)
        out = (b * tmf, w, amax)
        if key is not None:
            if len(self._memo) > 16:
                self._memo.clear()
            self._memo[key] = out
        return out

    def _batch_lean(self, w0, tm0):
        """:meth:`feasible_lean` of a batch's per-figure ellipses.  While both schedules are
        constant they are the same arrays at every stage, and the leans are kept (with the
        figures' beta ranges, :meth:`_beta_ranges`): a batch asked the table at every stage of
        every step, twice the cost of the rest of the step at 100 figures."""
        kept = self._batch
        if kept is not None and kept[0] is w0 and kept[1] is tm0:
            return kept[2]
        tmf = self.feasible_lean(w0, tm0)
        if w0 is self._omega0.constant_value and tm0 is self._theta_max.constant_value:
            self._batch = [w0, tm0, tmf, None]
        return tmf

    def _beta_ranges(self, tmf, w, idx):
        """``(lo, hi)`` of :meth:`.FeasibleTurns.beta_range` for the figures ``idx`` of a batch
        whose followed ellipses are ``(tmf, w)``; every figure's at once, and kept, when they
        are the ones :meth:`_batch_lean` keeps (``beta_range``'s own cache holds 64 figures, so a
        crowd of more re-solved every figure's range at each of its zero crossings)."""
        ranges = np.vectorize(self._feasible.beta_range, otypes=[float, float])
        kept = self._batch
        if kept is None or kept[2] is not tmf:
            return ranges(*(np.asarray(v)[idx] if np.ndim(v) else v for v in (tmf, w)))
        if kept[3] is None:
            kept[3] = ranges(*np.broadcast_arrays(tmf, w))
        return kept[3][0][idx], kept[3][1][idx]

    def _b(self, theta_v):
        """beta for a lean: the planned half-turn on its side."""
        if self._bp is None:
            return 1.0
        if type(theta_v) is float:
            return self._bp if theta_v >= 0.0 else self._bn
        return np.where(theta_v >= 0, self._bp, self._bn)

    def _half_turn(self, t, b):
        """:meth:`_ellipse` of the schedules at ``t`` for beta ``b``, kept per beta with its law
        on floats (:meth:`lean_law`) while both schedules are constant (``_fixed``,
        :meth:`_forget`)."""
        e = self._ellipse(self._omega0(t), self._theta_max(t), b)
        fixed = self._fixed
        if fixed is not None and type(b) is float:
            if len(fixed) > 16:
                fixed.clear()
            fixed[b] = (e, self._law_one(e, e, self.origin_radius))
        return e

    def target(self, t):
        side, bp = self._side, self._bp
        if type(side) is float:                 # one figure: :meth:`_b` without the call
            b = 1.0 if bp is None else bp if side >= 0.0 else self._bn
        else:
            b = 1.0 if side is None else self._b(side)
        fixed = self._fixed
        kept = fixed.get(b) if fixed is not None and type(b) is float else None
        e = self._half_turn(t, b) if kept is None else kept[0]
        return e[1], e[0]

    def lean_law(self, t, theta_v, omega_v):
        """The law of the module docstring about the half-turn's ellipse (:meth:`_ellipse`; beta
        by the side of the lean, :meth:`_b`); one figure on floats (:func:`ellipse_law_one`
        or the paper's, kept per half-turn)."""
        if type(theta_v) is float:
            bp = self._bp
            b = 1.0 if bp is None else bp if theta_v >= 0.0 else self._bn
            fixed = self._fixed
            kept = fixed.get(b) if fixed is not None and type(b) is float else None
            if kept is not None:
                return kept[1](t, theta_v, omega_v)
            e = self._half_turn(t, b)
            return self._alpha_one(theta_v, omega_v, e[0], e[1], e[2], self.origin_radius)
        tm, w, amax = self._ellipse(self.omega0(t), self.theta_max(t), self._b(theta_v))
        return self._alpha(theta_v, omega_v, tm, w, amax, self.origin_radius)

    def step_law(self, t):
        """:meth:`lean_law` on floats over the step begun at ``t``: while both schedules are
        constant, one law of the two half-turns' ellipses (:func:`ellipse_law_one`), without
        the look-ups of :meth:`lean_law` at every stage; kept until a beta or the table changes
        (``_step``: :meth:`_forget`, :meth:`begin_run`, :meth:`begin_step`, :meth:`_plan`)."""
        law = self._step
        if law is None:
            fixed, bp, bn = self._fixed, self._bp, self._bn
            if bp is None:
                bp = bn = 1.0
            if fixed is None or type(bp) is not float or type(bn) is not float:
                return self.lean_law
            law = self._step = self._law_one(self._fixed_turn(t, bp)[0],
                                             self._fixed_turn(t, bn)[0], self.origin_radius)
        return law

    def _fixed_turn(self, t, b):
        """``(ellipse, law)`` of the half-turn of beta ``b`` (a float) while both schedules are
        constant (``_fixed``, :meth:`_half_turn`)."""
        kept = self._fixed.get(b)
        if kept is None:
            self._half_turn(t, b)
            kept = self._fixed[b]
        return kept

register_controller(ControllerType(
    name="ellipse", label="Phase Ellipse",
    description="Sections 5.1-5.2: phase-ellipse control of the lean, with directional control "
                "of the heading",
    make=lambda fig, omega0, theta_max, heading, law: PhaseEllipse(
        fig.body, omega0, theta_max, heading, law=law, limits=fig.limits)))
