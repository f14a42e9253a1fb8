"""The turning pendulum on terrain, with speed as a state (docs/TERRAIN.md).

The paper's model (Section 3, Eqs. 1, 2, 21) on a surface ``z = h(x, y)`` (:mod:`.terrain`):
the state grows from ``(x, y, theta_dir, theta_v, omega_v)`` to
``(x, y, theta_dir, theta_v, omega_v, V_cm)`` (rows named by :data:`TERRAIN_STATE`).  ``x, y``
stay the foot's horizontal position and ``theta_dir`` its horizontal heading; ``theta_v`` is the
lean from the surface normal in the plane across the travel direction; ``C_f`` is the foot
path's curvature in the surface (its geodesic curvature).  In the foot's frame (tangent ``t``,
left ``b``, normal ``n``; docs/TERRAIN.md Section 2):

- Eq. (21) unchanged: ``V_f = V_cm / (1 - C_f l sin theta_v)``;
- Eq. (2) with the effective gravity of the surface frame:
  ``J alpha_v = G_n sin theta_v + (g_b - a_lat) cos theta_v`` with ``G_n = g_n + V_f^2 kappa_n``
  (gravity into the surface plus the foot's normal acceleration over a curved surface),
  ``g_b`` gravity to the left and ``a_lat = V_cm V_f C_f`` the centre of mass's centripetal
  acceleration (the paper's ``k``); flat ground gives ``G_n = g``, ``g_b = 0``: Eq. (2);
- Eq. (1) inverted the same way (its closed form with ``g sin th`` replaced by
  ``G_n sin th + g_b cos th``; ``kappa_n`` is taken at ``V_f = V_cm`` there, and the forward law
  recomputes ``alpha_v`` from the bounded ``C_f`` exactly, as Section 3 does for every bound);
- speed: ``dV_cm/dt = g_t - mu N / m - rho C_d A V_cm^2 / (2 m)`` with ``N`` the normal
  contact force ``m (G_n - l (alpha_v sin theta_v + omega_v^2 cos theta_v))``;
- the foot moves along ``t`` at ``V_f``; its horizontal heading turns at
  ``V_f (C_f turn_gain + kappa_n bend_gain)`` (the Darboux frame's ``dt/ds = C_f b + kappa_n n``
  seen from above).

Flat ground without friction or drag reduces to :func:`.dynamics.steer` (to round-off).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .dynamics import bound_cf
from .params import BodyParams, Limits
from .registry import SPORTS
from .validate import check
from .xp import Numpy, Scalar, backend
from .terrain import surface_frame

__all__ = ["TERRAIN_STATE", "V_CM", "Resistance", "RESISTANCE", "plumb_lean", "plumb_lean_along",
           "terrain_steer",
           "terrain_inverse_cf", "terrain_leg_force", "terrain_rk4_step"]

TERRAIN_STATE = ("x", "y", "theta_dir", "theta_v", "omega_v", "V_cm")
V_CM = 5


@dataclass(frozen=True)
class Resistance:
    """What slows the figure down: snow or rolling friction and air drag."""

    mu: float = 0.0
    """Coefficient of kinetic friction on snow, or of rolling resistance, dimensionless."""
    CdA: float = 0.0
    """Drag area ``C_d A``, m^2."""
    rho: float = 1.225
    """Air density, kg/m^3 (1.225: the ISA standard atmosphere at sea level)."""

    def __post_init__(self):
        check("mu", self.mu, "friction")                     # ranges: core/ranges.py
        check("CdA", self.CdA, "drag_area")
        check("rho", self.rho, "air_density")

    def drag_k(self, m: float) -> float:
        """``rho C_d A / (2 m)``, 1/m: the drag deceleration over ``V^2``."""
        return self.rho * self.CdA / (2.0 * m)


#: Each sport's friction and drag, ``name -> Resistance``: a live view of the sport registry
#: (:mod:`.sports`; each sport's record holds its values, with their sources).
RESISTANCE = SPORTS.view("resistance")


def plumb_lean(frame):
    """The equilibrium lean of a straight run (docs/TERRAIN.md Section 2): ``theta_v`` where
    ``g_n sin th + g_b cos th = 0``, i.e. ``-atan(g_b / g_n)``, the plumb line seen from the
    surface normal (0 on flat ground, leaning uphill on a traverse)."""
    if type(frame.g_lateral) is float:
        return math.atan2(-frame.g_lateral, frame.g_normal)
    return np.arctan2(-frame.g_lateral, frame.g_normal)


def plumb_lean_along(frame, heading, g: float):
    """:func:`plumb_lean` for a foot at the frame's point heading ``heading`` (horizontal, rad)
    instead of the frame's own heading: from the normal, ``g_b = -g b_z`` with
    ``b_z = n_x t_y - n_y t_x`` and ``t`` the heading lifted onto the surface."""
    xp = Scalar if type(frame.g_normal) is float and type(heading) is float else Numpy
    n = frame.n.tolist() if xp is Scalar else frame.n
    c, s = xp.cos(heading), xp.sin(heading)
    p = -(n[0] * c + n[1] * s) / n[2]                       # slope along the heading
    g_b = -g * (n[0] * s - n[1] * c) / (1.0 + p * p) ** 0.5
    return xp.atan2(-g_b, frame.g_normal)


def terrain_inverse_cf(body: BodyParams, frame, theta_v, alpha_v, V):
    """Eq. (1) on terrain: the ``C_f`` that gives ``alpha_v`` (closed form, physical root).

    ``J alpha = G_n sin th + g_b cos th - V V_f C_f cos th``, with ``V V_f = V^2 / (1 - C_f l
    sin th)``, factors like Eq. (1): ``C_f = K / (K l sin th + V^2 cos th)``,
    ``K = G_n sin th + g_b cos th - J alpha``.  Off the physical branch: ``sign(K) inf``.
    """
    xp = backend(theta_v, alpha_v, V, frame.g_lateral)
    s, c = xp.sin(theta_v), xp.cos(theta_v)
    G_n = frame.g_normal + V * V * frame.kappa_n
    k = G_n * s + frame.g_lateral * c - alpha_v * body.J
    den = k * body.l * s + V * V * c
    ok = den > 0.0
    return xp.where(ok, k / xp.where(ok, den, 1.0), xp.copysign(math.inf, k))


def terrain_steer(body: BodyParams, limits: Limits, resistance: Resistance, ground, C_f,
                  state, anchor=None, tau=0.0):
    """The right-hand side on terrain under a demanded curvature (bounded as in Section 3).

    ``state`` is ``(x, y, theta_dir, theta_v, omega_v, V_cm)`` (floats or arrays).  Returns
    ``(derivatives, C_f, alpha_v, V_f, N, frame)`` with ``N`` the normal contact force, N.
    """
    x, y, d, th, om, V = state
    fr = surface_frame(ground, x, y, d, body.g)
    xp = Scalar if type(th) is float and type(C_f) is float else Numpy
    s, c = xp.sin(th), xp.cos(th)
    cf = bound_cf(body, limits, C_f, s, anchor, tau, xp)
    ratio = 1.0 / (1.0 - cf * body.l * s)                      # Eq. (21): V_f / V_cm
    V_f = V * ratio
    G_n = fr.g_normal + V_f * V_f * fr.kappa_n
    alpha = (G_n * s + (fr.g_lateral - V * V_f * cf) * c) / body.J     # Eq. (2) on terrain
    N = body.m * (G_n - body.l * (alpha * s + om * om * c))
    dV = fr.g_along - resistance.mu * N / body.m - resistance.drag_k(body.m) * V * V
    turn = V_f * (cf * fr.turn_gain + fr.kappa_n * fr.bend_gain)
    tx, ty = (fr.t[0], fr.t[1]) if xp is Numpy else fr.t[:2].tolist()
    deriv = (V_f * tx, V_f * ty, turn, om, alpha, dV)
    return deriv, cf, alpha, V_f, N, fr


def terrain_leg_force(body: BodyParams, theta_v, omega_v, alpha_v, C_f, V, V_f, frame):
    """Appendix A's leg force on terrain: ``(F_leg, F_along)``, N.

    The ground reaction ``m (a_cm - g)`` in the leg's frame: along the leg
    ``m (G_n cos th + (a_lat - g_b) sin th - l omega_v^2)``, across it ``I_v alpha_v / l``
    (Eq. 13); flat ground gives :func:`.dynamics.leg_force`.
    """
    s, c = np.sin(theta_v), np.cos(theta_v)
    G_n = frame.g_normal + V_f * V_f * frame.kappa_n
    along = body.m * (G_n * c + (V * V_f * C_f - frame.g_lateral) * s
                      - body.l * omega_v * omega_v)
    return np.hypot(along, body.I_v * alpha_v / body.l), along


def terrain_rk4_step(body, limits, resistance, ground, state, t, dt, desired_cf, anchor):
    """One classical RK4 step of the terrain state under the steering law
    ``desired_cf(t, state)``, ``C_f`` bounded at every stage relative to ``anchor`` (the
    curvature at the start of the step), as :func:`.dynamics.rk4_step` does on flat ground."""
    state = np.asarray(state, dtype=float)

    one = state.ndim == 1                  # one figure: stepped on Python floats

    def f(tt, st, tau):
        st = st.tolist() if one else st
        cf = desired_cf(tt, st)
        return np.asarray(terrain_steer(body, limits, resistance, ground,
                                        float(cf) if one else cf, st, anchor, tau)[0])

    h = 0.5 * dt
    k1 = f(t, state, 0.0)
    k2 = f(t + h, state + h * k1, h)
    k3 = f(t + h, state + h * k2, h)
    k4 = f(t + dt, state + dt * k3, dt)
    return state + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
