"""Figures avoiding each other in Blender: Follow Path on several figures plans them in
their Planning Order, each around the bodies of those before it, through the crowd runner's
priority planning (the CLI's), in worker processes; a figure with no way round is named with
the figures in its way and nothing is written; Esc ends the planning and changes nothing."""
import math
import os
import signal
import tempfile
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from modal_stand_ins import Context, WindowManager  # noqa: E402
from scene_snapshot import diff, snapshot  # noqa: E402
from test_blender_crowd import ESC, curves, modal_crowd, started_workers  # noqa: E402
from test_blender_operators import add, make_path  # noqa: E402

from blender_turning.blender.jobs import crowd_job  # noqa: E402
from blender_turning.blender.scene import follow_scene, scene_adapters  # noqa: E402
from blender_turning.core.course.moving import MovingBodies, closest_approach  # noqa: E402
from blender_turning.crowd import Crowd, CrowdFigure, FollowPath, run_crowd  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]
CLEARANCE = 1.0


@pytest.fixture
def scene(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, 96
    sc.render.fps = 24
    return sc


def crossing(starts=((-20, 0), (0, -20)), at=(0, 0)):
    """Two skiers (10 m/s) whose straight paths cross at ``at``, where both arrive 2 s in."""
    figs = []
    for i, (x, y) in enumerate(starts):
        fig = add("SKIER", at=(x, y, 0.0))
        fig.turning.path = make_path([(x, y), at, (2 * at[0] - x, 2 * at[1] - y)], f"Path{i}")
        figs.append(fig)
    for fig in figs:
        fig.select_set(True)
    return figs


def planned(figs, avoid, clearance=CLEARANCE) -> list:
    job = crowd_job.CrowdFollow(figs, avoid=avoid, clearance=clearance)
    job.read(bpy.context)
    job.start()
    job.wait()
    return [r for _, r in job.results()]


def closest(figs, results) -> tuple:
    """(distance m, other figure) of the second figure's closest approach to the first's body
    (foot to CM ground point), sampled every 5 ms (the planner's rule holds between its steps:
    core/course/moving.py)."""
    tracks = [(f.name, r.trajectory, f.turning.com_height) for f, r in zip(figs, results)]
    return closest_approach(MovingBodies.from_tracks(tracks, dt=0.005))[figs[1].name][:2]


def test_crossing_figures_collide_alone_and_keep_the_clearance_avoiding(scene):
    figs = crossing()
    alone = planned(figs, avoid=False)
    together = planned(figs, avoid=True)
    assert [r.status for r in alone + together] == ["ok"] * 4
    d, other = closest(figs, alone)
    assert d < 0.05 and other == figs[0].name           # measured 1e-15: they run into each other
    d, other = closest(figs, together)
    # measured 1.052 m; the rule holds in continuous time, less the tracks' curve between the
    # planner's 0.05 s samples (sub-millimetre)
    assert d >= CLEARANCE - 1e-3 and other == figs[0].name
    # the first in planning order (by name: both Planning Order 0) goes as alone, the second
    # gives way
    np.testing.assert_array_equal(together[0].trajectory.data, alone[0].trajectory.data)
    assert np.abs(together[1].trajectory.x).max() > 0.5
    assert together[1].plan["priority"]["after"] == [figs[0].name]


def test_avoiding_is_the_core_priority_run_in_the_planning_order(scene):
    figs = crossing()
    figs[1].turning.crowd.priority = -1                 # the second plans first now
    figs[1].turning.crowd.time_offset = 0.05            # and starts a little later
    got = planned(figs, avoid=True, clearance=1.5)
    members = []
    for fig in figs:
        job = follow_scene.prepare(bpy.context, fig)
        members.append(CrowdFigure(fig.name, job.figure,
                                   FollowPath(crowd_job.figure_scene(fig.name, job)),
                                   time_offset=fig.turning.crowd.time_offset))
    core = run_crowd(Crowd("c", members, 1.0, priority=(figs[1].name, figs[0].name),
                           clearance=1.5))
    for r, want in zip(got, core.figures):               # bit for bit
        np.testing.assert_array_equal(r.trajectory.data, want.trajectory.data)
    assert got[0].plan["priority"]["after"] == [figs[1].name]
    alone = planned(figs, avoid=False)
    np.testing.assert_array_equal(got[1].trajectory.data, alone[1].trajectory.data)
    assert closest(figs[::-1], alone[::-1])[0] < 1.0            # measured 0.354 m: 0.05 s apart
    assert closest(figs[::-1], got[::-1])[0] >= 1.5 - 1e-3     # measured 2.28 m


def test_pairs_that_cannot_meet_plan_in_parallel_workers(scene):
    figs = crossing() + crossing(starts=((180, 0), (200, -20)), at=(200, 0))   # 200 m away
    job = crowd_job.CrowdFollow(figs, avoid=True, clearance=CLEARANCE)
    job.read(bpy.context)
    job.start()
    job.wait()
    started = len(job._pool._processes)
    got = [r for _, r in job.results()]
    assert [r.plan["priority"]["group"] for r in got] == [0, 0, 1, 1]
    assert started == 2                                 # one worker process per group
    np.testing.assert_array_equal(got[1].trajectory.data, planned(figs[:2], True)[1]
                                  .trajectory.data)


def crowd_file(figs, priority, clearance) -> dict:
    """The crossing as a crowd scene file for the CLI: each figure's body and limits as Follow
    Path reads them (float32 settings, its preset's planner curvature rate), its curve's Bezier
    control points, its start offset."""
    out = []
    for fig in figs:
        f = follow_scene.prepare(bpy.context, fig).figure
        b, lim = f.body, f.limits
        assert math.radians(math.degrees(lim.theta_fall)) == lim.theta_fall   # exact in the file
        out.append({"name": fig.name, "preset": "skier", "time_offset": fig.turning.crowd
                    .time_offset, "body": {"m": b.m, "l": b.l, "I_v": b.I_v, "V_cm": b.V_cm,
                                           "g": b.g},
                    "limits": {"C_f_max": lim.C_f_max, "dC_f_max": lim.dC_f_max,
                               "theta_fall_deg": math.degrees(lim.theta_fall)},
                    "follow": {"path": {"bezier": scene_adapters.bezier_control_points(
                        fig.turning.path).tolist()}}})
    return {"name": "crossing", "duration": 10, "figures": out, "priority": priority,
            "clearance": clearance}


def test_avoiding_equals_the_cli_crowd_of_the_same_scene(scene, tmp_path):
    import json
    import subprocess
    import sys
    from blender_turning.core.physics.trajectory import Trajectory
    figs = crossing()
    figs[0].turning.crowd.priority = 2
    got = planned(figs, avoid=True, clearance=1.25)
    (tmp_path / "crossing.json").write_text(json.dumps(
        crowd_file(figs, [figs[1].name, figs[0].name], 1.25)))
    run = subprocess.run([sys.executable, "-m", "blender_turning", "crowd",
                          str(tmp_path / "crossing.json"), "--out", str(tmp_path / "out")],
                         capture_output=True, text=True, env={**os.environ, "PYTHONPATH": str(
                             Path(__file__).resolve().parents[1])})
    assert run.returncode == 0, run.stderr
    for fig, r in zip(figs, got):                        # bit for bit (the CSVs hold repr)
        cli = Trajectory.from_csv(tmp_path / "out" / f"{fig.name}.csv")
        np.testing.assert_array_equal(r.trajectory.data, cli.data, err_msg=fig.name)
    assert np.abs(got[0].trajectory.y).max() > 0.5       # it gave way to the other


def test_follow_path_avoids_by_default_and_bakes_the_plans(scene):
    figs = crossing()
    assert bpy.ops.turning.follow_path(avoid=False) == {"FINISHED"}
    apart = [curves(f) for f in figs]
    assert bpy.ops.turning.follow_path() == {"FINISHED"}
    avoiding = [curves(f) for f in figs]
    loc = "location", 0
    # the first in order bakes the same keys; the second its own way round the first
    np.testing.assert_array_equal(avoiding[0][loc][1], apart[0][loc][1])

    def gap(c):                                         # the feet's distance at each frame
        n = min(len(c[0][loc][1]), len(c[1][loc][1]))
        return np.hypot(*(c[0]["location", i][1][:n] - c[1]["location", i][1][:n]
                          for i in (0, 1)))
    assert gap(apart).min() < 0.05                      # frame 49 is t = 2 s: they meet
    assert gap(avoiding).min() >= CLEARANCE - 1e-3      # feet apart at least as far as bodies


def test_a_figure_with_no_way_round_is_named_with_those_in_its_way(scene):
    # both start on the same spot at once: the second is inside the first's body from the start
    figs = crossing(starts=((-20, 0), (-20, 0.2)))
    figs[1].turning.path = make_path([(-20, 0.2), (0, -20), (20, -40)], "Away")
    before = snapshot()
    with pytest.raises(RuntimeError, match=rf"Follow Path: Skier\.001: no feasible plan.*with "
                                           rf"Skier \(planned before it\) within reach.*nothing "
                                           rf"was written"):
        bpy.ops.turning.follow_path()
    assert snapshot() == before, diff(before, snapshot())


def test_of_several_figures_without_a_plan_the_first_in_planning_order_is_named(scene):
    from test_blender_operators import make_wall
    figs = crossing(starts=((-20, 0), (-20, 0.2)))
    walls = bpy.data.collections.new("Walls")
    scene.collection.children.link(walls)
    walls.objects.link(make_wall("Wall", (15.0, 0.0), (1.0, 60.0)))    # across the first's way
    figs[0].turning.obstacles = walls
    # Skier.001 (active: first in the selection) plans second and fails where Skier stands
    assert bpy.context.view_layer.objects.active == figs[1]
    with pytest.raises(RuntimeError, match=r"Follow Path: Skier: no feasible plan.*\(and 1 more "
                                           r"figures\); nothing was written"):
        bpy.ops.turning.follow_path()


def test_esc_while_avoiding_ends_the_planning_and_leaves_the_scene_unchanged(scene):
    figs = crossing()
    before = snapshot()
    op_cls, fake, reports = modal_crowd(figs, avoid=True)
    job = fake._crowd
    assert job.crowd.priority == tuple(f.name for f in figs)
    procs = started_workers(job)
    assert procs
    assert op_cls.modal(fake, Context(WindowManager()), ESC) == {"CANCELLED"}
    assert [p.exitcode for p in procs] == [-signal.SIGTERM] * len(procs)
    assert not job._thread.is_alive()                   # the runner's thread ended too
    assert "cancelled" in reports[-1][1]
    assert snapshot() == before, diff(before, snapshot())


def test_esc_before_the_workers_got_the_plans_ends_the_planning_thread(scene):
    import time
    figs = crossing()
    job = crowd_job.CrowdFollow(figs, avoid=True)
    job.read(bpy.context)
    job.start()
    end = time.monotonic() + 60
    while not job._executor._queued and time.monotonic() < end:     # asked for, not pumped
        time.sleep(0.01)
    assert job._executor._queued
    job.cancel()
    assert not job._thread.is_alive()
    with pytest.raises(Exception):
        job.results()


def test_the_crowd_panel_shows_the_planning_order(scene):
    from blender_turning.blender.ui import crowd as panel_crowd
    from test_blender_operators import LayoutStub
    figs = crossing()
    figs[0].turning.crowd.priority = 3
    calls = []
    fake = type("P", (panel_crowd.FigurePanel,), {"layout": LayoutStub(calls)})()
    panel_crowd.VIEW3D_PT_turning_crowd.draw(fake, bpy.context)
    labels = [c[2].get("text", "") for c in calls if c[0] == "label"]
    assert "Follow Path plans: Skier.001, Skier" in labels


def test_crowd_names_are_the_objects_where_a_crowd_figure_can_have_them():
    # a crowd figure's name is its CSV file's: no path separator, no leading dot; unique
    assert crowd_job.member_names(["a/b", "a_b", ".x", "ok", "c\\d"]) == \
        ["a_b_1", "a_b", "_x", "ok", "c_d"]
