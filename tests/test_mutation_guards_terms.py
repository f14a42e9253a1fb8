"""Guards for physics terms in modules the other tests leave loose (scripts/mutate.py,
TESTING.md)."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import OpenLoop, PhaseEllipse, Schedule, preset, simulate, slalom_start
from blender_turning.core.controllers.ellipse_paper import (SLOW_FACTOR, paper_alpha,
                                                             paper_alpha_one)
from blender_turning.core.controllers.straight import Straight
from blender_turning.core.physics.dynamics import foot_speed
from blender_turning.core.physics.grip import SNOW
from blender_turning.core.physics.model import NO_RESISTANCE, RESISTANCE, plumb_lean
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.planner import PlannerSettings, Problem
from blender_turning.core.planner import terrain_problem
from blender_turning.core.planner.speed_cap import SpeedCap
from blender_turning.core.planner.terrain_problem import steepest_sine
from blender_turning.core.ground.terrain import Plane, surface_frame
from blender_turning.core.ground.terrain_gen import ski_slope


# -- the open-loop law (Section 4, Eq. 5: alpha_v = -omega0^2 theta_max sin(omega0 t)) ----------

@pytest.mark.parametrize("period, lean_deg", [(3.0, 10.0), (2.0, 20.0)])
def test_open_loop_lean_is_the_closed_form_sine_to_rk4_order(period, lean_deg):
    """From ``(theta_v, omega_v) = (0, omega0 theta_max)`` Eq. (5) integrates to ``theta_v =
    theta_max sin(omega0 t)`` exactly; the stepper's RK4 must reproduce it to 4th order, so the
    demand has to be evaluated at each RK4 stage's own time (not frozen at the step's start)."""
    fig = preset("skier")
    w, tm = 2 * math.pi / period, math.radians(lean_deg)
    err = []
    for dt in (0.02, 0.01):
        tr = simulate(fig, OpenLoop(fig.body, w, tm), 4 * period, dt, state0=(0, 0, 0, 0, w * tm))
        err.append(np.max(np.abs(tr.theta_v - tm * np.sin(w * tr.t))))
    # Measured: 4.7e-9 / 2.9e-10 rad (3 s, 10 deg) and 4.7e-8 / 3.0e-9 rad (2 s, 20 deg): the
    # ratio 16 of a 4th-order method.  A demand frozen over a step is 1st order (~1e-3 rad).
    assert err[0] < 2e-7
    assert err[0] / err[1] > 10.0


def test_open_loop_phase_is_the_integral_of_a_varying_omega0():
    """With ``omega0(t)`` a schedule the phase is ``int omega0 dt``: for a linear ramp
    ``omega0 = w0 + a t`` it is ``w0 t + a t^2 / 2``, which the trapezoid rule gives exactly."""
    body = preset("skier").body
    w0, a, tm, dt = 2.0, 0.1, 0.2, 0.02
    ctl = OpenLoop(body, Schedule.sampled([0.0, 100.0], [w0, w0 + 100.0 * a]), tm)
    state = np.zeros(5)
    worst = 0.0
    for k in range(500):
        ctl.begin_step(k * dt, state)
        for tau in (0.0, 0.5 * dt, dt):
            t = k * dt + tau
            phi = w0 * t + 0.5 * a * t * t
            want = -(w0 + a * t) ** 2 * tm * math.sin(phi)
            worst = max(worst, abs(ctl.lean_law(t, 0.0, 0.0) - want))
    # Exact up to round-off (10 s of phase summed in 500 steps: ~1e-13 rad); a left-rectangle
    # phase is a dt t / 2 = 0.01 rad behind at 10 s, an alpha error of ~1e-2 rad/s^2.
    assert worst < 1e-9


# -- the paper's phase-ellipse law (Section 5.1, Eqs. 3 and 5) -----------------------------------

def _ellipse_states(w, tm, r, n=72):
    phi = (np.arange(n) + 0.5) * (2 * math.pi / n)          # off the axes
    return r * tm * np.sin(phi), r * w * tm * np.cos(phi)


@pytest.mark.parametrize("w, tm", [(2.5, 0.35), (1.2, 0.15)])
def test_paper_law_on_the_target_ellipse_is_eq5(w, tm):
    """On the target ellipse both families of controlling ellipse are the target itself, so
    the demand is Eq. (5)'s ``alpha_v = -omega0^2 theta_v`` in all four quadrants."""
    th, om = _ellipse_states(w, tm, 1.0)
    amax = 1e3                                               # never clips here
    want = -w * w * th
    np.testing.assert_allclose(paper_alpha(th, om, tm, w, amax), want, rtol=1e-9, atol=1e-12)
    one = [paper_alpha_one(float(a), float(b), tm, w, amax) for a, b in zip(th, om)]
    np.testing.assert_allclose(one, want, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("r", [0.6, 0.9, 1.05])
def test_paper_law_follows_the_ellipse_through_the_state(r):
    """Off the target, Q1/Q3 (``theta_v omega_v > 0``) follow the Fig. 7a ellipse through the
    state with the lean intercept ``theta_max``: ``alpha_v = -omega_v^2 theta_v / (theta_max^2 -
    theta_v^2)``; Q2/Q4 the Fig. 7b ellipse with the rate intercept ``omega0 theta_max``:
    ``alpha_v = -(omega0 theta_max)^2 (1 - x^2) / theta_v``.  (Both are ``-omega0'^2 theta_v`` on
    their ellipse.)  Checked where that family exists (``|y| < 1``, resp. ``|x| < 1``) and a Fig.
    7a ellipse is not ``SLOW_FACTOR`` times slower than the target (there the module's rule
    beyond the paper switches family)."""
    w, tm = 2.0, 0.3
    th, om = _ellipse_states(w, tm, r)
    x, y = om / (w * tm), th / tm
    w13_sq = om * om / (tm * tm - th * th)
    a13 = -w13_sq * th
    a24 = -(w * tm) ** 2 * (1 - x * x) / th
    q13 = th * om > 0
    fig7a = q13 & (np.abs(y) < 1) & (w13_sq * SLOW_FACTOR ** 2 >= w * w)
    fig7b = ~q13 & (np.abs(x) < 1)
    assert np.count_nonzero(fig7a) >= 8 and np.count_nonzero(fig7b) >= 8
    amax = 1e3
    got = paper_alpha(th, om, tm, w, amax)
    one = np.array([paper_alpha_one(float(a), float(b), tm, w, amax) for a, b in zip(th, om)])
    for k, want in ((fig7a, a13), (fig7b, a24)):
        np.testing.assert_allclose(got[k], want[k], rtol=1e-9)
        np.testing.assert_allclose(one[k], want[k], rtol=1e-9)


# -- the free-speed planner's run-away limit (planner/terrain_problem.py, Eq. 21) ---------------

def _free_problem(slope_deg, resistance=NO_RESISTANCE, speed_cap=None):
    fig = preset("skier", V_cm=8.0)
    fig = replace(fig, limits=replace(fig.limits, dC_f_max=0.3))
    path = PathDistance(HermitePath.from_polyline([[0, 0], [40, 0]]), 12)
    st = PlannerSettings(n_stages=4, q=4, theta_bound=math.radians(40))
    ground = Plane(math.radians(slope_deg))
    return Problem(fig, path, Obstacles(), st, ground=ground, resistance=resistance,
                   speed_cap=speed_cap), ground


def test_run_away_limit_bounds_a_straight_run_down_the_fall_line():
    """A straight run (``C_f = 0``, upright down the fall line) with nothing slowing it gains
    ``g sin sigma`` a second: ``V(T) = V_0 + g sin sigma T`` (docs/TERRAIN.md).  Over the time a
    search simulates no branch is clipped as a run-away for that, so the limit is at least it."""
    p, ground = _free_problem(30.0)
    st = p.settings
    T = st.horizon + st.t_stage
    tr = simulate(p.figure, Straight(p.body), T, 0.01, state0=(0, 0, 0, 0, 0, 8.0),
                  ground=ground, resistance=NO_RESISTANCE)
    closed = 8.0 + p.body.g * math.sin(ground.slope) * tr.t[-1]
    assert tr.V_cm[-1] == pytest.approx(closed, rel=1e-12)   # RK4 exact on a linear rate
    # Measured: the limit 17.7 m/s, the run 15.36 m/s; without the gravity term 9.1 m/s.
    assert p.v_max >= closed


def test_run_away_limit_includes_eq21_at_the_lean_bound():
    """A branch at the lean bound and the largest curvature moves its foot at ``V / (1 - C_f l
    sin theta_v)`` (Eq. 21): faster than the body.  On a gentle slope (1 deg: the speed gains
    only 0.26 m/s in a search) the limit must still cover that (measured: foot 8.96 m/s at
    8 m/s, limit 9.39 m/s; without Eq. 21 8.26 m/s)."""
    p, _ = _free_problem(1.0)
    V_f = foot_speed(p.body, p.settings.theta_bound, p.limits.C_f_max, V_cm=p.V0)
    assert V_f > p.V0 * 1.1
    assert p.v_max >= V_f


@pytest.mark.parametrize("slope_deg, downhill_deg", [(18.0, 0.0), (35.0, 125.0)])
def test_steepest_sine_of_a_plane_is_its_steepest_descent(slope_deg, downhill_deg):
    """``|t_z|`` over all headings on a plane peaks down the fall line at ``sin sigma``: the
    module says it is exact there (a tangent would loosen the run-away limit)."""
    ground = Plane(math.radians(slope_deg), math.radians(downhill_deg))
    heads = np.linspace(-math.pi, math.pi, 7201)
    fr = surface_frame(ground, np.zeros_like(heads), np.zeros_like(heads), heads, 9.81)
    steepest = np.max(np.abs(fr.g_along)) / 9.81
    # The heading grid is 0.05 deg: the peak is missed by at most 1 - cos(0.025 deg) ~ 1e-7.
    assert steepest_sine(ground) == pytest.approx(steepest, rel=1e-6)


def test_planner_brake_at_the_foot_pulls_the_speed_to_the_cap_at_its_rate():
    """Above the cap the planner brakes at the foot for ``dV/dt = -(V - cap) / tau`` where the
    grip allows (docs/skidding.md): the brake ``b`` (a force over the mass at the foot) does
    work at the foot's speed, ``m V dV = -m b V_f dt``, so it slows the body by ``b V_f / V``.
    Turning states (``V_f / V`` = 1.03-1.06 here) just over the cap: the rate is exact to
    round-off; charged at the body's speed it would be 3-6% off."""
    cap = SpeedCap(9.0, SNOW["hard"])
    p, _ = _free_problem(19.0, RESISTANCE["skier"], cap)
    x = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.3, -0.2], [0.3, 0.4, -0.35],
                  [0.2, 0.0, -0.1], [9.2, 9.5, 9.1]])
    out = np.zeros((6, 3))
    _, _, V_f = terrain_problem.rhs(p, x, 0.0, np.array([0.1, 0.15, -0.12]), np.zeros(3), None,
                                    0.0, out)
    assert np.all(V_f / x[5] > 1.02)
    np.testing.assert_allclose(out[5], -(x[5] - 9.0) / cap.tau, rtol=1e-9)


# -- the free-speed stepper (core/physics/terrain_sim.py) ------------------------------------------

def test_distance_travelled_is_the_foot_paths_length_on_a_plane():
    """``s`` is the distance along the surface the foot covers: the integral of the foot's
    speed ``V_f = V_cm / (1 - C_f l sin theta_v)`` (Eq. 21), so it equals the length of the foot
    path ``(x, y, z)``.  Measured on a 10 s fall-line slalom on an 18 deg plane: within 2.8e-5
    of the polyline through the samples (its chords are that much short at dt 0.02 s; 7e-6 at
    0.01 s); the body's speed is 0.6% slower than the foot's here."""
    fig = preset("skier")
    w, tm, course = math.pi, math.radians(23), -math.pi / 2
    ctl = PhaseEllipse(fig.body, w, tm, heading=course)
    tr = simulate(fig, ctl, 10.0, 0.02, slalom_start(fig.body, w, tm, course, 0.0, 0.0),
                  ground=Plane(math.radians(18), course), resistance=RESISTANCE["skier"])
    chords = np.sqrt(np.diff(tr.x) ** 2 + np.diff(tr.y) ** 2 + np.diff(tr.z) ** 2)
    path = np.concatenate([[0.0], np.cumsum(chords)])
    assert np.max(np.abs(tr.s - path)) < 2e-4 * path[-1]


def test_a_fall_is_the_lean_from_the_plumb_lean():
    """The fall bound is on the lean from the plumb lean (the balance of a straight run, docs/
    TERRAIN.md Section 2), not from the surface normal: a straight traverse of a 30 deg plane
    stands at its plumb lean of ~30 deg uphill, so with ``theta_fall`` 20 deg it runs on,
    balanced, for the whole run."""
    fig = preset("skier")
    fig = replace(fig, limits=replace(fig.limits, theta_fall=math.radians(20)))
    plane = Plane(math.radians(30), -math.pi / 2)
    lean = plumb_lean(surface_frame(plane, 0.0, 0.0, 0.0, fig.body.g))
    assert lean > math.radians(25)
    tr = simulate(fig, Straight(fig.body), 3.0, 0.01, state0=(0, 0, 0, lean, 0, 10.0),
                  ground=plane, resistance=NO_RESISTANCE)
    assert tr.t[-1] == pytest.approx(3.0)
    # Held to round-off (an unstable equilibrium): measured within 1e-12 rad.
    assert np.max(np.abs(tr.theta_v - lean)) < 1e-9


def test_the_demo_slope_falls_at_its_angle():
    """``ski_slope(slope_deg=18)`` is an 18 deg plane under its rolls: over 1980 m of fall line
    the mean grade is ``tan 18 deg`` = 0.3249 (a rise over a run), within what the two rolls
    (each at most 2 m high) can add at the ends, 4 m / 1980 m = 2e-3 (measured 5.7e-4);
    ``sin 18 deg`` would be 0.016 off."""
    field = ski_slope(length=2000.0, width=20.0, cell=5.0, moguls=False)
    top, bottom = (float(field.derivatives(np.zeros(1), np.array([y]))[0][0])
                   for y in (990.0, -990.0))
    assert abs((top - bottom) / 1980.0 - math.tan(math.radians(18.0))) < 4.0 / 1980.0
