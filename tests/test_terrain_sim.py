"""Simulation on terrain through the ``simulate`` API: closed forms, reduction to
today's model, mirror symmetry, the phase-ellipse slalom down a mogul slope, speed control by
turning, frame output on terrain (docs/TERRAIN.md)."""
import math

import numpy as np
import pytest

from blender_turning.core import PhaseEllipse, Trajectory, preset, simulate, slalom_start
from blender_turning.core.controllers import Straight
from blender_turning.core.errors import FellOver, LeftTerrain, Stopped
from blender_turning.core.ground.terrain import FLAT, HeightField, Plane, surface_frame
from blender_turning.core.physics.model import RESISTANCE, Resistance, plumb_lean
from blender_turning.core.ground.terrain_gen import ski_slope
from blender_turning.core.controllers.braking import TargetSpeed
from blender_turning.core.physics.model import NO_RESISTANCE

SKIER = preset("skier")
BODY = SKIER.body
W, TM = math.pi, math.radians(23)               # the 2 s / 23 deg turn
STATE = ("x", "y", "theta_dir", "theta_v", "omega_v", "alpha_v", "C_f", "V_f", "F_leg", "phi")


def _slalom(heading=0.0, x=0.0, y=0.0):
    return PhaseEllipse(BODY, W, TM, heading=heading), slalom_start(BODY, W, TM, heading, x, y)


def test_flat_ground_without_resistance_is_todays_path_bit_for_bit():
    ctl, s0 = _slalom()
    today = simulate(SKIER, ctl, 20.0, 0.02, s0)
    ctl, _ = _slalom()
    same = simulate(SKIER, ctl, 20.0, 0.02, s0, ground=FLAT, resistance=NO_RESISTANCE)
    np.testing.assert_array_equal(same.data, today.data)
    assert np.all(today.z == 0.0) and np.all(today.V_cm == BODY.V_cm)
    # With friction the speed is free on zero slope too (docs/TERRAIN.md Section 4).
    ctl, _ = _slalom()
    slowed = simulate(SKIER, ctl, 2.0, 0.02, s0, ground=FLAT, resistance=RESISTANCE["skier"])
    assert slowed.V_cm[-1] < BODY.V_cm - 0.5 and slowed.meta["ground"] == "flat"


def test_straight_run_down_the_fall_line_through_simulate():
    """``V = V_T tanh(sqrt(A k) t + atanh(V0 / V_T))`` and the energy balance (TERRAIN.md 3-4)."""
    sigma, D = math.radians(18), math.radians(-70)
    res = RESISTANCE["skier"]
    A = BODY.g * (math.sin(sigma) - res.mu * math.cos(sigma))
    k = res.drag_k(BODY.m)
    V_T, V0, dt = math.sqrt(A / k), 2.0, 0.01
    traj = simulate(SKIER, Straight(BODY), 30.0, dt, (0, 0, D, 0, 0, V0),
                    ground=Plane(sigma, D), resistance=res)
    V = V_T * np.tanh(math.sqrt(A * k) * traj.t + math.atanh(V0 / V_T))
    np.testing.assert_allclose(traj.V_cm, V, rtol=1e-6)
    assert traj.V_cm[-1] > 0.9 * V_T
    np.testing.assert_array_equal(traj.C_f, 0.0)
    np.testing.assert_allclose(traj.theta_dir, D, atol=1e-15)
    # Energy: the drop (the z column) is the kinetic energy gained plus friction and drag work.
    N = BODY.m * BODY.g * math.cos(sigma)
    power = res.mu * N * traj.V_cm + BODY.m * k * traj.V_cm ** 3
    work = dt / 3 * (power[0] + power[-1] + 4 * power[1:-1:2].sum() + 2 * power[2:-1:2].sum())
    drop = BODY.m * BODY.g * (traj.z[0] - traj.z[-1])
    assert drop == pytest.approx(0.5 * BODY.m * (traj.V_cm[-1] ** 2 - V0 ** 2) + work, rel=1e-6)
    # The foot's distance is along the surface: the drop is s sin(sigma).
    assert traj.z[0] - traj.z[-1] == pytest.approx(traj.s[-1] * math.sin(sigma), rel=1e-6)


@pytest.mark.parametrize("beta_deg", [30, 90, -60])
def test_plumb_traverse_through_simulate(beta_deg):
    """Started at the plumb lean ``atan(tan sigma |sin beta|)`` uphill, ``C_f = 0`` holds the
    heading and the lean for 2 s to 1e-6 rad."""
    sigma, D = math.radians(30), math.radians(15)
    beta = math.radians(beta_deg)
    heading = D + math.atan2(math.sin(beta), math.cos(beta) * math.cos(sigma))
    theta0 = math.copysign(math.atan(math.tan(sigma) * abs(math.sin(beta))), math.sin(beta))
    traj = simulate(SKIER, Straight(BODY), 2.0, 0.01, (0, 0, heading, theta0, 0, 5.0),
                    ground=Plane(sigma, D), resistance=RESISTANCE["skier"])
    np.testing.assert_allclose(traj.theta_dir, heading, atol=1e-6)
    np.testing.assert_allclose(traj.theta_v, theta0, atol=1e-6)
    # The plumb lean is the one the controllers oscillate about.
    fr = surface_frame(Plane(sigma, D), traj.x, traj.y, traj.theta_dir, BODY.g)
    np.testing.assert_allclose(plumb_lean(fr), theta0, atol=1e-12)


def test_mirror_across_the_fall_line():
    """A slalom along a traverse and its mirror image across the fall line (here the x axis)."""
    plane = Plane(math.radians(20), 0.0)
    res = RESISTANCE["snowboarder"]
    fig = preset("snowboarder")
    body = fig.body
    heading = math.radians(35)
    a = simulate(fig, PhaseEllipse(body, W, TM, heading=heading), 12.0, 0.02,
                 slalom_start(body, W, TM, heading, 0.0, 1.0), ground=plane, resistance=res)
    x, y, d, th, om = slalom_start(body, W, TM, heading, 0.0, 1.0)
    b = simulate(fig, PhaseEllipse(body, W, TM, heading=-heading), 12.0, 0.02,
                 (x, -y, -d, -th, -om), ground=plane, resistance=res)
    assert np.abs(a.theta_v).max() > 0.3
    for name, sign in (("x", 1), ("y", -1), ("theta_dir", -1), ("theta_v", -1),
                       ("omega_v", -1), ("C_f", -1), ("V_cm", 1), ("z", 1)):
        np.testing.assert_allclose(getattr(b, name), sign * getattr(a, name), rtol=0,
                                   atol=1e-9, err_msg=name)


def _lean_about_plumb(traj, ground):
    fr = surface_frame(ground, traj.x, traj.y, traj.theta_dir, BODY.g)
    return traj.theta_v - plumb_lean(fr), plumb_lean(fr)


def test_slalom_down_a_mogul_slope_for_a_minute():
    """The phase-ellipse slalom down the fall line of the demo's 18 deg slope, through its
    mogul field: 60 s without falling (at the slope's terminal speed, ~27 m/s), the lean
    oscillating about the plumb lean, the mean heading on the fall line."""
    slope = ski_slope(length=1600.0, width=200.0, cell=2.0)
    fall = -math.pi / 2
    ctl, s0 = _slalom(fall, -40.0, 790.0)
    traj = simulate(SKIER, ctl, 60.0, 0.02, s0, ground=slope, resistance=RESISTANCE["skier"])
    late = traj.t >= 10.0
    assert traj.t[-1] == pytest.approx(60.0)
    assert np.mean((traj.x < -10) & (traj.y < -10)) > 0.3               # in the moguls
    assert traj.V_cm[-1] > 20.0                                         # it ran fast
    np.testing.assert_allclose(traj.z, slope.derivatives(traj.x, traj.y)[0], atol=1e-12)
    rel, _ = _lean_about_plumb(traj, slope)
    assert abs(np.mean(rel[late])) < math.radians(2)                    # measured 0.02 deg
    assert rel[late].max() > math.radians(15) and rel[late].min() < -math.radians(15)
    assert abs(np.mean(traj.theta_dir[late]) - fall) < math.radians(2)  # measured 0.05 deg


def test_traverse_slalom_oscillates_about_the_plumb_lean():
    """Across a plane the plumb lean is ~15 deg uphill: the slalom leans about it (not about the
    surface normal), and its mean heading is the commanded traverse."""
    plane = Plane(math.radians(18), -math.pi / 2)
    course = -math.pi / 2 + math.radians(60)
    ctl, s0 = _slalom(course)
    traj = simulate(SKIER, ctl, 30.0, 0.02, s0, ground=plane, resistance=RESISTANCE["skier"])
    late = traj.t >= 6.0
    rel, eq = _lean_about_plumb(traj, plane)
    assert np.mean(eq[late]) > math.radians(12)                         # uphill: left
    assert abs(np.mean(rel[late])) < math.radians(3)                    # measured 2.4 deg
    assert np.mean(traj.theta_v[late]) > math.radians(10)
    assert abs(np.mean(traj.theta_dir[late]) - course) < math.radians(3)  # measured 2.2 deg


def test_turn_shape_holds_while_the_speed_grows():
    """Down the fall line the speed grows from 10 to ~24 m/s; the turn keeps its commanded
    period (2 s) and lean (23 deg about the plumb lean)."""
    plane = Plane(math.radians(18), -math.pi / 2)
    ctl, s0 = _slalom(-math.pi / 2)
    traj = simulate(SKIER, ctl, 20.0, 0.02, s0, ground=plane, resistance=RESISTANCE["skier"])
    late = traj.t >= 4.0
    assert traj.V_cm[late].max() - traj.V_cm[late].min() > 8.0
    rel, _ = _lean_about_plumb(traj, plane)
    up = np.flatnonzero((rel[:-1] < 0) & (rel[1:] >= 0) & late[1:])
    assert len(up) >= 7
    np.testing.assert_allclose(np.diff(traj.t[up]), 2.0, atol=0.021)     # one step
    assert abs(rel[late]).max() == pytest.approx(TM, abs=math.radians(0.5))


def test_target_speed_brakes_by_turning_across_the_hill():
    """An 18 deg slope where the fall-line slalom runs away to ~27 m/s: with a target of 12 m/s
    the turns swing across the hill and the speed stays near the target."""
    plane = Plane(math.radians(18), -math.pi / 2)
    fall = -math.pi / 2
    ctl, s0 = _slalom(fall)
    free = simulate(SKIER, ctl, 60.0, 0.02, s0, ground=plane, resistance=RESISTANCE["skier"])
    ctl, _ = _slalom(fall)
    held = simulate(SKIER, ctl, 60.0, 0.02, s0, ground=plane, resistance=RESISTANCE["skier"],
                    target_speed=12.0)
    late = held.t >= 20.0
    assert free.V_cm[late].mean() > 25.0
    assert 10.0 < held.V_cm[late].mean() < 15.5          # measured 13.2 (14.1 before core/controllers/braking.py)
    assert held.V_cm[late].max() < 20.0                  # measured 18.0
    # It went down the hill, zig-zagging within the corridor (and a turn radius).
    assert held.y[-1] < -300.0
    assert np.abs(held.x).max() < TargetSpeed(12.0).corridor + 60.0
    assert held.x.max() > 40.0 and held.x.min() < -40.0
    assert ctl.heading(0.0) == fall                      # the controller's course is restored


def test_resample_on_terrain():
    """Frames on terrain: the samples come back, ``z`` is the ground at each row's (x, y), and
    a coarse run resampled matches a fine one."""
    slope = ski_slope(length=300.0, width=100.0, cell=2.0)
    fall = -math.pi / 2
    ctl, s0 = _slalom(fall, -20.0, 140.0)
    fine = simulate(SKIER, ctl, 8.0, 0.005, s0, ground=slope, resistance=RESISTANCE["skier"])
    with pytest.raises(ValueError, match="ground="):
        fine.resample(24)
    r = fine.resample(25, ground=slope)
    idx = np.round(r.t / 0.005).astype(int)
    for col in ("x", "y", "theta_dir", "theta_v", "omega_v", "V_cm", "s", "z"):
        np.testing.assert_allclose(getattr(r, col), getattr(fine, col)[idx], atol=1e-9,
                                   err_msg=col)
    coarse = Trajectory(fine.data[:, ::4], fine.meta).resample(24, ground=slope)
    ref = fine.resample(24, ground=slope)
    assert np.abs(coarse.theta_v - ref.theta_v).max() < 1e-4
    assert np.hypot(coarse.x - ref.x, coarse.y - ref.y).max() < 1e-3
    assert np.abs(coarse.V_cm - ref.V_cm).max() < 1e-3       # measured 2e-4 m/s, at a kink
    np.testing.assert_allclose(coarse.z, slope.derivatives(coarse.x, coarse.y)[0], atol=1e-12)


def test_csv_round_trip_and_legacy_files(tmp_path):
    ctl, s0 = _slalom(-math.pi / 2)
    traj = simulate(SKIER, ctl, 3.0, 0.02, s0, ground=Plane(math.radians(10), -math.pi / 2),
                    resistance=RESISTANCE["skier"])
    traj.to_csv(tmp_path / "t.csv")
    np.testing.assert_array_equal(Trajectory.from_csv(tmp_path / "t.csv").data, traj.data)
    # A file from before terrain: flat, V_cm from Eq. (21) with the body.
    ctl, s0 = _slalom()
    flat = simulate(SKIER, ctl, 3.0, 0.02, s0)
    cols = flat.columns()
    legacy = "t,x,y,theta_dir,theta_v,omega_v,alpha_v,C_f,F_leg,phi,V_f,s"
    rows = [legacy] + [",".join(repr(float(cols[c][i])) for c in legacy.split(","))
                       for i in range(len(flat))]
    (tmp_path / "old.csv").write_text("\n".join(rows) + "\n")
    with pytest.raises(ValueError, match="body="):
        Trajectory.from_csv(tmp_path / "old.csv")
    back = Trajectory.from_csv(tmp_path / "old.csv", body=BODY)
    np.testing.assert_allclose(back.V_cm, BODY.V_cm, rtol=1e-14)
    assert np.all(back.z == 0.0)


def test_runs_that_end_early_say_why():
    flat = Plane(0.0, 0.0)
    with pytest.raises(Stopped, match="stopped") as e:
        simulate(SKIER, Straight(BODY), 60.0, 0.02, (0, 0, 0, 0, 0, 3.0), ground=flat,
                 resistance=Resistance(mu=0.2))
    assert e.value.trajectory.V_cm[-1] < 0.5 < e.value.trajectory.V_cm[0]
    xs = np.arange(-50.0, 51.0, 2.0)
    X, Y = np.meshgrid(xs, xs)
    slope = HeightField(Plane(math.radians(15), -math.pi / 2).derivatives(X, Y)[0], -50, -50, 2)
    with pytest.raises(LeftTerrain) as e:
        simulate(SKIER, Straight(BODY), 60.0, 0.02, (0, 40, -math.pi / 2, 0, 0, 5.0),
                 ground=slope)
    assert e.value.trajectory.y[-1] > -50.0
    with pytest.raises(FellOver):                         # upright on a traverse falls downhill
        simulate(SKIER, Straight(BODY), 10.0, 0.02, (0, 0, 0.0, 0, 0, 5.0),
                 ground=Plane(math.radians(25), -math.pi / 2))
    with pytest.raises(ValueError, match="heading"):
        simulate(SKIER, PhaseEllipse(BODY, W, TM), 1.0, 0.02, ground=flat, target_speed=5.0)
    with pytest.raises(ValueError, match="target_speed"):
        TargetSpeed(0.0)


def test_one_figure_float_path_is_the_array_path():
    """One figure is stepped on Python floats (``derivatives_one``, the frame's float branch):
    the same numbers as the array formulas, to round-off."""
    slope = ski_slope(length=200.0, width=200.0, cell=2.0)
    rng = np.random.default_rng(11)
    for ground in (slope, Plane(math.radians(25), 0.7, 1.0, -2.0, 3.0)):
        for _ in range(100):
            x, y, d = (float(v) for v in (rng.uniform(-99, 99), rng.uniform(-99, 99),
                                          rng.uniform(-4, 4)))
            np.testing.assert_allclose(ground.derivatives_one(x, y),
                                       [float(v) for v in ground.derivatives(x, y)],
                                       rtol=1e-13, atol=1e-13)
            one = surface_frame(ground, x, y, d, BODY.g)
            arr = surface_frame(ground, np.array(x), np.array(y), np.array(d), BODY.g)
            assert type(one.g_lateral) is float
            for a, b in zip(one, arr):
                np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-13)


def test_resample_a_terrain_csv_given_its_ground(tmp_path):
    """A CSV has no meta: given the ground, the resistance and the body, its frames are the
    ones the trajectory itself gives."""
    plane = Plane(math.radians(15), -math.pi / 2)
    res = RESISTANCE["skier"]
    ctl, s0 = _slalom(-math.pi / 2)
    traj = simulate(SKIER, ctl, 4.0, 0.02, s0, ground=plane, resistance=res)
    traj.to_csv(tmp_path / "t.csv")
    back = Trajectory.from_csv(tmp_path / "t.csv")
    want = traj.resample(30, ground=plane)
    got = back.resample(30, body=BODY, ground=plane, resistance=res)
    np.testing.assert_allclose(got.data, want.data, rtol=0, atol=1e-12)
    # Without the resistance the speed's slope is wrong between samples.
    wrong = back.resample(30, body=BODY, ground=plane)
    assert np.abs(wrong.V_cm - want.V_cm).max() > 1e-4


def test_flat_ground_at_a_height_is_todays_run_lifted():
    """A flat plane at z0 (the figure's start height in Blender): today's run, ``z = z0``."""
    ctl, s0 = _slalom()
    today = simulate(SKIER, ctl, 5.0, 0.02, s0)
    ctl, _ = _slalom()
    lifted = simulate(SKIER, ctl, 5.0, 0.02, s0, ground=Plane(z0=2.0))
    np.testing.assert_array_equal(lifted.z, 2.0)
    cols = [c for c in today.columns() if c != "z"]
    for c in cols:
        np.testing.assert_array_equal(getattr(lifted, c), getattr(today, c), err_msg=c)
