"""Guards for physics mutants that the rest of the suite let through.

Each test checks a relation derived independently of the code it guards (Newton's law on the
centre of mass, the foot path's geometric curvature, the mirror symmetry of the model, closed
forms), so a dropped term, a flipped sign or a loosened bound shows.  The planner's and the
obstacles' guards are in ``test_mutation_guards_planner.py``.
``scripts/mutate.py`` holds the mutants these tests are meant to catch; docs/ARCHITECTURE.md
Section 4 the sign conventions.
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import FellOver, Limits, OpenLoop, Trajectory, preset, run, simulate
from blender_turning.core.physics.dynamics import bound_cf, foot_speed, leg_force

TWO_PI = 2 * math.pi


def unbounded(name="skier", **body):
    fig = preset(name, **body)
    return replace(fig, limits=Limits(theta_fall=math.radians(80)))


def open_loop_run(fig, period=2.0, lean_deg=23.0, duration=6.0, dt=0.002):
    w, tm = TWO_PI / period, math.radians(lean_deg)
    return simulate(fig, OpenLoop(fig.body, w, tm), duration, dt=dt, state0=(0, 0, 0, 0, w * tm))


def cm_path(tr, body):
    """Centre of mass in the world: the foot plus ``l`` along the leaned leg (Fig. 2), (3, n)."""
    th, d = tr.theta_v, tr.theta_dir
    return np.vstack([tr.x - body.l * np.sin(th) * np.sin(d),
                      tr.y + body.l * np.sin(th) * np.cos(d),
                      body.l * np.cos(th)])


# -- Appendix A: the leg force is Newton's law on the centre of mass -----------------------------
@pytest.mark.parametrize("name", ["skier", "cyclist", "snowboarder"])
def test_leg_force_is_newtons_law_on_the_centre_of_mass(name):
    """``F_leg`` (Eqs. 14-18) equals ``m |a_cm + g z|`` in the plane across the direction of
    travel, ``a_cm`` by second differences of the centre of mass's path.  The model holds V_cm
    constant (Section 3), so the along-track component is not part of it.  Measured error
    3.0e-6 m g at dt = 0.002 s (skier; it falls as dt^2: 1.2e-5 at 0.004, 7.6e-7 at 0.001), so
    2e-5 m g bounds it; dropping ``- l omega_v^2`` moves F_leg by ~0.16 m g.  The snowboarder's
    l = 0.95 m tells ``I_v alpha / l`` from ``I_v alpha l`` (the others have l = 1)."""
    fig = unbounded(name)
    b, dt = fig.body, 0.002
    tr = open_loop_run(fig, dt=dt)
    cm = cm_path(tr, b)
    acc = (cm[:, 2:] - 2 * cm[:, 1:-1] + cm[:, :-2]) / dt ** 2
    f = acc + np.array([[0.0], [0.0], [b.g]])
    d = tr.theta_dir[1:-1]
    along = np.stack([np.cos(d), np.sin(d), np.zeros_like(d)])
    f_across = f - (f * along).sum(axis=0) * along
    newton = b.m * np.linalg.norm(f_across, axis=0)
    err = np.abs(newton - tr.F_leg[1:-1]) / (b.m * b.g)
    assert err.max() < 2e-5, err.max()


def test_foot_speed_is_eq_21_and_the_trajectory_s_V_f():
    """Eq. (21) in closed form, at l != 1; and :func:`foot_speed` agrees with the V_f the
    integrator recorded (a separate formula in :mod:`.one_figure`)."""
    from blender_turning.core import BodyParams
    b = BodyParams(m=70.0, l=1.3, I_v=9.0, V_cm=7.0)
    assert foot_speed(b, 0.4, 0.12) == pytest.approx(7.0 / (1 - 0.12 * 1.3 * math.sin(0.4)),
                                                     rel=1e-15)
    fig = unbounded("snowboarder")
    tr = open_loop_run(fig, duration=2.0, dt=0.01)
    np.testing.assert_allclose(foot_speed(fig.body, tr.theta_v, tr.C_f), tr.V_f, rtol=1e-14)
    assert np.ptp(tr.V_f) > 1e-4                       # V_f does vary with C_f sin theta_v


def test_physical_margin_keeps_the_foot_below_ten_times_V_cm():
    """Section 3's physical branch needs ``1 - C_f l sin th > 0``; the core keeps it at least
    0.1 (docs/ARCHITECTURE.md, "The model"), so ``V_f <= 10 V_cm``: a demand beyond it is
    clamped to exactly that."""
    b = preset("cyclist").body
    lim = Limits(C_f_max=5.0)
    th = math.radians(40)
    cf = bound_cf(b, lim, 4.0, math.sin(th))
    assert 1 - cf * b.l * math.sin(th) == pytest.approx(0.1, rel=1e-12)
    assert foot_speed(b, th, cf) == pytest.approx(10 * b.V_cm, rel=1e-12)


def test_leg_force_components_at_simple_states():
    """Closed forms of Eqs. (14)-(18): upright and swinging with no steering, the leg carries
    ``m (g - l omega^2)`` (centripetal unloading); a pure lean acceleration adds the across
    component ``I_v alpha / l``."""
    from blender_turning.core import BodyParams
    b = BodyParams(m=70.0, l=1.3, I_v=9.0, V_cm=7.0)
    F, along = leg_force(b, 0.0, 1.5, 0.0, 0.0)
    assert along == pytest.approx(b.m * (b.g - b.l * 1.5 ** 2), rel=1e-14)
    assert F == pytest.approx(abs(along), rel=1e-14)
    F, along = leg_force(b, 0.0, 0.0, 2.0, 0.0)
    assert F == pytest.approx(math.hypot(b.m * b.g, b.I_v * 2.0 / b.l), rel=1e-14)
    # Steady left turn: the leg force points along the leaned leg, m sqrt(g^2 + a_lat^2).
    cf, th = 0.1, math.atan(b.V_cm ** 2 * 0.1 / b.g)
    F, along = leg_force(b, th, 0.0, 0.0, cf)
    Vf = b.V_cm / (1 - cf * b.l * math.sin(th))
    assert along == pytest.approx(b.m * (b.g * math.cos(th) + b.V_cm * Vf * cf * math.sin(th)),
                                  rel=1e-14)


# -- the foot path: curvature C_f, speed V_f (Eq. 21), heading rate V_f C_f -----------------------
def path_curvature(x, y, dt):
    """Signed curvature of the sampled foot path (central differences), (n - 2,)."""
    dx, dy = (x[2:] - x[:-2]) / (2 * dt), (y[2:] - y[:-2]) / (2 * dt)
    ddx, ddy = (x[2:] - 2 * x[1:-1] + x[:-2]) / dt ** 2, (y[2:] - 2 * y[1:-1] + y[:-2]) / dt ** 2
    return (dx * ddy - dy * ddx) / np.hypot(dx, dy) ** 3, np.hypot(dx, dy)


def check_foot_path(cols, dt):
    """The geometric curvature of (x, y) is C_f and its speed V_f; the heading advances by the
    trapezoid of V_f C_f.  Measured at dt = 0.002 (skier, 2 s / 23 deg open loop; each error
    falls as dt^2): curvature 2.4e-7 1/m (C_f peaks at 0.088), speed 1.07e-5 m/s (central
    differences of the chord), heading 6.9e-9 rad a step (3.8e-6 of the largest step).  With the
    heading integrated from C_f alone the curvature is off by a factor V_f ~ 10."""
    x, y, cf, vf, hd = (np.asarray(cols[k]) for k in ("x", "y", "C_f", "V_f", "theta_dir"))
    kappa, speed = path_curvature(x, y, dt)
    assert np.abs(kappa - cf[1:-1]).max() < 1e-6
    assert np.abs(speed - vf[1:-1]).max() < 3e-5
    rate = vf * cf
    step = np.diff(hd) - 0.5 * (rate[1:] + rate[:-1]) * dt
    assert np.abs(step).max() < 1e-5 * np.abs(np.diff(hd)).max()
    # s is the foot's distance travelled: each step's chord to 2.2e-7 of a step (measured;
    # the trapezoid of V_f against the chord).  At V_cm instead of V_f it is off by 1e-5.
    chord = np.hypot(np.diff(x), np.diff(y))
    assert cols["s"][0] == 0.0
    assert np.abs(np.diff(cols["s"]) - chord).max() < 1e-6 * chord.max()


def test_foot_path_curvature_is_C_f_one_figure():
    fig = unbounded()
    tr = open_loop_run(fig, dt=0.002)
    check_foot_path(tr.columns(), 0.002)


def test_foot_path_curvature_is_C_f_batch():
    """The numpy batch stepper (the planner's and the Blender bake's batch path)."""
    fig, dt = unbounded(), 0.002
    w, tm = TWO_PI / 2.0, math.radians(23)
    s0 = np.array([[0.0, 1.0], [0.0, 2.0], [0.0, 0.5], [0.0, 0.0], [w * tm, w * tm]])
    r = run(fig.body, fig.limits, OpenLoop(fig.body, w, tm), s0, 4.0, dt)
    for j in range(2):
        check_foot_path({k: v[:, j] for k, v in r.columns.items()}, dt)


# -- falls on either side (Section 3's fall bound; the model is mirror-symmetric) ----------------
def test_falls_to_the_right_are_detected_like_falls_to_the_left():
    fig = preset("skier")
    fig = replace(fig, limits=Limits(theta_fall=math.radians(60)))
    w, tm = TWO_PI / 2.0, math.radians(75)
    got = {}
    for side, phase0 in (("left", 0.0), ("right", math.pi)):
        with pytest.raises(FellOver) as e:
            simulate(fig, OpenLoop(fig.body, w, tm, phase0=phase0), 4.0,
                     state0=(0, 0, 0, 0, math.cos(phase0) * w * tm))
        got[side] = e.value
    assert got["left"].theta_v > math.radians(60) and got["right"].theta_v < -math.radians(60)
    assert got["right"].t == pytest.approx(got["left"].t, abs=1e-12)


def test_batch_fall_to_the_right_is_detected():
    fig = preset("skier")
    w, tm = TWO_PI / 2.0, math.radians(75)
    s0 = np.array([[0.0], [0.0], [0.0], [0.0], [-w * tm]])
    r = run(fig.body, Limits(theta_fall=math.radians(60)),
            OpenLoop(fig.body, w, tm, phase0=math.pi), s0, 4.0)
    assert r.fell_at is not None and r.columns["theta_v"][-1, 0] < -math.radians(60)


# -- the trajectory at a frame rate: the heading advances at V_f C_f between samples too ------
def test_resampled_trajectory_matches_a_finer_run():
    """Resampled at 30 fps from dt = 0.02 s, the state columns equal a run at dt = 1/300 s (whose
    every tenth sample is a frame): measured heading 6.4e-8 rad, lean 3.7e-8 rad, position
    6.9e-7 m.  Interpolating the heading with C_f as its rate instead of V_f C_f is ~1e-3 off."""
    fig = unbounded()
    w, tm = TWO_PI / 2, math.radians(23)
    s0 = (0, 0, 0, 0, w * tm)
    coarse = simulate(fig, OpenLoop(fig.body, w, tm), 4.0, dt=0.02, state0=s0).resample(30)
    fine = simulate(fig, OpenLoop(fig.body, w, tm), 4.0, dt=1 / 300, state0=s0)
    n = len(coarse)
    assert n == 121 and np.abs(coarse.t - fine.t[::10][:n]).max() < 1e-12
    for name, tol in (("theta_dir", 1e-6), ("theta_v", 1e-6), ("omega_v", 1e-6),
                      ("x", 5e-6), ("y", 5e-6)):
        err = np.abs(getattr(coarse, name) - getattr(fine, name)[::10][:n]).max()
        assert err < tol, (name, err)


# -- the trajectory contract: CSV header checked on read --------------------------------------
def test_trajectory_csv_header_is_checked_on_read(tmp_path):
    fig = unbounded()
    tr = open_loop_run(fig, duration=0.2, dt=0.02)
    good = tmp_path / "t.csv"
    tr.to_csv(good)
    back = Trajectory.from_csv(good)
    np.testing.assert_array_equal(back.data, tr.data)
    text = good.read_text().splitlines()
    cols = text[0].split(",")
    for name, header in (("swapped", ",".join([cols[1], cols[0]] + cols[2:])),
                         ("renamed", text[0].replace("theta_v", "lean")),
                         ("short", ",".join(cols[:-1]))):
        bad = tmp_path / f"{name}.csv"
        bad.write_text("\n".join([header] + text[1:]) + "\n")
        with pytest.raises(ValueError, match="header"):
            Trajectory.from_csv(bad)


# -- parameters: every field validated in the core (the CLI and Blender rely on it) -------------
@pytest.mark.parametrize("field, bad", [("m", math.nan), ("m", 0.0), ("l", math.nan),
                                        ("l", -1.0), ("I_v", math.nan), ("V_cm", math.nan),
                                        ("V_cm", 0.0), ("g", math.nan)])
def test_body_params_refuse_bad_values_naming_the_field(field, bad):
    from blender_turning.core import BodyParams
    with pytest.raises(ValueError, match=rf"^{field} = .*allowed range"):
        BodyParams(**{field: bad})


@pytest.mark.parametrize("field, bad", [("theta_fall", math.pi / 2), ("theta_fall", 0.0),
                                        ("theta_fall", math.nan), ("C_f_max", math.nan),
                                        ("C_f_max", 0.0), ("dC_f_max", -1.0)])
def test_limits_refuse_bad_values_naming_the_field(field, bad):
    with pytest.raises(ValueError, match=rf"^{field} = .*allowed range"):
        Limits(**{field: bad})


def test_inertia_term_J_of_eqs_1_and_2():
    """``J = (I_v + l^2 m) / (m l)`` (the roll inertia about the foot over m l), at l != 1."""
    from blender_turning.core import BodyParams
    b = BodyParams(m=70.0, l=1.3, I_v=9.0)
    assert b.J == pytest.approx((9.0 + 1.3 ** 2 * 70.0) / (70.0 * 1.3), rel=1e-15)
