"""Simulation on terrain: the loop of Fig. 4 with the ground and speed as a state.

:func:`simulate_terrain` steps one figure on a surface (:mod:`.terrain`) with friction and drag
(:class:`.terrain_dynamics.Resistance`) by classical RK4 on floats (:mod:`.terrain_one_figure`;
``C_f`` bounded at every stage as on flat ground, as :func:`.terrain_dynamics.terrain_rk4_step`).  Each step the controller is re-targeted
to the current speed (:meth:`~.controllers.base.Controller.follow_speed`), sees the lean from
the local plumb lean (:meth:`~.controllers.base.Controller.relative_state`) and steers by Eq. (1)
on terrain (:meth:`~.controllers.base.Controller.terrain_cf_law`).  :class:`TargetSpeed` brakes
by turning across the hill (docs/TERRAIN.md Section 6).

:func:`.simulate.simulate` sends a run here when it is given a ground that is not flat, friction
or drag, or a target speed; flat ground without them stays on today's path.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .controllers import Controller
from .controllers.feasible import fall_cause
from .errors import FellOver, LeftTerrain, Stopped
from .params import Figure, check_range
from .phase import phase
from .schedule import Schedule
from .terrain import FLAT, HeightField, OffTerrain, Plane, surface_frame
from .terrain_dynamics import Resistance, terrain_leg_force
from .terrain_one_figure import TerrainStage
from .trajectory import Trajectory, body_meta, resistance_meta

__all__ = ["TargetSpeed", "simulate_terrain", "describe_ground", "MIN_SPEED", "NO_RESISTANCE"]

NO_RESISTANCE = Resistance(mu=0.0, CdA=0.0)

MIN_SPEED = 0.5
"""m/s: below it the run stops (:class:`.errors.Stopped`).  The turning model is a body carried
by its speed (Eq. 1 needs ``V^2 cos th`` to balance gravity); near rest it asks for curvatures no
ski or wheel has."""


@dataclass(frozen=True)
class TargetSpeed:
    """Speed control by turning (docs/TERRAIN.md Section 6): skiers brake by turning across the
    hill.  The phase-ellipse controller's heading command (the *course*, e.g. the fall line)
    becomes ``course + side * offset`` with

        offset = max_offset * clip(e + I, 0, 1),   e = (V_cm - speed) / band,
    dI/dt = e / reset_time,  I held in [0, 1] (anti-windup),

    so at or below the target speed the slalom runs along the course, and the faster the figure
    is than the target the further across the hill its turns go (up to ``max_offset``); the
    integral term takes out most of a proportional rule's steady excess.  The side
    flips when the figure has drifted ``corridor`` metres to that side of the course line through
    its start: a run of wide turns zig-zagging down inside a corridor.  Each change of side swings
    the heading through the fall line, where the figure speeds up; on an 18 deg slope the mean
    speed stays ~2 m/s above the target (``tests/test_terrain_sim.py`` measures it; a fall-line
    slalom runs away to its terminal speed, ~27 m/s for the skier)."""

    speed: float
    """The target speed, m/s."""
    band: float = 2.0
    """Speed excess at which the offset is full, m/s."""
    max_offset: float = math.radians(85.0)
    """Largest heading offset from the course, rad."""
    corridor: float = 60.0
    """Half-width of the corridor about the course line, m."""
    reset_time: float = 10.0
    """Integral time of the rule, s (``inf``: proportional only)."""

    def __post_init__(self):
        check_range("target_speed", self.speed, 0.0, 100.0, lo_open=True)
        check_range("band", self.band, 0.0, 100.0, lo_open=True)
        check_range("max_offset", self.max_offset, 0.0, math.pi / 2)
        check_range("corridor", self.corridor, 0.0, 1e5, lo_open=True)
        check_range("reset_time", self.reset_time, 0.0, math.inf, lo_open=True)


class _Braking:
    """:class:`TargetSpeed` at run time: the heading schedule it gives the controller."""

    def __init__(self, rule: TargetSpeed, course: Schedule, x0: float, y0: float):
        self.rule, self.course, self.x0, self.y0 = rule, course, x0, y0
        self.side, self.offset, self.integral, self.t = 1.0, 0.0, 0.0, None

    def update(self, t: float, state) -> None:
        r = self.rule
        e = (float(state[5]) - r.speed) / r.band
        if self.t is not None:                  # anti-windup: the integral stays in [0, 1]
            self.integral = min(max(self.integral + e * (t - self.t) / r.reset_time, 0.0), 1.0)
        self.t = t
        self.offset = r.max_offset * min(max(e + self.integral, 0.0), 1.0)
        c = self.course(t)
        lateral = -(state[0] - self.x0) * math.sin(c) + (state[1] - self.y0) * math.cos(c)
        if self.side * lateral > r.corridor:
            self.side = -self.side

    def __call__(self, t: float) -> float:
        return self.course(t) + self.side * self.offset


def describe_ground(ground) -> str:
    """The ``meta["ground"]`` entry of a trajectory: ``"flat"`` or what the surface was."""
    if isinstance(ground, Plane):
        if ground.flat:
            return "flat"
        return (f"plane (slope {math.degrees(ground.slope):g} deg, downhill "
                f"{math.degrees(ground.downhill):g} deg)")
    if isinstance(ground, HeightField):
        return f"height field ({ground.nx} x {ground.ny}, cell {ground.cell:g} m)"
    return type(ground).__name__


def simulate_terrain(figure: Figure, controller: Controller, duration: float, dt: float,
                     state0=None, ground=FLAT, resistance: Resistance = NO_RESISTANCE,
                     C_f0=None, meta: dict | None = None,
                     target_speed: TargetSpeed | float | None = None) -> Trajectory:
    """Simulate one figure on ``ground`` with ``resistance``; returns a :class:`Trajectory`
    whose ``z`` is the ground under the foot and ``V_cm`` the speed (a state).

    ``state0``: ``(x, y, theta_dir, theta_v, omega_v)`` (starting at ``figure.body.V_cm``) or
    with a sixth entry ``V_cm``.  ``target_speed`` (m/s or a :class:`TargetSpeed`) needs a
    controller with a heading (the course).  Raises :class:`.errors.FellOver` past
    ``limits.theta_fall`` (the lean from the plumb lean: a skier leaning 20 deg uphill from the
    normal of a traverse stands upright) and :class:`.errors.Stopped` below
    :data:`MIN_SPEED` and :class:`.errors.LeftTerrain` at the edge of a height field, each with
    the trajectory so far."""
    body, limits = figure.body, figure.limits
    check_range("duration", duration, 0.0, 1e6, lo_open=True)
    check_range("dt", dt, 1e-5, 1.0)
    if state0 is None:
        w, tm = controller.target(0.0)
        state0 = (0.0, 0.0, 0.0, 0.0, w * tm)
    st = np.array(state0, float).ravel()
    if st.shape not in ((5,), (6,)) or not np.all(np.isfinite(st)):
        raise ValueError("state0 must be 5 or 6 finite numbers (x, y, theta_dir, theta_v, "
                         "omega_v[, V_cm])")
    if st.shape == (5,):
        st = np.append(st, body.V_cm)
    check_range("V_cm (state0)", st[5], MIN_SPEED, 100.0)
    ground.derivatives(st[0], st[1])              # off the terrain: fail before stepping
    brake = None
    if target_speed is not None:
        rule = target_speed if isinstance(target_speed, TargetSpeed) else TargetSpeed(target_speed)
        if getattr(controller, "heading", None) is None:
            raise ValueError("target_speed steers the heading: the controller needs a heading "
                             "(the course, e.g. the fall line)")
        brake = _Braking(rule, controller.heading, float(st[0]), float(st[1]))
    n = int(math.floor(duration / dt + 1e-9)) + 1
    info = {"preset": figure.name, "dt": dt, **body_meta(body), "ground": describe_ground(ground),
            **resistance_meta(resistance), **(meta or {})}
    if brake is not None:
        info["target_speed"] = brake.rule.speed
    course = getattr(controller, "heading", None)
    try:
        if brake is not None:
            # The command jumps across the fall line when the side flips: lean about the
            # plumb lean of the heading the figure has, which swings through it smoothly.
            controller.heading = Schedule.of(brake)
            controller.lean_about_heading = True
        rows, stop = _loop(body, limits, controller, ground, resistance, st, n, dt,
                           C_f0, brake)
    finally:
        if brake is not None:
            controller.heading = course
            controller.lean_about_heading = False
    traj = _trajectory(body, ground, np.array(rows, float), dt, info)
    if stop == "fell":
        raise FellOver(float(traj.t[-1]), float(rows[-1][-1]), traj,
                       fall_cause(limits, traj.C_f, traj.t))
    if stop == "stopped":
        raise Stopped(float(traj.t[-1]), float(traj.V_cm[-1]), traj)
    if stop == "left":
        raise LeftTerrain(float(traj.t[-1]), (traj.x[-1], traj.y[-1]), traj)
    return traj


def _loop(body, limits, controller, ground, resistance, st, n, dt, anchor, brake):
    """Up to ``n`` samples; rows of ``(state 6, alpha_v, C_f, V_f, omega0, theta_max, lean from
    the controller's equilibrium lean)``.  Classical RK4 on Python floats, written out
    (:mod:`.terrain_one_figure` for the stages), ``C_f`` bounded at every stage relative to the
    curvature at the step's start, as :func:`.terrain_dynamics.terrain_rk4_step` does.
    Returns ``(rows, None | "fell" | "stopped" | "left")``."""
    controller.begin_run(limits)
    rhs = TerrainStage(body, limits, resistance, ground, controller)
    derivatives, lean, stage = rhs.derivatives, rhs.lean, rhs.stage
    begin, target, fall = controller.begin_step, controller.target, limits.theta_fall
    anchor = None if anchor is None else float(anchor)
    x0, x1, x2, x3, x4, x5 = (float(v) for v in st)
    h, w6 = 0.5 * dt, dt / 6.0
    rows = []
    V_now = body.V_cm
    for i in range(n):
        t = i * dt
        if x5 != V_now:
            # Below MIN_SPEED the run stops at this row (a body slower than the table of ranges
            # allows is never made): the last row is steered at the minimum speed.
            controller.follow_speed(max(x5, MIN_SPEED))
            V_now = x5
        if brake is not None:
            brake.update(t, (x0, x1, x2, x3, x4, x5))
        try:
            dv = derivatives(x0, x1)
        except OffTerrain:                      # the step ended past the edge
            return rows, "left"
        rel = lean(t, x0, x1, x2, x3, dv)
        begin(t, (x0, x1, x2, rel, x4))
        a0, a1, a2, a3, a4, a5, alpha, V_f, cf = stage(t, x0, x1, x2, x3, x4, x5, anchor, dt,
                                                       dv)
        rows.append((x0, x1, x2, x3, x4, x5, alpha, cf, V_f, *target(t), rel))
        if abs(rel) > fall:
            return rows, "fell"
        if x5 < MIN_SPEED:
            return rows, "stopped"
        if i + 1 == n:
            break
        try:
            b0, b1, b2, b3, b4, b5 = stage(t + h, x0 + h * a0, x1 + h * a1, x2 + h * a2,
                                           x3 + h * a3, x4 + h * a4, x5 + h * a5, cf, h)[:6]
            c0, c1, c2, c3, c4, c5 = stage(t + h, x0 + h * b0, x1 + h * b1, x2 + h * b2,
                                           x3 + h * b3, x4 + h * b4, x5 + h * b5, cf, h)[:6]
            d0, d1, d2, d3, d4, d5 = stage(t + dt, x0 + dt * c0, x1 + dt * c1, x2 + dt * c2,
                                           x3 + dt * c3, x4 + dt * c4, x5 + dt * c5, cf, dt)[:6]
        except OffTerrain:
            return rows, "left"
        x0 += w6 * (a0 + 2.0 * (b0 + c0) + d0)
        x1 += w6 * (a1 + 2.0 * (b1 + c1) + d1)
        x2 += w6 * (a2 + 2.0 * (b2 + c2) + d2)
        x3 += w6 * (a3 + 2.0 * (b3 + c3) + d3)
        x4 += w6 * (a4 + 2.0 * (b4 + c4) + d4)
        x5 += w6 * (a5 + 2.0 * (b5 + c5) + d5)
        anchor = cf
    return rows, None


def _trajectory(body, ground, rec, dt, info) -> Trajectory:
    """The DESIGN.md columns (and ``z``, ``V_cm``) from the per-sample rows."""
    n = len(rec)
    x, y, d, th, om, V, alpha, cf, V_f, w, tm, rel = rec.T
    fr = surface_frame(ground, x, y, d, body.g)
    ds = 0.5 * (V_f[1:] + V_f[:-1]) * dt                 # along the surface (the foot's speed)
    cols = {"t": np.arange(n) * dt, "x": x, "y": y, "theta_dir": d, "theta_v": th,
            "omega_v": om, "alpha_v": alpha, "C_f": cf, "V_f": V_f, "z": fr.z, "V_cm": V,
            "F_leg": terrain_leg_force(body, th, om, alpha, cf, V, V_f, fr)[0],
            "phi": phase(rel, om, tm, w),
            "s": np.concatenate([[0.0], np.cumsum(ds)])}
    return Trajectory.from_columns(cols, info)
