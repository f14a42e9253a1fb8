"""The paper's phase-ellipse law of Section 5.1 (``PhaseEllipse(..., law="paper")``, CLI
``--law paper``), kept to compare with the default smooth law of :mod:`.ellipse`.

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

Even so its demand jumps between the two families' formulas near each apex, where the Fig. 7a
ellipse's ``omega0'^2 = omega_v^2 / (theta_max^2 - theta_v^2)`` is 0/0: C_f and F_leg twitch
twice per turn (measured in BENCHMARKS.md).
"""
from __future__ import annotations

import math

import numpy as np

from ..physics.xp import Scalar, backend

SLOW_FACTOR = 3.0
NEAR = 1.1


def paper_alpha(theta_v, omega_v, theta_max, omega0, alpha_max, origin_radius=0.05):
    """Section 5.1: the lean acceleration that takes the state onto the target ellipse (arrays;
    floats go to :func:`paper_alpha_one`, the same law as branches)."""
    if backend(theta_v, omega_v, theta_max, omega0, alpha_max) is Scalar:
        return paper_alpha_one(theta_v, omega_v, theta_max, omega0, alpha_max, origin_radius)
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


def paper_alpha_one(th, om, theta_max, omega0, alpha_max, origin_radius=0.05):
    """:func:`paper_alpha` for one figure on Python floats, as branches (the same law; one
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
