"""Equations of motion of the turning pendulum (Section 3, Appendix A).

The state of a figure is ``(x, y, theta_dir, theta_v, omega_v)`` (rows named by ``STATE``): foot
position (m), heading (rad, CCW from +x), lean (rad, > 0 leans left) and lean rate (rad/s).  The
control is the foot curvature ``C_f`` (1/m, > 0 curves left).  Sign conventions:
``docs/ARCHITECTURE.md`` Section 4.  Every function takes Python floats (one figure) or numpy
arrays (a batch, state shape ``(5, n)``); see :mod:`.xp`.
"""
from __future__ import annotations

import math

import numpy as np

from .params import BodyParams, Limits
from .xp import Numpy, Scalar, backend

STATE = ("x", "y", "theta_dir", "theta_v", "omega_v")
X, Y, THETA_DIR, THETA_V, OMEGA_V = range(5)

#: Fraction of the way to the singular curvature ``1/(l sin theta_v)`` that ``C_f`` may go
#: (Eq. 21 divides by ``1 - C_f l sin theta_v``).  Beyond it the foot would have to outrun the body.
PHYSICAL_MARGIN = 0.9
_TINY = 1e-300


def forward_alpha(body: BodyParams, theta_v, C_f, sin_t=None, cos_t=None, V_cm=None):
    """Eq. (2): lean acceleration ``alpha_v`` (rad/s^2) produced by the foot curvature ``C_f``.
    ``V_cm`` overrides ``body.V_cm`` (per sample, for a speed that varies)."""
    xp = backend(theta_v, C_f)
    s = xp.sin(theta_v) if sin_t is None else sin_t
    c = xp.cos(theta_v) if cos_t is None else cos_t
    V = body.V_cm if V_cm is None else V_cm
    k = C_f * V * V * c / (1.0 - C_f * body.l * s)
    return (body.g * s - k) / body.J


def inverse_cf(body: BodyParams, theta_v, alpha_v, sin_t=None, cos_t=None):
    """Eq. (1), the physical ("negative") root in closed form: the ``C_f`` giving ``alpha_v``.

    The quadratic factors as ``[k - (k l sin th + V^2 cos th) C_f](1 - C_f l sin th) = 0`` with
    ``k = g sin th - alpha_v J``; the root ``1/(l sin th)`` is spurious.  Where the physical
    denominator ``k l sin th + V^2 cos th`` is not positive the demand is unreachable on the
    physical branch and the result is ``sign(k) * inf``, for :func:`bound_cf` to clamp.
    """
    xp = backend(theta_v, alpha_v)
    s = xp.sin(theta_v) if sin_t is None else sin_t
    c = xp.cos(theta_v) if cos_t is None else cos_t
    k = body.g * s - alpha_v * body.J
    den = k * body.l * s + body.V_cm ** 2 * c
    ok = den > 0.0
    return xp.where(ok, k / xp.where(ok, den, 1.0), xp.copysign(math.inf, k))


def steering(controller):
    """``f(t, state) -> C_f`` on flat ground (floats or arrays): the controller's lean law
    (:meth:`~.controllers.base.Controller.lean_law`, asked about the lean from upright, flat
    ground's equilibrium lean) turned into ``C_f`` by Eq. (1) with the controller's body
    (:func:`inverse_cf`); ``C_f = 0`` for a controller without a lean law."""
    law = controller.lean_law
    if law is None:
        return lambda t, state: 0.0 * state[THETA_V]
    return lambda t, state: inverse_cf(controller.body, state[THETA_V],
                                       law(t, state[THETA_V], state[OMEGA_V]))


def physical_cf_limit(body: BodyParams, sin_t, xp=None):
    """Largest ``C_f`` toward the lean keeping ``1 - C_f l sin th >= 1 - PHYSICAL_MARGIN``."""
    xp = xp or backend(sin_t)
    return PHYSICAL_MARGIN / xp.maximum(body.l * xp.abs(sin_t), _TINY)


def bound_cf(body: BodyParams, limits: Limits, C_f, sin_t, anchor=None, tau=0.0, xp=None):
    """Section 3: clamp a demanded ``C_f`` to ``|C_f| <= C_f_max``, to the physical branch, and
    (given the curvature ``anchor`` at ``tau`` seconds ago) to ``|dC_f/dt| <= dC_f_max``."""
    xp = xp or backend(C_f, sin_t, anchor)
    cmax = limits.C_f_max
    lim = xp.minimum(cmax, physical_cf_limit(body, sin_t, xp))
    # The physical limit binds only on the side the body leans to (C_f sin th > 0).
    cf = xp.clip(C_f, xp.where(sin_t < 0, -lim, -cmax), xp.where(sin_t > 0, lim, cmax))
    if anchor is not None and limits.dC_f_max != math.inf:
        step = limits.dC_f_max * tau
        cf = xp.clip(cf, anchor - step, anchor + step)
    return cf


def foot_speed(body: BodyParams, theta_v, C_f, sin_t=None, V_cm=None):
    """Eq. (21): ``V_f = V_cm / (1 - C_f l sin theta_v)``, m/s (``V_cm`` overrides
    ``body.V_cm``)."""
    s = backend(theta_v).sin(theta_v) if sin_t is None else sin_t
    return (body.V_cm if V_cm is None else V_cm) / (1.0 - C_f * body.l * s)


def leg_force(body: BodyParams, theta_v, omega_v, alpha_v, C_f, V_cm=None):
    """Appendix A, Eqs. (14)-(18): the ground force on the foot, N.

    Returns ``(F_leg, F_along)``: the magnitude and its component along the leg (what the knees
    feel).  ``F_along = m (g cos th + V_cm V_f C_f sin th - l omega_v^2)``; the component across the
    leg is ``I_v alpha_v / l`` (the torque about the centre of mass, Eq. 13).  ``V_cm`` overrides
    ``body.V_cm`` (per sample, for a speed that varies).
    """
    xp = backend(theta_v, omega_v, alpha_v, C_f)
    s, c = xp.sin(theta_v), xp.cos(theta_v)
    V = body.V_cm if V_cm is None else V_cm
    V_f = V / (1.0 - C_f * body.l * s)                           # Eq. (21)
    along = body.m * (body.g * c + V * V_f * C_f * s - body.l * omega_v * omega_v)
    across = body.I_v * alpha_v / body.l
    return xp.hypot(along, across), along


def steer(body: BodyParams, limits: Limits, C_f, state, anchor, tau, V_cm=None):
    """The right-hand side under a demanded curvature (Fig. 4's loop body).

    ``C_f`` is bounded by :func:`bound_cf` relative to ``anchor`` (the curvature ``tau`` seconds
    earlier) and ``alpha_v`` is recomputed from the bounded value (Section 3).  ``V_cm``
    overrides ``body.V_cm`` (one value per column for a speed that varies, Section 6).
    Returns ``(derivative tuple, C_f, alpha_v, V_f)``.
    """
    th = state[THETA_V]
    xp = Scalar if type(th) is float else Numpy
    V = body.V_cm if V_cm is None else V_cm
    s, c = xp.sin(th), xp.cos(th)
    cf = bound_cf(body, limits, C_f, s, anchor, tau, xp)
    ratio = 1.0 / (1.0 - cf * body.l * s)                       # Eq. (21): V_f / V_cm
    V_f = V * ratio
    alpha = (body.g * s - cf * V * V * c * ratio) / body.J       # Eq. (2)
    d = state[THETA_DIR]
    return (V_f * xp.cos(d), V_f * xp.sin(d), V_f * cf, state[OMEGA_V], alpha), cf, alpha, V_f


def stage(body: BodyParams, limits: Limits, cf_law, t, state, anchor, tau):
    """:func:`steer` under a steering law: ``cf_law(t, state)`` is the demanded curvature."""
    return steer(body, limits, cf_law(t, state), state, anchor, tau)


def rk4_step(body: BodyParams, limits: Limits, state, t, dt, cf_law, anchor, k1=None):
    """One classical Runge-Kutta step of a ``(5, n)`` array (one figure on floats:
    :func:`.one_figure.integrate`, the same step fused).

    ``C_f`` is evaluated and bounded at every stage relative to ``anchor``, the curvature at the
    start of the step, so it is continuous and its rate bounded.  ``k1`` is the start derivative
    when the caller has it.  Returns the new state.
    """
    h = 0.5 * dt
    if k1 is None:
        k1 = stage(body, limits, cf_law, t, state, anchor, 0.0)[0]
    k1 = np.asarray(k1)
    k2 = np.asarray(stage(body, limits, cf_law, t + h, state + h * k1, anchor, h)[0])
    k3 = np.asarray(stage(body, limits, cf_law, t + h, state + h * k2, anchor, h)[0])
    k4 = np.asarray(stage(body, limits, cf_law, t + dt, state + dt * k3, anchor, dt)[0])
    return state + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)


__all__ = ["STATE", "X", "Y", "THETA_DIR", "THETA_V", "OMEGA_V", "PHYSICAL_MARGIN",
           "forward_alpha", "inverse_cf", "physical_cf_limit", "bound_cf", "foot_speed",
           "leg_force", "steer", "stage", "rk4_step"]
