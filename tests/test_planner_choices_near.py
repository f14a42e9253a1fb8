"""Finer choices near obstacles (``PlannerSettings.q_near``; docs/racing.md, "An obstacle on the
line"): a search with an obstacle within the horizon's reach tries ``q_near`` values of
``dC_f/dt``, so the line passes a tree on the path close instead of swinging wide."""
import numpy as np
import pytest

from blender_turning.core.course.scene import scene_from_dict
from blender_turning.core.validate import FieldError


def tree_scene(q, near=0, length=80.0):
    """A straight path with a 0.5 m tree on it halfway (clearance 0.5 m), the telemark at 8 m/s
    (scripts/tree_on_line.py's course, shorter)."""
    return scene_from_dict({
        "figure": {"preset": "telemark", "body": {"V_cm": 8.0}, "limits": {"dC_f_max": 0.3}},
        "path": {"points": [[0.0, 0.0], [length, 0.0]], "tangents": [[length, 0.0]] * 2},
        "clearance": 0.5,
        "obstacles": [{"type": "circle", "center": [length / 2, 0.0], "radius": 0.5}],
        "start": {"position": [0, 0], "heading_deg": 0},
        "planner": {"stages": 10, "choices": q, "choices_near": near, "stage_time": 0.3}})


def test_the_finer_choices_apply_only_with_an_obstacle_within_reach():
    problem = tree_scene(5, 9).problem()
    state = np.zeros(5)
    far, near = problem.local(np.zeros(2), state, 0.0), problem.local(np.array([30.0, 0.0]),
                                                                        state, 0.0)
    assert far.settings.q == 5 and len(far.u_values) == 5
    assert near.settings.q == 9 and len(near.u_values) == 9
    # 2 q - 1 values include q's: the finer search can do all the coarse one can.
    assert np.isin(far.u_values, near.u_values).all()
    assert tree_scene(5).problem().local(np.array([30.0, 0.0]), state, 0.0).settings.q == 5


def test_the_line_passes_the_tree_close():
    wide = np.abs(tree_scene(5).run().trajectory.y).max()
    close = np.abs(tree_scene(5, 9).run().trajectory.y).max()
    assert wide > 4.0
    assert close < 1.5   # the tree needs 1 m (0.5 m and the clearance); 1.34 m measured


def test_a_scenes_choices_near_is_checked():
    with pytest.raises(FieldError, match="choices_near"):
        tree_scene(5, 10)
