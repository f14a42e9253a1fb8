"""Equations of motion of the turning pendulum (Section 3, Appendix A), vectorised.

The state of a batch of ``n`` figures is an array of shape ``(5, n)`` (or ``(5,)`` for one),
rows named by ``STATE``: foot position ``x, y`` (m), heading ``theta_dir`` (rad, CCW from +x),
lean ``theta_v`` (rad, > 0 leans left) and lean rate ``omega_v`` (rad/s).  The control is the foot
curvature ``C_f`` (1/m, > 0 curves left).  Sign conventions: ``shared/DESIGN.md`` Section 1.
"""
from __future__ import annotations

import numpy as np

from .params import BodyParams, Limits

STATE = ("x", "y", "theta_dir", "theta_v", "omega_v")
X, Y, THETA_DIR, THETA_V, OMEGA_V = range(5)

#: Fraction of the way to the singular curvature ``1/(l sin theta_v)`` that ``C_f`` may go
#: (Eq. 21 divides by ``1 - C_f l sin theta_v``).  Beyond it the foot would have to outrun the body.
PHYSICAL_MARGIN = 0.9


def forward_alpha(body: BodyParams, theta_v, C_f, sin_t=None, cos_t=None):
    """Eq. (2): lean acceleration ``alpha_v`` (rad/s^2) produced by the foot curvature ``C_f``."""
    s = np.sin(theta_v) if sin_t is None else sin_t
    c = np.cos(theta_v) if cos_t is None else cos_t
    k = C_f * body.V_cm ** 2 * c / (1.0 - C_f * body.l * s)
    return (body.g * s - k) / body.J


def inverse_cf(body: BodyParams, theta_v, alpha_v, sin_t=None, cos_t=None):
    """Eq. (1), the physical ("negative") root in closed form: the ``C_f`` giving ``alpha_v``.

    The quadratic factors as ``[k - (k l sin th + V^2 cos th) C_f](1 - C_f l sin th) = 0`` with
    ``k = g sin th - alpha_v J``; the root ``1/(l sin th)`` is spurious.  Where the physical
    denominator ``k l sin th + V^2 cos th`` is not positive the demand is unreachable on the
    physical branch and the result is ``sign(k) * inf``, for :func:`bound_cf` to clamp.
    """
    s = np.sin(theta_v) if sin_t is None else sin_t
    c = np.cos(theta_v) if cos_t is None else cos_t
    k = body.g * s - np.asarray(alpha_v) * body.J
    den = k * body.l * s + body.V_cm ** 2 * c
    with np.errstate(divide="ignore", invalid="ignore"):
        cf = np.where(den > 0.0, k / np.where(den > 0.0, den, 1.0), np.sign(k) * np.inf)
    return cf


def physical_cf_limit(body: BodyParams, sin_t):
    """Largest ``C_f`` in the lean's direction keeping ``1 - C_f l sin th >= 1 - PHYSICAL_MARGIN``."""
    with np.errstate(divide="ignore"):
        return PHYSICAL_MARGIN / (body.l * np.abs(sin_t))


def bound_cf(body: BodyParams, limits: Limits, C_f, sin_t, anchor=None, tau=0.0):
    """Section 3: clamp a demanded ``C_f`` to ``|C_f| <= C_f_max``, to the physical branch, and
    (given the curvature ``anchor`` at ``tau`` seconds ago) to ``|dC_f/dt| <= dC_f_max``."""
    lim = np.minimum(limits.C_f_max, physical_cf_limit(body, sin_t))
    # The physical limit only binds on the side the body leans to (C_f sin th > 0).
    hi = np.where(sin_t > 0, lim, limits.C_f_max)
    lo = np.where(sin_t < 0, -lim, -limits.C_f_max)
    cf = np.clip(C_f, lo, hi)
    if anchor is not None and np.isfinite(limits.dC_f_max):
        step = limits.dC_f_max * tau
        cf = np.clip(cf, anchor - step, anchor + step)
    return cf


def foot_speed(body: BodyParams, theta_v, C_f, sin_t=None):
    """Eq. (21): ``V_f = V_cm / (1 - C_f l sin theta_v)``, m/s."""
    s = np.sin(theta_v) if sin_t is None else sin_t
    return body.V_cm / (1.0 - C_f * body.l * s)


def leg_force(body: BodyParams, theta_v, omega_v, alpha_v, C_f):
    """Appendix A, Eqs. (14)-(18): the ground force on the foot, N.

    Returns ``(F_leg, F_along)``: the magnitude and its component along the leg (what the knees
    feel).  ``F_along = m (g cos th + V_cm V_f C_f sin th - l omega_v^2)``; the component across the
    leg is ``I_v alpha_v / l`` (the torque about the centre of mass, Eq. 13).
    """
    s, c = np.sin(theta_v), np.cos(theta_v)
    V_f = foot_speed(body, theta_v, C_f, s)
    along = body.m * (body.g * c + body.V_cm * V_f * C_f * s - body.l * np.asarray(omega_v) ** 2)
    across = body.I_v * np.asarray(alpha_v) / body.l
    return np.hypot(along, across), along


def derivatives(body: BodyParams, state, C_f, sin_t, cos_t, out=None):
    """Time derivative of ``state`` under curvature ``C_f``; also returns ``alpha_v`` and ``V_f``."""
    V_f = body.V_cm / (1.0 - C_f * body.l * sin_t)
    alpha = forward_alpha(body, None, C_f, sin_t, cos_t)
    d = np.empty_like(state) if out is None else out
    th_dir = state[THETA_DIR]
    d[X] = V_f * np.cos(th_dir)
    d[Y] = V_f * np.sin(th_dir)
    d[THETA_DIR] = V_f * C_f
    d[THETA_V] = state[OMEGA_V]
    d[OMEGA_V] = alpha
    return d, alpha, V_f


def rk4_step(body: BodyParams, limits: Limits, state, t, dt, desired_cf, anchor, k1=None):
    """One classical Runge-Kutta step of the pendulum under a steering law.

    ``desired_cf(t, state)`` returns the demanded curvature; at every stage it is bounded by
    :func:`bound_cf` relative to ``anchor``, the curvature at the start of the step (so ``C_f`` is
    continuous and its rate bounded), and ``alpha_v`` is recomputed from the bounded value.
    ``k1`` is the derivative at the start, when the caller has it already.  Returns the state
    after ``dt``.
    """
    def stage(tt, s, tau):
        sin_t, cos_t = np.sin(s[THETA_V]), np.cos(s[THETA_V])
        cf = bound_cf(body, limits, desired_cf(tt, s), sin_t, anchor, tau)
        return derivatives(body, s, cf, sin_t, cos_t)[0]

    h = 0.5 * dt
    if k1 is None:
        k1 = stage(t, state, 0.0)
    k2 = stage(t + h, state + h * k1, h)
    k3 = stage(t + h, state + h * k2, h)
    k4 = stage(t + dt, state + dt * k3, dt)
    return state + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
