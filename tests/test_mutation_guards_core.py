"""Guards for physics mutants that the rest of the suite let through (issue 7, item 6).

Each test checks a relation derived independently of the code it guards (Newton's law on the
centre of mass, the foot path's geometric curvature, the mirror symmetry of the model, the
exhaustive search's optimum), so a dropped term, a flipped sign or a loosened bound shows.
``scripts/mutate.py`` holds the mutants these tests are meant to catch; docs/ARCHITECTURE.md
(section "Conventions") the sign conventions.
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import FellOver, Limits, OpenLoop, Trajectory, preset, run, simulate
from blender_turning.core.dynamics import bound_cf, foot_speed, leg_force
from blender_turning.core.obstacles import Obstacles
from blender_turning.core.path import HermitePath, PathDistance
from blender_turning.core.planner import PlannerSettings, Problem, exhaustive

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


def test_planner_stage_heading_rate_is_V_f_C_f():
    """Section 6.1's stage simulation (its own fused right-hand side): the heading advances by
    ``V_f C_f`` and the foot path's curvature is ``C_f``."""
    fig = preset("skier")
    fig = replace(fig, limits=replace(fig.limits, dC_f_max=0.3))
    path = HermitePath.from_points(np.array([[0.0, 0.0], [40.0, 0.0]]),
                                   np.array([[40.0, 0.0], [40.0, 0.0]]))
    st = PlannerSettings(n_stages=2, q=3, dt=0.01, sample_dt=0.1)
    pb = Problem(fig, PathDistance(path), Obstacles(), st)
    x0 = np.array([[0.0], [0.0], [0.0], [0.02], [0.0]])
    r = pb.simulate_stage(x0, np.array([0.0]), np.array([0.3]), np.zeros(1), np.zeros(1),
                          record=True)
    states = np.array(r.record["state"] + [r.state])[:, :, 0]          # (steps + 1, 5)
    cf = np.array(r.record["C_f"])[:, 0]
    vf = np.array(r.record["V_f"])[:, 0]
    rate = vf * cf
    dhd = np.diff(states[:, 2])
    # RK4 over a step whose curvature ramps: the heading step is the trapezoid of V_f C_f to
    # 1.7e-5 of the largest step (measured); with C_f alone it would be ~1/V_f of it.
    assert np.abs(dhd[:-1] - 0.5 * (rate[1:] + rate[:-1]) * st.dt).max() < 1e-4 * np.abs(dhd).max()
    assert np.abs(dhd).max() > 0.8 * st.dt * np.abs(rate).max()


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


def test_planner_marks_a_fall_to_the_right():
    fig = preset("skier")
    path = HermitePath.from_points(np.array([[0.0, 0.0], [40.0, 0.0]]),
                                   np.array([[40.0, 0.0], [40.0, 0.0]]))
    st = PlannerSettings(n_stages=2, q=3, theta_bound=math.radians(30))
    pb = Problem(fig, PathDistance(path), Obstacles(), st)
    lean = np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 0.0], [0.5, -0.5], [1.5, -1.5]])
    r = pb.simulate_stage(lean, np.zeros(2), np.zeros(2), np.zeros(2), np.zeros(2))
    assert r.fell.tolist() == [True, True]


# -- Section 6: the lower bound is admissible and tight, so a stronger one is not ---------------
def straight_problem(q=5, n=4, per_segment=12, **settings):
    fig = preset("skier", V_cm=8.0)
    fig = replace(fig, limits=replace(fig.limits, dC_f_max=0.3))
    path = HermitePath.from_points(np.array([[0.0, 0.0], [60.0, 0.0]]),
                                   np.array([[60.0, 0.0], [60.0, 0.0]]))
    st = PlannerSettings(n_stages=n, q=q, **settings)
    return Problem(fig, PathDistance(path, per_segment=per_segment), Obstacles(), st)


@pytest.mark.parametrize("offset", [0.0, 0.5, 2.0])
def test_lower_bound_is_admissible_and_tight_at_the_root(offset):
    """The bound on the whole horizon's cost from the root is at most the exhaustive optimum and
    at least half of it (measured 0.65, 0.63, 0.55 of it), so a bound made twice as strong is
    no longer admissible.  On the path (the pair floor bites), 0.5 m and 2 m beside it heading
    along it (the arc and reach bounds bite)."""
    pb = straight_problem()
    state = np.array([0.0, offset, 0.0, 0.0, 0.0])
    f_opt, _ = exhaustive(pb, state, 0.0)
    d0 = float(pb.distance(state[:2]))
    lb = float(pb.lower_bound(np.array([d0]), 0, state[:, None], np.array([0.0]), reach=True)[0])
    assert lb <= f_opt * (1 + 1e-9) + 1e-9
    assert lb >= 0.5 * f_opt, (lb, f_opt)


def test_lipschitz_bound_is_admissible_and_tight_heading_at_the_path():
    """10 m from the path heading straight at it, the foot closes in at nearly ``v_max`` a
    second: the Lipschitz bound alone (no state) is 0.895 of the exhaustive optimum, the full
    bound 0.917 (measured).  Halving the foot's largest travel per sample, or doubling the
    bound, exceeds the optimum."""
    pb = straight_problem()
    state = np.array([0.0, 10.0, -math.pi / 2, 0.0, 0.0])
    f_opt, _ = exhaustive(pb, state, 0.0)
    d0 = float(pb.distance(state[:2]))
    lip = float(pb.lower_bound(np.array([d0]), 0)[0])
    full = float(pb.lower_bound(np.array([d0]), 0, state[:, None], np.array([0.0]),
                                reach=True)[0])
    assert 0.85 * f_opt <= lip <= full <= f_opt * (1 + 1e-9) + 1e-9, (lip, full, f_opt)


# -- Section 6: obstacles keep their clearance ------------------------------------------------
@pytest.mark.parametrize("side", [1.0, -1.0])
@pytest.mark.parametrize("kind", ["segment", "circle", "polygon"])
def test_clearance_is_kept_from_every_kind_of_obstacle(kind, side):
    """A track segment passing 0.3 m from the obstacle (on either side of it: ``side``) collides
    with clearance 0.35, not 0.25; also in :meth:`Obstacles.near`'s local copy for a centre
    1.2 m from the obstacle (beyond the radius 1 but within radius + clearance)."""
    shapes = {"segment": dict(segments=[[[5.0, 0.3], [5.0, 3.0]]]),
              "circle": dict(circles=[[5.0, 1.3, 1.0]]),
              "polygon": dict(polygons=[[[4.0, 0.3], [6.0, 0.3], [5.0, 2.0]]])}[kind]
    flip = np.array([1.0, side])
    shapes = {k: [np.array(v[0]) * (np.append(flip, 1.0) if k == "circles" else flip)]
              for k, v in shapes.items()}
    a, b = np.array([[0.0, 0.0]]), np.array([[10.0, 0.0]])
    a_near, b_near = np.array([[5.0, 0.0]]), np.array([[5.05, 0.0]])
    for clearance, hit in ((0.35, True), (0.25, False)):
        obs = Obstacles(**shapes, clearance=clearance)
        assert obs.collides(a, b).tolist() == [hit], (kind, clearance)
        local = obs.near((5.0, -0.9 * side), 1.0)
        assert local.collides(a_near, b_near).tolist() == [hit], (kind, clearance)
        assert obs.min_distance([[5.0, 0.0]])[0] == pytest.approx(0.3, abs=1e-12)


def test_collinear_segments_apart_are_not_crossing():
    """Segments on one line do not cross: their distance is the gap between them (exactly 0 only
    when they touch or overlap), so a track running along a road edge short of it is clear."""
    from blender_turning.core.obstacles import segment_distance
    p = lambda x, y: np.array([x, y], float)                     # noqa: E731
    assert segment_distance(p(0, 0), p(1, 0), p(2.5, 0), p(3, 0)) == pytest.approx(1.5, abs=1e-15)
    assert segment_distance(p(0, 0), p(1, 1), p(3, 3), p(2, 2)) == pytest.approx(math.sqrt(2),
                                                                                 abs=1e-15)
    assert segment_distance(p(0, 0), p(1, 0), p(1, 0), p(3, 0)) == 0.0
    obs = Obstacles(segments=[[[12.0, 0.0], [20.0, 0.0]]], clearance=0.5)
    assert obs.collides([[0.0, 0.0]], [[10.0, 0.0]]).tolist() == [False]
    assert obs.collides([[0.0, 0.0]], [[11.6, 0.0]]).tolist() == [True]


def test_scene_clearance_reaches_the_planner():
    from blender_turning.core.scene import scene_from_dict
    doc = {"figure": {"preset": "skier"},
           "path": {"polyline": [[0, 0], [30, 0]]}, "clearance": 0.6,
           "obstacles": [{"type": "circle", "center": [10, 1.0], "radius": 0.5}]}
    scene = scene_from_dict(doc)
    obs = scene.problem().obstacles
    assert obs.clearance == 0.6
    # The rim is 0.5 m from the line y = 0: inside the 0.6 m clearance.
    assert obs.collides([[0.0, 0.0]], [[20.0, 0.0]]).tolist() == [True]


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


def test_arc_bound_is_admissible_and_tight_on_the_hardest_steering_branch():
    """The arc bound (Problem.sample_bounds with a state): the foot stays within ``r(tau)`` of
    the arc of its curvature.  A path parallel to the heading 1 m to the left, the branch that
    steers left as hard as it may (``u = +dC_f_max``): its samples are at least the bound from
    the path while its lean is within the bound (the first 3 samples), and its deviation from
    the arc reaches 0.685 of ``r`` there (measured; a 5 deg lean bound and dt = 0.01 s keep r's
    allowance for a faster foot and for RK4's stages small), so a radius half as large is no
    longer admissible.  (At the default 30 deg and 0.05 s the branch reaches only 0.47 of r.)"""
    fig = preset("skier", V_cm=8.0)
    fig = replace(fig, limits=replace(fig.limits, dC_f_max=0.3))
    path = HermitePath.from_points(np.array([[-10.0, 1.0], [60.0, 1.0]]),
                                   np.array([[70.0, 0.0], [70.0, 0.0]]))
    st = PlannerSettings(n_stages=4, q=5, dt=0.01, theta_bound=math.radians(5))
    pb = Problem(fig, PathDistance(path, per_segment=400), Obstacles(), st)
    x, c, s = np.zeros((5, 1)), np.zeros(1), np.zeros(1)
    bound = pb.sample_bounds(np.array([1.0]), 0, x, c)[0, :st.lookahead]
    d, lean = [], []
    for _ in range(st.n_stages):
        r = pb.simulate_stage(x, c, pb.u_values[-1:], np.zeros(1), s, record=True)
        states = np.array(r.record["state"][1:] + [r.state])[:, :, 0]
        every = states[st.steps_per_sample - 1::st.steps_per_sample]
        d += list(pb.distance(every[:, :2]))
        lean += list(np.cumsum(np.abs(states[:, 3]) > st.theta_bound)
                     [st.steps_per_sample - 1::st.steps_per_sample] + (lean[-1] if lean else 0))
        x, c, s = r.state, r.C_f, r.s
    d, standing = np.array(d[:st.lookahead]), np.array(lean[:st.lookahead]) == 0
    assert standing.sum() >= 3
    assert np.all(d[standing] >= bound[standing] - 1e-12), (d, bound)
    assert np.max((1.0 - d[standing]) / (1.0 - bound[standing])) > 0.6
