"""The turns a body can do: the nearest feasible ellipse.

Section 5.1 notes that the bounds on ``C_f`` and ``dC_f/dt`` "usually lengthen the time required
to reach the desired phase ellipse".  When the commanded ellipse itself needs more than the bounds
allow, the figure never reaches it: the bounded curvature cannot hold the lean and it falls.  A
skier in that case makes a wider turn.  On the ellipse ``(theta_max, omega0)`` the demand is
Eq. (5), ``alpha_v = -omega0^2 theta_v`` with ``theta_v = theta_max sin u``, and Eq. (1) gives the
curvature in closed form (``k = g sin th + omega0^2 J th``, ``J = (I_v + l^2 m)/(m l)``):

    C_f(th) = k / (k l sin th + V^2 cos th),
    dC_f/dt = C_f'(th) omega_v,  C_f'(th) = (k' V^2 cos th + k V^2 sin th - k^2 l cos th) / den^2,
    k' = g cos th + omega0^2 J,  omega_v = omega0 theta_max cos u.

An ellipse is *feasible* when over a quarter turn (sampled at 65 phases; ``C_f`` peaks at the apex)
``|C_f| <= CF_SHARE C_f_max``, ``C_f l sin th <= CF_SHARE PHYSICAL_MARGIN`` (Section 3's physical
branch), ``|dC_f/dt| <= RATE_SHARE dC_f_max`` and ``theta_max <= theta_fall - LEAN_MARGIN``.  The
shares leave the law authority to correct errors (a start off the ellipse, a schedule change)
without sitting on a bound for long.  Each need grows with ``theta_max`` at a fixed ``omega0``, so
the feasible leans at a frequency are ``[0, max_lean(omega0)]``, tabulated once per body and
limits on a log grid of ``omega0`` (to within ``LEAN_TOL`` below the largest, interpolated
linearly).

The rule (documented for the user): **keep the commanded period, lower the lean** to
``min(theta_max, max_lean(omega0))``.  The period is the animator's rhythm (gates, music); the
lean always has a feasible value (the needs vanish with it), a longer period does not (the
``g sin th`` part of ``C_f`` stays, so at low speed no period is slow enough).  Directional
control's modified half-turn ``(beta theta_max, omega0 / beta)`` is kept feasible the same way:
:meth:`FeasibleTurns.beta_range` bounds beta, and the rest of the heading change is left to the
following half-turns (Eq. 7 measures it again at the next crossing).
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from contextlib import contextmanager
from functools import lru_cache

import numpy as np

from ..physics.dynamics import PHYSICAL_MARGIN
from .heading_table import BETA_MAX, BETA_MIN
from ..physics.params import BodyParams, Limits

CF_SHARE = 0.9
RATE_SHARE = 0.9
STEER_BETAS = (0.8, 1.1)
"""Directional control keeps half-turns it may flatten and sharpen by these betas (Section
5.2, ``(beta theta_max, omega0 / beta)``): the steering room of
:meth:`FeasibleTurns.steerable_lean` for a heading held (corrections only)."""
BRAKE_BETAS = (0.7, 1.25)
"""The steering room braking by turning across the hill needs (:mod:`..braking`: the mean
heading moves all the time): the speed is held within tests/test_braking.py's bounds with it,
not with ``STEER_BETAS``."""
LEAN_MARGIN = math.radians(8.0)
BOUNDS = ("C_f_max", "physical branch", "dC_f_max", "theta_fall")
_PHASES = np.linspace(0.0, 0.5 * math.pi, 65)
_PERIODS = (0.02, 1000.0)           # s: the log grid of omega0 spans these periods
_N_OMEGA = 256
LEAN_TOL = 1e-12
"""rad: the tabulated lean is at most this far below the largest feasible one.  Closing the
brackets to 1e-12 instead of 1e-9 costs a round or two of false position (10.6 against 13.8 ms
a table, measured on a shared machine) and keeps the leans within 1e-12 rad of a full
bisection's."""


@dataclass(frozen=True)
class FeasibleTurn:
    """The turn the figure follows instead of a commanded one it cannot do (SI units)."""

    commanded_lean: float
    """theta_max asked for, rad."""
    lean: float
    """theta_max followed, rad (at most the commanded one)."""
    period: float
    """2 pi / omega0, s (the commanded period: the rule keeps it)."""
    bound: str | None
    """The bound that limits the lean (one of ``BOUNDS``), ``None`` when not limited."""
    t: float = 0.0
    """When it was (first) followed, s."""
    beta: float = 1.0
    """Whose bound it is: 1 the turn's own; else the half-turn directional control may sharpen
    (beta > 1) or flatten (beta < 1) to, ``(beta theta_max, omega0 / beta)``, whose room to
    steer the lean gives up (:meth:`FeasibleTurns.steerable_lean`)."""

    @property
    def limited(self) -> bool:
        return self.bound is not None

    def why(self) -> str:
        """``"C_f_max"``, ``"theta_fall (less 8 deg)"``, and for a modified half-turn's bound
        ``" of the half-turn sharpened to 1.1 (heading control's room)"`` after it."""
        text = self.bound + (" (less 8 deg)" if self.bound == "theta_fall" else "")
        if self.beta != 1.0:
            text += (f" of the half-turn {'sharpened' if self.beta > 1 else 'flattened'} to "
                     f"{self.beta:g} (heading control's room)")
        return text

    def brief(self) -> str:
        """``"61.77 deg at period 2.000 s (asked 70.00 deg; limited by C_f_max ...)"`` or
        ``"... (as asked)"``."""
        text = f"{math.degrees(self.lean):.2f} deg at period {self.period:.3f} s"
        if not self.limited:
            return text + " (as asked)"
        return text + (f" (asked {math.degrees(self.commanded_lean):.2f} deg; limited by "
                       f"{self.why()})")

    def describe(self) -> str:
        text = f"lean {math.degrees(self.lean):.2f} deg at period {self.period:.3f} s"
        if self.limited:
            text += (f" (asked {math.degrees(self.commanded_lean):.2f} deg; limited by "
                     f"{self.why()} from t = {self.t:.2f} s)")
        return text


@dataclass(frozen=True)
class TurnsFollowed:
    """What a run's report says of the turns it followed (:attr:`.ellipse.PhaseEllipse.report`):
    the most limited turn and, where the lean followed changed over the run (what the bounds
    allow depends on the speed: a figure gathering speed down a slope holds more lean), the one
    it ended on -- or, when it ended on the most limited, the one it started on -- in time
    order; ``lo``-``hi`` the leans followed over the run, rad."""

    turns: tuple
    lo: float
    hi: float

    @classmethod
    def of(cls, followed) -> "TurnsFollowed | None":
        """From the turns a run followed, each when it began (``None`` for none)."""
        if not followed:
            return None
        worst = min(followed, key=lambda f: f.lean / f.commanded_lean)  # the first of equals
        other = followed[-1] if followed[-1] is not worst else followed[0]
        turns = (worst,) if other is worst else tuple(sorted((worst, other), key=lambda f: f.t))
        leans = [f.lean for f in followed]
        return cls(turns, min(leans), max(leans))

    @classmethod
    def from_dict(cls, d: dict) -> "TurnsFollowed":
        """The inverse of ``dataclasses.asdict`` (a trajectory's meta holds it)."""
        return cls(tuple(FeasibleTurn(**t) for t in d["turns"]), d["lo"], d["hi"])

    @property
    def limited(self) -> bool:
        return any(t.limited for t in self.turns)

    @property
    def worst(self) -> FeasibleTurn:
        """The most limited turn (the one whose bound the report names first)."""
        return min(self.turns, key=lambda f: f.lean / f.commanded_lean)

    def describe(self) -> str:
        """One turn: :meth:`FeasibleTurn.describe`.  Two: ``"lean 61.77-70.00 deg over the run:
        61.77 deg at period 2.000 s (asked 70.00 deg; limited by C_f_max ...) from t = 0.00 s,
        70.00 deg at period 2.000 s (as asked) from t = 2.96 s on"``."""
        if len(self.turns) == 1:
            return self.turns[0].describe()
        a, b = self.turns
        return (f"lean {math.degrees(self.lo):.2f}-{math.degrees(self.hi):.2f} deg over the run: "
                f"{a.brief()} from t = {a.t:.2f} s, {b.brief()} from t = {b.t:.2f} s on")


#: The trajectory ``meta`` key of a run's limited turns (``asdict`` of its TurnsFollowed).
TURN_KEY = "turn_limited"


def turn_meta(report: TurnsFollowed | None) -> dict:
    """``{TURN_KEY: asdict(report)}`` for a trajectory's meta when ``report`` says a turn was
    limited, else ``{}`` (each turn the one asked for, or no report)."""
    return {} if report is None or not report.limited else {TURN_KEY: asdict(report)}


def fall_cause(limits: Limits, C_f, t, window: float = 1.0) -> str:
    """Why a run fell, from its recorded curvature over the last ``window`` seconds: which of
    Section 3's bounds held ``C_f`` (a controller that does not keep its demand feasible, like
    the open-loop law of Section 4, falls when the bounds cut it)."""
    C_f, t = np.asarray(C_f, float), np.asarray(t, float)
    last = t >= t[-1] - window
    causes = []
    if np.abs(C_f[last]).max() >= limits.C_f_max * (1 - 1e-9):
        causes.append(f"|C_f| held at C_f_max = {limits.C_f_max:g} 1/m")
    if last.sum() > 1:
        rate = np.abs(np.diff(C_f[last])) / np.diff(t[last])
        if rate.max() >= limits.dC_f_max * (1 - 1e-6):
            causes.append(f"|dC_f/dt| held at dC_f_max = {limits.dC_f_max:g} 1/(m s)")
    if not causes:
        return "no curvature bound was active: the motion commanded leans past theta_fall"
    return "the turn needs more than the figure can do: " + " and ".join(causes)


def ellipse_needs(body: BodyParams, theta_max, omega0):
    """What following the ellipse needs, per bound of ``BOUNDS`` (in that order): peak ``C_f``
    (1/m), peak ``C_f l sin th``, peak ``|dC_f/dt|`` (1/(m s)) and the lean (rad).  Arrays
    broadcast; the last axis of the work is the quarter turn's phases."""
    return _needs((body.V_cm ** 2, body.l, body.g, body.J), theta_max, omega0)


def _needs(of, theta_max, omega0):
    """:func:`ellipse_needs` of the body read as ``of = (V_cm^2, l, g, J)``: floats, or arrays
    of one value per frequency (shape ``(n, 1)``: several bodies' tables solved at once, each
    element by the same float operations as its own body's)."""
    tm = np.asarray(theta_max, float)[..., None]
    w2 = np.square(np.asarray(omega0, float))[..., None]
    th = tm * np.sin(_PHASES)
    s, c = np.sin(th), np.cos(th)
    VV, l, g, J = of
    k = g * s + w2 * J * th
    den = k * l * s + VV * c
    cf = k / den
    dcf = (g * c + w2 * J) * VV * c + k * VV * s - k * k * l * c
    rate = np.abs(dcf) / (den * den) * np.sqrt(w2) * tm * np.cos(_PHASES)
    return (cf.max(-1), (cf * l * s).max(-1), rate.max(-1), tm[..., 0])


class FeasibleTurns:
    """``max_lean(omega0)`` and the feasible range of beta for one body and its limits."""

    #: The grid intervals the last drag step that took the table asked about (a set, from the
    #: first drag step that takes it, :func:`nearby_tables`; ``None``: not recorded): where the
    #: next body's :class:`PreviewTurns` at this speed are solved.  ``_step``: that drag step
    #: (the count of ``nearby_tables`` blocks): a later one records afresh, so the intervals
    #: of earlier settings (another Turn Period) do not pile up.
    _asked, _step = None, 0

    def __init__(self, body: BodyParams, limits: Limits):
        self.body, self.limits = body, limits
        fall = limits.theta_fall
        self.allowed = (CF_SHARE * limits.C_f_max, CF_SHARE * PHYSICAL_MARGIN,
                        RATE_SHARE * limits.dC_f_max,
                        fall - LEAN_MARGIN if fall > 2 * LEAN_MARGIN else 0.5 * fall)
        self._lw = np.linspace(math.log(2 * math.pi / _PERIODS[1]),
                               math.log(2 * math.pi / _PERIODS[0]), _N_OMEGA)
        self._lean, self._bound = self._tabulate()
        self._leans = self._lean.tolist()
        self._lw0, self._dlw = float(self._lw[0]), float(self._lw[1] - self._lw[0])
        self._ranges = {}

    def _tabulate(self):
        """The leans and bounds at every frequency of the grid (:meth:`_solve`)."""
        return self._solve(np.exp(self._lw))

    def _ratio(self, theta_max, omega0, of=None):
        """Largest need / allowed over the bounds (<= 1: feasible) and which bound it is (of the
        body read as ``of``, :func:`_needs`; by default this table's)."""
        needs = (ellipse_needs(self.body, theta_max, omega0) if of is None else
                 _needs(of, theta_max, omega0))
        r = np.stack([n / a for n, a in zip(needs, self.allowed)])
        return r.max(0), r.argmax(0)

    def _solve(self, omega0, of=None):
        """The largest feasible lean at each ``omega0``, to within ``LEAN_TOL``: a bracket
        ``lo`` (feasible) < ``hi`` (not) per frequency, narrowed until it is shorter than
        ``LEAN_TOL``, and ``lo`` returned.  The need grows with the lean smoothly between the
        bounds' crossings (linearly for the small leans of the fast turns, where it is the rate
        bound), so a false-position step (Illinois: the end kept twice has its ratio halved)
        lands next to the root; it is moved ``LEAN_TOL / 2`` past the end that moved last, so
        that the next step lands on the root's other side and closes the bracket.  When two
        rounds did not halve a bracket the next is a bisection step, so none takes more than
        three times as many rounds as bisection (40 at 1e-12 rad).  Only the brackets still
        open are evaluated; a frequency whose top lean is feasible has none.  ``of``: the body
        of each frequency (:func:`_needs`; by default this table's)."""
        lo = np.zeros_like(omega0)
        hi = np.full_like(omega0, self.allowed[3])
        f_hi = self._ratio(hi, omega0, of)[0] - 1.0
        f_lo = np.full_like(omega0, -1.0)           # no lean, no need
        lean = np.where(f_hi <= 0.0, hi, 0.0)
        i = np.flatnonzero(f_hi > 0.0)
        lo, hi, f_lo, f_hi, w = lo[i], hi[i], f_lo[i], f_hi[i], omega0[i]
        each = of is not None                       # the body per frequency: kept with it
        bodies = tuple(a[i] for a in of) if each else None
        w1 = w2 = np.full(i.size, np.inf)           # the bracket's width 1 and 2 rounds ago
        side = np.zeros(i.size, np.int8)            # the end moved last: -1 lo, 1 hi
        for _ in range(200):
            if not i.size:
                break
            width = hi - lo
            fp = lo - f_lo * width / (f_hi - f_lo) - 0.5 * LEAN_TOL * side
            mid = np.where(width <= 0.5 * w2, fp, 0.5 * (lo + hi))
            mid = np.where((mid > lo) & (mid < hi), mid, 0.5 * (lo + hi))
            f = self._ratio(mid, w, bodies)[0] - 1.0
            ok = f <= 0.0
            # Illinois: an end kept for the second round running counts half as much.
            f_lo = np.where(ok, f, np.where(side == 1, 0.5 * f_lo, f_lo))
            f_hi = np.where(ok, np.where(side == -1, 0.5 * f_hi, f_hi), f)
            side = np.where(ok, -1, 1).astype(np.int8)
            lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
            w1, w2 = width, w1
            done = hi - lo <= LEAN_TOL
            lean[i[done]] = lo[done]
            keep = ~done
            i, lo, hi, f_lo, f_hi, w = i[keep], lo[keep], hi[keep], f_lo[keep], f_hi[keep], w[keep]
            w1, w2, side = w1[keep], w2[keep], side[keep]
            if each:
                bodies = tuple(a[keep] for a in bodies)
        else:
            raise RuntimeError("feasible lean: the bracket did not close")
        # The binding bound: the one that fails first just above the lean.
        return lean, self._ratio(np.minimum(lean * (1 + 1e-6) + 1e-12, np.pi / 2 - 1e-6),
                                 omega0, of)[1]

    def max_lean(self, omega0: float) -> float:
        """The largest feasible ``theta_max`` at ``omega0`` (rad), linear in ``log omega0``
        between the grid's nodes (a frequency off the grid is solved directly)."""
        f = (math.log(omega0) - self._lw0) / self._dlw
        if not 0.0 <= f <= _N_OMEGA - 1:
            return float(self._solve(np.array([float(omega0)]))[0][0])
        i = min(int(f), _N_OMEGA - 2)
        if self._asked is not None:
            self._asked.add(i)
        a = f - i
        return self._leans[i] + a * (self._leans[i + 1] - self._leans[i])

    def max_leans(self, omega0) -> np.ndarray:
        """:meth:`max_lean` of every frequency of an array, the same numbers (the same float
        operations, element by element) without a Python call per element: a crowd's batch of
        thousands of figures asks for it every step."""
        w = np.asarray(omega0, float)
        # math.log, as max_lean: numpy's log differs from it in the last bit now and then.
        f = (np.fromiter(map(math.log, w.ravel()), float, w.size).reshape(w.shape)
             - self._lw0) / self._dlw
        inside = (f >= 0.0) & (f <= _N_OMEGA - 1)
        i = np.minimum(np.where(inside, f, 0.0).astype(int), _N_OMEGA - 2)
        if self._asked is not None and inside.any():
            self._asked.update(range(int(i[inside].min()), int(i[inside].max()) + 1))
        a = np.where(inside, f, 0.0) - i
        leans = np.asarray(self._leans, float)
        out = leans[i] + a * (leans[i + 1] - leans[i])
        if not inside.all():
            out = np.where(inside, out, 0.0)
            off = ~inside
            out[off] = [float(self._solve(np.array([float(v)]))[0][0]) for v in w[off]]
        return out

    def steerable_lean(self, omega0: float, betas=STEER_BETAS) -> float:
        """The largest lean at ``omega0`` that directional control can still steer (rad): the
        turn itself feasible (:meth:`max_lean`) and its half-turns modified by each beta of
        ``betas`` -- ``(beta theta_max, omega0 / beta)``, Section 5.2 -- feasible too.
        On the feasible boundary no modified half-turn is feasible (a sharper one needs more
        C_f or lean, a flatter and faster one more C_f rate), so the room comes from the shape
        of the turn at the bounds: a turn whose modified half-turns fit keeps all its lean,
        one at the bounds gives up what they need (``1 - 1 / 1.1`` of a turn bound by its lean
        or its ``g sin`` curvature, about 9 %)."""
        return min([self.max_lean(omega0)] +
                   [self.max_lean(omega0 / b) / b for b in betas])

    def steerable_leans(self, omega0, betas=STEER_BETAS) -> np.ndarray:
        """:meth:`steerable_lean` of every frequency of an array (the same numbers)."""
        w = np.asarray(omega0, float)
        out = self.max_leans(w)
        for b in betas:
            out = np.minimum(out, self.max_leans(w / b) / b)
        return out

    def bound(self, omega0: float) -> str:
        """The bound that limits the lean at ``omega0`` (nearest grid node)."""
        f = (math.log(omega0) - self._lw0) / self._dlw
        if self._asked is not None:
            self._asked.add(min(max(int(f), 0), _N_OMEGA - 2))
        return BOUNDS[int(self._bound[min(max(int(round(f)), 0), _N_OMEGA - 1)])]

    def beta_range(self, theta_max: float, omega0: float):
        """``(lo, hi)``: the betas around 1 whose modified half-turn ``(beta theta_max,
        omega0 / beta)`` is feasible, within ``[BETA_MIN, BETA_MAX]`` (Section 5.2 with the
        bounds of Sections 3 and 6.1).  ``(theta_max, omega0)`` itself should be feasible."""
        key = (theta_max, omega0)
        if key in self._ranges:
            ends, nodes = self._ranges[key]
            if self._asked is not None:             # what it asked when it was found
                self._asked.update(nodes)
            return ends
        asked, self._asked = self._asked, set()     # the intervals its bisection asks

        def ok(b):
            return b * theta_max <= self.max_lean(omega0 / b) * (1 + 1e-12)

        ends = []
        for end in (BETA_MIN, BETA_MAX):
            if ok(end):
                ends.append(end)
                continue
            good, bad = 1.0, end
            for _ in range(40):
                mid = math.sqrt(good * bad)
                good, bad = (mid, bad) if ok(mid) else (good, mid)
            ends.append(good)
        nodes, self._asked = self._asked, asked
        if asked is not None:
            asked.update(nodes)
        if len(self._ranges) > 64:
            self._ranges.clear()
        self._ranges[key] = ((ends[0], ends[1]), nodes)
        return ends[0], ends[1]


class PreviewTurns(FeasibleTurns):
    """:class:`FeasibleTurns` solved only at the frequencies asked for, for a drag step in
    Live Preview (:func:`nearby_tables`).  :meth:`_solve` treats every frequency alone, so each
    lean and bound is bit for bit the full table's (tests/test_feasible_turns.py).

    Where: a drag step's run asks the same few grid intervals as the step before it (the turn
    at a constant period, the half-turns directional control sharpens and flattens, the points
    of heading control's beta range, which bisects between ``omega0 / BETA_MAX`` and
    ``omega0 / BETA_MIN``): 3-15 a table on the cyclist.  :func:`preview_tables` solves those
    the nearest body's table at each speed recorded (``_asked``, :func:`_previews`; no margin:
    one more node each way solved 40-70 % more, 28 % more time, for 6 misses in 150 tables
    instead of 10), for every speed at once
    (the cyclist's 7: 110 frequencies, 5-8 ms, against 7 x 74 in 20-45 ms).  An interval
    asked outside them (``misses``) solves the grid from ``AROUND[0]`` nodes below it to
    ``AROUND[1]`` above (``log 3`` and ``log 5`` over the grid's step, with a margin: the
    whole beta range, 74 of the 256 frequencies) in one :meth:`_solve`."""

    AROUND = (30, 42)

    def _tabulate(self):
        self._solved = [False] * _N_OMEGA
        self._asked, self._step = set(), _NEARBY[1]
        self.misses = 0         # the solves of intervals not planned (AROUND)
        return np.zeros(_N_OMEGA), np.zeros(_N_OMEGA, np.intp)

    def _need(self, lo: int, hi: int) -> None:
        """Nodes ``lo`` to ``hi - 1`` solved (and those about them, ``AROUND``)."""
        if all(self._solved[lo:hi]):
            return
        self.misses += 1
        a, b = max(0, lo - self.AROUND[0]), min(_N_OMEGA, hi + self.AROUND[1])
        idx = np.array([k for k in range(a, b) if not self._solved[k]])
        self._fill(idx, *self._solve(np.exp(self._lw)[idx]))

    def _fill(self, idx, lean, bound) -> None:
        self._lean[idx], self._bound[idx] = lean, bound
        for k, v in zip(idx.tolist(), lean.tolist()):
            self._leans[k] = v
            self._solved[k] = True

    def _node(self, omega0: float) -> int:
        return min(max(int((math.log(omega0) - self._lw0) / self._dlw), 0), _N_OMEGA - 2)

    def _plan(self, asked) -> np.ndarray:
        """The nodes unsolved of those the grid intervals ``asked`` read."""
        nodes = {k for i in asked for k in (i, i + 1)}
        return np.array(sorted(k for k in nodes if not self._solved[k]), np.intp)

    def max_lean(self, omega0: float) -> float:
        i = self._node(omega0)
        if not (self._solved[i] and self._solved[i + 1]):
            self._need(i, i + 2)
        return super().max_lean(omega0)

    def max_leans(self, omega0) -> np.ndarray:
        w = np.asarray(omega0, float)
        if w.size:      # one node more each way: numpy's log may differ from math.log's
            self._need(max(self._node(float(w.min())) - 1, 0),
                       min(self._node(float(w.max())) + 3, _N_OMEGA))
        return super().max_leans(w)

    def bound(self, omega0: float) -> str:
        i = self._node(omega0)
        self._need(i, i + 2)
        return super().bound(omega0)


def preview_tables(plans) -> None:
    """Each ``(table, asked)`` of ``plans`` (:class:`PreviewTurns` of one limits) solved about
    the grid intervals ``asked`` (:meth:`PreviewTurns._plan`), all in one :meth:`_solve`:
    its cost is mostly its rounds, the same for one frequency as for a hundred."""
    plans = [(t, t._plan(asked)) for t, asked in plans]
    plans = [(t, idx) for t, idx in plans if idx.size]
    if not plans:
        return
    w = np.concatenate([np.exp(t._lw)[idx] for t, idx in plans])
    of = tuple(np.concatenate([np.full(idx.size, v) for (t, idx), v in zip(plans, col)])[:, None]
               for col in zip(*[(t.body.V_cm ** 2, t.body.l, t.body.g, t.body.J)
                                for t, _ in plans]))
    lean, bound = plans[0][0]._solve(w, of)
    start = 0
    for t, idx in plans:
        t._fill(idx, lean[start:start + idx.size], bound[start:start + idx.size])
        start += idx.size


@lru_cache(maxsize=256)
def _feasible_turns(body: BodyParams, limits: Limits) -> FeasibleTurns:
    return FeasibleTurns(body, limits)


#: ``[relative tolerance or None, the nearby_tables blocks entered]``: see
#: :func:`nearby_tables`.
_NEARBY = [None, 0]
#: What a table reads of its body (:func:`ellipse_needs`): the mass and the roll inertia only
#: through ``J = (I_v + l^2 m) / (m l)``, so nearness is measured on these.
_BODY_FIELDS = ("l", "J", "V_cm", "g")


def feasible_turns(body: BodyParams, limits: Limits) -> FeasibleTurns:
    """:class:`FeasibleTurns` for ``body`` and ``limits``, built once (about 6 ms).  256: a run
    down a slope passes through a table per 0.5 m/s of speed (10 to 27.5 m/s: 36), and a
    cache smaller than one run's sweep would rebuild every table on every run.  Inside
    :func:`nearby_tables`, a table already built for a nearby body."""
    table = _TABLES.get((body, limits))
    rel = _NEARBY[0]
    if table is None and rel is not None:
        table = _nearest(body, limits, rel) or _previews(body, limits, rel)
    if table is None:
        return _keep(_TABLES, (body, limits), _feasible_turns(body, limits))
    if rel is not None and table._step != _NEARBY[1]:
        table._asked, table._step = set(), _NEARBY[1]     # this drag step's asks, recorded
    return table


def _nearest(body: BodyParams, limits: Limits, rel: float) -> FeasibleTurns | None:
    """The table built for the body nearest ``body`` within ``rel`` (:func:`nearby_tables`),
    the newest of equals, or ``None``."""
    # The speed first (the tables of a run lie 0.5 m/s apart): a body whose speed alone is
    # further than rel is not near; the others by every field.
    V = body.V_cm
    near = [(_body_distance(b, body), i, table)
            for i, ((b, lim), table) in enumerate([*_TABLES.items(), *_PREVIEWS.items()])
            if abs(b.V_cm - V) / V <= rel and lim == limits]
    near = [n for n in near if n[0] <= rel]
    return min(near, key=lambda n: (n[0], -n[1]))[2] if near else None


def _previews(body: BodyParams, limits: Limits, rel: float) -> PreviewTurns:
    """``body``'s own :class:`PreviewTurns`, kept; with it those of ``body`` at each speed a
    recorded table (``_asked``) of a body within ``PLAN_REACH`` of it in ``l``, ``J`` and
    gravity was asked at (a run's speeds) that have no table within ``rel``: all solved at
    once about the grid intervals the nearest such body's table at that speed (the newest of
    equals) was asked (:func:`preview_tables`)."""
    own = _keep(_PREVIEWS, (body, limits), PreviewTurns(body, limits))
    nearest: dict = {}                  # speed: (distance, -order, the intervals asked)
    for i, ((b, lim), t) in enumerate([*_TABLES.items(), *_PREVIEWS.items()]):
        if lim == limits and t._asked:
            d = _body_distance(b, body, ("l", "J", "g"))
            if d <= PLAN_REACH and (d, -i) < nearest.get(b.V_cm, (math.inf,))[:2]:
                nearest[b.V_cm] = (d, -i, t._asked)
    plans = []
    for V, (_, _, where) in nearest.items():
        other = body.at_speed(V)
        if other == body:
            plans.append((own, where))
        elif _nearest(other, limits, rel) is None:
            plans.append((_keep(_PREVIEWS, (other, limits), PreviewTurns(other, limits)), where))
    preview_tables(plans)
    return own


#: How far (relative, in ``l``, ``J`` and gravity) a body's recorded tables plan another's
#: preview tables (:func:`_previews`): a drag's earlier steps (a step past 2 % from the body
#: before, several such steps back), not another figure's body.
PLAN_REACH = 0.1


def _keep(tables: dict, key, table):
    """``table`` kept in ``tables`` under ``key``, the oldest dropped past 256."""
    tables[key] = table
    while len(tables) > 256:
        tables.pop(next(iter(tables)))
    return table


def _body_distance(a: BodyParams, b: BodyParams, fields=_BODY_FIELDS) -> float:
    """The largest relative difference of what ``a``'s table reads from what ``b``'s does
    (``_BODY_FIELDS``)."""
    return max(abs(getattr(a, f) - getattr(b, f)) / abs(getattr(b, f)) if getattr(b, f) else
               (0.0 if getattr(a, f) == 0 else math.inf) for f in fields)


#: The tables built, oldest first (what :func:`nearby_tables` searches).
_TABLES: dict = {}
#: The drag steps' own tables (:class:`PreviewTurns`), oldest first: only :func:`nearby_tables`
#: takes them, a bake outside it builds its body's whole table.
_PREVIEWS: dict = {}


@contextmanager
def nearby_tables(rel: float):
    """Within this block :func:`feasible_turns` answers with a table built before for a body
    whose centre-of-mass height ``l``, inertia term ``J`` (Eqs. 1 and 2: the mass and the roll
    inertia act on the turns through it alone), speed and gravity are each within ``rel``
    (relative) of the one asked for, with the same limits, when there is one (the nearest
    such body): a Body slider's drag step in Live Preview then costs no new table (a run
    passes through several, ~7 ms each).  The mass moves ``J`` by a fraction of its own move
    (``I_v / (m l J)`` of it: 0.15 for the cyclist, 0.14 for the skier), so a mass slider
    stays near a table about 7 times as long as it would on the mass itself.  When there is
    none, the body's own, solved only about the frequencies the run asks for
    (:class:`PreviewTurns`: its leans and bounds those of the whole table, at about half of
    its cost), kept for the next steps.  The turns a nearby table allows are those of its body:
    with ``l`` and ``J`` within 2 % its leans are the body's own to 2.03 % (0.91 deg), with the
    speed within 2 % to 4.4 % (2.05 deg) (measured over six presets' tables at 1, 3, 8 and
    20 m/s, leans above 1 deg, tests/test_feasible_turns.py); the bake when the drag ends builds
    the body's whole table."""
    old, _NEARBY[0] = _NEARBY[0], float(rel)
    _NEARBY[1] += 1
    try:
        yield
    finally:
        _NEARBY[0] = old
