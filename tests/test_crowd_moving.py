"""Figures as moving obstacles: the foot-CM segment, its side, its time."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core.physics.trajectory import COLUMNS, Trajectory
from blender_turning.core.course.moving import MovingBodies, closest_approach


def track(t, x, y, theta_dir=0.0, theta_v=0.0):
    t = np.asarray(t, float)
    cols = {c: np.zeros_like(t) for c in COLUMNS}
    cols.update(t=t, x=np.broadcast_to(x, t.shape), y=np.broadcast_to(y, t.shape),
                theta_dir=np.broadcast_to(theta_dir, t.shape),
                theta_v=np.broadcast_to(theta_v, t.shape))
    return Trajectory.from_columns(cols)


T = np.linspace(0.0, 10.0, 101)
STILL = track(T, 0.0, 0.0)                                   # upright at the origin
PASSER = track(T, T - 5.0, 1.0, theta_v=math.radians(-30))   # leans right, towards -y


def test_the_cm_leans_to_the_left_of_the_heading_by_l_sin_theta_v():
    b = MovingBodies.from_tracks([("still", STILL, 1.0), ("passer", PASSER, 1.0)])
    foot, cm = b.at(5.0)
    np.testing.assert_allclose(foot[1], [0.0, 1.0], atol=1e-12)
    np.testing.assert_allclose(cm[1], [0.0, 0.5], atol=1e-12)        # 1 - sin 30 deg
    near = closest_approach(b)
    assert near["still"][0] == pytest.approx(0.5) and near["still"][1] == "passer"
    assert near["passer"][2] == pytest.approx(5.0)


def steps(a, b):
    """Track steps ``a[i] -> b[i]`` of upright figures (foot = body point) as
    ``MovingBodies.collides`` takes them: shape (2, 2, m)."""
    foot = np.stack([np.asarray(a, float).T, np.asarray(b, float).T], axis=1)
    return foot, foot


def test_a_step_collides_only_while_the_body_is_there():
    late = track(T + 20.0, 0.0, 0.0)                              # the same spot, 20 s later
    b = MovingBodies.from_tracks([("still", STILL, 1.0), ("late", late, 1.0)], clearance=0.3)
    foot, body = steps([[-1.0, 0.2], [-1.0, 0.2], [-1.0, 0.6]], [[1.0, 0.2]] * 3)
    np.testing.assert_array_equal(b.collides(foot, body, [5.0, 15.0, 5.0], 0.1),
                                  [True, False, False])
    np.testing.assert_array_equal(b.collides(foot, body, [25.0, 35.0, -5.0], 0.1),
                                  [True, False, False])
    assert closest_approach(b)["still"] == (math.inf, None, None)    # never in the shot together
    with pytest.raises(ValueError, match="not on the moving bodies' grid"):
        b.collides(foot, body, [5.03, 5.0, 5.0], 0.1)
    with pytest.raises(ValueError, match="sampling step"):
        b.collides(foot, body, [5.0, 5.0, 5.0], 0.05)


def test_a_body_of_one_sample_is_there_for_no_step():
    """A figure whose plan failed at its start leaves one sample: a moment, not a step (as a
    body's last sample ends its last step), so nothing collides with it, and nothing fails."""
    b = MovingBodies.from_tracks([("stuck", track([2.0], 0.0, 0.0), 1.0)], clearance=0.3)
    foot, body = steps([[-1.0, 0.0], [-1.0, 0.0]], [[1.0, 0.0]] * 2)
    np.testing.assert_array_equal(b.collides(foot, body, [1.9, 2.0], 0.1), [False, False])


def test_bodies_that_cross_between_the_samples_collide():
    """At both ends of the step they are 0.78 m apart, half way through on top of each other:
    the rule holds in continuous time (core/course/moving.py), not only at the samples."""
    t = np.round(np.arange(0, 21) * 0.1, 12)
    runner = track(t, 10.0 * (t - 1.0), 0.0)                     # along x at 10 m/s
    b = MovingBodies.from_tracks([("runner", runner, 1.0)], dt=0.1, clearance=0.3)
    foot, body = steps([[0.5, -0.6]], [[0.5, 0.6]])               # along y, 1.0 s to 1.1 s
    assert b.collides(foot, body, [1.0], 0.1)[0]
    assert not b.collides(foot, body, [1.3], 0.1)[0]              # 3 m behind it by then
    # Crossing a third of the way through: no moment tested (multiples of 1/16 of the step)
    # comes within 1 cm; the bound left after the halvings does, and counts (module doc).
    foot, body = steps([[1 / 3, -0.4]], [[1 / 3, 0.8]])
    b1 = replace(b, clearance=0.01)
    assert b1.collides(foot, body, [1.0], 0.1)[0]
    assert not b1.collides(foot + np.array([[[0.3]], [[0.0]]]), body + np.array(
        [[[0.3]], [[0.0]]]), [1.0], 0.1)[0]                      # 0.3 m to the side: clear
    # Side by side at the same speed 0.5 m apart: no relative motion, no false alarm.
    foot, body = steps([[0.0, 0.5]], [[1.0, 0.5]])
    assert not b.collides(foot, body, [1.0], 0.1)[0]
    assert b.collides(foot, body - np.array([[[0.0], [0.0]], [[0.25], [0.25]]]), [1.0],
                      0.1)[0]                                     # leaning towards it


def test_near_keeps_only_bodies_that_come_near_within_the_window():
    b = MovingBodies.from_tracks([("still", STILL, 1.0), ("passer", PASSER, 1.0)],
                                 clearance=0.5)
    assert b.near((0.0, 0.0), 1.0).names == ("still", "passer")
    assert b.near((-4.0, 2.0), 1.0, 0.0, 2.0).names == ("passer",)      # passer at x = -5..-3
    assert b.near((4.0, 2.0), 1.0, 0.0, 2.0).names == ()                # not there yet
    assert b.near((4.0, 2.0), 1.0, 8.0, 9.5).names == ("passer",)
    # The passer reaches the box (x >= 2.5) at 7.5 s: a window ending after that keeps it.
    assert b.near((4.0, 2.0), 1.0, 0.0, 7.55).names == ("passer",)
    assert b.near((4.0, 2.0), 1.0, 0.0, 6.5).names == ()
    assert b.near((-4.0, 2.0), 1.0, 2.45, 5.0).names == ("passer",)     # leaves at 2.5 s
    assert b.near((-4.0, 2.0), 1.0, 3.5, 5.0).names == ()
    log = []
    logged = MovingBodies.from_tracks([("passer", PASSER, 1.0)], clearance=0.5, log=log)
    logged.near((4.0, 2.0), 1.0, 8.0, 9.5)
    assert log == [(4.0, 2.0, 1.0, 8.0, 9.5)] and logged.seen_by(log).tolist() == [True]


@pytest.mark.parametrize("seed", range(6))
def test_the_grid_closest_approach_is_the_all_pairs_one(seed):
    """closest_approach's grid (near-linear) gives the all-pairs answers exactly: distances,
    the other body and the time, ties included (rounded positions make many), on crowds from
    packed to sparse, with bodies absent from some samples."""
    from blender_turning.core.course.moving import _closest_brute
    rng = np.random.default_rng(seed)
    for _ in range(40):
        n, S = int(rng.integers(1, 40)), int(rng.integers(1, 25))
        scale = 10 ** rng.uniform(-1, 3)
        foot = rng.uniform(-scale, scale, (n, S, 2))
        if rng.random() < 0.3:
            foot = np.round(foot)
        # Segments up to about a spacing long, so that the grid's bound h - 2 r matters.
        cm = foot + rng.uniform(-1, 1, (n, S, 2)) * scale / math.sqrt(n) * (rng.random() < 0.8)
        gone = rng.random((n, S)) < 0.2
        foot[gone] = cm[gone] = np.nan
        b = MovingBodies(tuple(f"b{i}" for i in range(n)), 0.1, 3, foot, cm)
        assert closest_approach(b) == _closest_brute(b)


def test_a_closer_body_just_outside_the_cells_is_not_missed():
    """A's nearest body B sits just outside the 3 x 3 cells around A (cells h = 1001 /
    sqrt(104) = 98.16 m wide here: 104 bodies over 1001 m; the cells end at y = 196.3 m),
    pointing at A: 96.5 m away; a body D inside them is 97 m away.  A candidate farther than
    h - 2 r (96.16 m) proves nothing, so the answer must be B, found with wider cells."""
    pts = [((0.0, 97.0), (0.0, 99.0)),              # A: mid (0, 98), at the top of its cell
           ((0.0, 195.5), (0.0, 197.5)),            # B: mid y 196.5, past the cells' 196.3
           ((97.0, 97.0), (97.0, 99.0)),            # D: inside the cells, 97 m from A
           ((500.0, -1.0), (500.0, 1.0))]           # sets the grid's origin at y = 0
    pts += [((1000.0 + 0.01 * i, 1000.0), (1000.0 + 0.01 * i, 1000.0)) for i in range(100)]
    foot = np.array([[p[0]] for p in pts])
    cm = np.array([[p[1]] for p in pts])
    b = MovingBodies(tuple(["A", "B", "D", "far"] + [f"c{i}" for i in range(100)]), 0.1, 0,
                     foot, cm)
    d, other, _ = closest_approach(b)["A"]
    assert other == "B" and d == pytest.approx(96.5)
