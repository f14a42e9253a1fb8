"""Figures as moving obstacles (issue 11): the foot-CM segment, its side, its time."""
import math

import numpy as np
import pytest

from blender_turning.core.trajectory import COLUMNS, Trajectory
from blender_turning.core.moving import MovingBodies, closest_approach


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


def test_a_step_collides_only_while_the_body_is_there():
    late = track(T + 20.0, 0.0, 0.0)                              # the same spot, 20 s later
    b = MovingBodies.from_tracks([("still", STILL, 1.0), ("late", late, 1.0)], clearance=0.3)
    a, c = np.array([[-1.0, 0.2], [-1.0, 0.2], [-1.0, 0.6]]), np.array([[1.0, 0.2]] * 3)
    np.testing.assert_array_equal(b.collides([5.0, 15.0, 5.0], a, c), [True, False, False])
    np.testing.assert_array_equal(b.collides([25.0, 35.0, -5.0], a, c), [True, False, False])
    assert closest_approach(b)["still"] == (math.inf, None, None)    # never in the shot together
