"""The planner checks the body as well as the foot against obstacles: the
ground point under the centre of mass, ``foot + l sin(theta_v) (-sin theta_dir, cos theta_dir)``."""
import math

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.planner import PlannerSettings, Problem


def problem(obstacles=Obstacles()):
    fig = preset("skier")
    path = HermitePath.from_polyline([[0, 0], [60, 0]])
    return Problem(fig, PathDistance(path), obstacles, PlannerSettings(n_stages=3, q=3))


def test_body_point_is_to_the_side_of_the_lean():
    p = problem()
    l = p.body.l
    # Heading +x, leaning left (theta_v > 0): the body is over +y; heading +y: over -x.
    st = np.array([[1.0, 1.0, -2.0], [2.0, 2.0, 0.0], [0.0, math.pi / 2, math.pi],
                   [0.3, 0.3, -0.2], [0.0, 0.0, 0.0]])
    got = p.body_point(st)
    s3, s2 = l * math.sin(0.3), l * math.sin(-0.2)
    np.testing.assert_allclose(got, [[1.0, 1.0 - s3, -2.0], [2.0 + s3, 2.0, 0.0 - s2]],
                               atol=1e-12)


def leaning_stage(p, lean=0.4):
    """One stage from a left lean with no steering: the foot runs nearly straight along y = 0
    while the body sways over y = l sin(theta_v) > 0."""
    x0 = np.array([[0.0], [0.0], [0.0], [lean], [0.0]])
    r = p.simulate_stage(x0, np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1), record=True)
    states = np.concatenate(r.record["state"] + [r.state], axis=1)
    return x0, states


@pytest.mark.parametrize("side, hit", [(1, True), (-1, False)])
def test_a_panel_the_foot_clears_but_the_body_crosses_is_a_collision(side, hit):
    """A short panel across the body's track, on the side it leans to, that the foot clears by
    0.25 m or more: a collision.  The same panel mirrored to the other side: none."""
    x0, states = leaning_stage(problem())
    foot = states[:2].T
    body = problem().body_point(states).T
    k = len(foot) // 2
    assert body[k, 1] - foot[k, 1] > 0.35                  # the body really is aside
    lo, hi = body[k, 1] - 0.1, body[k, 1] + 0.3
    panel = side * np.array([[[foot[k, 0], lo], [foot[k, 0], hi]]]) * [side, 1]
    obs = Obstacles(segments=panel, clearance=0.0)
    assert not obs.collides(foot[:-1], foot[1:]).any()     # the foot alone clears it
    assert obs.min_distance(foot).min() > 0.25
    assert bool(obs.collides(body[:-1], body[1:]).any()) is hit
    p = problem(obs)
    r = p.simulate_stage(x0, np.zeros(1), np.zeros(1), np.zeros(1), np.zeros(1))
    assert bool(r.collided[0]) is hit


def test_local_problem_keeps_obstacles_only_the_body_can_reach():
    """``Problem.local`` drops obstacles that cannot matter within one horizon: one the body
    (up to l to the side) or the dead-end stage after the horizon can reach must stay."""
    p = problem()
    reach = p.reach()
    far = reach + 0.5 * p.body.l
    obs = Obstacles(segments=[[[0.0, far], [1.0, far]]], circles=[[0.0, -reach - 50, 1.0]])
    local = problem(obs).local(np.zeros(2))
    assert len(local.obstacles.segments) == 1 and len(local.obstacles.circles) == 0
