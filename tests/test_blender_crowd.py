"""Crowds in Blender: Add Crowd makes the core's formations, Bake Turns bakes each
figure the core's trajectory for its start offset, Follow Path on several figures plans each in
a worker process exactly as it plans it alone, Esc leaves the scene unchanged, a user's rig is a
template too, and the workers start safely from inside Blender (spawn, no script re-run, the
extension's package name)."""
import importlib
import math
import os
import signal
import sys
import tempfile
import types
from pathlib import Path

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from modal_stand_ins import Context, WindowManager  # noqa: E402
from rig_fixtures import activate, mixamo_skeleton  # noqa: E402
from scene_snapshot import diff, snapshot  # noqa: E402
from test_blender_operators import add, make_path  # noqa: E402

import blender_turning  # noqa: E402
from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.jobs import crowd_job  # noqa: E402
from blender_turning.blender.scene import follow_scene, scene_adapters  # noqa: E402
from blender_turning.blender.scene import retarget_adapter as ra  # noqa: E402
from blender_turning.core import (DEFAULT_DT, BodyParams, Figure, Limits,  # noqa: E402
                                  PhaseEllipse, Schedule, simulate)
from blender_turning.crowd import (Crowd, CrowdFigure, Turns, follow_leader,  # noqa: E402
                                   stage, synchronized)
from blender_turning.crowd.poses import map_task  # noqa: E402
from blender_turning.crowd.runner import crowd_tasks, run_task  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]
ESC = type("E", (), {"type": "ESC"})()
TIMER = type("E", (), {"type": "TIMER"})()
F32 = np.float32


@pytest.fixture
def scene(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, 96
    sc.render.fps = 24
    return sc


def f32(v) -> float:
    """``v`` as a float property stores it."""
    return float(F32(v))


def crowd_of(fig):
    return next(c for c in bpy.data.collections if c.get("turning_crowd") and
                fig.name in c.objects)


def curves(fig) -> dict:
    """``{(data_path, index): (frames, values)}`` of the figure's F-curves."""
    out = {}
    for fc in bake.baked_channels(fig).fcurves:
        co = np.empty(2 * len(fc.keyframe_points))
        fc.keyframe_points.foreach_get("co", co)
        out[fc.data_path, fc.array_index] = (co[0::2], co[1::2])
    return out


def core_member(fig) -> CrowdFigure:
    """The core's crowd member of a figure with turns, read off its settings."""
    s = fig.turning
    return CrowdFigure("m", Figure("skier", BodyParams(m=s.mass, l=s.com_height, I_v=s.inertia,
                                                       V_cm=s.speed),
                                   Limits(s.curvature_max, s.curvature_rate_max, s.fall_angle)),
                       Turns(s.period, s.lean, s.heading), (s.start[0], s.start[1]))


# -- Add Crowd ------------------------------------------------------------------------------------

@pytest.mark.parametrize("staging", ["ALONG_TRACK", "WAIT"])
def test_follow_the_leader_is_the_core_formation(scene, staging):
    lead = add("SKIER", at=(2.0, 1.0, 0.0))
    expected = stage(core_member(lead), follow_leader(
        core_member(lead), 5, 1.25, "time", [-1.5, 1.5], seed=7, body_jitter=0.05,
        timing_jitter=0.3, period_jitter=0.1, name="m"), lead.turning.heading, staging.lower())
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=5, gap_time=1.25,
                                     lateral=1.5, alternate=True, seed=7, body_jitter=0.05,
                                     timing_jitter=0.3, period_jitter=0.1,
                                     staging=staging) == {"FINISHED"}
    coll = crowd_of(lead)
    figs = sorted((o for o in coll.objects if o.type == "ARMATURE"), key=lambda o: o.name)
    assert [o.name for o in figs] == ["Skier"] + [f"Skier {k}" for k in range(1, 6)]
    assert set(bpy.context.selected_objects) >= set(figs)     # Bake Turns does them all
    for fig, m in zip(figs[1:], expected):
        s = fig.turning
        assert s.crowd.time_offset == f32(m.time_offset)
        assert (s.mass, s.com_height, s.inertia) == tuple(map(f32, (m.figure.body.m,
                                                                    m.figure.body.l,
                                                                    m.figure.body.I_v)))
        assert s.period == f32(m.controller.period)
        assert (s.start[0], s.start[1]) == (f32(m.position[0]), f32(m.position[1]))
        assert s.start_heading == lead.turning.start_heading
        assert fig.data is lead.data                        # a linked duplicate
        assert fig.children[0].data is lead.children[0].data
        assert fig.children[0].modifiers["Armature"].object is fig
    # the followers alternate sides: 1.5 m right, left, ... of the heading (+Y)
    assert [round(o.turning.start[0] - 2.0, 5) for o in figs[1:]] == [1.5, -1.5] * 2 + [1.5]


def test_synchronized_antiphase_pair_mirrors_its_lean(scene):
    lead = add("SKIER")
    expected = synchronized(core_member(lead), 2, 3.0, True, "m")
    assert bpy.ops.turning.add_crowd(formation="SYNCHRONIZED", count=2, spacing=3.0,
                                     antiphase=True) == {"FINISHED"}
    a, b = (bpy.data.objects[f"Skier {k}"] for k in (1, 2))
    for fig, m in zip((a, b), expected):
        assert (fig.turning.start[0], fig.turning.start[1]) == tuple(map(f32, m.position))
        assert fig.turning.crowd.first_turn == m.first_turn.upper()
    assert (a.turning.crowd.first_turn, b.turning.crowd.first_turn) == ("LEFT", "RIGHT")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    la, lb = curves(a)['["turn_lean"]', 0][1], curves(b)['["turn_lean"]', 0][1]
    assert np.abs(la).max() > 0.3
    # the mirror image about the heading (Section 1's symmetry): lean exactly negated
    np.testing.assert_array_equal(la, -lb)


def test_bad_formation_is_reported_and_nothing_changes(scene):
    add("SKIER")
    before = snapshot()
    with pytest.raises(RuntimeError, match=r"timing_jitter = 0\.8 is outside the allowed "
                                           r"range \[0, 0\.5\]"):
        bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", gap_time=1.0, timing_jitter=0.8)
    with pytest.raises(RuntimeError, match="Peloton: the template has no path curve"):
        bpy.ops.turning.add_crowd(formation="PELOTON")
    assert snapshot() == before, diff(before, snapshot())


@pytest.mark.parametrize("given, words", [
    ({"count": 0}, r"count = 0 is outside the allowed range \[1, 10000\]"),
    ({"count": -5}, r"count = -5 is outside the allowed range \[1, 10000\]"),
    ({"count": 10001}, r"count = 10001 is outside"),
    ({"gap_time": -1.0}, r"gap_time = -1.0 is outside"),
    ({"abreast": 0, "formation": "PELOTON"}, r"abreast = 0 is outside"),
])
def test_counts_and_ranges_from_python_are_refused_not_clamped(scene, given, words):
    """A script passes any number; Blender would clamp it to a hard limit in silence (count 0
    became 1 follower): the operator refuses it by name, as the crowd file's reader does."""
    add("SKIER")
    before = snapshot()
    with pytest.raises(RuntimeError, match=words):
        bpy.ops.turning.add_crowd(**given)
    assert snapshot() == before, diff(before, snapshot())


# -- Bake Turns on a crowd ------------------------------------------------------------------------

def core_pose_track(fig, frames):
    """The core's trajectory of ``fig``'s settings from its start, on the crowd's clock (its
    start offset), mapped by the core crowd's mapping (:func:`..crowd.poses.map_task`)."""
    s = fig.turning
    m = core_member(fig)
    fps = 24.0
    w, lean = 2 * math.pi / s.period, s.lean
    ctl = PhaseEllipse(m.figure.body, Schedule.constant(w), Schedule.constant(lean),
                       Schedule.constant(s.heading), limits=m.figure.limits)
    x, y, heading = s.start[0], s.start[1], s.start_heading   # where it stood, as baked
    rate = -w * lean if s.crowd.first_turn == "RIGHT" else w * lean
    offset = s.crowd.time_offset
    traj = simulate(m.figure, ctl, frames / fps - offset + 2 * DEFAULT_DT,
                    state0=(x, y, heading, 0.0, rate))
    cols = traj.columns()
    cols["t"] = cols["t"] + offset
    traj = type(traj).from_columns(cols, traj.meta)
    return map_task((fps, 1, [("skier", traj)]))[0]


def test_baking_the_crowd_gives_each_figure_the_core_trajectory_at_its_offset(scene):
    lead = add("SKIER")
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=3, gap_time=0.7,
                                     lateral=2.0, seed=3, body_jitter=0.1,
                                     timing_jitter=0.2, period_jitter=0.1) == {"FINISHED"}
    figs = [lead] + [bpy.data.objects[f"Skier {k}"] for k in (1, 2, 3)]
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    for fig in figs:
        want = core_pose_track(fig, scene.frame_end - scene.frame_start)
        got = curves(fig)
        offset = fig.turning.crowd.time_offset
        frames = got["location", 0][0]
        # keyed from the first frame at or after its start, to the last frame
        assert frames[0] == 1 + math.ceil(offset * 24 - 1e-9) and frames[-1] == scene.frame_end
        n = len(frames)
        np.testing.assert_array_equal(want.frames[:n], frames)
        # F-curves hold float32: half a unit in the last place of up to 40 m is 1.9e-6 m, of an
        # angle up to pi 1.2e-7 (measured: 1.8e-6 m, 1.5e-8 rad)
        for i in range(3):
            np.testing.assert_allclose(got["location", i][1], want.location[:n, i], atol=5e-6)
            np.testing.assert_allclose(got["rotation_euler", i][1], want.rotation[:n, i],
                                       atol=1e-7)
        np.testing.assert_allclose(got['["turn_lean"]', 0][1], want.props["turn_lean"][:n],
                                   atol=1e-7)
        thigh = got['pose.bones["thigh.L"].rotation_quaternion', 1][1]
        np.testing.assert_allclose(thigh, want.bones["thigh.L"].rotation[:n, 1], atol=1e-7)


def test_an_active_crowd_collection_is_baked_whole(scene):
    lead = add("SKIER")
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=2,
                                     gap_time=1.0) == {"FINISHED"}
    coll = crowd_of(lead)
    for o in bpy.context.selected_objects:
        o.select_set(False)
    vl = bpy.context.view_layer
    vl.active_layer_collection = vl.layer_collection.children[coll.name]
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    for o in coll.objects:      # the followers (no differences) play the leader's bake
        if o.type == "ARMATURE":
            action = bake.figure_action(o)
            assert action is not None and len(compat.all_fcurves(action)), o


@pytest.mark.installed
def test_a_users_rig_is_a_template(scene):
    rig = mixamo_skeleton()
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="CYCLIST", bone_map="MIXAMO") == {"FINISHED"}
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=2, gap_time=1.0,
                                     lateral=2.0, staging="WAIT") == {"FINISHED"}
    followers = [bpy.data.objects[f"{rig.name} {k}"] for k in (1, 2)]
    pieces = {eq.name for eq in rig.turning.rig.equipment.objects}
    for fig in followers:
        assert ra.is_user_rig(fig) and fig.data is rig.data
        eq = fig.turning.rig.equipment
        assert eq is not None and eq is not rig.turning.rig.equipment
        assert len(eq.objects) == len(pieces)
        for obj in eq.objects:                 # tied to the new figure, never the template
            targets = [c.target for c in obj.constraints if c.type == "CHILD_OF"]
            drivers = [t.id for fc in (obj.animation_data.drivers if obj.animation_data
                                       else ()) for v in fc.driver.variables for t in v.targets]
            assert all(t is fig for t in targets + drivers), obj.name
            assert obj.parent is None or obj.parent.name in {o.name for o in eq.objects}
    assert bpy.ops.turning.bake_turns(share=False) == {"FINISHED"}
    # A follower without random differences is its leader's motion 1 s (24 frames) later, 2 m
    # to the left of the start direction.
    lead, late = curves(rig), curves(followers[0])
    left = np.array([-math.sin(rig.turning.start_heading), math.cos(rig.turning.start_heading)])
    assert late["location", 0][0][0] == 25
    n = len(late["location", 0][0])
    for i in range(2):              # float32 keys (measured 1.8e-6 m)
        np.testing.assert_allclose(late["location", i][1], lead["location", i][1][:n]
                                   + 2.0 * left[i], atol=5e-6)
    for key, (frames, values) in late.items():      # measured 5e-17
        if key[0].startswith("pose.bones"):
            np.testing.assert_allclose(values, lead[key][1][:n], atol=1e-12, err_msg=str(key))
    # so, sharing, it plays the leader's bake from frame 25, moved 2 m (its strip from the
    # scene's first frame, holding the first pose: bake.held_from)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    action, strip = bake.shared_source(followers[0])
    assert action == bake.find_bake(rig)[0]
    assert (strip.frame_start, strip.action_frame_start, strip.frame_end) == (1, -23,
                                                                            scene.frame_end)
    np.testing.assert_allclose(followers[0].delta_location[:2], 2.0 * left, atol=5e-6)
    # Remove Figure on it: its rig back as it was, the other follower still plays the bake
    activate(followers[0])
    assert bpy.ops.turning.remove_figure() == {"FINISHED"}
    assert tuple(followers[0].delta_location) == (0.0, 0.0, 0.0)
    assert bake.shared_source(followers[1])[0] == action == bake.find_bake(rig)[0]


# -- Follow Path on several figures ---------------------------------------------------------------

def path_figures(count=3):
    figs = []
    for i in range(count):
        fig = add("TELEMARK", at=(8.0 * i, 0.0, 0.0))
        fig.turning.path = make_path([(8.0 * i, 0), (8.0 * i + 3, -12), (8.0 * i - 2, -22)],
                                     f"Path{i}")
        fig.turning.plan_curvature_rate = 0.3
        figs.append(fig)
    for fig in figs:
        fig.select_set(True)
    return figs


def test_plans_in_the_workers_equal_each_figure_planned_alone(scene):
    figs = path_figures()
    figs[2].turning.crowd.time_offset = 0.5
    job = crowd_job.CrowdFollow(figs)
    job.read(bpy.context)
    job.start()
    job.wait()
    results = job.results()
    assert [name for name, _ in results] == [f.name for f in figs]
    for fig, (_, r) in zip(figs, results):
        alone = follow_scene.prepare(bpy.context, fig).run()
        got = r.trajectory.columns()
        for c, v in alone.trajectory.columns().items():       # bit for bit; t on the crowd clock
            want = v + fig.turning.crowd.time_offset if c == "t" else v
            np.testing.assert_array_equal(got[c], want, err_msg=c)


@pytest.mark.installed
def test_follow_path_bakes_every_selected_figure_as_alone(scene):
    figs = path_figures(2)
    assert bpy.ops.turning.follow_path() == {"FINISHED"}
    together = [curves(f) for f in figs]
    end = scene.frame_end
    for fig, want in zip(figs, together):
        bpy.ops.turning.clear_bake()
        activate(fig)
        assert bpy.ops.turning.follow_path() == {"FINISHED"}
        got = curves(fig)
        assert got.keys() == want.keys()
        for key in want:
            np.testing.assert_array_equal(got[key][1], want[key][1], err_msg=str(key))
        for f in figs:
            f.select_set(True)
    assert end == max(len(c["location", 0][0]) for c in together)


def modal_crowd(figs, avoid=True, clearance=1.0):
    """A stand-in ``self`` for ``TURNING_OT_follow_path.modal`` with several figures planning."""
    reports = []
    fake = type("Op", (), {"report": lambda self, kind, msg: reports.append((kind, msg))})()
    fake._timer, fake._job = object(), None
    fake.avoid, fake.clearance = avoid, clearance
    fake._crowd = crowd_job.prepare_crowd(fake, bpy.context, figs)
    fake._crowd.start()
    return bpy.types.TURNING_OT_follow_path, fake, reports


def started_workers(job, timeout=60.0):
    """The worker processes of ``job``, once the planning thread's first plans have been handed
    to them (as the modal operator's timer does)."""
    import time
    end = time.monotonic() + timeout
    while not job._pool._processes and time.monotonic() < end:
        job.pump()
        time.sleep(0.01)
    return list(job._pool._processes.values())


@pytest.mark.installed
def test_esc_ends_the_workers_and_leaves_the_scene_unchanged(scene):
    figs = path_figures()
    before = snapshot()
    op_cls, fake, reports = modal_crowd(figs)
    procs = started_workers(fake._crowd)
    assert procs
    wm = WindowManager()
    assert op_cls.modal(fake, Context(wm), ESC) == {"CANCELLED"}
    # ended mid-plan (SIGTERM), not left to finish their plans
    assert [p.exitcode for p in procs] == [-signal.SIGTERM] * len(procs)
    assert "end" in wm.progress and "cancelled" in reports[-1][1]
    assert snapshot() == before, diff(before, snapshot())


def test_modal_follow_path_shows_one_progress_bar_then_bakes_all(scene):
    import time
    figs = path_figures(2)
    op_cls, fake, reports = modal_crowd(figs)
    wm = WindowManager()
    end = time.monotonic() + 120
    while (ret := op_cls.modal(fake, Context(wm), TIMER)) == {"RUNNING_MODAL"} and \
            time.monotonic() < end:
        time.sleep(0.05)
    assert ret == {"FINISHED"}, reports
    values = [v for v in wm.progress if isinstance(v, int)]
    assert values == sorted(values) and values[-1] == 100
    assert "baked 2 figures" in reports[-1][1]
    assert all(bake.figure_action(f).name == f.name for f in figs)


def test_a_figure_without_a_plan_fails_the_crowd_and_writes_nothing(scene):
    figs = path_figures(2)
    walls = bpy.data.collections.new("Walls")
    scene.collection.children.link(walls)
    from test_blender_operators import make_wall
    walls.objects.link(make_wall("Wall", (8.0, -6.0), (40.0, 1.0)))   # across the second's way
    figs[1].turning.obstacles = walls
    before = snapshot()
    with pytest.raises(RuntimeError, match=r"Follow Path: Telemark\.001: no feasible plan.*"
                                           r"nothing was written"):
        bpy.ops.turning.follow_path()
    assert snapshot() == before, diff(before, snapshot())


# -- the worker processes inside Blender ----------------------------------------------------------

def test_workers_do_not_run_the_script_blender_was_started_with(scene, tmp_path, monkeypatch):
    """``blender -b --python job.py``: ``__main__`` is the job; spawn would run it again in
    every worker (where it fails: no bpy in Blender's own Python)."""
    script = tmp_path / "job.py"
    script.write_text("raise SystemExit('a worker ran the job script again')\n")
    main = types.ModuleType("__main__")
    main.__file__ = str(script)
    monkeypatch.setitem(sys.modules, "__main__", main)
    fig = path_figures(1)[0]
    fig.turning.crowd.time_offset = 0.25                   # one late figure: the crowd job
    assert bpy.ops.turning.follow_path() == {"FINISHED"}
    assert sys.modules["__main__"] is main


@pytest.fixture
def extension_package(monkeypatch):
    """This package imported as Blender imports an extension: ``bl_ext.<repository>.<id>``,
    the first two names modules Blender makes as its junction modules do
    (``_bpy_internal/extensions/junction_module.py``): a placeholder ``__file__`` such as
    ``"[bl_ext]"``, no ``__path__`` on the first, the repository's folder on the second."""
    root = Path(blender_turning.__file__).resolve().parents[1]
    if not root.name.isidentifier():
        pytest.skip(f"the checkout's folder {root.name!r} is not a module name")
    ns = types.ModuleType("bl_ext_test")
    ns.__file__ = "[bl_ext_test]"
    repo = types.ModuleType("bl_ext_test.repo")
    repo.__file__ = "[bl_ext_test.repo]"
    repo.__path__ = [str(root.parent)]
    monkeypatch.setitem(sys.modules, "bl_ext_test", ns)
    monkeypatch.setitem(sys.modules, "bl_ext_test.repo", repo)
    name = f"bl_ext_test.repo.{root.name}.blender_turning"
    yield name
    for key in [k for k in sys.modules if k.startswith("bl_ext_test.")]:
        del sys.modules[key]


def test_workers_load_tasks_of_the_package_under_its_extension_name(scene, extension_package):
    ext = extension_package
    job_mod = importlib.import_module(ext + ".blender.jobs.workers")
    crowd_mod = importlib.import_module(ext + ".crowd")
    core = importlib.import_module(ext + ".core")
    assert job_mod._worker_stubs() == [("bl_ext_test", []),
                                       ("bl_ext_test.repo", sys.modules["bl_ext_test.repo"]
                                        .__path__)]
    crowd = crowd_mod.Crowd("c", [crowd_mod.CrowdFigure("a", core.preset("skier"),
                                                        crowd_mod.Turns(2.0, 0.4))], 3.0)
    task = crowd_mod.runner.crowd_tasks(crowd)[0]
    pool = job_mod.worker_pool(1)
    try:
        with job_mod._plain_main():
            out = pool.submit(crowd_mod.runner.run_task, task).result(timeout=120)
    finally:
        pool.shutdown()
    here = run_task(crowd_tasks(Crowd("c", [CrowdFigure("a", blender_turning.core.preset(
        "skier"), Turns(2.0, 0.4))], 3.0))[0])
    np.testing.assert_array_equal(out[0].trajectory.data, here[0].trajectory.data)


def road_figure():
    lead = add("CYCLIST")
    lead.turning.path = make_path([(0, 0), (0, -40), (20, -80)])
    return lead


def path_of(fig):
    from blender_turning.core.course.path import HermitePath
    return HermitePath.from_bezier(scene_adapters.bezier_control_points(fig.turning.path))


@pytest.mark.parametrize("staging", ["ALONG_TRACK", "WAIT"])
def test_followers_on_a_road_follow_the_core_offset_paths(scene, staging):
    """Each follower's curve is the road offset sideways, its gap cut off its end, and (along
    the track) a straight lead-in of its gap before it (docs/layers.md)."""
    from blender_turning.crowd import offset_path
    lead = road_figure()
    road = path_of(lead)
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=2, gap_distance=5.0,
                                     gap_by="DISTANCE", lateral=1.0, alternate=True,
                                     staging=staging) == {"FINISHED"}
    along = staging == "ALONG_TRACK"
    for k, d in ((1, -1.0), (2, 1.0)):
        fig = bpy.data.objects[f"Cyclist {k}"]
        off = offset_path(road, d)
        want = off.led_in(5.0 * k).split(off.length())[0] if along else \
            off.split(off.length() - 5.0 * k)[0]
        got = path_of(fig)
        for a in ("knots", "t_out", "t_in"):   # float32 up to 90 m: ulp 7.6e-6 (measured 5.7e-6)
            np.testing.assert_allclose(getattr(got, a), getattr(want, a), atol=2e-5)
        np.testing.assert_allclose(fig.turning.start[:2], got.knots[0], atol=1e-5)
        assert fig.turning.crowd.time_offset == (0.0 if along else
                                                 f32(k * 5.0 / lead.turning.speed))


def test_a_peloton_starts_where_the_core_places_its_rows(scene):
    from blender_turning.blender.scene import crowd_scene
    from blender_turning.crowd import offset_path, peloton
    lead = road_figure()
    road = path_of(lead)
    member = crowd_scene.template_member(bpy.context, lead, path=True)
    want = peloton(member, 5, 4.0, abreast=2, spacing=0.8, name="m")
    assert bpy.ops.turning.add_crowd(formation="PELOTON", count=5, row_gap=4.0, abreast=2,
                                     row_spacing=0.8) == {"FINISHED"}
    for k, m in enumerate(want, start=1):
        fig = bpy.data.objects[f"Cyclist {k}"]
        start = path_of(fig).knots[0]
        np.testing.assert_allclose(start, m.state0()[:2], atol=1e-5)   # float32 (1e-6)
        assert fig.turning.crowd.time_offset == 0.0
        lateral = ((k - 1) % 2 * 0.8 - 0.4) if k < 5 else 0.0   # rows of 2, the last of 1
        # each row ends as far short of the road's end as it starts behind the front row
        off = offset_path(road, lateral)
        end = off.split(off.length() - 4.0 * ((k - 1) // 2))[0] if k > 2 else off
        np.testing.assert_allclose(path_of(fig).knots[-1], end.knots[-1], atol=1e-5)
        np.testing.assert_allclose(path_of(fig).knots[-1], m.controller.scene.path.knots[-1],
                                   atol=1e-5)


def test_a_figure_that_cannot_be_read_is_named_and_nothing_changes(scene):
    figs = path_figures(2)
    figs[1].turning.path = make_path([(8, 0)], "OnePoint")
    before = snapshot()
    with pytest.raises(RuntimeError, match=r"Follow Path: Telemark\.001: path 'OnePoint' has 1 "
                                           r"point\(s\); it needs at least 2"):
        bpy.ops.turning.follow_path()
    assert snapshot() == before, diff(before, snapshot())


@pytest.mark.installed
def test_the_crowd_panel_draws_the_settings_and_add_crowd(scene):
    from blender_turning.blender.ui import crowd as panel_crowd
    from test_blender_operators import LayoutStub
    add("SKIER")
    calls = []
    cls = panel_crowd.VIEW3D_PT_turning_crowd
    assert cls.poll(bpy.context)
    fake = type("P", (panel_crowd.FigurePanel,), {"layout": LayoutStub(calls)})()
    cls.draw(fake, bpy.context)
    drawn = [c[1][1] for c in calls if c[0] == "prop"] + [c[1][0] for c in calls
                                                         if c[0] == "operator_menu_enum"]
    assert drawn == ["time_offset", "first_turn", "priority", "turning.add_crowd"]
    assert any("act on 1 figure (the selection)" in c[2].get("text", "") for c in calls
               if c[0] == "label")
