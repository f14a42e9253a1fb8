"""Figures that start closer than the crowd's clearance (riders of a peloton side by side, a
synchronised line) keep half their start distance from each other instead of having no feasible
start (crowd/priority.py, docs/crowds.md "Figures that start close"); every other pair keeps the
clearance, as before."""
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core.course.moving import MovingBodies
from blender_turning.core.course.obstacles import segment_distance
from blender_turning.crowd import FollowPath, crowd_from_dict, run_crowd
from blender_turning.crowd import priority as priority_

PLANNER = {"stages": 6, "choices": 5, "stage_time": 0.3, "lean_bound_deg": 35}
#: A straight, a rounded quarter turn to the left (about 7 m radius), a straight (Bezier
#: control points).
ROAD = [[0, 0], [10, 0], [20, 0], [30, 0], [37, 0], [43, 6], [43, 13], [43, 20], [43, 30],
        [43, 40]]


def peloton(spacing=0.8, gap=2.0, **extra):
    """Four cyclists two abreast, rows ``gap`` m apart, on a road round a corner."""
    return {"name": "bunch", "duration": 12, **extra, "formations": [
        {"type": "peloton", "count": 4, "gap_m": gap, "abreast": 2, "spacing_m": spacing,
         "template": {"name": "r", "preset": "cyclist", "body": {"V_cm": 7.0},
                      "limits": {"dC_f_max": 0.4},
                      "follow": {"path": {"bezier": ROAD}, "planner": PLANNER}}}]}


def pair_closest(crowd, result, a, b, dt=0.005) -> float:
    """The closest approach of ``a``'s and ``b``'s foot-CM segments while both are in the shot,
    sampled every ``dt`` (the planner's rule holds between its 0.05 s steps)."""
    tracks = [(n, result[n].trajectory, crowd[n].figure.body.l) for n in (a, b)]
    bodies = MovingBodies.from_tracks(tracks, dt=dt)
    d = segment_distance(bodies.foot[0], bodies.cm[0], bodies.foot[1], bodies.cm[1])
    return float(np.nanmin(d))


@pytest.fixture(scope="module")
def bunch():
    crowd = crowd_from_dict(peloton(priority="all", clearance=1.0))
    return crowd, run_crowd(crowd)


def test_a_peloton_two_abreast_is_planned_each_around_the_others(bunch):
    crowd, res = bunch
    assert [r.status for r in res.figures] == ["ok"] * 4, [r.message for r in res.figures]
    names = [f.name for f in crowd.figures]
    for i, a in enumerate(names):
        for b in names[:i]:
            start = float(np.hypot(*(np.array(crowd[a].state0()[:2]) -
                                     crowd[b].state0()[:2])))
            keep = 1.0 if start > 1.0 else priority_.START_SHARE * start
            got = pair_closest(crowd, res, a, b)
            # side by side (0.8 m: keep 0.4 m) or one behind the other (2 m: keep 1 m); the
            # rule holds between the 0.05 s steps up to the tracks' curve (sub-millimetre)
            assert got >= keep - 1e-3, (a, b, start, got)
    # the riders of a row stay a bunch (measured closest 0.4-0.8 m), not scattered
    assert pair_closest(crowd, res, names[0], names[1]) < 0.8


def test_pair_clearances_shrink_only_for_pairs_that_start_inside_the_clearance(bunch):
    crowd, res = bunch
    f = crowd.figures[3]                              # back row, right
    tracks = [(n, res[n].trajectory, crowd[n].figure.body.l) for n in
              (crowd.figures[0].name, crowd.figures[1].name, crowd.figures[2].name)]
    got = priority_.pair_clearances(f, tracks, 1.0)
    # front row 2 m ahead (clearance kept), its row-mate 0.8 m to its left: half of that
    np.testing.assert_allclose(got, [1.0, 1.0, 0.4], atol=1e-9)
    assert priority_.pair_clearances(f, tracks, 0.3).tolist() == [0.3] * 3   # all outside
    late = [(n, type(tr)(tr.data[:, tr.t > 0.5], tr.meta), l)   # not in the shot at its start
            for n, tr, l in tracks]
    assert priority_.pair_clearances(f, late, 1.0).tolist() == [1.0] * 3
    # read when f starts: 1 s later the others are 7 m on, and f keeps the clearance
    later = replace(f, time_offset=1.0)
    assert priority_.pair_clearances(later, tracks, 1.0).tolist() == [1.0] * 3
    # from its body, foot to CM ground point: leaning 30 deg right, towards its row-mate
    state0 = np.array(f.controller.scene.state0, float)
    state0[3] = np.radians(-30.0)
    leaning = replace(f, controller=FollowPath(replace(f.controller.scene, state0=state0)))
    x, y, head = state0[:3]
    foot = np.array([x, y])
    cm = foot - f.figure.body.l * 0.5 * np.array([-np.sin(head), np.cos(head)])
    mate = crowd.figures[2].state0()[:2]                 # upright at the start
    want = priority_.START_SHARE * float(segment_distance(foot, cm, mate, mate))
    assert want < 0.3
    assert priority_.pair_clearances(leaning, tracks, 1.0)[2] == pytest.approx(want, abs=1e-12)
    bodies = priority_.bodies_for(f, tracks, 1.0)
    np.testing.assert_array_equal(bodies.clearances(), got)
    assert bodies.near(crowd.figures[2].state0()[:2], 0.1, 0.0, 0.1).clearances().tolist() \
        == [0.4]


def test_without_the_share_a_peloton_side_by_side_has_no_feasible_start(monkeypatch):
    monkeypatch.setattr(priority_, "START_SHARE", 1.0)     # the full start distance
    crowd = crowd_from_dict(peloton(priority="all", clearance=1.0))
    res = run_crowd(crowd)
    assert res.figures[1].status == "infeasible"
    assert "no feasible plan at t = 0.00 s" in res.figures[1].message


def test_pairs_that_start_apart_plan_bit_for_bit_as_with_one_clearance():
    # riders 0.8 m apart keeping 0.5 m: no pair starts inside the clearance, the per-body
    # clearances are all 0.5 and the plans those of one clearance for every body
    crowd = crowd_from_dict(peloton(priority="all", clearance=0.5))
    res = run_crowd(crowd)
    assert [r.status for r in res.figures] == ["ok"] * 4
    f = crowd.figures[3]
    tracks = [(g.name, res[g.name].trajectory, g.figure.body.l) for g in crowd.figures[:3]]
    assert priority_.pair_clearances(f, tracks, 0.5).tolist() == [0.5] * 3
    scalar = MovingBodies.from_tracks(tracks, f.controller.scene.settings.dt, 0.5,
                                      shift=f.time_offset)
    again = f.controller.scene.run(scalar)
    np.testing.assert_array_equal(again.trajectory.data, res[f.name].trajectory.data)


@pytest.mark.parametrize("seed", range(4))
def test_each_body_keeps_its_own_clearance(seed):
    """``collides`` with a clearance per body is, column by column, the OR over the bodies of
    ``collides`` with that body alone and its clearance (the box tests, the bisection of steps
    in doubt and ``near`` each use the body's own); ``near`` keeps each kept body's."""
    rng = np.random.default_rng(seed)
    n, S, m, dt = 6, 30, 40, 0.05
    foot = np.cumsum(rng.normal(0, 0.3, (n, S, 2)), axis=1) + rng.uniform(-6, 6, (n, 1, 2))
    cm = foot + rng.normal(0, 0.4, (n, S, 2))
    cl = rng.uniform(0.05, 1.5, n)
    names = tuple(f"b{j}" for j in range(n))
    every = MovingBodies(names, dt, 0, foot, cm, cl)
    mine_foot = np.cumsum(rng.normal(0, 0.3, (2, 9, m)), axis=1) + rng.uniform(-6, 6, (2, 1, m))
    mine_body = mine_foot + rng.normal(0, 0.3, (2, 9, m))
    t0 = dt * rng.integers(0, S - 9, m)
    got = every.collides(mine_foot, mine_body, t0, dt)
    want = np.zeros(m, bool)
    for j in range(n):
        one = MovingBodies(names[j:j + 1], dt, 0, foot[j:j + 1], cm[j:j + 1], float(cl[j]))
        want |= one.collides(mine_foot, mine_body, t0, dt)
    np.testing.assert_array_equal(got, want)
    assert 0 < want.sum() < m                          # some columns collide, some do not
    kept = every.near((0.0, 0.0), 2.0, 0.0, 0.5)
    np.testing.assert_array_equal(kept.clearances(), cl[[names.index(k) for k in kept.names]])


def test_a_synchronized_line_from_a_path_template_rides_it_side_by_side():
    from blender_turning.crowd import offset_path
    template = peloton()["formations"][0]["template"]
    crowd = crowd_from_dict({"name": "line", "duration": 10, "formations": [
        {"type": "synchronized", "count": 3, "spacing_m": 1.5, "template": template}]})
    road = crowd_from_dict({"name": "one", "duration": 10, "figures": [template]}).figures[0]
    for k, f in enumerate(crowd.figures):
        want = offset_path(road.controller.scene.path, (k - 1) * 1.5)
        np.testing.assert_allclose(f.controller.scene.path.knots, want.knots, atol=1e-9)
        np.testing.assert_allclose(f.state0()[:2], want.knots[0], atol=1e-9)
