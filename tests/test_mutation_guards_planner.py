"""Guards for planner and obstacle mutants that the rest of the suite let through
(Section 6): the stage simulation's heading rate and fall test, lower bounds that are
admissible *and tight* (so a bound made stronger is caught), obstacle clearance.
``scripts/mutate.py`` holds the mutants these tests are meant to catch.
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.planner import PlannerSettings, Problem, exhaustive


def test_planner_stage_heading_rate_is_V_f_C_f():
    """Section 6.1's stage simulation (its own loop over the core's right-hand side): the heading
    advances by ``V_f C_f`` over every step while ``C_f`` ramps at the largest rate."""
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


def test_planner_marks_a_fall_to_the_right():
    """A node leaning and falling either way is marked fallen (mirror images)."""
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
    from blender_turning.core.course.obstacles import segment_distance
    p = lambda x, y: np.array([x, y], float)                     # noqa: E731
    assert segment_distance(p(0, 0), p(1, 0), p(2.5, 0), p(3, 0)) == pytest.approx(1.5, abs=1e-15)
    assert segment_distance(p(0, 0), p(1, 1), p(3, 3), p(2, 2)) == pytest.approx(math.sqrt(2),
                                                                                 abs=1e-15)
    assert segment_distance(p(0, 0), p(1, 0), p(1, 0), p(3, 0)) == 0.0
    obs = Obstacles(segments=[[[12.0, 0.0], [20.0, 0.0]]], clearance=0.5)
    assert obs.collides([[0.0, 0.0]], [[10.0, 0.0]]).tolist() == [False]
    assert obs.collides([[0.0, 0.0]], [[11.6, 0.0]]).tolist() == [True]


def test_scene_clearance_reaches_the_planner():
    from blender_turning.core.course.scene import scene_from_dict
    doc = {"figure": {"preset": "skier"},
           "path": {"polyline": [[0, 0], [30, 0]]}, "clearance": 0.6,
           "obstacles": [{"type": "circle", "center": [10, 1.0], "radius": 0.5}]}
    scene = scene_from_dict(doc)
    obs = scene.problem().obstacles
    assert obs.clearance == 0.6
    # The rim is 0.5 m from the line y = 0: inside the 0.6 m clearance.
    assert obs.collides([[0.0, 0.0]], [[20.0, 0.0]]).tolist() == [True]




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
