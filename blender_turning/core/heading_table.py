"""Directional control's turn modifier beta (Section 5.2, Eqs. 6-12).

``dtheta_dir(theta_max, omega0)`` is the heading change over one half-turn (Eq. 6).  A modified
half-turn on the ellipse ``(beta theta_max, omega0 / beta)`` changes the heading by
``dtheta_dir(beta theta_max, omega0 / beta)``; Eq. (8) asks for ``beta`` giving a wanted change.
Eq. (11)/(12) solve it under small angles; where they do not hold (``omega0 > 2 pi / 2 s`` or
``theta_max > 10 deg``) the paper's table with Newton-Raphson is used.  The table is simulated,
not approximated: each entry is a half-turn of the open-loop law on that ellipse, all entries in
one vectorised batch.
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from .dynamics import THETA_DIR, THETA_V, inverse_cf, rk4_step
from .params import BodyParams, Limits
from .phase import open_loop_alpha

#: beta is kept in this range: a half-turn 5x shallower or 3x sharper than planned is the most the
#: controller asks for; a change beyond it is spread over the following half-turns.
BETA_MIN, BETA_MAX = 0.2, 3.0
SMALL_OMEGA0 = 2 * math.pi / 2.0
SMALL_THETA = math.radians(10.0)
_FEW = 64          # below this many ellipses, solve_beta solves each on floats


def simulate_half_turns(body: BodyParams, theta_max, omega0, steps: int = 96):
    """Heading change over one half-turn (phase 0 -> 180 deg) on each ellipse, rad (Eq. 6)."""
    theta_max, omega0 = np.broadcast_arrays(np.asarray(theta_max, float), np.asarray(omega0, float))
    shape = theta_max.shape
    th, w = theta_max.ravel().copy(), omega0.ravel().copy()
    n = th.size
    state = np.zeros((5, n))
    state[4] = w * th                      # on the ellipse at phase 0
    dt = (np.pi / w) / steps
    unbounded = Limits()

    def desired(t, s):
        return inverse_cf(body, s[THETA_V], open_loop_alpha(w * t, th, w))

    t = np.zeros(n)
    for _ in range(steps):
        state = rk4_step(body, unbounded, state, t, dt, desired, None)
        t = t + dt
    return state[THETA_DIR].reshape(shape)


class HeadingTable:
    """``dtheta_dir`` on a grid of ``(theta_max, log omega0)``, bilinear, for one body."""

    def __init__(self, body: BodyParams, n_theta: int = 48, n_omega: int = 48,
                 theta_range=(math.radians(0.5), math.radians(60.0)),
                 period_range=(0.4, 12.0)):
        self.body = body
        self.theta = np.linspace(*theta_range, n_theta)
        self.log_w = np.linspace(math.log(2 * math.pi / period_range[1]),
                                 math.log(2 * math.pi / period_range[0]), n_omega)
        T, W = np.meshgrid(self.theta, np.exp(self.log_w), indexing="ij")
        self.values = simulate_half_turns(body, T, W)
        self._curves = {}
        # Plain floats for value_one.
        self._rows = self.values.tolist()
        self._t0, self._t1 = float(self.theta[0]), float(self.theta[-1])
        self._lw0, self._lw1 = float(self.log_w[0]), float(self.log_w[-1])
        self._dth = float(self.theta[1] - self.theta[0])
        self._dlw = float(self.log_w[1] - self.log_w[0])

    def __call__(self, theta_max, omega0):
        """Bilinear interpolation (clamped to the grid) of ``dtheta_dir``."""
        th = np.clip(np.asarray(theta_max, float), self.theta[0], self.theta[-1])
        lw = np.clip(np.log(np.asarray(omega0, float)), self.log_w[0], self.log_w[-1])
        dth = self.theta[1] - self.theta[0]
        dlw = self.log_w[1] - self.log_w[0]
        fi = np.minimum((th - self.theta[0]) / dth, len(self.theta) - 1 - 1e-9)
        fj = np.minimum((lw - self.log_w[0]) / dlw, len(self.log_w) - 1 - 1e-9)
        i, j = fi.astype(int), fj.astype(int)
        a, b = fi - i, fj - j
        v = self.values
        return ((1 - a) * (1 - b) * v[i, j] + a * (1 - b) * v[i + 1, j]
                + (1 - a) * b * v[i, j + 1] + a * b * v[i + 1, j + 1])

    def value_one(self, theta_max: float, omega0: float) -> float:
        """:meth:`__call__` for one point on Python floats (the one-figure controller solves
        Eq. 8 at every half-turn; numpy's per-call cost would dominate)."""
        t, lw = self.theta, self.log_w
        th = min(max(theta_max, self._t0), self._t1)
        lg = min(max(math.log(omega0), self._lw0), self._lw1)
        fi = min((th - self._t0) / self._dth, len(t) - 1 - 1e-9)
        fj = min((lg - self._lw0) / self._dlw, len(lw) - 1 - 1e-9)
        i, j = int(fi), int(fj)
        a, b = fi - i, fj - j
        r0, r1 = self._rows[i], self._rows[i + 1]
        return ((1 - a) * (1 - b) * r0[j] + a * (1 - b) * r1[j]
                + (1 - a) * b * r0[j + 1] + a * b * r1[j + 1])

    def beta_range(self, theta_max, omega0):
        """The betas whose modified ellipse stays on the grid and in [BETA_MIN, BETA_MAX]."""
        lo = np.maximum.reduce([np.full_like(np.asarray(theta_max, float), BETA_MIN),
                                self.theta[0] / theta_max, omega0 / math.exp(self.log_w[-1])])
        hi = np.minimum.reduce([np.full_like(np.asarray(theta_max, float), BETA_MAX),
                                self.theta[-1] / theta_max, omega0 / math.exp(self.log_w[0])])
        return lo, np.maximum(hi, lo)

    def _curve(self, theta_max: float, omega0: float):
        """``(beta, dtheta_dir(beta theta_max, omega0 / beta))`` on 257 betas, cached."""
        key = (theta_max, omega0)
        if key not in self._curves:
            if len(self._curves) > 64:
                self._curves.clear()
            lo, hi = self.beta_range(np.float64(theta_max), np.float64(omega0))
            b = np.linspace(float(lo), float(hi), 257)
            v = self(b * theta_max, omega0 / b)
            self._curves[key] = (b, np.maximum.accumulate(v))   # monotone for np.interp
        return self._curves[key]

    def solve_beta(self, theta_max, omega0, wanted, iterations: int = 12):
        """Eq. (8) by safeguarded Newton-Raphson: beta with dtheta_dir(b th, w / b) = wanted.

        An unreachable ``wanted`` gives the end of the range closest to it (never NaN).
        """
        if all(isinstance(v, (float, int)) for v in (theta_max, omega0, wanted)):
            return self._solve_one(float(theta_max), float(omega0), float(wanted), iterations)
        if np.ndim(theta_max) == 0 and np.ndim(omega0) == 0 and np.size(wanted) <= _FEW:
            # A few figures of a batch crossing at once: a float solve each is ~100x cheaper
            # than numpy iterations on a handful of elements.
            tm, w = float(theta_max), float(omega0)
            return np.array([self._solve_one(tm, w, float(v), iterations)
                             for v in np.ravel(wanted)]).reshape(np.shape(wanted))
        theta_max, omega0, wanted = np.broadcast_arrays(
            np.asarray(theta_max, float), np.asarray(omega0, float), np.asarray(wanted, float))
        lo, hi = self.beta_range(theta_max, omega0)

        def F(b):
            return self(b * theta_max, omega0 / b) - wanted

        f_lo, f_hi = F(lo), F(hi)
        if theta_max.ndim == 0 or (np.ptp(theta_max) == 0 and np.ptp(omega0) == 0):
            # One ellipse for all: invert its sampled curve dtheta_dir(beta) as the first guess.
            b, v = self._curve(float(theta_max.flat[0]), float(omega0.flat[0]))
            beta = np.interp(wanted, v, b)
        else:
            beta = linear_beta(self.body, theta_max, omega0, wanted - self(theta_max, omega0))
        beta = np.clip(beta, lo, hi)
        a, c = lo.copy(), hi.copy()            # bracket: F(a) <= 0 <= F(c) where reachable
        for _ in range(iterations):
            f = F(beta)
            done = np.abs(f) < 1e-9           # 1e-9 rad of heading: converged, frozen
            if np.all(done):
                break
            a = np.where(f <= 0, beta, a)
            c = np.where(f > 0, beta, c)
            h = 1e-4 * beta
            df = (F(beta + h) - F(beta - h)) / (2 * h)
            with np.errstate(divide="ignore", invalid="ignore"):
                nb = beta - f / df
            bad = ~np.isfinite(nb) | (nb < a) | (nb > c)
            beta = np.where(done, beta, np.where(bad, 0.5 * (a + c), nb))
        beta = np.where(f_lo >= 0, lo, np.where(f_hi <= 0, hi, beta))
        return beta


    def _solve_one(self, theta_max, omega0, wanted, iterations):
        """:meth:`solve_beta` for one ellipse on floats: the same steps, without numpy."""
        lo = max(BETA_MIN, self._t0 / theta_max, omega0 / math.exp(self._lw1))
        hi = max(min(BETA_MAX, self._t1 / theta_max, omega0 / math.exp(self._lw0)), lo)
        value = self.value_one

        def F(b):
            return value(b * theta_max, omega0 / b) - wanted

        f_lo, f_hi = F(lo), F(hi)
        if f_lo >= 0:
            return lo
        if f_hi <= 0:
            return hi
        b, v = self._curve(theta_max, omega0)
        beta = min(max(float(np.interp(wanted, v, b)), lo), hi)
        a, c = lo, hi
        for _ in range(iterations):
            f = F(beta)
            if abs(f) < 1e-9:
                break
            if f <= 0:
                a = beta
            else:
                c = beta
            h = 1e-4 * beta
            df = (F(beta + h) - F(beta - h)) / (2 * h)
            nb = beta - f / df if df != 0.0 else math.nan
            beta = 0.5 * (a + c) if not (a <= nb <= c) else nb
        return beta


def linear_beta(body: BodyParams, theta_max, omega0, dtheta_h):
    """Eqs. (11)/(12): ``beta = sqrt(1 + dtheta_h V_f omega0 / (2 g theta_max))``, with ``V_f ~ V_cm``.

    ``dtheta_h`` is the extra heading change wanted over the half-turn in the turn's own sense
    (positive = more turn), which covers both equations.  Clamped to [BETA_MIN, BETA_MAX].
    """
    r = 1.0 + np.asarray(dtheta_h) * body.V_cm * omega0 / (2.0 * body.g * theta_max)
    return np.sqrt(np.clip(r, BETA_MIN ** 2, BETA_MAX ** 2))


@lru_cache(maxsize=16)
def heading_table(body: BodyParams) -> HeadingTable:
    """The table for ``body``, built once per body (about 0.1 s)."""
    return HeadingTable(body)
