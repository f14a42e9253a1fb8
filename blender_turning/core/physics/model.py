"""The turning model on any ground: one right-hand side (docs/TERRAIN.md, docs/ARCHITECTURE.md
Section 5).

The paper's inverted pendulum (Section 3, Eqs. 1, 2, 21; Appendix A, Eqs. 13-21) on a ground
``z = h(x, y)``: :func:`Flat` (the paper's ground, the zero-slope plane), :class:`.terrain.Plane`
or :class:`.terrain.HeightField`.  The state is ``(x, y, theta_dir, theta_v, omega_v, V_cm)``
(rows named by :data:`STATE`): ``x, y`` the foot's horizontal position, ``theta_dir`` its
horizontal heading, ``theta_v`` the lean from the surface normal in the plane across the travel
direction, ``omega_v`` its rate and ``V_cm`` the body's speed.  ``C_f`` is the foot path's
curvature in the surface (its geodesic curvature).  In the foot's frame (tangent ``t``, left
``b``, normal ``n``; docs/TERRAIN.md Section 1):

- Eq. (21): ``V_f = V_cm / (1 - C_f l sin theta_v)``;
- Eq. (2) with the effective gravity of the surface frame (docs/TERRAIN.md Section 2):
  ``J alpha_v = G_n sin theta_v + (g_b - a_lat) cos theta_v``, ``G_n = g_n + V_f^2 kappa_n``
  (gravity into the surface plus the foot's normal acceleration over a curved surface), ``g_b``
  gravity to the left and ``a_lat = V_cm V_f C_f`` the centre of mass's centripetal acceleration
  (the paper's ``k``); flat ground gives ``G_n = g``, ``g_b = 0``: Eq. (2);
- Eq. (1) inverted the same way (:func:`inverse_cf`);
- the speed (docs/TERRAIN.md Sections 3-4): with ``held`` the paper's implicit forward force holds
  ``V_cm`` (``dV_cm/dt = 0``, Section 3 of the paper); otherwise energy balances:
  ``dV_cm/dt = g_t - (mu N / m) V_f / V_cm - rho C_d A V_cm^2 / (2 m) + l omega_v V_f C_f cos
  theta_v`` (gravity on the body, friction at the foot, drag on the body, and the part of the
  lean's motion the carving foot turns into speed), ``N = m (G_n - l (alpha_v sin theta_v +
  omega_v^2 cos theta_v))`` the normal contact force;
- the foot moves along ``t`` at ``V_f``; its horizontal heading turns at
  ``V_f (C_f turn_gain + kappa_n bend_gain)`` (the Darboux frame's ``dt/ds = C_f b + kappa_n n``
  seen from above; docs/TERRAIN.md Section 1).

:func:`rhs` is the reference: written once, on floats or arrays; :func:`steering` is how a
controller steers on it (its lean law, about :func:`equilibrium_lean`, through Eq. 1).  The fast
paths are kernels behind the two, each tested against them (``tests/test_model_kernels.py``):
:func:`.dynamics.steer` with :func:`.dynamics.steering` (flat ground at a held speed, arrays),
:mod:`.one_figure` (the same on floats), :mod:`.terrain_one_figure` (any ground, floats),
:mod:`.planner.flat_stage` (the planner's fused flat stage).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .dynamics import bound_cf
from .params import BodyParams, Limits
from ..ground.terrain import FLAT, HeightField, LazyHeightField, Plane, surface_frame
from ..registry import SPORT_PRESETS, SPORTS, ChainView
from ..validate import check
from .xp import Numpy, Scalar, backend

__all__ = ["STATE", "V_CM", "Flat", "Plane", "HeightField", "LazyHeightField", "FLAT",
           "Resistance", "RESISTANCE", "NO_RESISTANCE", "speed_held", "plumb_lean",
           "plumb_lean_along", "equilibrium_lean", "steering", "rhs", "inverse_cf", "leg_force",
           "rk4_step"]

STATE = ("x", "y", "theta_dir", "theta_v", "omega_v", "V_cm")
V_CM = 5


def Flat(z0: float = 0.0) -> Plane:
    """The paper's ground: the horizontal plane at height ``z0`` (m), the zero-slope
    :class:`.terrain.Plane` (not a family of its own: every formula of :func:`rhs` holds with
    its zero slope and curvature)."""
    return FLAT if z0 == 0.0 else Plane(0.0, 0.0, z0=z0)


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

    @property
    def free(self) -> bool:
        """True when nothing slows the figure (no friction, no drag)."""
        return self.mu == 0.0 and self.CdA == 0.0

    def drag_k(self, m: float) -> float:
        """``rho C_d A / (2 m)``, 1/m: the drag deceleration over ``V^2``."""
        return self.rho * self.CdA / (2.0 * m)


NO_RESISTANCE = Resistance(mu=0.0, CdA=0.0)

#: Each sport's friction and drag, ``name -> Resistance``: a live view of the sport registry
#: (:mod:`.sports`; each sport's record holds its values, with their sources), then of the
#: sports' own presets (:mod:`.equipment`: their sport's).
RESISTANCE = ChainView(SPORTS.view("resistance"), SPORT_PRESETS.view("resistance"))


def speed_held(ground, resistance: Resistance) -> bool:
    """Whether the speed is held (the paper's constant ``V_cm``, kept by an implicit forward
    force, Section 3): on flat ground with nothing slowing the figure.  Anywhere else the speed
    is a state that balances energy (:func:`rhs`, docs/TERRAIN.md Section 4)."""
    return bool(getattr(ground, "flat", False)) and resistance.free


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


def equilibrium_lean(controller, frame, t):
    """The lean a controller's lean law is asked about, as the lean from it (docs/TERRAIN.md
    Section 6): the plumb lean along the controller's commanded mean heading ``heading(t)``
    when it holds one (it does not swing with each turn's heading, which would force the lean
    at the turn's own frequency; a target speed's command, :mod:`..controllers.braking`, moves
    continuously), else the plumb lean of the current heading (:func:`plumb_lean`); upright
    on flat ground."""
    heading = getattr(controller, "heading", None)
    if heading is None:
        return plumb_lean(frame)
    return plumb_lean_along(frame, heading(t), controller.body.g)


def steering(controller, ground):
    """``f(t, state) -> C_f`` on ``ground`` (``state`` the six rows of :data:`STATE`, one figure
    on floats or a batch on arrays): the controller's lean law
    (:meth:`~.controllers.base.Controller.lean_law`) asked about the lean from
    :func:`equilibrium_lean`, so the lean oscillates about the equilibrium, not about the
    surface normal, and its ``alpha_v`` turned into ``C_f`` by Eq. (1) on the ground at the
    state's speed with the controller's body (:func:`inverse_cf`).  ``C_f = 0`` for a
    controller without a lean law.  The reference the kernels' steering is held to."""
    law = controller.lean_law
    if law is None:
        return lambda t, st: 0.0 * st[3]

    def cf(t, st):
        if np.ndim(st[0]) == 0:                               # one figure: Python floats
            st = [float(v) for v in st]
        fr = surface_frame(ground, st[0], st[1], st[2], controller.body.g)
        rel = st[3] - equilibrium_lean(controller, fr, t)
        return inverse_cf(controller.body, fr, st[3], law(t, rel, st[4]), st[5])

    return cf


def inverse_cf(body: BodyParams, frame, theta_v, alpha_v, V):
    """Eq. (1) on any ground: the ``C_f`` that gives ``alpha_v`` (closed form, physical root).

    ``J alpha = G_n sin th + g_b cos th - V V_f C_f cos th``, with ``V V_f = V^2 / (1 - C_f l
    sin th)``, factors like Eq. (1): ``C_f = K / (K l sin th + V^2 cos th)``,
    ``K = G_n sin th + g_b cos th - J alpha`` (``kappa_n`` taken at ``V_f = V``; docs/TERRAIN.md
    Section 2).  Off the physical branch: ``sign(K) inf``, for :func:`.dynamics.bound_cf`.
    """
    xp = backend(theta_v, alpha_v, V, frame.g_lateral)
    s, c = xp.sin(theta_v), xp.cos(theta_v)
    G_n = frame.g_normal + V * V * frame.kappa_n
    k = G_n * s + frame.g_lateral * c - alpha_v * body.J
    den = k * body.l * s + V * V * c
    ok = den > 0.0
    return xp.where(ok, k / xp.where(ok, den, 1.0), xp.copysign(math.inf, k))


def rhs(body: BodyParams, limits: Limits, ground, C_f, state, anchor=None, tau=0.0,
        resistance: Resistance = NO_RESISTANCE, held: bool = False, brake=None):
    """The model's right-hand side under a demanded curvature (module docstring).

    ``C_f`` is bounded as in Section 3 (:func:`.dynamics.bound_cf`, relative to ``anchor``, the
    curvature ``tau`` seconds earlier) and ``alpha_v`` recomputed from the bounded value.
    ``state`` is ``(x, y, theta_dir, theta_v, omega_v, V_cm)`` (floats or arrays); ``held``
    holds the speed (the paper's constant ``V_cm``).  ``brake`` (a :class:`.grip.FootBrake`)
    adds the snow's (road's) braking force at the foot, bounded by the grip's friction circle
    together with the turn's lateral force (docs/skidding.md Section 2): ``dV_cm/dt`` loses
    ``F_brake / m V_f / V_cm`` (the force works at the foot's speed, as friction does); ``None``
    is the carved model, unchanged.  Returns ``(derivatives, C_f, alpha_v,
    V_f, N, frame)`` with ``N`` the normal contact force, N.
    """
    x, y, d, th, om, V = state
    fr = surface_frame(ground, x, y, d, body.g)
    xp = Scalar if type(th) is float and type(C_f) is float else Numpy
    s, c = xp.sin(th), xp.cos(th)
    cf = bound_cf(body, limits, C_f, s, anchor, tau, xp)
    ratio = 1.0 / (1.0 - cf * body.l * s)                      # Eq. (21): V_f / V_cm
    V_f = V * ratio
    G_n = fr.g_normal + V_f * V_f * fr.kappa_n
    alpha = (G_n * s + (fr.g_lateral - V * V_f * cf) * c) / body.J     # Eq. (2) on the ground
    N = body.m * (G_n - body.l * (alpha * s + om * om * c))
    if held:
        dV = 0.0 * V
    else:                                                      # docs/TERRAIN.md Section 4
        dV = (fr.g_along - resistance.mu * N / body.m * ratio
              - resistance.drag_k(body.m) * V * V + body.l * om * c * V_f * cf)
        if brake is not None:                                  # docs/skidding.md Section 2
            F_lat = V * V_f * cf + body.l * (alpha * c - om * om * s) - fr.g_lateral
            dV = dV - brake.bound(N / body.m, F_lat, th) * ratio       # grip.foot_lateral
    turn = V_f * (cf * fr.turn_gain + fr.kappa_n * fr.bend_gain)
    tx, ty = (fr.t[0], fr.t[1]) if xp is Numpy else fr.t[:2].tolist()
    deriv = (V_f * tx, V_f * ty, turn, om, alpha, dV)
    return deriv, cf, alpha, V_f, N, fr


def leg_force(body: BodyParams, theta_v, omega_v, alpha_v, C_f, V, V_f, frame):
    """Appendix A's leg force on any ground: ``(F_leg, F_along)``, N.

    The ground reaction ``m (a_cm - g)`` in the leg's frame: along the leg
    ``m (G_n cos th + (a_lat - g_b) sin th - l omega_v^2)``, across it ``I_v alpha_v / l``
    (Eq. 13); flat ground gives :func:`.dynamics.leg_force` (Eqs. 14-18).
    """
    s, c = np.sin(theta_v), np.cos(theta_v)
    G_n = frame.g_normal + V_f * V_f * frame.kappa_n
    along = body.m * (G_n * c + (V * V_f * C_f - frame.g_lateral) * s
                      - body.l * omega_v * omega_v)
    return np.hypot(along, body.I_v * alpha_v / body.l), along


def rk4_step(body, limits, ground, state, t, dt, cf_law, anchor,
             resistance: Resistance = NO_RESISTANCE, held: bool = False):
    """One classical RK4 step of the state under the steering law ``cf_law(t, state)``,
    ``C_f`` bounded at every stage relative to ``anchor`` (the curvature at the start of the
    step; docs/ARCHITECTURE.md Section 5, Integration)."""
    state = np.asarray(state, dtype=float)
    one = state.ndim == 1                  # one figure: stepped on Python floats

    def f(tt, st, tau):
        st = st.tolist() if one else st
        cf = cf_law(tt, st)
        return np.asarray(rhs(body, limits, ground, float(cf) if one else cf, st, anchor, tau,
                              resistance, held)[0])

    h = 0.5 * dt
    k1 = f(t, state, 0.0)
    k2 = f(t + h, state + h * k1, h)
    k3 = f(t + h, state + h * k2, h)
    k4 = f(t + dt, state + dt * k3, dt)
    return state + (dt / 6.0) * (k1 + 2.0 * (k2 + k3) + k4)
