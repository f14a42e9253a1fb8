"""Speed control by turning on terrain (docs/TERRAIN.md Section 6): skiers brake by
turning across the hill.  :class:`TargetSpeed` is the setting, :class:`_Braking` the rule at run
time: the heading schedule :func:`.terrain_sim.simulate_free` gives the phase-ellipse
controller (``brake.update(t, state)`` once per step, ``brake(t)`` the commanded heading).

The rule, from the speed equation (docs/TERRAIN.md Section 3)
``dV/dt = g_t - mu N / m - k V^2``:

1. *How much gravity along the track the speed can take.*  With ``N / m ~ g_n`` (the turn's own
   load is left to the integral term), the along-track gravity that makes the speed error decay
   with the time constant ``tau`` is ``g_t* = mu g_n + k V^2 - (e + I) / tau``,
   ``e = V - V_target``, ``dI/dt = e / reset_time`` (integrated only while the angle below is
   not held at a bound: anti-windup).
2. *Which heading gives it.*  On the local plane (the ground's gradient at the foot, low-passed
   over ``slope_time``: slope ``sigma``, fall line ``D``) a horizontal heading at ``delta``
   from the fall line has ``g_t = g tan(sigma) cos(delta) / sqrt(1 + tan^2(sigma) cos^2(delta))``
   (docs/TERRAIN.md Section 1), so ``cos(delta*) = q / (sqrt(1 - q^2) tan(sigma))`` with
   ``q = g_t* / g``, held in ``[0, max_angle]``.  The heading is ``D + side delta*`` (or the
   course itself when the course is already that far from the fall line).
3. *What the body can follow.*  The commanded heading moves toward it no faster than
   ``turn_share`` of the fastest mean-heading rate directional control has at the current speed
   (:meth:`.controllers.ellipse.PhaseEllipse.mean_heading_rate`), and never leads the figure's
   own mean heading (low-passed over half a turn) by more than ``reach`` toward the goal: a
   change of side swings the command through the fall line at a rate the figure can follow, and
   the lean, taken about the plumb lean of the commanded heading, stays near its ellipse.
4. *Where.*  The side flips when the swing back to the course would carry the figure past the
   corridor's edge (``corridor`` metres to that side of the course line through its start) or
   the terrain's (a height field's extent).  The swing's lateral distance is
   ``V T |sin o_f| + V (1 - cos o_s) / r + 1 / C_f_max``: ``o_f`` the figure's heading offset
   from the course, ``o_s`` the larger of it and the command's, ``T`` one turn period (the
   figure lags the command by up to a period: directional control acts at the lean's zero
   crossings and the half-turn under way turns the wrong way), ``r`` the rate of item 3, and one
   tightest turn radius to spare.
5. *Round turns.*  When the turns swing 45 deg or more each side and their own track more than
   half the corridor (:func:`round_turns`: speed control's turns, docs/skidding.md Section 3)
   no zig-zag fits:
   the command keeps the turns' mean line on the course line, ``-atan(lateral / (V T))``
   from the course, and the turns and the skid brake.

Measured over a grid of sports, slopes and targets, and the limits of braking by carving:
docs/TERRAIN.md Section 6 (``scripts/braking_grid.py``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..validate import check
from .feasible import BRAKE_BETAS, feasible_turns
from .heading_table import heading_table

__all__ = ["TargetSpeed", "RoundTurns", "round_turns"]


@dataclass(frozen=True)
class TargetSpeed:
    """Speed control by turning across the hill (module docstring; docs/TERRAIN.md Section 6)."""

    speed: float
    """The target speed, m/s."""
    tau: float = 3.0
    """Time constant the speed error decays with, s (a turn and a half of 2 s)."""
    reset_time: float = 10.0
    """Integral time of the rule, s (``inf``: no integral term)."""
    max_angle: float = math.radians(90.0)
    """Largest angle between the commanded heading and the local fall line, rad."""
    corridor: float = 100.0
    """Half-width of the corridor about the course line the track keeps within, m."""
    turn_share: float = 1.0
    """Share of the fastest mean-heading rate the command may move at."""
    reach: float = math.radians(60.0)
    """Largest angle between the commanded heading and the figure's mean heading, rad."""
    slope_time: float = 1.0
    """Low-pass time of the ground's gradient the rule reads, s (moguls are not fall lines)."""

    def __post_init__(self):
        check("target_speed", self.speed, "brake_speed")      # ranges: core/ranges.py
        for name in ("tau", "reset_time", "max_angle", "corridor", "turn_share", "reach",
                     "slope_time"):
            check(name, getattr(self, name), f"brake_{name}")


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


ROUND_LEAN = math.radians(45.0)
"""The lean of the round turns, rad: a recreational skier's carved turn (radius
``V^2 / (g tan 40 deg)``: 12 m at 10 m/s), leaving the hard-pack circle ``sqrt(1 - tan^2)`` =
0.64 of the load to skid with at the turn's apex (docs/skidding.md Section 1)."""
ROUND_SWING = 1.0
"""The most the speed swings through one of the round turns, m/s (+-10% of 10 m/s)."""
LATERAL_SHARE = 0.7
"""The share of the corridor the round turns' own lateral swing may take."""


def _bessel(n: int, a: float) -> float:
    """``J_n(a)``, the Bessel function of the first kind, by its power series (to round-off for
    ``|a| <= pi``: the terms fall as ``(a/2)^2k / (k! (k+n)!)``)."""
    h = 0.5 * a
    term = h ** n / math.factorial(n)
    total = term
    for k in range(1, 24):
        term *= -h * h / (k * (k + n))
        total += term
    return total


@dataclass(frozen=True)
class RoundTurns:
    """The turns :func:`round_turns` chooses, and what they do on the slope."""

    omega0: float
    """The ellipse's frequency, rad/s."""
    theta_max: float
    """The lean asked, rad."""
    amplitude: float
    """The heading's swing each side of the fall line, rad."""
    pull: float
    """The mean of ``cos`` (heading from the fall line): the share of gravity's pull down the
    fall line the turns leave."""
    speed_swing: float
    """The speed's swing each side of its mean through a turn, m/s."""
    lateral: float
    """The track's swing each side of its mean line, m."""

    g: float
    """Gravity, m/s^2."""
    slope: float
    """The slope they are for, rad."""
    J: float
    """The figure's ``(I_v + m l^2) / (m l)``, m."""

    def start(self, heading: float, V: float, x: float = 0.0, y: float = 0.0) -> tuple:
        """The state at phase 0 of these turns about ``heading`` (the fall line), at speed
        ``V``: upright, leaning out at the ellipse's rate, the heading at the bottom of its
        swing on the slope at ``V`` (:func:`_turn_on_slope`)."""
        a = _turn_on_slope(self.g, self.J, self.slope, V, self.theta_max, self.omega0)[0]
        return (x, y, heading - a, 0.0, self.omega0 * self.theta_max, V)


def _turn_on_slope(g: float, J: float, slope: float, V: float, lean: float, w: float,
                   periods: int = 5, n: int = 64):
    """The heading of a turn on the ellipse ``theta = lean sin(w t)`` at speed ``V`` about the
    fall line of a plane of ``slope`` (rad), settled.  On flat ground the ellipse turns the
    heading at ``V_f C_f = (g sin theta + w^2 J theta) / (V cos theta)`` (Eq. 21 with Eq. 1,
    :mod:`.heading_table`; ``J = (I_v + m l^2) / (m l)``); on the slope gravity's normal part
    ``g cos(slope)`` holds the lean and its part across the track, ``g sin(slope) sin psi``,
    turns the figure down the fall line:
    ``dpsi/dt = (g_n sin theta + w^2 J theta) / (V cos theta) - g sin(slope) sin(psi) / V``.
    Returns ``(amplitude, mean cos psi, speed swing, lateral swing)`` over the last period
    (classical RK4, ``n`` steps a period; the speed and the track swing from the pull's and
    the heading's oscillation at the mean speed ``V``)."""
    g_n, pull = g * math.cos(slope), g * math.sin(slope)
    h = 2.0 * math.pi / (w * n)
    wj = w * w * J

    def f(t, p):
        th = lean * math.sin(w * t)
        return ((g_n * math.sin(th) + wj * th) / math.cos(th) - pull * math.sin(p)) / V

    t, p = 0.0, 0.0
    psi = []
    for i in range(periods * n):
        k1 = f(t, p)
        k2 = f(t + 0.5 * h, p + 0.5 * h * k1)
        k3 = f(t + 0.5 * h, p + 0.5 * h * k2)
        k4 = f(t + h, p + h * k3)
        p += h * (k1 + 2.0 * k2 + 2.0 * k3 + k4) / 6.0
        t += h
        if i >= (periods - 1) * n:
            psi.append(p)
    psi = np.array(psi)
    psi -= 0.5 * (psi.max() + psi.min())        # about the mean heading (flat: no settling)
    cos = np.cos(psi)
    dv = np.cumsum(pull * (cos - cos.mean())) * h          # the speed's swing
    dx = np.cumsum(V * np.sin(psi)) * h                     # the track's, across the fall line
    return (0.5 * float(np.ptp(psi)), float(cos.mean()), 0.5 * float(np.ptp(dv)),
            0.5 * float(np.ptp(dx)))


def round_turns(figure, slope: float, resistance, speed: float, corridor: float,
                lean: float = ROUND_LEAN, swing: float = ROUND_SWING) -> RoundTurns:
    """The phase-ellipse turn a good skier brakes with at ``speed`` (m/s) on a slope of
    ``slope`` (rad) within ``corridor`` (m each side of the course line): round turns that
    finish across the fall line on a gentle slope, shorter ones as the slope steepens
    (docs/skidding.md Section 3).

    The lean ``lean`` (at most what the ellipse follows with the braking rule's
    ``BRAKE_BETAS``, :mod:`.feasible`); the frequency the slowest (the roundest turn) whose
    settled heading on the slope (:func:`_turn_on_slope`) swings at most 90 deg each side of the
    fall line (the turn finishes across it) with (1) a mean pull down the fall line at least
    the friction and drag at ``speed``: the turns alone do not brake below it; (2) a speed
    swing of at most ``swing``; (3) a lateral swing of at most :data:`LATERAL_SHARE` of the
    corridor (the braking rule keeps the mean line in the rest); (4) a period of at most 20 s.
    On flat ground, or when nothing needs braking, the quickest turn of the scan (2 s)."""
    g = figure.body.g
    feasible = feasible_turns(replace(figure.body, V_cm=speed), figure.limits)
    drag = resistance.mu * g * math.cos(slope) + resistance.drag_k(figure.body.m) * speed ** 2
    best = None
    for w in np.geomspace(math.pi, 2.0 * math.pi / 20.0, 40):     # 2 s to 20 s, slower on
        w = float(w)
        th = min(lean, feasible.steerable_lean(w, BRAKE_BETAS))
        a, pull, dv, dx = _turn_on_slope(g, figure.body.J, slope, speed, th, w)
        if best is not None and (a > 0.5 * math.pi or g * math.sin(slope) * pull < drag
                                 or dv > swing or dx > LATERAL_SHARE * corridor):
            break
        best = RoundTurns(w, lean, a, pull, dv, dx, g, slope, figure.body.J)
    return best


class _Braking:
    """:class:`TargetSpeed` at run time: the heading schedule it gives the controller."""

    def __init__(self, rule: TargetSpeed, controller, figure, ground, resistance, state0,
                 speed=None):
        self.rule, self.ctl, self.ground = rule, controller, ground
        self.speed = (lambda t: rule.speed) if speed is None else speed
        """The target speed at a time, m/s: the rule's, or a schedule (a keyed target)."""
        self.course = controller.heading
        # Turning across the hill moves the mean heading all the time: the room it steers in.
        controller.steer_betas = BRAKE_BETAS
        self.g, self.k = figure.body.g, resistance.drag_k(figure.body.m)
        self.mu, self.radius = resistance.mu, 1.0 / figure.limits.C_f_max
        self.x0, self.y0 = float(state0[0]), float(state0[1])
        self.extent = getattr(ground, "extent", None)
        self.period = lambda t: 2.0 * math.pi / float(controller.omega0(t))
        self.side, self.offset, self.integral, self.t = 1.0, 0.0, 0.0, None
        self.grad = None
        self.mean_off = _wrap(float(state0[2]) - float(self.course(0.0)))
        self.angle = 0.0
        """The angle from the local fall line asked for in the last step, rad."""

    def _gradient(self, x, y, dt):
        one = getattr(self.ground, "derivatives_one", None)
        d = one(x, y) if one is not None else self.ground.derivatives(x, y)
        hx, hy = float(d[1]), float(d[2])
        if self.grad is None or self.rule.slope_time <= 0.0:
            self.grad = (hx, hy)
        else:
            a = min(dt / self.rule.slope_time, 1.0)
            self.grad = (self.grad[0] + a * (hx - self.grad[0]),
                         self.grad[1] + a * (hy - self.grad[1]))
        return self.grad

    def _room(self, x, y, ux, uy):
        """Distance from ``(x, y)`` along ``(ux, uy)`` to the terrain's edge (inf: a plane)."""
        if self.extent is None:
            return math.inf
        x_lo, x_hi, y_lo, y_hi = self.extent
        room = math.inf
        if ux > 1e-12:
            room = min(room, (x_hi - x) / ux)
        elif ux < -1e-12:
            room = min(room, (x_lo - x) / ux)
        if uy > 1e-12:
            room = min(room, (y_hi - y) / uy)
        elif uy < -1e-12:
            room = min(room, (y_lo - y) / uy)
        return room

    def _round(self, t: float, V: float, corridor: float) -> bool:
        """Whether the turns are round (:func:`round_turns`): their heading swings at least
        45 deg each side of the mean and their track more than half the corridor, ``2 J1(A) V /
        omega0`` at the target speed ``V``, ``A`` half of Eq. 6's change on flat ground (at
        least the swing on a slope, where gravity turns the figure back down), at most 90 deg.
        A racer's quick turns in a narrow course are not (they zig-zag as before)."""
        change = getattr(self.ctl, "half_turn_change", None)
        if change is None:
            return False
        w, V_t = float(self.ctl.omega0(t)), float(self.speed(t))
        a = 0.5 * float(change(self.ctl.feasible_lean(w, float(self.ctl.theta_max(t))), w))
        a = min(a * V / V_t, 0.5 * math.pi)          # Eq. 6's change goes as 1 / V
        return a >= 0.25 * math.pi and 2.0 * _bessel(1, a) * V_t / w > 0.5 * corridor

    def update(self, t: float, state) -> None:
        r = self.rule
        x, y, V = float(state[0]), float(state[1]), float(state[5])
        dt = 0.0 if self.t is None else t - self.t
        self.t = t
        hx, hy = self._gradient(x, y, dt)
        tan_s = math.hypot(hx, hy)
        g_n = self.g / math.sqrt(1.0 + tan_s * tan_s)
        # 1. The along-track gravity the speed can take (Section 3's speed equation).
        e = V - self.speed(t)
        q = (self.mu * g_n + self.k * V * V - (e + self.integral) / r.tau) / self.g
        # 2. The angle from the fall line that gives it (the local plane).
        if tan_s < 1e-9:
            cos_d = 1.0                               # flat: nothing to gain by turning
        elif q >= 1.0:
            cos_d = -1.0
        elif q <= -1.0:
            cos_d = 1.0
        else:
            cos_d = q / (math.sqrt(1.0 - q * q) * tan_s)
        cos_d = min(max(cos_d, math.cos(r.max_angle)), 1.0)
        held = (tan_s < 1e-9 or (e > 0 and cos_d <= math.cos(r.max_angle))
                or (e < 0 and cos_d >= 1.0))
        if not held:
            self.integral += e * dt / r.reset_time
        self.angle = math.acos(cos_d)
        fall = math.atan2(-hy, -hx) if tan_s > 1e-9 else self.course(t)
        c = self.course(t)
        w = _wrap(c - fall)
        # 4. The side: flip at the corridor's edge or the terrain's, before the swing back needs.
        rate = r.turn_share * self.ctl.mean_heading_rate(t)
        lat_x, lat_y = -math.sin(c), math.cos(c)
        lateral = (x - self.x0) * lat_x + (y - self.y0) * lat_y
        off = _wrap(float(state[2]) - c)                 # the heading the figure has
        swing = max(abs(off), abs(self.offset)) if off * self.offset > 0.0 else abs(self.offset)
        margin = (V * self.period(t) * abs(math.sin(off)) + V * (1.0 - math.cos(swing)) / rate
                  + self.radius)
        s = self.side
        if self._round(t, V, r.corridor):
            # Round turns (round_turns) take most of the corridor: no room for a zig-zag; the
            # turns brake, and the mean line is steered back to the course line over a turn.
            want = -math.atan(lateral / (V * self.period(t)))
        else:
            if self.offset * s > 0.0 and (s * lateral + margin > r.corridor
                                          or self._room(x, y, s * lat_x, s * lat_y) < margin):
                self.side = s = -s
            want = 0.0 if abs(w) >= self.angle else s * self.angle - w
        # 3. Toward it no faster than the body can follow, and within ``reach`` of the mean
        # heading the figure has (low-passed over half a turn).
        step = rate * dt
        self.offset += min(max(want - self.offset, -step), step)
        a = min(dt / (0.5 * self.period(t)), 1.0)
        self.mean_off += a * _wrap(off - self.mean_off)
        lead = _wrap(self.offset - self.mean_off)
        if abs(lead) > r.reach and lead * _wrap(want - self.mean_off) > 0.0:
            # Leading the figure toward the goal by more than the reach: wait for it.  (A figure
            # that has overshot the goal is not followed: the command stays to bring it back.)
            self.offset = self.mean_off + math.copysign(r.reach, lead)

    def __call__(self, t: float) -> float:
        return self.course(t) + self.offset
