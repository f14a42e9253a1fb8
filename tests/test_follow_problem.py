"""One builder of the path-following problem (core/course/follow_problem.py) for scene files and
Blender's Follow Path: the same run-out, time limit, clearance, settings and start."""
import math

import numpy as np
import pytest

from blender_turning.blender.jobs.follow_job import FollowJob
from blender_turning.core import preset
from blender_turning.core.errors import PathNotFinished
from blender_turning.core.course.follow_problem import (DEFAULT_CLEARANCE, TIME_LIMIT_FACTOR,
                                                 FollowSetup, start_state)
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath
from blender_turning.core.planner import PlannerSettings
from blender_turning.core.course.scene import scene_from_dict

BEZIER = [[0, 0], [4, 0], [8, -12], [12, -12], [16, -12], [20, 0], [24, 0]]


def scene_doc(**extra):
    return {"figure": {"preset": "telemark", "limits": {"dC_f_max": 0.3}},
            "path": {"bezier": BEZIER}, "obstacles": [], **extra}


def test_scene_and_blender_build_the_same_problem():
    """The constants that used to differ (run-out, time limit, clearance, batch) are one."""
    sc = scene_from_dict(scene_doc())
    fig = sc.figure
    job = FollowJob(fig, np.array(BEZIER, float), [])     # the job imports no bpy
    a, b = sc.problem(), job.problem
    assert a.settings == b.settings == PlannerSettings()
    assert a.obstacles.clearance == b.obstacles.clearance == DEFAULT_CLEARANCE
    np.testing.assert_array_equal(a.distance.samples, b.distance.samples)    # same run-out
    assert job.duration == pytest.approx(sc.setup().time_limit())
    assert job.duration == pytest.approx(TIME_LIMIT_FACTOR * sc.path.length() / fig.body.V_cm)
    np.testing.assert_array_equal(start_state(job.path), sc.state0)


def test_run_out_is_one_horizons_reach_along_the_end_direction():
    sc = scene_from_dict(scene_doc())
    p = sc.problem()
    last = p.distance.path.knots[-1]
    end, d = sc.path.knots[-1], sc.path.end_direction()
    np.testing.assert_allclose(last, end + d * p.reach(), atol=1e-12)


def test_time_limit_is_a_failure_naming_how_far_it_got():
    """A duration-free run that cannot reach the end in time raises, with the progress."""
    fig = preset("skier")
    path = HermitePath.from_polyline([[0, 0], [200, 0]])
    setup = FollowSetup(fig, path, Obstacles(), PlannerSettings(n_stages=3, q=3))
    # Start 60 m down the path's side: it is not followed from its start.
    state0 = start_state(path, position=[0.0, 60.0])
    with pytest.raises(PathNotFinished) as info:
        setup.run(state0)
    e = info.value
    assert e.t == pytest.approx(setup.time_limit(), abs=0.31)
    assert e.length == pytest.approx(200.0) and e.progress < 200.0
    assert f"got {e.progress:.1f} m of 200.0 m along the path" in str(e)
    assert e.trajectory is not None and e.trajectory.t[-1] == pytest.approx(e.t)


def test_a_given_duration_is_not_a_failure():
    fig = preset("skier")
    path = HermitePath.from_polyline([[0, 0], [200, 0]])
    setup = FollowSetup(fig, path, Obstacles(), PlannerSettings(n_stages=3, q=3))
    res = setup.run(duration=0.9)
    assert not res.reached_end and res.trajectory.t[-1] == pytest.approx(0.9)


def test_progress_is_reported_before_every_replanning():
    fig = preset("skier")
    path = HermitePath.from_polyline([[0, 0], [30, 0]])
    setup = FollowSetup(fig, path, Obstacles(), PlannerSettings(n_stages=3, q=3))
    seen = []
    res = setup.run(on_replan=lambda t, xy, frac: seen.append((t, frac)))
    assert res.reached_end and len(seen) == len(res.replans)
    fr = [f for _, f in seen]
    assert fr[0] == 0.0 and fr == sorted(fr) and fr[-1] > 0.8
    assert math.isclose(res.progress, path.length(64))
