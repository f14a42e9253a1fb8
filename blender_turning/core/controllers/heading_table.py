"""Directional control's turn modifier beta (Section 5.2, Eqs. 6-12).

``dtheta_dir(theta_max, omega0)`` is the heading change over one half-turn (Eq. 6).  A modified
half-turn on the ellipse ``(beta theta_max, omega0 / beta)`` changes the heading by
``dtheta_dir(beta theta_max, omega0 / beta)``; Eq. (8) asks for the ``beta`` giving a wanted
change.

The paper approximates ``dtheta_dir`` under small angles (Eqs. 9-12) and otherwise tabulates it
from simulation.  It has an exact closed form, so neither is needed.  With the curvature of
Eq. (1) (physical root, ``k = g sin th - alpha_v J``), Eq. (21) gives

    1 - C_f l sin th = V^2 cos th / (k l sin th + V^2 cos th),   so   V_f C_f = k / (V cos th),

a function of the lean and the demanded ``alpha_v`` alone.  On the open-loop ellipse (Eq. 5,
``alpha_v = -omega0^2 theta_v``, ``theta_v = theta_max sin u``, ``u = omega0 t``) the half-turn's
heading change (Eq. 10 with Eq. 21's ``V_f``, not the paper's constant one) is therefore

    dtheta_dir = g theta_max A(theta_max) / (V omega0) + omega0 J theta_max B(theta_max) / V,
    A(th) = (1/th) int_0^pi tan(th sin u) du,    B(th) = int_0^pi sin u / cos(th sin u) du,

with ``J = (I_v + l^2 m) / (m l)``.  ``A`` and ``B`` depend on the lean only (both 2 at
``th -> 0``, which is Eqs. 9-10); they are computed once by Gauss-Legendre quadrature on a fine
grid and interpolated linearly (relative error < 2e-6, tested against simulated half-turns).  The
speed enters in closed form, so there is no table per body, no grid edge in ``omega0`` or
``theta_max`` to clamp at (the old table started at 0.5 deg), and no simulation that can fail at
low speed (the old table held NaN at 0.5 m/s).
"""
from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ..physics.params import BodyParams

#: beta is kept in this range: a half-turn 5x shallower or 3x sharper than planned is the most the
#: controller asks for (the body's own bounds are usually tighter: :mod:`.controllers.feasible`);
#: a change beyond it is spread over the following half-turns.
BETA_MIN, BETA_MAX = 0.2, 3.0
#: Leans beyond this are evaluated at it (``A`` grows without bound toward 90 deg; no figure leans
#: this far without falling).
THETA_TOP = math.radians(85.0)
_N_GRID = 4097
_N_GAUSS = 64


@lru_cache(maxsize=1)
def _lean_factors():
    """``(theta grid, A, B)``: the lean factors of the closed form on ``[0, THETA_TOP]``."""
    theta = np.linspace(0.0, THETA_TOP, _N_GRID)
    return (theta,) + lean_factors(theta)


def lean_factors(theta, n: int = _N_GAUSS):
    """``(A(theta), B(theta))`` by ``n``-point Gauss-Legendre quadrature (the integrands are
    symmetric about ``u = pi/2``: twice the integral over ``[0, pi/2]``)."""
    x, w = np.polynomial.legendre.leggauss(n)
    u = 0.25 * math.pi * (x + 1.0)                       # [-1, 1] -> [0, pi/2]
    w = 0.5 * math.pi * w                                 # 2 * (pi/4) * w
    th = np.asarray(theta, float)
    ts = th[..., None] * np.sin(u)
    safe = np.where(th > 0.0, th, 1.0)
    A = np.where(th > 0.0, (np.tan(ts) @ w) / safe, 2.0)
    B = (np.sin(u) / np.cos(ts)) @ w
    return A, B


class HeadingTable:
    """``dtheta_dir(theta_max, omega0)`` for one body (the closed form of the module docstring)
    and the solution of Eq. (8) for beta."""

    def __init__(self, body: BodyParams):
        self.body = body
        theta, A, B = _lean_factors()
        self._theta, self._A, self._B = theta, A, B
        self._Al, self._Bl = A.tolist(), B.tolist()
        self._h = float(theta[1] - theta[0])
        self._gv = body.g / body.V_cm
        self._jv = body.J / body.V_cm

    def __call__(self, theta_max, omega0):
        """The half-turn's heading change, rad (arrays or numbers)."""
        th = np.minimum(np.asarray(theta_max, float), THETA_TOP)
        w = np.asarray(omega0, float)
        A = np.interp(th, self._theta, self._A)
        B = np.interp(th, self._theta, self._B)
        return th * (self._gv * A / w + self._jv * w * B)

    def value_one(self, theta_max: float, omega0: float) -> float:
        """:meth:`__call__` on Python floats (the one-figure controller solves Eq. 8 at every
        half-turn; numpy's per-call cost would dominate)."""
        th = theta_max if theta_max < THETA_TOP else THETA_TOP
        f = th / self._h
        i = min(int(f), _N_GRID - 2)
        a = f - i
        A = self._Al[i] + a * (self._Al[i + 1] - self._Al[i])
        B = self._Bl[i] + a * (self._Bl[i + 1] - self._Bl[i])
        return th * (self._gv * A / omega0 + self._jv * omega0 * B)

    def solve_beta(self, theta_max, omega0, wanted, lo=BETA_MIN, hi=BETA_MAX,
                   iterations: int = 30):
        """Eq. (8) by safeguarded Newton-Raphson: beta in ``[lo, hi]`` with
        ``dtheta_dir(beta theta_max, omega0 / beta) = wanted``.  The change grows with beta, so an
        unreachable ``wanted`` gives the end of the range closest to it (never NaN)."""
        if all(isinstance(v, (float, int)) for v in (theta_max, omega0, wanted, lo, hi)):
            return self._solve_one(float(theta_max), float(omega0), float(wanted), float(lo),
                                   float(hi), iterations)
        theta_max, omega0, wanted, lo, hi = np.broadcast_arrays(
            *(np.asarray(v, float) for v in (theta_max, omega0, wanted, lo, hi)))

        def F(b):
            return self(b * theta_max, omega0 / b) - wanted

        a, c = lo.copy(), hi.copy()
        beta = np.clip(1.0 + 0.0 * wanted, a, c)
        done = np.zeros(beta.shape, bool)
        for _ in range(iterations):
            f = F(beta)
            # Each ellipse stops alone, exactly where it would in a batch of its own (a crowd's
            # figures give the same result whatever they are batched with).
            done = done | (np.abs(f) < 1e-12)
            if np.all(done):
                break
            a = np.where(f <= 0, beta, a)
            c = np.where(f > 0, beta, c)
            h = 1e-6 * beta
            df = (F(beta + h) - F(beta - h)) / (2 * h)
            nb = beta - f / np.where(df > 0, df, np.inf)
            beta = np.where(done, beta, np.where((nb > a) & (nb < c), nb, 0.5 * (a + c)))
        return np.where(F(lo) >= 0, lo, np.where(F(hi) <= 0, hi, beta))

    def _solve_one(self, theta_max, omega0, wanted, lo, hi, iterations):
        """:meth:`solve_beta` for one ellipse on floats: the same steps, without numpy."""
        value = self.value_one

        def F(b):
            return value(b * theta_max, omega0 / b) - wanted

        if F(lo) >= 0:
            return lo
        if F(hi) <= 0:
            return hi
        a, c = lo, hi
        beta = min(max(1.0, a), c)
        for _ in range(iterations):
            f = F(beta)
            if abs(f) < 1e-12:
                break
            if f <= 0:
                a = beta
            else:
                c = beta
            h = 1e-6 * beta
            df = (F(beta + h) - F(beta - h)) / (2 * h)
            nb = beta - f / df if df > 0.0 else math.nan
            beta = nb if a < nb < c else 0.5 * (a + c)
        return beta


def linear_beta(body: BodyParams, theta_max, omega0, dtheta_h):
    """Eqs. (11)/(12): ``beta = sqrt(1 + dtheta_h V_f omega0 / (2 g theta_max))``, with
    ``V_f ~ V_cm``.

    ``dtheta_h`` is the extra heading change wanted over the half-turn in the turn's own sense
    (positive = more turn), which covers both equations.  Clamped to [BETA_MIN, BETA_MAX].
    """
    r = 1.0 + np.asarray(dtheta_h) * body.V_cm * omega0 / (2.0 * body.g * theta_max)
    return np.sqrt(np.clip(r, BETA_MIN ** 2, BETA_MAX ** 2))


@lru_cache(maxsize=16)
def heading_table(body: BodyParams) -> HeadingTable:
    """The half-turn heading change for ``body`` (cheap: the lean factors are shared)."""
    return HeadingTable(body)
