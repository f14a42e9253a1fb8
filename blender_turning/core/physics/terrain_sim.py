"""The loop of Fig. 4 with the speed a state: one figure on any ground, behind
:func:`.simulate.simulate`.

:func:`simulate_free` steps one figure on a surface (:mod:`.terrain`) with friction and drag
(:class:`.model.Resistance`) by classical RK4 on floats (:mod:`.terrain_one_figure`;
``C_f`` bounded at every stage as on flat ground, as :func:`.model.rk4_step`).
Each step the controller is re-targeted to the current speed
(:meth:`~.controllers.base.Controller.follow_speed`), sees the lean from the equilibrium lean
(:func:`.model.equilibrium_lean`) and steers by its lean law through Eq. (1) on terrain
(:func:`.model.steering`).  :class:`TargetSpeed` brakes by turning
across the hill (docs/TERRAIN.md Section 6).

:func:`.simulate.simulate` sends a run here unless the speed is held
(:func:`.model.speed_held`: flat ground with nothing slowing the figure, the paper's model).
"""
from __future__ import annotations

import math
from itertools import chain

import numpy as np

from ..controllers.braking import TargetSpeed, _Braking
from .skidding import Skidding, _Skid, skid_meta, stand_rows
from ..controllers import Controller
from ..controllers.feasible import fall_cause
from ..errors import FellOver, LeftTerrain, Stopped
from .params import Figure, check_range
from ..controllers.phase import phase
from ..controllers.schedule import Schedule
from ..ground.terrain import FLAT, HeightField, OffTerrain, Plane, surface_frame
from . import model
from .model import NO_RESISTANCE, Resistance
from .terrain_one_figure import TerrainStage
from .trajectory import Trajectory, body_meta, resistance_meta

__all__ = ["simulate_free", "describe_ground", "MIN_SPEED", "REACH"]

MIN_SPEED = 0.5
"""m/s: below it the run stops (:class:`.errors.Stopped`).  The turning model is a body carried
by its speed (Eq. 1 needs ``V^2 cos th`` to balance gravity); near rest it asks for curvatures no
ski or wheel has."""

REACH = 2.0
"""A run with ``stride`` > 1 (:func:`_loop`) steps with ``dt`` while the lean's rate carries it
across zero within REACH times the coarse step it would take (the rate of the lean from the
equilibrium lean is not ``omega_v`` on terrain: the margin catches most of what the linear
guess misses)."""

GRID = 3
"""After steps of ``dt`` (about a zero crossing of the lean, or a table that changes the turn), a
run with ``stride`` > 1 (:func:`_loop`) takes its next coarse step from a step ``i`` that GRID
divides: the same steps as coarse steps of ``GRID dt`` alone there.  Resuming coarse steps at
once left a snowboarder at 12 m/s on a 12 deg slope 2.6 m from the bake 30 s in (0.8 m on the
grid; BENCHMARKS.md, "Live Preview on a Ground mesh: longer coarse steps")."""

SPAN = 1.25
"""A coarse step (:func:`_loop`) moves at most SPAN cells of a height field: the spline rounds a
mesh's creases over about a cell (Blender's Ground mesh is sampled at a quarter of its faces),
and a step whose stages lie further apart misses them.  The benchmark's cyclist (1.4-4.6 m/s,
0.25 m cells) steps 3-5 ``dt`` at a time; a figure too fast for ``GRID dt`` takes the bake's
steps (a snowboarder at 12 m/s on such ground, stepped coarsely, ended 12 m from the bake 20 s
in).
docs/live-preview.md has the errors measured."""


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


def simulate_free(figure: Figure, controller: Controller, duration: float, dt: float,
                  state0=None, ground=FLAT, resistance: Resistance = NO_RESISTANCE,
                  C_f0=None, meta: dict | None = None,
                  target_speed: TargetSpeed | float | None = None,
                  skidding: Skidding | None = None, stride: int = 1,
                  keep: float = 0.0) -> Trajectory:
    """Simulate one figure on ``ground`` with ``resistance``; returns a :class:`Trajectory`
    whose ``z`` is the ground under the foot and ``V_cm`` the speed (a state).

    ``state0``: ``(x, y, theta_dir, theta_v, omega_v)`` (starting at ``figure.body.V_cm``) or
    with a sixth entry ``V_cm``.  ``target_speed`` (m/s, a :class:`TargetSpeed` or a
    :class:`.schedule.Schedule` of m/s: a keyed target) needs a controller with a heading (the
    course).  Raises :class:`.errors.FellOver` past
    ``limits.theta_fall`` (the lean from the plumb lean: a skier leaning 20 deg uphill from the
    normal of a traverse stands upright) and :class:`.errors.Stopped` below
    :data:`MIN_SPEED` and :class:`.errors.LeftTerrain` at the edge of a height field, each with
    the trajectory so far.

    ``skidding`` (:class:`.skidding.Skidding`, docs/skidding.md) brakes at the foot within the
    grip: a style other than ``carve`` skids for what turning across the hill leaves of
    ``target_speed``; a stop skids to rest, and the figure then stands still across the fall line
    to the end of ``duration`` (no :class:`.errors.Stopped`).

    ``stride`` > 1 (a preview, :func:`_loop`): steps of up to ``stride dt`` (at least
    :data:`GRID`) away from the zero crossings of the lean (from the equilibrium lean), steps of
    ``dt`` on the same grid about them, a sample at each step's start (``t`` on the grid of
    ``dt``, not evenly spaced: :meth:`.Trajectory.resample` takes it); not with
    ``target_speed`` or ``skidding``.

    ``keep`` (s): a run that ends the trajectory leaves out the samples before the last one at
    or before ``keep`` (a window's run: the frames resampled from there on are the whole
    trajectory's, bit for bit; ``s`` counts from the start)."""
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
    if skidding is not None and not skidding.brakes(target_speed):
        skidding = None                          # the paper's carved model, unchanged
    brake = None
    schedule = None                          # a target speed that changes over time
    if isinstance(target_speed, Schedule):
        schedule = target_speed
        target_speed = schedule.constant_value
        if target_speed is None:
            target_speed = check_range("target speed at t = 0 s", float(schedule(0.0)), 0.0,
                                       100.0, lo_open=True)
            schedule = _checked(schedule)
        else:
            schedule = None
    if target_speed is not None:
        rule = target_speed if isinstance(target_speed, TargetSpeed) else \
            TargetSpeed(target_speed) if skidding is None else \
            TargetSpeed(target_speed, corridor=skidding.corridor)
        if getattr(controller, "heading", None) is None:
            raise ValueError("target_speed steers the heading: the controller needs a heading "
                             "(the course, e.g. the fall line)")
        brake = _Braking(rule, controller, figure, ground, resistance, st, schedule)
    if type(stride) is not int or not (stride == 1 or GRID <= stride <= 10):
        raise ValueError(f"stride = {stride!r} is not 1 or a whole number of steps in "
                         f"[{GRID}, 10]")
    if stride > 1 and (target_speed is not None or skidding is not None):
        raise ValueError("stride > 1 steps the carved model only: give no target_speed or "
                         "skidding with it")
    n = int(math.floor(duration / dt + 1e-9)) + 1
    info = {"preset": figure.name, "dt": dt, **body_meta(body),
            "ground": describe_ground(ground), **resistance_meta(resistance), **(meta or {})}
    if stride > 1:
        info["stride"] = stride
    if brake is not None:
        info["target_speed"] = brake.rule.speed
    if skidding is not None:
        info.update(skid_meta(skidding))
    course = getattr(controller, "heading", None)
    skid = None if skidding is None else _Skid(
        skidding, controller, figure, None if brake is None else brake.speed)
    try:
        if brake is not None:
            controller.heading = Schedule.of(brake)
        stage = TerrainStage(body, limits, resistance, ground, controller)
        if skid is not None:
            skid.stage = stage
        rows, stop, at = _loop(body, limits, controller, ground, st, n, dt, C_f0, brake, stage,
                               skid, stride)
    finally:
        if brake is not None:
            controller.heading = course
        if skid is not None:
            skid.restore()
    if stop == "halted":
        rows, stop = stand_rows(rows, n, ground, body.g, skidding.grip), None
    # The rows' floats into one array (np.array of a list of tuples: twice the time).
    steps = np.arange(len(rows)) if at is None else np.array(at)
    first = 0 if stop is not None else _first_kept(steps, dt, keep)
    traj = _trajectory(body, ground, rows, steps, dt, info, first)
    if stop == "fell":
        raise FellOver(float(traj.t[-1]), float(rows[-1][11]), traj,
                       fall_cause(limits, traj.C_f, traj.t))
    if stop == "stopped":
        raise Stopped(float(traj.t[-1]), float(traj.V_cm[-1]), traj)
    if stop == "left":
        raise LeftTerrain(float(traj.t[-1]), (traj.x[-1], traj.y[-1]), traj)
    return traj


def preview_stride(period: float, dt: float, longest: int = 6, per_turn: int = 30) -> int:
    """A preview's ``stride`` (:func:`simulate_free`) for turns of ``period`` s at the shortest:
    steps of at most ``period / per_turn`` (at least :data:`GRID` dt, at most ``longest`` dt).
    Fewer than 30 steps a turn took a skier on moguls (2 s turns, 10 m/s, 2 m cells) metres
    from the bake over 12 s (BENCHMARKS.md, "Live Preview on a Ground mesh: longer coarse
    steps"); ``longest`` 1 is the bake's own step."""
    steps = int(period / (per_turn * dt) + 1e-9)
    return min(longest, max(GRID, steps))


def _checked(schedule: Schedule):
    """``schedule`` of a target speed, each value checked when read (m/s, (0, 100])."""
    def at(t):
        return check_range(f"target speed at t = {t:g} s", float(schedule(t)), 0.0, 100.0,
                           lo_open=True)
    return Schedule(at)


def _loop(body, limits, controller, ground, st, n, dt, anchor, brake, rhs, skid, stride=1):
    """Up to ``n`` steps of ``dt``; rows of ``(state 6, alpha_v, C_f, V_f, omega0, theta_max, lean
    from the controller's equilibrium lean, F_brake / m, skid)``.  Classical RK4 on Python
    floats, written out (``rhs``, a :class:`.terrain_one_figure.TerrainStage`, for the stages),
    ``C_f`` bounded at every stage relative to the curvature at the step's start, as
    :func:`.model.rk4_step` does; ``skid`` (:class:`.skidding._Skid`) sets the braking command
    of each step.  Returns ``(rows, None | "fell" | "stopped" | "halted" | "left", steps)``
    (``halted``: a commanded stop came to rest; ``steps``: each row's ``i`` on the grid of
    ``dt``, ``None`` with ``stride = 1``: a row at every step).

    ``stride`` > 1 (a preview; no ``brake``, no ``skid``): a row at each step's start, and one
    RK4 step of ``k dt`` (``k`` up to ``stride``, as far as :data:`SPAN` allows) where the lean
    (from the equilibrium lean) keeps its sign, else steps of ``dt``.  What makes a run's error
    first order in ``dt`` on terrain happens at the lean's zero crossings: directional control
    plans the coming half-turn at the step before one (Section 5.2,
    :meth:`.PhaseEllipse.begin_step`: a crossing within the step, ``theta_v + omega_v dt``
    across zero) and the law switches to its ellipse there (a jump in ``alpha_v`` inside a
    step), and so does a controller taking new feasible turns at a speed it passes where they
    change the law (:meth:`.Controller.changes_between`).  Stepped with ``dt`` on the same grid,
    those steps take the ``stride = 1`` run's instants.  A coarse step is tried after a coarse
    step or, after steps of ``dt``, from a step :data:`GRID` divides, where the lean's rate does
    not carry it across zero within :data:`REACH` times its length, and kept only if the
    controller does not change over it and it ends on the same side with no crossing within its
    length ahead (where ``begin_step``, seeing the long step behind it, would plan).  Where a
    coarse step may be taken (slow enough for :data:`SPAN` at ``GRID dt``), a step of any length
    reads the ground three times, not four (:func:`advance`: the midpoints share a read, the end
    is carried from stage 4); faster, the preview's steps are the ``stride = 1`` run's, bit for
    bit.  A step's first stage bounds the rate of ``C_f`` relative to the last step's, ``last``
    s before (Section 3). The fall and a stop are checked at the rows."""
    controller.begin_run(limits)
    foot = rhs.foot
    derivatives, lean, stage = rhs.derivatives, rhs.lean, rhs.stage
    begin, target, fall = controller.begin_step, controller.target, limits.theta_fall
    follow, changes = controller.follow_speed, controller.changes_between
    step_law, use_law = controller.step_law, rhs.use_law
    anchor = None if anchor is None else float(anchor)
    x0, x1, x2, x3, x4, x5 = (float(v) for v in st)
    step_f, h_f, w6_f = dt, 0.5 * dt, dt / 6.0
    cells = SPAN * getattr(ground, "cell", math.inf) / dt    # the speed moving SPAN cells a dt
    at = None if stride == 1 else []
    x_lo, x_hi, y_lo, y_hi = getattr(ground, "extent", (-math.inf, math.inf, -math.inf,
                                                        math.inf))
    low = MIN_SPEED                 # the speed the controller is steered at: max(V, low)
    plain = brake is None and skid is None

    def advance(t, step, h, w6, shared, x0, x1, x2, x3, x4, x5, a0, a1, a2, a3, a4, a5,
                cf):
        """RK4's stages 2-4 and the step: the state at the step's end and the ground there
        (``None``: to be read there), 7 floats.  A coarse step reads the ground once for both
        midpoint stages: stage 3's foot lies ``h (k2 - k1)`` from stage 2's (about a
        millimetre at 3 m/s), and takes stage 2's slopes carried there to first order by its
        curvatures, and its curvatures (``tests/test_terrain_preview.py``'s cyclist: within
        0.01 mm of the run reading the ground there over 30 s; 4-5 mm with the slopes held, not
        carried); the step's end, a few millimetres from stage 4's foot, takes stage 4's ground
        carried the same way (the next step's first stage and the lean the controller sees
        there: within the midpoints' bounds of the ground's)."""
        px, py = x0 + h * a0, x1 + h * a1
        dv = derivatives(px, py) if shared else None
        t_h = t + h
        b0, b1, b2, b3, b4, b5, _, _, _ = stage(
            t_h, px, py, x2 + h * a2, x3 + h * a3, x4 + h * a4, x5 + h * a5, cf, h, dv)
        qx, qy = x0 + h * b0, x1 + h * b1
        if dv is not None:          # stage 2's slopes carried by its curvatures (first order)
            hx, hy, hxx, hxy, hyy = dv
            mx, my = qx - px, qy - py
            dv = (hx + hxx * mx + hxy * my, hy + hxy * mx + hyy * my, hxx, hxy, hyy)
        c0, c1, c2, c3, c4, c5, _, _, _ = stage(
            t_h, qx, qy, x2 + h * b2, x3 + h * b3, x4 + h * b4, x5 + h * b5, cf, h, dv)
        sx, sy = x0 + step * c0, x1 + step * c1
        if dv is not None:
            dv = derivatives(sx, sy)
        d0, d1, d2, d3, d4, d5, _, _, _ = stage(
            t + step, sx, sy, x2 + step * c2, x3 + step * c3, x4 + step * c4, x5 + step * c5,
            cf, step, dv)
        y0 = x0 + w6 * (a0 + 2.0 * (b0 + c0) + d0)
        y1 = x1 + w6 * (a1 + 2.0 * (b1 + c1) + d1)
        if dv is not None and x_lo <= y0 <= x_hi and y_lo <= y1 <= y_hi:
            hx, hy, hxx, hxy, hyy = dv            # stage 4's, carried the same way
            ex, ey = y0 - sx, y1 - sy
            dv = (hx + hxx * ex + hxy * ey, hy + hxy * ex + hyy * ey, hxx, hxy, hyy)
        else:
            dv = None
        return (y0, y1, x2 + w6 * (a2 + 2.0 * (b2 + c2) + d2),
                x3 + w6 * (a3 + 2.0 * (b3 + c3) + d3), x4 + w6 * (a4 + 2.0 * (b4 + c4) + d4),
                x5 + w6 * (a5 + 2.0 * (b5 + c5) + d5), dv)

    rows = []
    append = rows.append
    V_now = body.V_cm
    V_law = low if low > V_now else V_now
    i, ahead, last, near, law_now = 0, None, dt, None, None
    while True:
        t = i * dt
        if x5 != V_now:
            # Below MIN_SPEED the run stops at this row (a body slower than the table of ranges
            # allows is never made): the last row is steered at the minimum speed.
            V_now, V_law = x5, low if low > x5 else x5
            follow(V_law)
        if not plain:
            if brake is not None and not (skid is not None and skid.stopping):
                brake.update(t, (x0, x1, x2, x3, x4, x5))
            if skid is not None:
                skid.update(t, (x0, x1, x2, x3, x4, x5), foot)
        if ahead is None:
            if near is not None:                # carried from the last step's stage 4
                dv = near
            else:
                try:
                    dv = derivatives(x0, x1)
                except OffTerrain:              # the step ended past the edge
                    return rows, "left", at
            rel = lean(t, x0, x1, x2, x3, dv)
        else:                                   # found by the coarse step that led here
            dv, rel = ahead
            ahead = None
        begin(t, (x0, x1, x2, rel, x4))
        if at is not None:
            at.append(i)
        law = step_law(t)
        if law is not law_now:
            use_law(law)
            law_now = law
        a0, a1, a2, a3, a4, a5, alpha, V_f, cf = stage(t, x0, x1, x2, x3, x4, x5, anchor, last,
                                                       dv)
        step, h, w6, k, y = step_f, h_f, w6_f, 1, None
        slow = stride > 1 and x5 * GRID <= cells    # the preview's reads shared (advance)
        # The coarse step: up to stride dt, SPAN cells, the run's end; after steps of dt, from
        # the grid of GRID dt.
        kc = (stride if x5 * stride <= cells else int(cells / x5)) if slow else 1
        if kc > n - 1 - i:
            kc = n - 1 - i
        if kc > 1 and (last != step_f or i % GRID == 0) and \
                rel * (rel + x4 * (REACH * kc * dt)) > 0.0:
            step_c = kc * dt
            h_c, w6_c = 0.5 * step_c, step_c / 6.0
            try:
                y = advance(t, step_c, h_c, w6_c, True, x0, x1, x2, x3, x4, x5, a0, a1, a2, a3,
                            a4, a5, cf)
                if changes(V_law, low if low > y[5] else y[5]):
                    raise _Fine
                dv_y = y[6]
                if dv_y is None:
                    dv_y = derivatives(y[0], y[1])
                rel_y = lean(t + step_c, y[0], y[1], y[2], y[3], dv_y)
                if rel * rel_y <= 0.0 or rel_y * (rel_y + y[4] * step_c) <= 0.0:
                    raise _Fine
                step, h, w6, k, ahead = step_c, h_c, w6_c, kc, (dv_y, rel_y)
            except (_Fine, OffTerrain):
                y = None
        skid_b = skid_a = 0.0
        if skid is not None:
            skid_b = foot[0]
            skid_a = skid.skid(skid_b, foot[1], foot[2], x3)
        w, tm = target(t)
        append((x0, x1, x2, x3, x4, x5, alpha, cf, V_f, w, tm, rel, skid_b, skid_a))
        if abs(rel) > fall:
            return rows, "fell", at
        if x5 < low:
            return rows, "halted" if skid is not None and skid.stopping else "stopped", at
        if i + 1 >= n:
            break
        if y is None:
            try:
                y = advance(t, step, h, w6, slow, x0, x1, x2, x3, x4, x5, a0, a1, a2, a3, a4,
                            a5, cf)
            except OffTerrain:
                return rows, "left", at
            x0, x1, x2, x3, x4, x5, near = y
        else:
            x0, x1, x2, x3, x4, x5, near = y
            near = None
        anchor, last = cf, step
        i += k
    return rows, None, at


class _Fine(Exception):
    """A coarse step of :func:`_loop` that steps of ``dt`` must take instead."""


def _first_kept(steps: np.ndarray, dt: float, keep: float) -> int:
    """The last of the samples at ``steps dt`` at or before ``keep`` (0 before the first)."""
    return max(0, int(np.searchsorted(steps * dt, keep, side="right")) - 1)


def _trajectory(body, ground, rows, steps, dt, info, first=0) -> Trajectory:
    """The trajectory columns (docs/ARCHITECTURE.md Section 3) from the per-sample rows at the
    times ``steps dt``, from row ``first`` on (``s`` from the first row)."""
    n = len(rows)
    # The rows' floats into one array (np.array of a list of tuples: twice the time).
    rec = np.fromiter(chain.from_iterable(rows[first:]), float, (n - first) * len(rows[0]))
    x, y, d, th, om, V, alpha, cf, V_f, w, tm, rel, brake, skid = rec.reshape(n - first, -1).T
    fr = surface_frame(ground, x, y, d, body.g)
    V_all = V_f if first == 0 else np.fromiter((r[8] for r in rows), float, n)
    # Along the surface (the foot's speed) over the steps between the rows (one dt: dt itself).
    ds = 0.5 * (V_all[1:] + V_all[:-1]) * (np.diff(steps) * dt)
    cols = {"t": steps[first:] * dt, "x": x, "y": y, "theta_dir": d, "theta_v": th,
            "omega_v": om, "alpha_v": alpha, "C_f": cf, "V_f": V_f, "z": fr.z, "V_cm": V,
            "F_leg": model.leg_force(body, th, om, alpha, cf, V, V_f, fr)[0],
            "phi": phase(rel, om, tm, w),
            "s": np.concatenate([[0.0], np.cumsum(ds)])[first:], "brake": brake, "skid": skid,
            "ski_heading": d + skid}
    return Trajectory.from_columns(cols, info)
