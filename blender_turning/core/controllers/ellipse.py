"""The parameterized controller of Section 5: phase-ellipse control (5.1) with directional
control (5.2).  Works on one figure (floats) or a batch (arrays).

Section 5.1, read geometrically (docs/ARCHITECTURE.md Section 5): the controlling ellipse through
the current state shares the target's lean intercept ``theta_max`` in quadrants 1 and 3 (Fig. 7a)
and its rate intercept ``omega0 theta_max`` in quadrants 2 and 4 (Fig. 7b).  On any ellipse of
Eq. (3) ``alpha_v = -omega0'^2 theta_v`` (Eq. 5), so

- Q1/Q3: ``omega0'^2 = omega_v^2 / (theta_max^2 - theta_v^2)``;
- Q2/Q4: ``beta^2 = y^2 / (1 - x^2)``, ``omega0' = omega0 / beta``
  (``y = theta_v/theta_max``, ``x = omega_v/(omega0 theta_max)``).

The paper's ``omega0' = omega_v / (theta_max cos phi)`` uses the phase on the *controlling*
ellipse, ``cos phi' = sqrt(1 - y^2)``; with the target's phase it would not pass through the state.
Beyond the paper: in Q1/Q3 a Fig. 7a ellipse more than ``SLOW_FACTOR`` times slower than the
target is replaced by the Fig. 7b ellipse through the state.  Otherwise a state with little lean
rate creeps toward ``theta_max`` on an ever slower ellipse and never arrives when ``theta_max``
grows over time; and ``(0 < theta_v < theta_max, omega_v = 0)`` is a fixed point of the paper's
law (a steady circle).  The Fig. 7b ellipse turns back at once and meets the target at the
``omega_v`` axis.

Also beyond the paper: a state just outside the target in Q1/Q3 (``|y| >= 1``) is steered by the
Fig. 7b ellipse through it, and one in Q2/Q4 with ``|x| >= 1`` by the Fig. 7a ellipse, where those
exist.  Both meet the target at the next axis and agree with the on-ellipse law at ``r = 1``, so
the demand is continuous across the target ellipse; the paper's ``+-alpha_max`` right outside it
made the lean chatter at every turn's apex (period jitter of ~0.2% at dt = 0.02 s).  Only states
on neither family get ``alpha_v = -alpha_max sign(omega_v)`` (+ in Q2, Q3; - in Q1, Q4).  A small
disc around the origin gets a fixed push, and every demand is clipped to ``|alpha_v| <= alpha_max``.
"""
from __future__ import annotations

import math

import numpy as np

from ..dynamics import OMEGA_V, THETA_DIR, THETA_V
from ..one_figure import scalar_inverse_cf
from ..heading_table import SMALL_OMEGA0, SMALL_THETA, heading_table, linear_beta
from ..params import BodyParams
from ..schedule import Schedule
from ..xp import Scalar, backend
from .base import Controller


SLOW_FACTOR = 3.0
NEAR = 1.1


def ellipse_alpha(theta_v, omega_v, theta_max, omega0, alpha_max, origin_radius=0.05):
    """Section 5.1: the lean acceleration that takes the state onto the target ellipse (arrays;
    floats go to :func:`ellipse_alpha_one`, the same law as branches)."""
    if backend(theta_v, omega_v, theta_max, omega0, alpha_max) is Scalar:
        return ellipse_alpha_one(theta_v, omega_v, theta_max, omega0, alpha_max, origin_radius)
    th, om = theta_v, omega_v
    y = th / theta_max
    x = om / (omega0 * theta_max)
    den = theta_max * theta_max - th * th
    w13_sq = om * om / np.where(den > 0.0, den, 1.0)           # omega0'^2 of the Fig. 7a ellipse
    on_a = den > 0.0                           # |y| < 1: a Fig. 7a ellipse passes through
    on_b = (np.abs(x) < 1.0) & (th != 0.0)     # |x| < 1: a Fig. 7b ellipse passes through
    slow = (w13_sq * SLOW_FACTOR ** 2 < omega0 * omega0) & (th != 0.0) & on_a
    # Preferred family: Fig. 7a in quadrants 1, 3 (and on the axes) unless slow, else Fig. 7b.
    prefer_b = (th * om < 0.0) | slow
    prefer_a = ~prefer_b
    a13 = -w13_sq * th
    a24 = -(omega0 * theta_max) ** 2 * (1.0 - x * x) / np.where(th != 0.0, th, 1.0)
    # The other family only for states near the target (within NEAR on the preferred family's
    # axis): far outside, the paper's +-alpha_max is what brings the lean back.
    near = np.where(prefer_a, np.abs(y) < NEAR, np.abs(x) < NEAR)
    use_a = on_a & (prefer_a | near)
    use_b = on_b & (prefer_b | near)
    away = -alpha_max * np.where(om != 0.0, np.sign(om), np.sign(th))
    a = np.where(prefer_a & on_a, a13, np.where(use_b, a24, np.where(use_a, a13, away)))
    a = np.where(np.hypot(x, y) < origin_radius, 0.5 * alpha_max, a)
    return np.minimum(np.maximum(a, -alpha_max), alpha_max)


def ellipse_alpha_one(th, om, theta_max, omega0, alpha_max, origin_radius=0.05):
    """:func:`ellipse_alpha` for one figure on Python floats, as branches (the same law; one
    figure is stepped ~12,000 times a minute of motion, so it skips the branches not taken)."""
    y = th / theta_max
    x = om / (omega0 * theta_max)
    if math.hypot(x, y) < origin_radius:
        return 0.5 * alpha_max
    den = theta_max * theta_max - th * th
    on_a = den > 0.0
    w13_sq = om * om / den if on_a else om * om
    prefer_b = th * om < 0.0 or (on_a and th != 0.0 and w13_sq * SLOW_FACTOR ** 2 < omega0 * omega0)
    if on_a and not prefer_b:
        a = -w13_sq * th
    else:
        near = abs(x) < NEAR if prefer_b else abs(y) < NEAR
        if abs(x) < 1.0 and th != 0.0 and (prefer_b or near):
            a = -(omega0 * theta_max) ** 2 * (1.0 - x * x) / th
        elif on_a and near:
            a = -w13_sq * th
        else:
            a = -alpha_max * ((om > 0.0) - (om < 0.0) if om != 0.0 else (th > 0.0) - (th < 0.0))
    return -alpha_max if a < -alpha_max else (alpha_max if a > alpha_max else a)


class PhaseEllipse(Controller):
    """Turn frequency ``omega0(t)``, sharpness ``theta_max(t)`` and optionally heading
    ``theta_h(t)``, each a number, a callable of time or a :class:`Schedule`.

    ``alpha_max`` (rad/s^2) defaults to ``2 omega0^2 theta_max``: twice the peak of the target's own
    ``alpha_v``.  ``directional`` picks how beta is found: ``"auto"`` (Eq. 11/12 where the
    small-angle approximation holds, else the table), ``"linear"`` or ``"table"``.
    """

    def __init__(self, body: BodyParams, omega0, theta_max, heading=None, alpha_max=None,
                 origin_radius: float = 0.05, directional: str = "auto"):
        super().__init__(body)
        if directional not in ("auto", "linear", "table"):
            raise ValueError(f"directional = {directional!r} is not one of auto, linear, table")
        self.omega0 = Schedule.of(omega0)
        self.theta_max = Schedule.of(theta_max)
        self.heading = None if heading is None else Schedule.of(heading)
        self.alpha_max = alpha_max
        self.origin_radius = origin_radius
        self.directional = directional
        self._beta = None          # modifier of the current half-turn, per figure
        self._side = None          # +1 during a left half-turn (theta_v >= 0), -1 right

    # -- Section 5.2 -------------------------------------------------------------------------
    def half_turn_change(self, theta_max, omega0):
        """``dtheta_dir(theta_max, omega0)`` of Eq. (6), rad."""
        return heading_table(self.body).value_one(float(theta_max), float(omega0))

    def _solve_beta(self, theta_max, omega0, wanted):
        use_linear = self.directional == "linear" or (
            self.directional == "auto" and omega0 <= SMALL_OMEGA0 + 1e-12
            and theta_max <= SMALL_THETA + 1e-12)
        if use_linear:
            extra = wanted - self.half_turn_change(theta_max, omega0)
            return linear_beta(self.body, theta_max, omega0, extra)
        return heading_table(self.body).solve_beta(theta_max, omega0, wanted)

    def begin_step(self, t, state):
        th, om = state[THETA_V], state[OMEGA_V]
        if type(th) is float and self._beta is not None:     # one figure, most steps: no crossing
            if (1.0 if th > 0 else -1.0 if th < 0 else 1.0 if om >= 0 else -1.0) == self._side:
                return
        xp = backend(th)
        side = xp.where(th > 0, 1.0, xp.where(th < 0, -1.0, xp.where(om >= 0, 1.0, -1.0)))
        if self._beta is None:
            self._beta = 1.0 if xp is Scalar else np.ones_like(th)
            near_axis = xp.abs(th) < 0.05 * self.theta_max(t)
            self._side = xp.where(near_axis, -side, side)     # a start on the axis is a crossing
        crossed = side != self._side
        self._side = side
        if self.heading is None or not xp.any(crossed):
            self._beta = xp.where(crossed, 1.0, self._beta)
            return
        w, tm = self.omega0(t), self.theta_max(t)
        change = self.half_turn_change(tm, w)
        if xp is Scalar:
            self._beta = float(self._modifier(state[THETA_DIR], side, t, tm, w, change))
        else:                                   # solve only for the figures that crossed
            idx = np.nonzero(crossed)[0]
            beta = np.array(self._beta, float)
            beta[idx] = self._modifier(state[THETA_DIR][idx], side[idx], t, tm, w, change)
            self._beta = beta

    def _modifier(self, theta_dir, side, t, tm, w, change):
        """beta of the half-turn starting now on ``side`` (Eqs. 7-12)."""
        # Mean heading: the heading is at an extreme at a crossing (C_f is in phase with theta_v).
        mean = theta_dir + side * 0.5 * change
        err = (self.heading(t) - mean + math.pi) % (2 * math.pi) - math.pi
        wanted = change + side * err                                # Eq. (7), in the turn's sense
        return self._solve_beta(tm, w, wanted)

    # -- Section 5.1 -------------------------------------------------------------------------
    def target(self, t):
        b = 1.0 if self._beta is None else self._beta
        return self.omega0(t) / b, b * self.theta_max(t)

    def scalar_cf_law(self):
        """:meth:`desired_cf` for one figure on floats (:func:`ellipse_alpha_one`, Eq. 1),
        with constant schedules read once."""
        inverse, ellipse = scalar_inverse_cf(self.body), self._ellipse
        w_s, tm_s, r0 = self.omega0, self.theta_max, self.origin_radius
        wc, tc = w_s.constant_value, tm_s.constant_value

        def law(t, state):
            tm, w, amax = ellipse(wc if wc is not None else w_s(t),
                                  tc if tc is not None else tm_s(t))
            th = state[3]
            return inverse(th, ellipse_alpha_one(th, state[4], tm, w, amax, r0))

        return law

    def _ellipse(self, w0, tm0):
        """``(theta_max, omega0, alpha_max)`` of the half-turn's ellipse: the target modified
        by its beta (Section 5.2)."""
        b = 1.0 if self._beta is None else self._beta
        amax = self.alpha_max if self.alpha_max is not None else 2.0 * w0 * w0 * tm0
        return b * tm0, w0 / b, amax

    def desired_alpha(self, t, state):
        tm, w, amax = self._ellipse(self.omega0(t), self.theta_max(t))
        return ellipse_alpha(state[THETA_V], state[OMEGA_V], tm, w, amax, self.origin_radius)
