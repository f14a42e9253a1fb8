"""The simulation loop of Fig. 4: control, bound, integrate, record.

:func:`run` steps any batch shape; :func:`simulate` is the one-figure front end that returns a
:class:`Trajectory`.  Integration is classical RK4 (docs/ARCHITECTURE.md Section 5: Euler drifts);
``C_f`` is evaluated and bounded at every stage, so the recorded ``alpha_v`` is the one the
bounded curvature produces (Section 3).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ..controllers import Controller
from ..controllers.feasible import fall_cause
from .dynamics import THETA_V, leg_force, rk4_step, stage, steering
from ..errors import FellOver
from ..controllers.heading_table import heading_table
from .one_figure import integrate
from .params import BodyParams, Figure, Limits, check_range
from ..controllers.phase import phase
from ..controllers.schedule import Schedule
from ..ground.terrain import FLAT
from .model import NO_RESISTANCE, Resistance, speed_held
from ..registry import SPORTS
from .skidding import lean_within_grip
from .terrain_sim import simulate_free
from .trajectory import COLUMNS, Trajectory, body_meta

DEFAULT_DT = 0.02
"""Default integration step, s.  RK4 at 50 Hz tracks a 2 s turn to ~1e-6 rad (tests measure it)."""


@dataclass(frozen=True)
class Run:
    """Raw result of :func:`run`: ``columns[name]`` has shape ``(n_samples,) + batch_shape``.

    ``falls`` lists ``(index, t)`` for every figure that fell, in the order they fell (index 0
    for one figure); ``fell_at`` is the first of those times (``None``: nobody fell).  A fallen
    figure of a batch holds NaN from the sample after its fall on."""

    columns: dict
    fell_at: float | None = None
    falls: tuple = ()


def run(body: BodyParams, limits: Limits, controller: Controller, state0, duration: float,
        dt: float = DEFAULT_DT, C_f0=None, stop_on_fall: bool = True, speed=None) -> Run:
    """Integrate ``state0`` (shape ``(5,)`` for one figure, ``(5, n)`` for a batch).

    One figure is stepped on Python floats (:mod:`.one_figure`), a batch on numpy arrays; the
    formulas are the same and tests hold the two to round-off.  ``C_f0`` is the curvature just
    before the start (for the rate bound); ``None`` lets the first demand through unrated.  With
    ``stop_on_fall`` a figure stops at the first sample where its ``|theta_v|`` exceeds
    ``limits.theta_fall``: one figure ends the run there, a figure of a batch stops alone (its
    later samples NaN) while the others go on; the run ends early only when
    every figure has fallen.  :attr:`Run.falls` reports who fell and when.
    ``speed`` (a :class:`~.schedule.Schedule` of ``V_cm`` in m/s, one figure only) makes the
    forward speed vary over time, held over each step at its value at the step's start (as the
    planner's speed profile, Section 6); ``None`` or a constant keeps ``body.V_cm``.
    """
    check_range("duration", duration, 0.0, 1e6, lo_open=True)
    check_range("dt", dt, 1e-5, 1.0)
    n = int(math.floor(duration / dt + 1e-9)) + 1
    arr = np.array(state0, float)
    if arr.shape[0] != 5 or arr.ndim > 2 or not np.all(np.isfinite(arr)):
        raise ValueError("state0 must be finite with shape (5,) or (5, n)")
    speed = None if speed is None else Schedule.of(speed)
    if speed is not None and speed.constant_value is not None:
        speed = None if speed.constant_value == body.V_cm else speed
    if speed is not None and arr.ndim != 1:
        raise ValueError("a speed schedule is for one figure: state0 must have shape (5,)")
    if arr.ndim == 1:
        V_cm = None
        if speed is not None:
            V_cm = np.array([speed(i * dt) for i in range(n)], float)
            for i in np.nonzero(~(V_cm > 0) | ~(V_cm <= 100.0))[0][:1]:
                check_range(f"speed at t = {i * dt:g} s", V_cm[i], 0.0, 100.0, lo_open=True)
        rows, fell_at = integrate(body, limits, controller, arr, n, dt,
                                  None if C_f0 is None else float(C_f0),
                                  limits.theta_fall if stop_on_fall else None,
                                  None if V_cm is None else V_cm.tolist())
        rec = np.array(rows, float)
        return _columns(body, rec, dt, () if fell_at is None else ((0, fell_at),),
                        None if V_cm is None else V_cm[:len(rec)])
    controller.begin_run(limits)
    state = arr
    anchor = None if C_f0 is None else np.asarray(C_f0, float)
    # Per sample: state, alpha_v, C_f, V_f, omega0, theta_max.
    rec = np.empty((n, 10) + arr.shape[1:])
    fell = np.full(arr.shape[1:], np.inf)              # time of each figure's fall
    anyone = False                                     # has any figure fallen yet?
    desired = steering(controller)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        for i in range(n):
            t = i * dt
            controller.begin_step(t, state)
            k1, cf, alpha, V_f = stage(body, limits, desired, t, state, anchor, dt)
            rec[i, :5] = state
            rec[i, 5], rec[i, 6], rec[i, 7], rec[i, 8], rec[i, 9] = alpha, cf, V_f, \
                *controller.target(t)
            if stop_on_fall and (anyone or np.any(np.abs(state[THETA_V]) > limits.theta_fall)):
                anyone = True
                fell[(np.abs(state[THETA_V]) > limits.theta_fall) & (fell == np.inf)] = t
                rec[i][:, fell < t] = np.nan    # stepped on (cheaper than masking), not shown
                if np.all(fell <= t):
                    n = i + 1
                    break
            if i + 1 < n:
                state = rk4_step(body, limits, state, t, dt, desired, cf, k1)
                anchor = cf
    order = np.argsort(fell, kind="stable")
    falls = tuple((int(k), float(fell[k])) for k in order if fell[k] != np.inf)
    return _columns(body, rec[:n], dt, falls)


def _columns(body: BodyParams, rec: np.ndarray, dt: float, falls: tuple, V_cm=None) -> Run:
    """The columns of docs/ARCHITECTURE.md Section 3 from the records ``(n, 10, ...)``; ``V_cm``
    the speed at each sample when it varies."""
    n = rec.shape[0]
    cols = {"t": np.broadcast_to((np.arange(n) * dt).reshape((n,) + (1,) * (rec.ndim - 2)),
                                 rec.shape[:1] + rec.shape[2:]).copy()}
    for j, name in enumerate(("x", "y", "theta_dir", "theta_v", "omega_v", "alpha_v", "C_f",
                              "V_f")):
        cols[name] = rec[:, j]
    cols["phi"] = phase(cols["theta_v"], cols["omega_v"], rec[:, 9], rec[:, 8])
    cols["F_leg"] = leg_force(body, cols["theta_v"], cols["omega_v"], cols["alpha_v"],
                              cols["C_f"], V_cm)[0]
    # Foot distance travelled: trapezoid on V_f (the foot moves at V_f, Eq. 21).
    ds = 0.5 * (cols["V_f"][1:] + cols["V_f"][:-1]) * dt
    cols["s"] = np.concatenate([np.zeros((1,) + ds.shape[1:]), np.cumsum(ds, axis=0)])
    cols["z"] = np.zeros_like(cols["t"])                # flat ground
    cols["V_cm"] = np.full_like(cols["t"], body.V_cm) if V_cm is None else np.asarray(V_cm, float)
    return Run(cols, falls[0][1] if falls else None, falls)


def slalom_start(body: BodyParams, omega0: float, theta_max: float, heading: float = 0.0,
                 x: float = 0.0, y: float = 0.0) -> tuple:
    """The state at phase 0 of a slalom centred on ``heading``: upright, leaning out at the
    ellipse's rate ``omega0 theta_max``, the heading at the bottom of its swing, half a
    half-turn's change (Eq. 6) below the mean."""
    swing = float(heading_table(body)(theta_max, omega0))
    return (x, y, heading - 0.5 * swing, 0.0, omega0 * theta_max)


def simulate(figure: Figure, controller: Controller, duration: float, dt: float = DEFAULT_DT,
             state0=None, C_f0=None, meta: dict | None = None, speed=None, ground=FLAT,
             resistance: Resistance | None = None, target_speed=None,
             skidding=None, stride: int = 1, keep: float = 0.0) -> Trajectory:
    """Simulate one figure on ``ground`` (:mod:`.model`: ``Flat()``, the default, a
    :class:`.terrain.Plane` or a :class:`.terrain.HeightField`); raise a
    :class:`.errors.RunEnded` (:class:`.errors.FellOver`, :class:`.errors.Stopped`,
    :class:`.errors.LeftTerrain`, with the trajectory so far) if the run ends early.

    The speed: on flat ground with nothing slowing the figure (``resistance`` ``None`` or free,
    no ``target_speed``) the paper's implicit forward force holds it (:func:`.model.speed_held`)
    at ``figure.body.V_cm`` or along ``speed`` (``V_cm`` over time, see :func:`run`): the paper's
    model, bit for bit.  Anywhere else it is a state that balances energy (docs/TERRAIN.md
    Sections 3-4; ``state0`` may carry ``V_cm`` as a sixth entry), slowed by ``resistance``
    (:class:`.model.Resistance`) and braked to ``target_speed`` (m/s or
    :class:`.braking.TargetSpeed`) by turning across the hill and, with ``skidding`` (a
    :class:`.skidding.Skidding`: a style, the grip, a stop), by skidding within the grip
    (docs/skidding.md).  The trajectory's ``z`` is the ground under the foot.

    A tyre (the sport's grip, or ``skidding``'s) holds the lean to what its grip allows
    (:func:`.skidding.lean_within_grip`); ``meta["grip_limited"]`` then says so.

    ``stride`` > 1: a preview on terrain, steps of up to ``stride dt`` away from the lean's zero
    crossings (:func:`.terrain_sim.simulate_free`); the paper's model takes a coarser ``dt``.
    ``keep`` (s; where the speed is a state): the trajectory from its last sample at or before
    ``keep`` on (:func:`.terrain_sim.simulate_free`); the paper's model keeps every sample."""
    grip = skidding.grip if skidding is not None else getattr(
        SPORTS.get(figure.name), "grip", None)
    with lean_within_grip(controller, grip) as report:
        traj = _simulate(figure, controller, duration, dt, state0, C_f0, meta, speed, ground,
                         resistance, target_speed, skidding, stride, keep)
    if report:
        traj.meta["grip_limited"] = report[0]
    return traj


def _simulate(figure, controller, duration, dt, state0, C_f0, meta, speed, ground, resistance,
              target_speed, skidding, stride=1, keep=0.0) -> Trajectory:
    """:func:`simulate` with the lean as given."""
    ground = FLAT if ground is None else ground
    res = NO_RESISTANCE if resistance is None else resistance
    brakes = skidding is not None and skidding.brakes(target_speed)
    if target_speed is not None or brakes or not speed_held(ground, res):
        if speed is not None:
            raise ValueError("speed is a state on terrain (it follows the slope): give a "
                             "speed schedule or a ground, not both")
        return simulate_free(figure, controller, duration, dt, state0, ground, res, C_f0, meta,
                             target_speed, skidding, stride, keep)
    if stride != 1:
        raise ValueError(f"stride = {stride!r}: the paper's model (flat ground, the speed held) "
                         "steps every dt; give it a coarser dt instead")
    if ground.z0 != 0.0:                                  # flat ground at a height
        traj = _simulate(figure, controller, duration, dt, state0, C_f0, meta, speed, FLAT,
                         None, None, None)
        return Trajectory.from_columns({**traj.columns(), "z": traj.z + ground.z0}, traj.meta)
    if state0 is not None and len(state0) == 6:          # a terrain state on flat ground
        figure = replace(figure, body=replace(figure.body, V_cm=float(state0[5])))
        state0 = tuple(state0)[:5]
    if state0 is None:
        w, tm = controller.target(0.0)
        state0 = (0.0, 0.0, 0.0, 0.0, w * tm)
    r = run(figure.body, figure.limits, controller, state0, duration, dt, C_f0, speed=speed)
    info = {"preset": figure.name, "dt": dt, **body_meta(figure.body), **(meta or {})}
    traj = Trajectory.from_columns(r.columns, info)
    if r.fell_at is not None:
        raise FellOver(r.fell_at, float(traj.theta_v[-1]), traj,
                       fall_cause(figure.limits, traj.C_f, traj.t))
    return traj


__all__ = ["run", "simulate", "slalom_start", "Run", "DEFAULT_DT", "COLUMNS"]
