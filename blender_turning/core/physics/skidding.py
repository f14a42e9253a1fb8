"""Speed control by skidding, stops, wedges and side-slips (docs/skidding.md Sections 3-5).

:class:`Skidding` is the setting (a style, the grip, a stop), :class:`_Skid` the rule at run
time: once per step :meth:`_Skid.update` sets the braking command at the foot
(:class:`.grip.FootBrake`, bounded by the friction circle at every RK4 stage,
:func:`.model.rhs`) and, for a stop, the heading and the lean the controller follows.

**Turn first, skid for what remains.**  The turning rule (:mod:`.braking`) holds the speed by
turning across the hill; the skid only brakes what turning cannot:
``F_brake / m = (e - e_0) / tau + I`` when positive, ``e = V - V_target``, ``e_0`` a dead band,
``dI/dt = e / (tau T)`` (``I >= 0``).  On a gentle slope turning holds the mean speed, ``e``
averages to 0 and ``I`` drains; on a steep one the corridor bounds how far the figure turns
across the hill, ``e`` stays positive and ``I`` grows until the skid holds the rest
(docs/skidding.md Section 3 measures the shares).

**Styles.**  ``carve``: no skid (the paper's model).  ``skid``: skidded turns, the skid angle at
most :data:`.grip.SKID_MAX_TURNING`.  ``wedge`` (snowplough): both skis edged inward at
``+-skid`` from the travel; their lateral forces cancel and their braking adds, so the brake is
bounded by ``mu_grip N sin(WEDGE_MAX)`` whatever the turn; a beginner's wedge is its brake, so
it holds the speed where the slope steepens (the brake that holds it, plus the error over
``tau``, no dead band); ``skid`` records the wedge's
half-angle ``asin(F_brake / (mu_grip N))``.  ``slip`` (the snowboarder's side-slip): the board
across the fall line, sliding down it under the brake, turns small.

**A stop** at ``stop_at``: the ski goes across the travel (skid up to 90 deg) edged at
:data:`STOP_EDGE`, the braking force the whole circle, the course held and the turns dying out;
below :data:`.terrain_sim.MIN_SPEED` the figure stands still across the fall line
(:func:`stand_rows`).  A tyre brakes within its circle without a skid angle.
"""
from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from .grip import SKID_MAX_STOP, SKID_MAX_TURNING, SNOW, FootBrake, Grip, skid_angle
from ..controllers.schedule import Schedule
from ..ground.terrain import surface_frame
from ..validate import check

__all__ = ["Skidding", "STYLES", "STOP_SIDES", "STOP_EDGE", "WEDGE_MAX", "turning_share",
           "lean_within_grip", "skid_meta", "stand_rows"]

STYLES = ("carve", "skid", "wedge", "slip")
STOP_SIDES = ("heel", "toe")
STOP_EDGE = math.radians(35.0)
"""The edge angle of a hockey stop, rad (the skier leans back against the skid)."""
WEDGE_MAX = math.radians(25.0)
"""The widest wedge, half-angle, rad (a snowplough's skis 30-50 deg apart)."""
WEDGE_EDGE = math.radians(15.0)
"""The wedge's inward edge angle, rad."""
SLIP_LEAN = math.radians(6.0)
"""The largest lean of a side-slip's small turns (the falling leaf), rad."""
STOP_LEAN = math.radians(3.0)
"""What the turns' lean dies out to in a stop, rad."""


@dataclass(frozen=True)
class Skidding:
    """How the figure brakes (module docstring)."""

    style: str = "skid"
    """``carve``, ``skid``, ``wedge`` or ``slip``."""
    grip: Grip = SNOW["hard"]
    """The friction circle at the foot (:mod:`.grip`)."""
    stop_at: float | None = None
    """When a stop begins, s (``None``: no stop)."""
    stop_side: str | None = None
    """The board's edge in a stop or a side-slip: ``heel`` (the rider faces downhill, the
    board's nose turned left of the travel for a regular rider) or ``toe``; ``None``: the side
    the turn under way gives (a slip: ``heel``)."""
    corridor: float = 25.0
    """The half-width of the piste about the course line through the start, m: the turning
    rule's corridor (:class:`.braking.TargetSpeed`) when the target speed is a number."""
    tau: float = 1.0
    """The skid's time constant, s."""
    dead_band: float = 0.5
    """The speed error turning alone is left to, m/s."""
    reset_time: float = 20.0
    """The skid's integral time, s (twice the turning rule's: turning acts first)."""

    def brakes(self, target) -> bool:
        """Whether the foot ever brakes with the target speed ``target`` (``None``: none): a
        stop, or a style other than ``carve`` with a target; otherwise the carved model."""
        return self.stop_at is not None or (self.style != "carve" and target is not None)

    def __post_init__(self):
        if self.style not in STYLES:
            raise ValueError(f"style = {self.style!r} is not one of {', '.join(STYLES)}")
        if self.stop_side not in (None,) + STOP_SIDES:
            raise ValueError(f"stop_side = {self.stop_side!r} is not one of "
                             f"{', '.join(STOP_SIDES)}")
        if self.stop_at is not None:
            check("stop_at", self.stop_at, "stop_at")
        if not isinstance(self.grip, Grip):
            raise ValueError(f"grip = {self.grip!r} is not a core.physics.grip.Grip")


class _Skid:
    """:class:`Skidding` at run time for one figure (module docstring)."""

    def __init__(self, rule: Skidding, controller, figure, target):
        self.rule, self.ctl, self.target = rule, controller, target
        """The target speed at a time (m/s) or ``None``: brake only to stop."""
        self.stage = None
        """The :class:`.terrain_one_figure.TerrainStage` whose ``brake`` this sets."""
        self.g = figure.body.g
        self.integral, self.t = 0.0, None
        self.stopping = False
        self.side = {"heel": 1.0, "toe": -1.0, None: 0.0}[rule.stop_side]
        if rule.style == "slip" and self.side == 0.0:
            self.side = 1.0                      # a side-slip on the heel edge unless told
        tyre = rule.grip.kind == "tyre"
        self.skid_max = SKID_MAX_STOP if tyre or rule.style in ("wedge", "slip") else \
            SKID_MAX_TURNING
        self.edge = WEDGE_EDGE if rule.style == "wedge" else 0.0
        self.theta_max = getattr(controller, "theta_max", None)
        self.heading = getattr(controller, "heading", None)
        # The lean the controller follows (one schedule, set before the run, that reads
        # self.lean): a slip's small turns, a stop's turns dying out.
        tm = self.theta_max
        self.lean = (lambda t: min(float(tm(t)), SLIP_LEAN)) if rule.style == "slip" else tm
        if tm is not None and (rule.style == "slip" or rule.stop_at is not None):
            controller.theta_max = Schedule(lambda t: self.lean(t))

    def restore(self) -> None:
        """Give the controller back its own lean schedule and heading."""
        if self.theta_max is not None:
            self.ctl.theta_max, self.ctl.heading = self.theta_max, self.heading

    def update(self, t: float, state, foot) -> None:
        """Set the step's braking command from the last step's ``foot``
        (:attr:`.terrain_one_figure.TerrainStage.foot`: the foot's lateral force over the mass,
        for the side of a stop; the normal force and the brake that would hold the speed, for
        a wedge)."""
        F_lat, N_m, hold = foot[1], foot[2], foot[3]
        r = self.rule
        V = float(state[5])
        dt = 0.0 if self.t is None else t - self.t
        self.t = t
        if r.stop_at is not None and t >= r.stop_at:
            if not self.stopping:
                self.stopping = True
                if self.side == 0.0:
                    self.side = 1.0 if F_lat >= 0.0 else -1.0
                if self.theta_max is not None:
                    t0, tm = t, self.lean
                    self.lean = lambda tt: max(STOP_LEAN, float(tm(tt)) * math.exp(-(tt - t0)))
                    self.ctl.heading = None      # no directional control: the turns die out
            self.stage.brake = FootBrake(math.inf, r.grip, SKID_MAX_STOP,
                                         0.0 if r.grip.kind == "tyre" else STOP_EDGE)
            return
        if self.target is None:
            self.stage.brake = FootBrake(0.0, r.grip, self.skid_max, self.edge)
            return
        e = V - self.target(t)
        self.integral = max(0.0, self.integral + e * dt / (r.tau * r.reset_time))
        if r.style == "wedge":
            # A beginner's wedge is its brake: it holds the speed wherever the slope steepens
            # (``hold``), and the error decays in ``tau``; at most the widest wedge.
            b = max(0.0, hold + e / r.tau + self.integral)
            b = min(b, r.grip.mu_at(self.edge) * (N_m if N_m > 0.0 else self.g)
                    * math.sin(WEDGE_MAX))
        else:
            b = max(0.0, (e - r.dead_band) / r.tau + self.integral)
        self.stage.brake = FootBrake(b, r.grip, self.skid_max, self.edge)

    def skid(self, brake: float, F_lat: float, N_m: float, theta_v: float) -> float:
        """The recorded skid angle of a sample (docs/skidding.md Section 2), rad."""
        if self.rule.grip.kind == "tyre":
            return 0.0
        if self.rule.style == "wedge" and not self.stopping:
            mu = self.rule.grip.mu_at(max(abs(theta_v), self.edge))
            return math.asin(min(brake / (mu * N_m), 1.0)) if N_m > 0.0 else 0.0
        if self.stopping or self.rule.style == "slip":
            return self.side * math.atan2(brake, max(self.side * F_lat, 0.0))
        return float(skid_angle(brake, F_lat, 1.0))


def turning_share(traj, ground, g: float) -> float:
    """The share of the braking done by turning across the hill (docs/skidding.md Section 3):
    ``W_turn / (W_turn + W_skid)``, ``W_turn = integral (g sin sigma - g_t) V_f dt`` the work
    gravity would have done straight down the fall line and did not, ``W_skid = integral
    F_brake / m V_f dt`` the skid's (per unit mass)."""
    fr = surface_frame(ground, traj.x, traj.y, traj.theta_dir, g)
    sin_s = np.sqrt(np.maximum(1.0 - np.asarray(fr.n[2]) ** 2, 0.0))
    dt = np.diff(traj.t)
    w_turn = np.sum(((g * sin_s - fr.g_along) * traj.V_f)[:-1] * dt)
    w_skid = np.sum((traj.brake * traj.V_f)[:-1] * dt)
    return float(w_turn / (w_turn + w_skid)) if w_turn + w_skid > 0.0 else 1.0


def skid_meta(rule: Skidding) -> dict:
    """The ``meta`` entries that record a :class:`Skidding`."""
    out = {"style": rule.style, "grip": rule.grip.kind, "grip.mu": rule.grip.mu,
           "grip.name": rule.grip.name}
    if rule.stop_at is not None:
        out["stop_at"] = float(rule.stop_at)
        out["stop_side"] = rule.stop_side or ""
    return out


def stand_rows(rows: list, n: int, ground, g: float, grip: Grip) -> list:
    """``rows`` (the terrain loop's, :func:`.terrain_sim._loop`) completed to ``n`` rows by a
    figure standing still where its stop ended: at rest (``V_cm = V_f = 0``), plumb, a ski or
    board across the fall line (the one of the two directions nearer its heading at rest; a
    tyre, or flat ground, keeps its heading); the ground holds it (static friction, ``brake``
    0)."""
    x, y, d, _, _, _, _, _, _, w, tm, _, _, skid = rows[-1]
    hx, hy = (float(v) for v in ground.derivatives(x, y)[1:3])
    if grip.kind == "tyre" or math.hypot(hx, hy) < 1e-9:
        skid = 0.0 if grip.kind == "tyre" else skid
    else:
        fall, ski = math.atan2(-hy, -hx), d + skid
        across = min((fall + 0.5 * math.pi, fall - 0.5 * math.pi),
                     key=lambda a: abs(_wrap(a - ski)))
        skid = _wrap(across - d)
    fr = surface_frame(ground, x, y, d, g)
    plumb = math.atan2(-float(fr.g_lateral), float(fr.g_normal))
    still = (x, y, d, plumb, 0.0, 0.0, 0.0, 0.0, 0.0, w, tm, 0.0, 0.0, skid)
    return rows + [still] * (n - len(rows))


def _wrap(a: float) -> float:
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@contextmanager
def lean_within_grip(controller, grip):
    """While in the block, a tyre's figure leans no further than its grip holds
    (docs/skidding.md Section 5): a steady turn needs ``F_lat / N = tan theta_v`` from the
    road, so the controller's ``theta_max`` is held to ``atan(mu)``.  Yields a list that holds
    the report (one line) once a lean asked was limited; snow (a ski skids instead) and
    controllers without a ``theta_max`` pass unchanged."""
    report = []
    tm = getattr(controller, "theta_max", None)
    if grip is None or grip.kind != "tyre" or tm is None:
        yield report
        return
    cap = math.atan(grip.mu)

    def held(t):
        v = float(tm(t))
        if v > cap and not report:
            report.append(f"the lean asked ({math.degrees(v):.1f} deg at t = {t:g} s) is more "
                          f"than the tyre's grip holds (mu {grip.mu:g}): limited to "
                          f"{math.degrees(cap):.1f} deg")
        return min(v, cap)

    const = tm.constant_value
    controller.theta_max = Schedule.constant(min(const, cap)) if const is not None else \
        Schedule(held)
    if const is not None:
        held(0.0)
    try:
        yield report
    finally:
        controller.theta_max = tm
