"""Sections 4-5: open-loop turns, the phase-ellipse controller and directional control."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import (Limits, OpenLoop, PhaseEllipse, Schedule, preset, run,
                                  simulate, slalom_start)
from blender_turning.core.physics.dynamics import THETA_DIR, inverse_cf, rk4_step
from blender_turning.core.controllers.heading_table import heading_table
from blender_turning.core.controllers.phase import open_loop_alpha
from blender_turning.core.controllers.phase import ellipse_radius

TWO_PI = 2 * math.pi
FIG6 = [(2.0, 23.0), (3.0, 23.0), (2.0, 7.0)]        # the three ellipses of Fig. 6


def chord_headings(tr):
    """Direction of travel over each full turn: between successive upward zero crossings of
    theta_v (phase 0), the direction of the foot's displacement.  Returns (times, headings)."""
    th = tr.theta_v
    up = np.nonzero((th[:-1] < 0) & (th[1:] >= 0))[0]
    f = -th[up] / (th[up + 1] - th[up])                  # linear interpolation of the crossing
    t = tr.t[up] + f * (tr.t[up + 1] - tr.t[up])
    x = tr.x[up] + f * (tr.x[up + 1] - tr.x[up])
    y = tr.y[up] + f * (tr.y[up + 1] - tr.y[up])
    return t[1:], np.arctan2(np.diff(y), np.diff(x))


@pytest.mark.parametrize("period,lean", FIG6)
def test_open_loop_tracks_the_sinusoid(skier_unbounded, period, lean):
    w, tm = TWO_PI / period, math.radians(lean)
    tr = simulate(skier_unbounded, OpenLoop(skier_unbounded.body, w, tm), 10 * period,
                  state0=(0, 0, 0, 0, w * tm))
    err = np.abs(tr.theta_v - tm * np.sin(w * tr.t)).max()
    # RK4 at 0.02 s: measured 7.8e-6 deg (2 s / 23 deg), 1.5e-6 and 2.4e-6 deg; O(dt^4).
    assert math.degrees(err) < 3e-5


@pytest.mark.parametrize("period,lean", FIG6)
def test_symmetric_slalom_does_not_drift(skier_unbounded, period, lean):
    w, tm = TWO_PI / period, math.radians(lean)
    fig = skier_unbounded
    tr = simulate(fig, OpenLoop(fig.body, w, tm), 10 * period,
                  state0=slalom_start(fig.body, w, tm))
    _, heads = chord_headings(tr)
    drift = np.degrees(heads[-1] - heads[0]) / (len(heads) - 1)
    # Measured 9.1e-6, 2.6e-6, 2.4e-6 deg per period (RK4 at 0.02 s; Euler drifts ~1.7 deg).
    assert abs(drift) < 3e-5
    # Centred by the heading table's half-turn swing (bilinear, <= 7.5e-4 relative): measured
    # -0.0092, -0.0072, -0.0025 deg.
    assert abs(math.degrees(heads.mean())) < 0.03


def test_simulation_is_mirror_symmetric(skier):
    w, tm = TWO_PI / 2, math.radians(20)
    s0 = (0.0, 0.0, 0.3, math.radians(5), 0.2)
    a = simulate(skier, PhaseEllipse(skier.body, w, tm, heading=0.2), 8.0, state0=s0)
    m0 = (0.0, 0.0, -0.3, -math.radians(5), -0.2)
    b = simulate(skier, PhaseEllipse(skier.body, w, tm, heading=-0.2), 8.0, state0=m0)
    for col in ("theta_v", "omega_v", "C_f", "theta_dir", "y", "alpha_v"):
        np.testing.assert_allclose(getattr(b, col), -getattr(a, col), atol=1e-9)
    np.testing.assert_allclose(b.x, a.x, atol=1e-9)
    np.testing.assert_allclose(b.F_leg, a.F_leg, rtol=1e-12)


STARTS = [(0, 0), (0, 30), (0, -40), (10, 0), (10, 30), (10, -40), (-10, 30), (-10, -40),
          (23, 0), (30, 0), (-30, 0), (35, -20), (-35, 20), (0, 150), (5, -120), (1, 1)]


@pytest.mark.parametrize("th0,om0", STARTS)
def test_ellipse_controller_converges_within_two_periods(skier, th0, om0):
    w, tm = TWO_PI / 2, math.radians(23)
    tr = simulate(skier, PhaseEllipse(skier.body, w, tm), 6.0,
                  state0=(0, 0, 0, math.radians(th0), math.radians(om0)))
    r = ellipse_radius(tr.theta_v, tr.omega_v, tm, w)
    after = tr.t >= 2 * 2.0
    # 2% of the ellipse's size is 0.46 deg of lean: the bounds' transients are long gone.
    assert np.abs(r[after] - 1).max() < 0.02
    lim = skier.limits
    assert np.abs(tr.C_f).max() <= lim.C_f_max * (1 + 1e-12)
    assert (np.abs(np.diff(tr.C_f)) / np.diff(tr.t)).max() <= lim.dC_f_max * (1 + 1e-9)


def test_controller_follows_a_mid_run_change_of_ellipse(skier):
    w1, tm1, w2, tm2 = TWO_PI / 2, math.radians(23), TWO_PI / 3, math.radians(15)
    w = Schedule(lambda t: w1 if t < 6 else w2)
    tm = Schedule(lambda t: tm1 if t < 6 else tm2)
    tr = simulate(skier, PhaseEllipse(skier.body, w, tm), 14.0,
                  state0=slalom_start(skier.body, w1, tm1))
    before = (tr.t > 2) & (tr.t < 6)
    after = tr.t > 6 + 2 * 3.0
    assert np.abs(ellipse_radius(tr.theta_v, tr.omega_v, tm1, w1)[before] - 1).max() < 0.02
    assert np.abs(ellipse_radius(tr.theta_v, tr.omega_v, tm2, w2)[after] - 1).max() < 0.02


@pytest.mark.parametrize("change_deg", [5, -5, 10, -10])
def test_heading_change_is_met(skier, change_deg):
    w, tm = TWO_PI / 2, math.radians(23)
    head = Schedule(lambda t: 0.0 if t < 4 else math.radians(change_deg))
    tr = simulate(skier, PhaseEllipse(skier.body, w, tm, heading=head), 14.0,
                  state0=slalom_start(skier.body, w, tm))
    t, h = chord_headings(tr)
    assert np.abs(np.degrees(h[t < 4])).max() < 0.5
    # The modified half-turn starts at the first crossing after 4 s; from the turn after that
    # the heading holds the new value.
    done = t > 4 + 2 * 2.0
    assert done.sum() >= 2
    assert np.abs(np.degrees(h[done]) - change_deg).max() < 0.5


def test_unreachable_heading_change_is_spread_over_turns(skier):
    w, tm = TWO_PI / 2, math.radians(23)
    tr = simulate(skier, PhaseEllipse(skier.body, w, tm, heading=math.radians(60)), 30.0,
                  state0=slalom_start(skier.body, w, tm))
    assert np.all(np.isfinite(tr.data))
    t, h = chord_headings(tr)
    assert abs(math.degrees(h[-1]) - 60) < 0.5


def simulate_half_turns(body, theta_max, omega0, steps=400):
    """Heading change over one half-turn (phase 0 -> 180 deg) of the open-loop law, simulated
    (RK4, no bounds): the independent check of the closed form in core/controllers/heading_table.py."""
    th, w = np.broadcast_arrays(np.asarray(theta_max, float), np.asarray(omega0, float))
    state = np.zeros((5, th.size))
    state[4] = w * th
    dt, t = (np.pi / w) / steps, np.zeros(th.size)

    def desired(tt, s):
        return inverse_cf(body, s[3], open_loop_alpha(w * tt, th, w))

    for _ in range(steps):
        state = rk4_step(body, Limits(), state, t, dt, desired, None)
        t = t + dt
    return state[THETA_DIR]


@pytest.mark.parametrize("name,speed,top", [("skier", 10.0, 60), ("cyclist", 6.0, 60),
                                            ("skier", 0.5, 10), ("snowboarder", 30.0, 60)])
def test_heading_table_matches_direct_simulation(name, speed, top):
    """The closed form dtheta_dir = theta_max (g A / (V omega0) + omega0 J B / V) against
    simulated half-turns, from 0.05 deg (below the old table's 0.5 deg edge) to 60 deg and at
    0.5 m/s (where the old simulated table held NaN; there the simulation itself fails beyond
    ~10 deg, where 1 - C_f l sin th -> 0 makes V_f stiff).  RK4 with 400 steps is good to ~5e-8,
    the interpolated lean factors to ~2e-6."""
    body = replace(preset(name).body, V_cm=speed)
    rng = np.random.default_rng(3)
    th = np.radians(np.concatenate([[0.05, 0.2, 0.45, 1.0, 3.0], rng.uniform(3, top, 35)]))
    w = TWO_PI / rng.uniform(0.5, 12.0, 40)
    got = heading_table(body)(th, w)
    assert np.all(np.isfinite(got))
    np.testing.assert_allclose(got, simulate_half_turns(body, th, w), rtol=3e-6)


def test_half_turn_change_matches_eqs_9_and_10_for_small_leans():
    """Independent of the table machinery: for a small lean, Eqs. (9)-(10) integrate to
    dtheta_dir = 2 theta_max (g + omega0^2 J) / (V_cm omega0) (V_f ~ V_cm); the neglected terms
    are O(theta_max^2) and C_f l sin(theta_v): about 1e-4 relative at 1 deg."""
    body = preset("skier").body
    th = np.radians([0.5, 1.0, 1.0, 1.0])
    w = TWO_PI / np.array([2.0, 2.0, 4.0, 1.2])
    expect = 2 * th * (body.g + w * w * body.J) / (body.V_cm * w)
    np.testing.assert_allclose(simulate_half_turns(body, th, w), expect, rtol=3e-4)   # 9.4e-5


def test_leg_force_relative_variation_is_independent_of_mass_and_speed():
    base = replace(preset("skier"), limits=Limits(theta_fall=math.radians(80)))
    w, tm = TWO_PI / 2, math.radians(23)
    rel = []
    for scale, speed in ((1.0, 10.0), (1.6, 10.0), (1.0, 16.0), (0.7, 6.0)):
        body = replace(base.body, m=75 * scale, I_v=12 * scale, V_cm=speed)
        fig = replace(base, body=body)
        tr = simulate(fig, OpenLoop(body, w, tm), 4.0, state0=(0, 0, 0, 0, w * tm))
        rel.append(tr.F_leg / (body.m * body.g))
    for r in rel[1:]:
        np.testing.assert_allclose(r, rel[0], rtol=1e-9)
    assert 0.1 < rel[0].max() - rel[0].min() < 0.8      # the paper's ~+-30% swing


def test_batch_equals_single_runs(skier):
    w, tm = TWO_PI / 2, math.radians(23)
    starts = np.array([[0, 0, 0, 0, w * tm], [1, 2, 0.5, 0.1, 0.0], [0, 0, -0.2, -0.2, 0.3]]).T
    batch = run(skier.body, skier.limits, PhaseEllipse(skier.body, w, tm, heading=0.1),
                starts, 6.0)
    for j in range(3):
        one = run(skier.body, skier.limits, PhaseEllipse(skier.body, w, tm, heading=0.1),
                  starts[:, j], 6.0)
        for k in ("x", "y", "theta_dir", "theta_v", "C_f", "phi", "F_leg"):
            np.testing.assert_allclose(batch.columns[k][:, j], one.columns[k], atol=1e-10)


def test_fall_is_reported(skier):
    from blender_turning.core import FellOver
    with pytest.raises(FellOver) as e:
        simulate(skier, PhaseEllipse(skier.body, TWO_PI / 2, math.radians(23)), 5.0,
                 state0=(0, 0, 0, math.radians(40), math.radians(150)))
    assert e.value.t < 1.0 and len(e.value.trajectory) > 1


def test_paper_law_is_continuous_across_the_target():
    """The paper's law (law="paper") with this project's extension across the target ellipse."""
    from blender_turning.core.controllers.ellipse_paper import paper_alpha as ellipse_alpha
    w, tm = TWO_PI / 2, math.radians(23)
    amax = 2 * w * w * tm
    phi = np.linspace(0.01, TWO_PI - 0.01, 997)
    phi = phi[np.abs(np.sin(2 * phi)) > 0.05]            # off the axes (quadrant boundaries)
    # Both laws are ill-conditioned near the axes (the Fig. 7a one by 1 / cos^2 phi near the apex),
    # so the two sides are 1e-10 apart: a jump would show, the conditioning does not.
    eps = 1e-10
    a_in = ellipse_alpha((1 - eps) * tm * np.sin(phi), (1 - eps) * w * tm * np.cos(phi), tm, w,
                         amax)
    a_out = ellipse_alpha((1 + eps) * tm * np.sin(phi), (1 + eps) * w * tm * np.cos(phi), tm,
                          w, amax)
    # On the ellipse both families give Eq. (5): alpha = -omega0^2 theta_v.
    np.testing.assert_allclose(a_in, -w * w * tm * np.sin(phi), atol=1e-5 * amax)
    np.testing.assert_allclose(a_out, a_in, atol=1e-5 * amax)
    # (Floats and arrays agree: tests/test_one_figure.py, on every branch boundary too.)


def test_closed_loop_converges_with_the_step(skier):
    """On the ellipse the law is continuous, so RK4 converges: over 15 turns dt = 0.02 s stays
    within 0.3 deg of dt = 0.005 s.  (With the paper's +-alpha_max right outside the ellipse the
    apexes chattered and the two drifted apart by 1.4 deg in 10 s.)  Transients through the C_f
    and alpha_v clamps are not smooth and leave an O(dt) phase offset, so the start is on it."""
    w, tm = TWO_PI / 2, math.radians(23)
    fine = simulate(skier, PhaseEllipse(skier.body, w, tm), 30.0, dt=0.005)
    coarse = simulate(skier, PhaseEllipse(skier.body, w, tm), 30.0, dt=0.02)
    assert math.degrees(np.abs(coarse.theta_v - fine.theta_v[::4]).max()) < 0.3


@pytest.mark.parametrize("name", ["omega0", "theta_max"])
def test_a_schedule_set_on_the_controller_is_the_one_its_lean_law_follows(name):
    """The float lean law keeps the ellipse per beta while the schedules are constant; giving the
    controller another schedule (as the grip and skidding do) makes the law follow it at once,
    equal to the array law asked the same."""
    fig = preset("skier")
    w, tm = 2 * math.pi / 2.0, math.radians(23)
    ctl = PhaseEllipse(fig.body, w, tm)
    ctl.begin_run(fig.limits)
    before = ctl.lean_law(0.0, 0.1, 0.2)
    setattr(ctl, name, Schedule.constant(0.7 * (w if name == "omega0" else tm)))
    after = ctl.lean_law(0.0, 0.1, 0.2)
    assert after == ctl.lean_law(0.0, np.array([0.1]), np.array([0.2]))[0]
    assert abs(after - before) > 0.03                   # measured: 0.050 and 0.239 rad/s^2
