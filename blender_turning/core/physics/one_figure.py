"""One figure on Python floats: the loop of Fig. 4 fused for speed.

:func:`.dynamics.steer` and :func:`.dynamics.rk4_step` are written once for numpy arrays (a
batch, the planner).  Stepping one figure through them costs ~1 us of numpy dispatch per
operation, so one figure runs here instead: the controller's lean law turned into ``C_f`` by
Eq. (1), the same Section 3 right-hand side (bounds on ``C_f``, Eq. 21, Eq. 2) and the same
classical RK4 on floats, with the body's constants bound as locals and each sine and cosine of
a stage taken once.  ``tests/test_model_kernels.py`` holds the stage to :func:`.model.rhs` at
round-off level.
"""
from __future__ import annotations

import math
from dataclasses import replace

from .dynamics import PHYSICAL_MARGIN
from .params import BodyParams, Limits


def rhs(body: BodyParams, limits: Limits, law, law_body: BodyParams):
    """``stage(t, x0, x1, x2, x3, x4, anchor, tau) -> (d0, d1, d2, d3, d4, C_f, alpha_v, V_f)``.

    ``law(t, theta_v, omega_v)`` is the demanded lean acceleration (a controller's
    :meth:`~.controllers.base.Controller.lean_law`; ``None``: ``C_f = 0``), turned into ``C_f``
    by Eq. (1) with ``law_body`` (the controller's body; :func:`.dynamics.inverse_cf`: the
    physical root, ``sign(k) inf`` off the physical branch).  ``C_f`` is bounded as in
    :func:`.dynamics.bound_cf` (``|C_f| <= C_f_max``, the physical branch on the side of the
    lean, ``|dC_f/dt| <= dC_f_max`` from ``anchor`` over ``tau``, none when ``anchor`` is
    ``None``) and ``alpha_v`` recomputed from the bounded value (Eq. 2).
    """
    g, l, J, V = body.g, body.l, body.J, body.V_cm
    VV = V * V
    lg, ll, lJ, lVV = law_body.g, law_body.l, law_body.J, law_body.V_cm ** 2
    cmax, rate = limits.C_f_max, limits.dC_f_max
    rated = rate != math.inf
    sin, cos, inf, copysign = math.sin, math.cos, math.inf, math.copysign

    def stage(t, x0, x1, x2, x3, x4, anchor, tau):
        s, c = sin(x3), cos(x3)
        if law is None:
            cf = 0.0
        else:                                                   # Eq. (1), the physical root
            k = lg * s - law(t, x3, x4) * lJ
            den = k * ll * s + lVV * c
            cf = k / den if den > 0.0 else copysign(inf, k)
        ls = l * s
        # Section 3's physical branch binds only on the side the body leans to.
        lo = -cmax if ls >= 0.0 else max(-cmax, PHYSICAL_MARGIN / ls)
        hi = cmax if ls <= 0.0 else min(cmax, PHYSICAL_MARGIN / ls)
        if cf < lo:
            cf = lo
        elif cf > hi:
            cf = hi
        if rated and anchor is not None:
            step = rate * tau
            if cf < anchor - step:
                cf = anchor - step
            elif cf > anchor + step:
                cf = anchor + step
        ratio = 1.0 / (1.0 - cf * ls)                               # Eq. (21): V_f / V_cm
        V_f = V * ratio
        alpha = (g * s - cf * VV * c * ratio) / J                   # Eq. (2)
        return V_f * cos(x2), V_f * sin(x2), V_f * cf, x4, alpha, cf, alpha, V_f

    return stage


def integrate(body: BodyParams, limits: Limits, controller, state, n: int, dt: float, anchor,
              theta_fall: float | None, speed=None):
    """Up to ``n`` samples of RK4 from ``state`` (5 floats); C_f is bounded at every stage
    relative to the curvature at the step's start.  Returns ``(rows, fell_at)`` where each row is
    ``(x, y, theta_dir, theta_v, omega_v, alpha_v, C_f, V_f, omega0, theta_max)``; the run stops
    at the first sample with ``|theta_v| > theta_fall`` (``None``: never).

    ``speed`` (``V_cm`` at each of the ``n`` step starts, m/s) makes the speed vary: it is held
    over each step at its value at the step's start, as the planner's ``SpeedProfile`` does
    (Section 6), and the controller steers with it
    (:meth:`~.controllers.base.Controller.follow_speed`)."""
    controller.begin_run(limits)
    V_now = body.V_cm
    stage = rhs(body, limits, controller.lean_law, controller.body)
    begin, target = controller.begin_step, controller.target
    fall = math.inf if theta_fall is None else theta_fall
    h, w6 = 0.5 * dt, dt / 6.0
    x0, x1, x2, x3, x4 = (float(v) for v in state)
    rows = []
    append = rows.append
    for i in range(n):
        t = i * dt
        if speed is not None and speed[i] != V_now:
            V_now = speed[i]
            controller.follow_speed(V_now)                  # the controller's own body model
            steered = controller.body
            moved = steered if controller.nominal_body is body else replace(body, V_cm=V_now)
            stage = rhs(moved, limits, controller.lean_law, controller.body)
        begin(t, (x0, x1, x2, x3, x4))
        a0, a1, a2, a3, a4, cf, alpha, V_f = stage(t, x0, x1, x2, x3, x4, anchor, dt)
        append((x0, x1, x2, x3, x4, alpha, cf, V_f, *target(t)))
        if abs(x3) > fall:
            return rows, t
        if i + 1 == n:
            break
        b0, b1, b2, b3, b4, _, _, _ = stage(t + h, x0 + h * a0, x1 + h * a1, x2 + h * a2,
                                            x3 + h * a3, x4 + h * a4, cf, h)
        c0, c1, c2, c3, c4, _, _, _ = stage(t + h, x0 + h * b0, x1 + h * b1, x2 + h * b2,
                                            x3 + h * b3, x4 + h * b4, cf, h)
        d0, d1, d2, d3, d4, _, _, _ = stage(t + dt, x0 + dt * c0, x1 + dt * c1, x2 + dt * c2,
                                            x3 + dt * c3, x4 + dt * c4, cf, dt)
        x0 += w6 * (a0 + 2.0 * (b0 + c0) + d0)
        x1 += w6 * (a1 + 2.0 * (b1 + c1) + d1)
        x2 += w6 * (a2 + 2.0 * (b2 + c2) + d2)
        x3 += w6 * (a3 + 2.0 * (b3 + c3) + d3)
        x4 += w6 * (a4 + 2.0 * (b4 + c4) + d4)
        anchor = cf
    return rows, None
