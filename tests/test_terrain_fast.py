"""The float stepper on any ground (core/physics/terrain_one_figure.py, behind ``simulate``): the height
field on floats, whole runs against the reference model's loop (``model.rhs`` and
``model.rk4_step``, core/physics/model.py) to round-off, and the controller's part in it (one stage
against the model: tests/test_model_kernels.py)."""
import math

import numpy as np
import pytest

from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start
from blender_turning.core.controllers import Straight
from blender_turning.core.controllers.feasible import feasible_turns
from blender_turning.core.errors import LeftTerrain
from blender_turning.core.ground.terrain import HeightField, Plane, surface_frame
from blender_turning.core.physics import model
from blender_turning.core.physics.model import RESISTANCE, plumb_lean
from blender_turning.core.ground.terrain_gen import ski_slope
from blender_turning.core.physics.terrain_one_figure import TerrainStage

SKIER = preset("skier")
BODY = SKIER.body
W, TM = math.pi, math.radians(23)
ROUGH = HeightField(np.random.default_rng(3).normal(0.0, 0.4, (13, 17)), -5.0, 2.0, 0.7)


def _points(ground, rng, n):
    x_lo, x_hi, y_lo, y_hi = ground.extent
    xs, ys = rng.uniform(x_lo, x_hi, n), rng.uniform(y_lo, y_hi, n)
    # Cell corners and the top and right edges too (where the cell index is clamped).
    i, j = rng.integers(0, ground.nx, n // 4), rng.integers(0, ground.ny, n // 4)
    xs = np.concatenate([xs, x_lo + i * ground.cell, [x_hi, x_hi, x_lo]])
    ys = np.concatenate([ys, y_lo + j * ground.cell, [y_hi, y_lo, y_hi]])
    return xs.tolist(), ys.tolist()


def test_cell_polynomials_are_the_spline():
    """``derivatives_one`` (per-cell coefficients, Horner) against the biquintic's weights of the
    array path: h and its first and second derivatives, on a rough random grid, at cell corners
    and edges."""
    rng = np.random.default_rng(5)
    xs, ys = _points(ROUGH, rng, 400)
    one = np.array([ROUGH.derivatives_one(x, y) for x, y in zip(xs, ys)])
    arr = np.array(ROUGH.derivatives(np.array(xs), np.array(ys))).T
    scale = np.abs(arr).max(0)                     # each column's own size
    np.testing.assert_allclose(one, arr, rtol=0, atol=1e-13 * scale.max())
    assert np.all(scale[3:] > 1.0)                 # a grid that really bends


def test_off_the_grid_raises_on_floats_too():
    with pytest.raises(ValueError, match="off the terrain"):
        ROUGH.derivatives_one(-5.01, 3.0)


def _relative_state(controller, ground, state, t):
    """``state`` (6 rows) as the controller's lean law sees it at ``t``: 5 floats, the lean
    taken from :func:`.model.equilibrium_lean`."""
    x, y, d, th, om = (float(v) for v in state[:5])
    fr = surface_frame(ground, x, y, d, controller.body.g)
    return (x, y, d, th - model.equilibrium_lean(controller, fr, t), om)


def _array_loop(figure, controller, ground, res, st, n, dt):
    """The terrain loop through the reference: the lean from :func:`.model.equilibrium_lean`
    and :func:`.model.steering`, and the state as a batch of one (shape (6, 1)) through
    :func:`.model.rhs` for the row and :func:`.model.rk4_step` for the step."""
    body, limits = figure.body, figure.limits
    controller.begin_run(limits)
    law = model.steering(controller, ground)

    def law1(t, s):
        return np.atleast_1d(law(t, [float(v[0]) for v in s]))

    st, anchor, rows, V_now = np.array(st, float)[:, None], None, [], body.V_cm
    for i in range(n):
        t = i * dt
        if st[5, 0] != V_now:
            V_now = float(st[5, 0])
            controller.follow_speed(V_now)
        rel = _relative_state(controller, ground, st[:, 0], t)
        controller.begin_step(t, rel)
        _, cf, alpha, V_f, _, _ = model.rhs(body, limits, ground, law1(t, st), st,
                                                anchor, dt, resistance=res)
        rows.append((*st[:, 0], alpha[0], cf[0], V_f[0], rel[3]))
        anchor = cf
        st = model.rk4_step(body, limits, ground, st, t, dt, law1, anchor, resistance=res)
    return np.array(rows)


@pytest.mark.parametrize("case", ["mogul slope", "no course", "plane traverse", "straight"])
def test_fused_run_is_the_array_loop(case):
    """12 s of a slalom down the mogul field (speed changing every step, the feasible tables
    following it), the same without a course (the lean about the plumb lean), a traverse
    slalom on a plane, and a straight run: every column of every sample agrees with the array
    loop to 5e-11 of its size (measured: 1.1e-11 on the mogul slope, 7e-12 without a course,
    2e-14 on the plane: round-off carried by the controller's feedback over 600 steps)."""
    slope = ski_slope(length=400.0, width=200.0, cell=2.0)
    fall = -math.pi / 2
    if case in ("mogul slope", "no course"):
        ground, heading, x, y = slope, fall, -40.0, 150.0
    else:
        ground, heading, x, y = Plane(math.radians(20), fall), fall + 1.0, 0.0, 0.0
    res, dt, n = RESISTANCE["skier"], 0.02, 600
    if case == "straight":                  # a traverse held at the plumb lean (unstable: 2 s)
        lean = plumb_lean(surface_frame(ground, x, y, heading, BODY.g))
        make, s0, n = (lambda: Straight(BODY)), (x, y, heading, lean, 0.0, 8.0), 100
    else:
        course = None if case == "no course" else heading      # no course: the plumb lean
        make = lambda: PhaseEllipse(BODY, W, TM, heading=course)         # noqa: E731
        s0 = (*slalom_start(BODY, W, TM, heading, x, y), BODY.V_cm)
    fast = simulate(SKIER, make(), (n - 1) * dt, dt, s0, ground=ground, resistance=res)
    ref = _array_loop(SKIER, make(), ground, res, s0, n, dt)
    cols = ("x", "y", "theta_dir", "theta_v", "omega_v", "V_cm", "alpha_v", "C_f", "V_f")
    tol = 5e-11
    assert len(fast) == n
    for k, name in enumerate(cols):
        want = ref[:, k]
        np.testing.assert_allclose(getattr(fast, name), want, rtol=0,
                                   atol=tol * max(1.0, np.abs(want).max()), err_msg=name)
    assert np.ptp(fast.V_cm) > 1.0                                      # not a toy run
    if case != "straight":
        assert np.abs(fast.theta_v).max() > 0.2
    fr = surface_frame(ground, fast.x, fast.y, fast.theta_dir, BODY.g)
    np.testing.assert_allclose(fast.z, fr.z, atol=1e-12)


class _Recorder:
    """A ground that records where the stepper evaluates it (each step: the row's point, then
    RK4 stages 2, 3 and 4)."""

    def __init__(self, ground):
        self.ground, self.xs = ground, []

    def derivatives_one(self, x, y):
        self.xs.append(x)
        return self.ground.derivatives_one(x, y)

    def derivatives(self, x, y):
        return self.ground.derivatives(x, y)


def test_a_step_that_ends_off_the_grid_is_left_terrain():
    """All four RK4 stages of a step inside the grid, the step's result past its edge (a
    slalom along +x at dt = 0.1 s: the result runs ahead of stage 4 by ~0.3 mm at some steps):
    LeftTerrain with the trajectory so far, not the height field's own error."""
    dt, heading = 0.1, 0.0

    def run(field):
        ctl = PhaseEllipse(BODY, W, TM, heading=heading)
        return simulate(SKIER, ctl, 20.0, dt, slalom_start(BODY, W, TM, heading), ground=field)

    rec = _Recorder(HeightField(np.zeros((41, 400)), -10.0, -20.0, 1.0))
    run(rec)
    stages = np.array(rec.xs[:-1]).reshape(-1, 4)            # row, stages 2-4 of each step
    ahead = np.append(stages[1:, 0], rec.xs[-1]) - stages.max(1)
    i = int(np.argmax(ahead))
    assert ahead[i] > 1e-4
    edge = stages[i].max() + 0.5 * ahead[i]                  # between stage 4 and the result
    n = 150
    with pytest.raises(LeftTerrain) as err:
        run(HeightField(np.zeros((41, n + 1)), edge - n * 1.0, -20.0, 1.0))
    assert len(err.value.trajectory) == i + 1


def test_the_feasible_table_follows_the_speed_grid():
    """``follow_speed`` looks the table up only when the speed's grid changes; after any
    sequence of speeds it is the table at the current grid speed."""
    from dataclasses import replace
    from blender_turning.core.controllers.ellipse import SPEED_GRID
    ctl = PhaseEllipse(BODY, W, TM, heading=0.0)
    ctl.begin_run(SKIER.limits)
    for V in (10.0, 10.2, 12.7, 12.9, 9.1, 9.4, 13.2):
        ctl.follow_speed(V)
        grid = math.floor(V / SPEED_GRID) * SPEED_GRID
        assert ctl._feasible is feasible_turns(replace(BODY, V_cm=grid), SKIER.limits)
    ctl.begin_run(SKIER.limits)                    # a new run: the table of its body (13.2)
    assert ctl._feasible is feasible_turns(ctl.body, SKIER.limits)
    ctl.follow_speed(13.3)                         # the grid speed of before, a table anew
    assert ctl._feasible is feasible_turns(replace(BODY, V_cm=13.0), SKIER.limits)


def test_the_ellipse_followed_is_feasible_at_the_current_speed():
    """After the speed drops to where the commanded 23 deg turn is not feasible, the ellipse
    the controller follows (its target, and the float law the stepper uses) is the one the new
    table allows, not one remembered from the faster speed."""
    ctl = PhaseEllipse(BODY, W, TM, heading=0.0)
    ctl.begin_run(SKIER.limits)
    ctl.follow_speed(12.0)
    fast = ctl.target(0.0)[1], ctl.lean_law(0.0, 0.1, 0.2)
    ctl.follow_speed(5.2)
    slow = ctl.target(0.0)[1], ctl.lean_law(0.0, 0.1, 0.2)
    assert slow[0] == ctl.feasible_lean(W, TM) < fast[0] - math.radians(2)
    # The float law keeps the ellipse per beta; the array law asks the table each time.
    assert slow[1] == ctl.lean_law(0.0, np.array([0.1]), np.array([0.2]))[0] != fast[1]


def test_a_body_at_another_speed_is_the_replaced_body():
    """``BodyParams.at_speed`` (the controller follows the speed every step on terrain) is
    ``replace(body, V_cm=...)``: equal, same hash, same ``J``, and its speed is checked."""
    from dataclasses import replace
    body = preset("cyclist").body
    fast = body.at_speed(13.7)
    assert fast == replace(body, V_cm=13.7) and hash(fast) == hash(replace(body, V_cm=13.7))
    assert fast.J == replace(body, V_cm=13.7).J and body.V_cm != 13.7
    with pytest.raises(ValueError, match="V_cm"):
        body.at_speed(-1.0)


def test_a_stage_takes_the_rows_equilibrium_only_with_its_derivatives():
    """The step's first stage reuses the equilibrium lean the row's ``lean`` found when it is
    given the row's own derivatives; a stage elsewhere (other derivatives, or none) finds its
    own."""
    slope = ski_slope(length=120.0, width=120.0, cell=2.0)
    ctl = PhaseEllipse(BODY, W, TM, heading=-math.pi / 2 + 0.4)
    ctl.begin_run(SKIER.limits)
    rhs = TerrainStage(BODY, SKIER.limits, RESISTANCE["skier"], slope, ctl)
    here, there = (3.0, -7.0, -1.2), (20.0, 11.0, -1.9)
    rhs.lean(0.5, *here, 0.1, rhs.derivatives(*here[:2]))
    own = rhs.stage(0.5, *there, 0.1, 0.3, 9.0, None, 0.01)
    assert rhs.stage(0.5, *there, 0.1, 0.3, 9.0, None, 0.01, rhs.derivatives(*there[:2])) == own
    dv = rhs.derivatives(*there[:2])
    rhs.lean(0.5, *there, 0.1, dv)
    assert rhs.stage(0.5, *there, 0.1, 0.3, 9.0, None, 0.01, dv) == own
