"""The parameterized controller of Section 5: phase-ellipse control (5.1) with directional
control (5.2).  Vectorised over a batch of figures.

Section 5.1, read geometrically (``shared/DESIGN.md`` Section 2): the controlling ellipse through
the current state shares the target's lean intercept ``theta_max`` in quadrants 1 and 3 (Fig. 7a)
and its rate intercept ``omega0 theta_max`` in quadrants 2 and 4 (Fig. 7b).  On any ellipse of
Eq. (3) ``alpha_v = -omega0'^2 theta_v`` (Eq. 5), so

- Q1/Q3: ``omega0'^2 = omega_v^2 / (theta_max^2 - theta_v^2)``;
- Q2/Q4: ``beta^2 = y^2 / (1 - x^2)``, ``omega0' = omega0 / beta``
  (``y = theta_v/theta_max``, ``x = omega_v/(omega0 theta_max)``).

The paper's ``omega0' = omega_v / (theta_max cos phi)`` uses the phase on the *controlling*
ellipse, ``cos phi' = sqrt(1 - y^2)``; with the target's phase it would not pass through the state.
States on no controlling ellipse get ``alpha_v = -alpha_max sign(omega_v)`` (+ in Q2, Q3; - in Q1,
Q4), a small disc around the origin gets a fixed push, and every demand is clipped to
``|alpha_v| <= alpha_max``.
"""
from __future__ import annotations

import numpy as np

from ..dynamics import OMEGA_V, THETA_DIR, THETA_V
from ..heading_table import SMALL_OMEGA0, SMALL_THETA, heading_table, linear_beta
from ..params import BodyParams
from ..schedule import Schedule
from .base import Controller


def ellipse_alpha(theta_v, omega_v, theta_max, omega0, alpha_max, origin_radius=0.05):
    """Section 5.1: the lean acceleration that takes the state onto the target ellipse."""
    th, om = np.asarray(theta_v, float), np.asarray(omega_v, float)
    y = th / theta_max
    x = om / (omega0 * theta_max)
    q13 = th * om >= 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        a13 = -om * om * th / (theta_max * theta_max - th * th)
        a24 = -(omega0 * theta_max) ** 2 * (1.0 - x * x) / th
    inside = np.where(q13, np.abs(y) < 1.0, np.abs(x) < 1.0)
    a = np.where(q13, a13, a24)
    away = -alpha_max * np.where(om != 0.0, np.sign(om), np.sign(th))
    a = np.where(inside & np.isfinite(a), a, away)
    a = np.where(np.hypot(x, y) < origin_radius, 0.5 * alpha_max, a)
    return np.clip(a, -alpha_max, alpha_max)


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
        return heading_table(self.body)(theta_max, omega0)

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
        side = np.where(th > 0, 1.0, np.where(th < 0, -1.0, np.where(om >= 0, 1.0, -1.0)))
        if self._beta is None:
            self._beta = np.ones_like(np.asarray(th, float))
            near_axis = np.abs(th) < 0.05 * self.theta_max(t)
            self._side = np.where(near_axis, -side, side)     # a start on the axis is a crossing
        crossed = side != self._side
        self._side = side
        if self.heading is None or not np.any(crossed):
            self._beta = np.where(crossed, 1.0, self._beta)
            return
        w, tm = self.omega0(t), self.theta_max(t)
        change = self.half_turn_change(tm, w)
        # Mean heading: the heading is at an extreme at a crossing (C_f is in phase with theta_v).
        mean = state[THETA_DIR] + side * 0.5 * change
        err = np.angle(np.exp(1j * (self.heading(t) - mean)))        # wrapped to (-pi, pi]
        wanted = change + side * err                                # Eq. (7), in the turn's sense
        beta = self._solve_beta(tm, w, wanted)
        self._beta = np.where(crossed, beta, self._beta)

    # -- Section 5.1 -------------------------------------------------------------------------
    def target(self, t):
        b = self._beta if self._beta is not None else 1.0
        return self.omega0(t) / b, b * self.theta_max(t)

    def desired_alpha(self, t, state):
        w, tm = self.target(t)
        amax = self.alpha_max if self.alpha_max is not None else \
            2.0 * self.omega0(t) ** 2 * self.theta_max(t)
        return ellipse_alpha(state[THETA_V], state[OMEGA_V], tm, w, amax, self.origin_radius)

