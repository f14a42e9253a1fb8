"""The shipped scenes (Figs. 16-18, Photo 5): collision-free, within every bound, physically
consistent; the tree-skiing routes for N = 10 and N = 12; a closed corridor is reported."""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from blender_turning.core.physics.dynamics import rk4_step
from blender_turning.core.errors import PlanInfeasible
from blender_turning.core.course.scene import load_scene, scene_from_dict

SCENES = Path(__file__).resolve().parents[1] / "scenes"
NAMES = ["tree_skiing", "slalom", "cyclist_corner", "potholes",
         # Scenes tried as a user would.
         "snowboard_hairpin", "cyclist_chicane", "start_facing_away"]
_RUNS = {}


def run(name, **changes):
    key = (name, tuple(sorted(changes.items())))
    if key not in _RUNS:
        scene = load_scene(SCENES / f"{name}.json")
        if changes:
            scene = scene.with_settings(**changes)
        _RUNS[key] = (scene, scene.run())
    return _RUNS[key]


@pytest.mark.parametrize("name", NAMES)
def test_shipped_scene_is_feasible_and_within_bounds(name):
    scene, result = run(name)
    tr = result.trajectory
    lim, st = scene.figure.limits, scene.settings
    assert result.reached_end
    xy = np.column_stack([tr.x, tr.y])
    assert not scene.obstacles.collides(xy[:-1], xy[1:]).any()
    # The body's ground point too (l sin(theta_v) to the side of the lean).
    off = scene.figure.body.l * np.sin(tr.theta_v)
    cm = np.column_stack([tr.x - off * np.sin(tr.theta_dir), tr.y + off * np.cos(tr.theta_dir)])
    assert not scene.obstacles.collides(cm[:-1], cm[1:]).any()
    # Progress along the path by arc length: the whole path.
    assert result.progress == pytest.approx(scene.path.length(64), rel=1e-9)
    # No executed plan ended in a dead end where one that does not existed.
    assert not any(r.dead_end and r.viable for r in result.replans)
    assert np.all(np.abs(tr.theta_v) <= st.theta_bound)
    assert np.all(np.abs(tr.C_f) <= lim.C_f_max + 1e-12)
    rate = np.abs(np.diff(tr.C_f)) / np.diff(tr.t)
    assert np.all(rate <= lim.dC_f_max * (1 + 1e-9))
    assert all(r.stats.proven for r in result.replans)
    assert np.all(np.isfinite(tr.phi)) and np.all((tr.phi >= 0) & (tr.phi < 2 * math.pi))


@pytest.mark.parametrize("name", NAMES)
def test_the_dynamics_hold_along_the_result(name):
    """Re-integrate every stage from its recorded start with the applied dC_f/dt and the core's
    RK4: the recorded states follow.  (Stage by stage: the pendulum is unstable, so rounding
    differences between a scalar and a batched integration grow over a whole course.)"""
    scene, result = run(name)
    tr = result.trajectory
    st, body, lim = scene.settings, scene.figure.body, scene.figure.limits
    assert len(tr) == len(result.replans) * st.steps_per_stage + 1
    for j, rp in enumerate(result.replans):
        k = j * st.steps_per_stage
        x, cf = tr.data[1:6, k].copy(), tr.C_f[k]

        def desired(tau, _s, c0=cf, u=rp.u):
            return min(max(c0 + u * tau, -lim.C_f_max), lim.C_f_max)
        for i in range(st.steps_per_stage):
            np.testing.assert_allclose(x, tr.data[1:6, k + i], rtol=0, atol=1e-9)
            assert tr.C_f[k + i] == pytest.approx(desired(i * st.dt, None), abs=1e-12)
            x = np.asarray(rk4_step(body, lim, x, i * st.dt, st.dt, desired, tr.C_f[k + i]),
                           float)
        np.testing.assert_allclose(x, tr.data[1:6, k + st.steps_per_stage], rtol=0, atol=1e-9)
    # Independent of the integrator: heading and position change as Eq. (21) says.
    mid = 0.5 * (tr.V_f[1:] * tr.C_f[1:] + tr.V_f[:-1] * tr.C_f[:-1])
    np.testing.assert_allclose(np.diff(tr.theta_dir) / np.diff(tr.t), mid, atol=2e-3)


def side_of_first_tree(traj, tree):
    return int(np.sign(np.interp(tree[0], traj.x, traj.y) - tree[1]))


def test_tree_skiing_routes_differ_for_10_and_12_stages():
    """Fig. 16: planning two stages further ahead passes the first tree on the other side."""
    scene, r10 = run("tree_skiing", n_stages=10)
    _, r12 = run("tree_skiing", n_stages=12)
    tree = scene.obstacles.circles[0]            # the tree on the path at x = 30 m
    assert side_of_first_tree(r10.trajectory, tree) == 1       # N = 10: left of it
    assert side_of_first_tree(r12.trajectory, tree) == -1      # N = 12: right of it
    # And the N = 10 route passes the clump at x = 44-48 m on its far (left) side.
    assert np.interp(44.0, r10.trajectory.x, r10.trajectory.y) > 4.0
    assert np.interp(44.0, r12.trajectory.x, r12.trajectory.y) < 0.0


def closed_corridor():
    return {
        "name": "closed corridor",
        "figure": {"preset": "cyclist", "limits": {"dC_f_max": 0.4}},
        "path": {"polyline": [[0, 0], [60, 0]]},
        "clearance": 0.3,
        "obstacles": [{"type": "segment", "from": [-5, -3], "to": [80, -3]},
                      {"type": "segment", "from": [-5, 3], "to": [80, 3]},
                      {"type": "segment", "from": [30, -3], "to": [30, 3]}],
        "planner": {"stages": 6, "choices": 3},
    }


def test_closed_corridor_raises_plan_infeasible_with_the_position():
    scene = scene_from_dict(closed_corridor())
    with pytest.raises(PlanInfeasible) as info:
        scene.run()
    e = info.value
    x, y = e.position
    assert 0.0 < x < 30.0 and abs(y) < 3.0
    assert f"({x:.2f}, {y:.2f})" in str(e) and f"t = {e.t:.2f} s" in str(e)
    assert e.trajectory is not None and e.trajectory.t[-1] == pytest.approx(e.t)
    # It gave up only once the wall was within one horizon's reach.
    assert 30.0 - x <= scene.problem().reach()


def test_speed_may_vary_with_distance():
    doc = closed_corridor()
    doc["obstacles"] = doc["obstacles"][:2]
    doc["speed"] = {"by": "distance", "at": [0, 20, 40], "V_cm": [6, 4, 7]}
    scene = scene_from_dict(doc)
    tr = scene.run().trajectory
    v_cm = tr.V_f * (1 - tr.C_f * scene.figure.body.l * np.sin(tr.theta_v))
    np.testing.assert_allclose(v_cm, np.interp(tr.s, [0, 20, 40], [6, 4, 7]), atol=0.05)


@pytest.mark.parametrize("change, message", [
    (lambda d: d["obstacles"].append({"type": "circle", "center": [1, 2], "radius": -1}),
     "scene: obstacles[3].radius = -1 is outside the allowed range (0, 10000] m"),
    (lambda d: d["obstacles"].append({"type": "tree", "center": [1, 2]}),
     "scene: obstacles[3].type = 'tree' is not one of circle, segment, polygon"),
    (lambda d: d["planner"].update(stages=0), "scene: planner.stages = 0"),
    (lambda d: d["planner"].update(speling=3), "scene: planner.speling is not a known field"),
    (lambda d: d.update(path={"points": [[0, 0], [1, 0]]}), "scene: path.tangents"),
    (lambda d: d.update(path={"bezier": [[0, 0], [1, 0], [2, 0]]}), "scene: path.bezier"),
    (lambda d: d["figure"].update(preset="unicyclist"), "scene: figure.preset"),
    (lambda d: d.update(clearance="wide"), "scene: clearance = 'wide' is not a number"),
    (lambda d: d.update(speed={"by": "time", "at": [0, 1], "V_cm": [5, -1]}),
     "scene: speed.V_cm[1] = -1"),
])
def test_bad_scenes_name_the_field(change, message):
    doc = closed_corridor()
    change(doc)
    with pytest.raises(ValueError) as info:
        scene_from_dict(doc)
    assert message in str(info.value)
    assert "\n" not in str(info.value)


@pytest.mark.parametrize("name", NAMES)
def test_shipped_scene_files_load(name):
    scene = load_scene(SCENES / f"{name}.json")
    assert len(scene.obstacles) > 0
    json.loads((SCENES / f"{name}.json").read_text())["description"]
