"""Operators on the bpy wheel: polls that say why, presets, bad input reported with nothing
half-written, Bake Turns reading back equal to the mapping, baking twice = once, Clear Bake,
Follow Path (infeasible plan, cancel) leaving the scene as it was."""
import os
import tempfile
import time

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from scene_snapshot import snapshot  # noqa: E402

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.scene import follow_scene, scene_adapters  # noqa: E402
from blender_turning.blender.ui import presets  # noqa: E402
from blender_turning.blender.jobs.follow_job import Cancelled  # noqa: E402
from blender_turning.blender.jobs.pipeline import figure_pose_track  # noqa: E402
from blender_turning.blender.scene.scene_adapters import (PLAN_CURVATURE_RATE,  # noqa: E402
                                                          FrameRange)
from blender_turning.core.physics.params import PRESETS  # noqa: E402
from blender_turning.core.registry import SPORT_PRESETS  # noqa: E402
from modal_stand_ins import Context, WindowManager  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]
OPERATORS = ("add_figure", "bake_turns", "follow_path", "clear_bake")


def have_mapping():
    try:
        from blender_turning.mapping import map_trajectory  # noqa: F401
    except ImportError:
        return False
    return True


needs_mapping = pytest.mark.skipif(not have_mapping(), reason="the mapping layer is not there")


@pytest.fixture
def scene(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, 72
    sc.render.fps = 24
    return sc


def add(sport="SKIER", at=(0, 0, 0)):
    bpy.context.scene.cursor.location = at
    assert bpy.ops.turning.add_figure(sport=sport) == {"FINISHED"}
    return bpy.context.view_layer.objects.active


def test_every_operator_has_undo_and_a_poll():
    for name in OPERATORS:
        cls = getattr(bpy.types, f"TURNING_OT_{name}")
        assert {"REGISTER", "UNDO"} <= cls.bl_options, name


@pytest.mark.parametrize("op, why", [("bake_turns", "No figure selected"),
                                     ("clear_bake", "No figure selected"),
                                     ("follow_path", "No figure selected")])
def test_poll_says_why(scene, op, why):
    with pytest.raises(RuntimeError, match=why):
        getattr(bpy.ops.turning, op)()


def test_poll_without_bake_or_path(scene):
    add()
    with pytest.raises(RuntimeError, match="no baked turns"):
        bpy.ops.turning.clear_bake()
    with pytest.raises(RuntimeError, match="path curve"):
        bpy.ops.turning.follow_path()
    scene.frame_end = scene.frame_start
    with pytest.raises(RuntimeError, match="at least two frames"):
        bpy.ops.turning.bake_turns()


@pytest.mark.installed
@pytest.mark.parametrize("sport", ["SKIER", "SNOWBOARDER", "TELEMARK", "CYCLIST"])
def test_add_figure_at_cursor_from_preset(scene, sport):
    obj = add(sport, at=(3, -2, 0))
    assert obj.type == "ARMATURE" and obj.select_get()
    assert tuple(obj.location) == pytest.approx((3, -2, 0))
    s, fig = obj.turning, PRESETS[sport.lower()]
    assert s.is_figure and s.sport == sport
    assert (s.mass, s.com_height, s.speed) == pytest.approx((fig.body.m, fig.body.l, fig.body.V_cm))
    assert s.curvature_max == pytest.approx(fig.limits.C_f_max, rel=1e-6)
    body = obj.children[0]
    assert body.type == "MESH" and body.modifiers[0].object == obj


def test_sport_presets_are_the_sport_records(scene):
    """Each sport's preset (the Sport Presets menu's entry) sets its record's numbers back; a
    sport's own preset with equipment (the racers, the carver) applies to a figure of its
    sport and names its equipment, which the figure's core Figure carries."""
    for sport, fig in PRESETS.items():
        own = SPORT_PRESETS.get(sport)
        obj = add((own.sport if own else sport).upper())
        s = obj.turning
        s.mass, s.inertia, s.curvature_rate_max, s.plan_curvature_rate = 99.0, 3.0, 4.0, 0.9
        assert bpy.ops.turning.apply_figure_preset(sport=sport.upper()) == {"FINISHED"}
        assert s.sport == (own.sport if own else sport).upper()
        assert s.equipment.preset == (sport if own else "")
        assert scene_adapters.figure_from_settings(s).name == sport
        assert (s.mass, s.com_height, s.inertia, s.speed) == pytest.approx(
            (fig.body.m, fig.body.l, fig.body.I_v, fig.body.V_cm), rel=1e-6)
        assert (s.curvature_max, s.curvature_rate_max, s.fall_angle) == pytest.approx(
            (fig.limits.C_f_max, fig.limits.dC_f_max, fig.limits.theta_fall), rel=1e-6)
        assert s.plan_curvature_rate == pytest.approx(PLAN_CURVATURE_RATE[sport] if not own
                                                      else own.plan_curvature_rate)
    obj = add("SNOWBOARDER")
    with pytest.raises(RuntimeError, match="Skier preset would not change its rig"):
        bpy.ops.turning.apply_figure_preset(sport="SLALOM_RACER")
    assert obj.turning.equipment.preset == ""
    assert bpy.ops.turning.apply_figure_preset(sport="CARVER") == {"FINISHED"}
    assert bpy.ops.turning.apply_figure_preset(sport="SNOWBOARDER") == {"FINISHED"}
    assert obj.turning.equipment.preset == ""
    obj.turning.equipment.preset = "gs_racer"               # not a snowboarder's preset
    with pytest.raises(ValueError, match=r"turning.equipment.preset\) = 'gs_racer' is not a "
                                         r"preset of the snowboarder \(carver"):
        scene_adapters.figure_from_settings(obj.turning)


def test_bad_setting_is_reported_and_nothing_written(scene):
    obj = add("SKIER")
    obj.turning.lean = obj.turning.fall_angle          # beyond the fall bound: a bad input
    before = snapshot()
    with pytest.raises(RuntimeError, match="lean"):
        bpy.ops.turning.bake_turns()
    assert snapshot() == before


@needs_mapping
def test_bake_turns_reads_back_equal_to_the_mapping(scene):
    obj = add("SKIER")
    obj.turning.period = 2.5
    obj.keyframe_insert("turning.period", frame=1)     # a keyed controller parameter
    obj.turning.period = 1.8
    obj.keyframe_insert("turning.period", frame=72)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    frames = FrameRange.of_scene(scene)
    _, track = figure_pose_track(obj, frames)
    fcs = {(fc.data_path, fc.array_index): fc for fc in bake.baked_channels(obj).fcurves}
    assert ("turning.period", 0) in {(fc.data_path, fc.array_index)   # the user's keys stay,
                                     for fc in compat.channels(obj).fcurves}  # in the tweaks
    for bone, ch in track.bones.items():
        for attr, arr in (("location", ch.location), ("rotation_quaternion", ch.rotation)):
            if arr is None:
                continue
            for i in range(arr.shape[1]):
                fc = fcs[(f'pose.bones["{bone}"].{attr}', i)]
                co = np.empty(2 * len(fc.keyframe_points), np.float32)
                fc.keyframe_points.foreach_get("co", co)
                np.testing.assert_array_equal(co[0::2], np.arange(1, 73))
                np.testing.assert_allclose(co[1::2], arr[:, i], atol=2e-6)
    assert obj.turning.foot_track is not None
    assert len(obj.turning.foot_track.data.splines[0].points) == 72


@pytest.mark.installed
@needs_mapping
def test_bake_twice_equals_once_and_clear_restores(scene):
    obj = add("SKIER")
    before = snapshot()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    once = snapshot()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert snapshot() == once
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    after = snapshot()
    # The figure is back where it was, with no action and no foot track.
    assert after == before
    assert obj.turning.foot_track is None
    assert all(tuple(pb.rotation_quaternion) == (1, 0, 0, 0) for pb in obj.pose.bones)


def make_path(points, name="Path"):
    curve = bpy.data.curves.new(name, "CURVE")
    sp = curve.splines.new("BEZIER")
    sp.bezier_points.add(len(points) - 1)
    for bp, (x, y) in zip(sp.bezier_points, points):
        bp.co = (x, y, 0)
        bp.handle_left_type = bp.handle_right_type = "AUTO"
    obj = bpy.data.objects.new(name, curve)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def make_wall(name, center, size):
    mesh = bpy.data.meshes.new(name)
    sx, sy = size[0] / 2, size[1] / 2
    mesh.from_pydata([(-sx, -sy, 0), (sx, -sy, 0), (sx, sy, 0), (-sx, sy, 0),
                      (-sx, -sy, 1), (sx, -sy, 1), (sx, sy, 1), (-sx, sy, 1)], [],
                     [(0, 1, 2, 3), (4, 5, 6, 7)])
    obj = bpy.data.objects.new(name, mesh)
    obj.location = (*center, 0)
    return obj


def test_path_with_one_point_is_reported(scene):
    obj = add("CYCLIST")
    obj.turning.path = make_path([(0, 0)])
    bpy.context.view_layer.objects.active = obj
    before = snapshot()
    with pytest.raises(RuntimeError, match="needs at least 2"):
        bpy.ops.turning.follow_path()
    assert snapshot() == before


def test_infeasible_plan_is_reported_and_scene_unchanged(scene):
    obj = add("CYCLIST")
    obj.turning.path = make_path([(0, 0), (0, -30)])
    walls = bpy.data.collections.new("Walls")
    scene.collection.children.link(walls)
    walls.objects.link(make_wall("Wall", (0, -8), (60, 1.0)))   # across the road
    obj.turning.obstacles = walls
    bpy.context.view_layer.objects.active = obj
    before = snapshot()
    with pytest.raises(RuntimeError, match=r"no feasible plan at t = [\d.]+ s, position.*"
                                           r"\(nearest obstacle: 'Wall', [\d.]+ m away\)"):
        bpy.ops.turning.follow_path()
    assert snapshot() == before


def test_cancelled_follow_path_leaves_scene_unchanged(scene):
    obj = add("TELEMARK")
    obj.turning.path = make_path([(0, 0), (3, -12), (-3, -24), (0, -36)])
    before = snapshot()
    job = follow_scene.prepare(bpy.context, obj)
    job.start()
    job.cancel(wait=True)                                 # what ESC does in the modal operator
    assert isinstance(job.error, Cancelled) or job.result is not None
    assert snapshot() == before


@pytest.mark.installed
@needs_mapping
@pytest.mark.parametrize("sport", ["SKIER", "TELEMARK"])
def test_follow_path_bakes_and_fits_the_frame_range(scene, sport):
    obj = add(sport)                                 # the preset's planner curvature rate
    obj.turning.path = make_path([(0, 0), (3, -12), (-3, -24), (0, -36)])
    assert bpy.ops.turning.follow_path() == {"FINISHED"}
    action = bake.figure_action(obj)
    assert action.name == obj.name
    # The foot follows the curve (within 3 m) to its end; the scene's range fits the run.
    track = obj.turning.foot_track.data.splines[0].points
    co = np.empty(4 * len(track))
    track.foreach_get("co", co)
    xy = co.reshape(-1, 4)[:, :2]
    curve = scene_adapters.bezier_control_points(obj.turning.path)
    from blender_turning.core.course.path import HermitePath
    samples = HermitePath.from_bezier(curve).sample(64)
    dist = np.min(np.linalg.norm(xy[:, None, :] - samples[None, :, :], axis=2), axis=1)
    assert dist.max() < 3.0, dist.max()
    assert np.linalg.norm(xy[-1] - (0, -36)) < 3.0
    assert scene.frame_end == scene.frame_start + len(track) - 1
    fc = next(f for f in bake.baked_channels(obj).fcurves if f.data_path == "location")
    assert len(fc.keyframe_points) == len(track)


class LayoutStub:
    """Stands in for ``UILayout`` (no windows in background mode): records every call."""

    def __init__(self, calls):
        self.calls = calls

    def __getattr__(self, name):
        def call(*args, **kwargs):
            self.calls.append((name, args, kwargs))
            return LayoutStub(self.calls)
        return call

    def __setattr__(self, name, value):
        if name != "calls":
            return
        object.__setattr__(self, name, value)


@pytest.mark.installed
def test_panels_draw_every_setting(scene):
    from blender_turning.blender.ui import panel
    obj = add("SKIER")
    ctx = bpy.context
    drawn = []
    for cls in panel.classes:
        if hasattr(cls, "poll"):
            assert cls.poll(ctx)
        calls = []
        mixins = tuple(b for b in cls.__mro__[1:] if b.__module__ == panel.__name__)
        fake = type("P", mixins, {"layout": LayoutStub(calls)})()
        cls.draw(fake, ctx)
        drawn += [c[1][1] for c in calls if c[0] == "prop" and len(c[1]) > 1]
        drawn += [c[1][0] for c in calls if c[0] == "operator"]
    for name in ("period", "lean", "heading", "use_heading", "mass", "speed", "curvature_max",
                 "path", "obstacles"):
        assert name in drawn, name
    for op in ("turning.bake_turns", "turning.clear_bake", "turning.follow_path"):
        assert op in drawn, op
    assert obj.turning.is_figure


def modal_operator(obj):
    """A stand-in ``self`` for ``TURNING_OT_follow_path.modal`` with the job running."""
    op_cls = bpy.types.TURNING_OT_follow_path
    reports = []
    fake = type("Op", (), {"report": lambda self, kind, msg: reports.append((kind, msg)),
                           "_cleanup": op_cls._cleanup, "_complete": op_cls._complete})()
    fake._job = follow_scene.prepare(bpy.context, obj)
    fake._fig_uid, fake._timer = obj.session_uid, object()
    fake._job.start()
    return op_cls, fake, reports


def test_esc_in_the_modal_follow_path_leaves_the_scene_unchanged(scene):
    obj = add("TELEMARK")
    obj.turning.path = make_path([(0, 0), (3, -12), (-3, -24), (0, -36), (0, -60)])
    obj.turning.plan_curvature_rate = 0.3
    before = snapshot()
    op_cls, fake, reports = modal_operator(obj)
    wm = WindowManager()
    esc = type("E", (), {"type": "ESC"})()
    assert op_cls.modal(fake, Context(wm), esc) == {"CANCELLED"}
    assert fake._job.done() and "end" in wm.progress
    assert reports and "cancelled" in reports[0][1]
    assert snapshot() == before


@pytest.mark.installed
@needs_mapping
def test_modal_follow_path_reports_progress_then_bakes(scene):
    obj = add("TELEMARK")
    obj.turning.path = make_path([(0, 0), (3, -12), (-3, -24), (0, -36)])
    obj.turning.plan_curvature_rate = 0.3
    op_cls, fake, reports = modal_operator(obj)
    wm = WindowManager()
    timer = type("E", (), {"type": "TIMER"})()
    while True:
        ret = op_cls.modal(fake, Context(wm), timer)
        if ret != {"RUNNING_MODAL"}:
            break
        time.sleep(0.02)                   # Blender's timer ticks; leave the planner the GIL
    assert ret == {"FINISHED"}, reports
    values = [v for v in wm.progress if isinstance(v, int)]
    assert values and values == sorted(values) and values[-1] == 100
    assert bake.figure_action(obj).name == obj.name


@needs_mapping
def test_first_bake_starts_where_the_figure_was_moved(scene):
    obj = add("SKIER")
    obj.location = (5.0, -3.0, 0.0)
    obj.rotation_euler = (0.0, 0.0, 0.4)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    first = obj.turning.foot_track.data.splines[0].points[0].co
    assert (first[0], first[1]) == pytest.approx((5.0, -3.0), abs=1e-5)
    assert obj.turning.start_heading == pytest.approx(0.4 + np.pi / 2, abs=1e-6)


@needs_mapping
def test_keyed_lean_is_followed_over_time(scene):
    """Section 5: parameters specified over time.  Lean keyed from 8 to 28 deg over 10 s."""
    scene.frame_end = 241
    obj = add("SNOWBOARDER")
    obj.turning.lean = np.radians(8.0)
    obj.keyframe_insert("turning.lean", frame=1)
    obj.turning.lean = np.radians(28.0)
    obj.keyframe_insert("turning.lean", frame=241)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    fc = next(f for f in bake.baked_channels(obj).fcurves if f.data_path == '["turn_lean"]')
    co = np.empty(2 * len(fc.keyframe_points), np.float32)
    fc.keyframe_points.foreach_get("co", co)
    lean = np.abs(co[1::2])
    early, late = lean[:72].max(), lean[-72:].max()
    assert np.degrees(early) < 14.0 and np.degrees(late) > 20.0, (np.degrees(early),
                                                                  np.degrees(late))


def test_obstacle_footprints_and_path_points_in_world_space(scene):
    from blender_turning.blender.scene.scene_adapters import (bezier_control_points,
                                                              obstacle_footprints)
    coll = bpy.data.collections.new("Obs")
    scene.collection.children.link(coll)
    wall = make_wall("W", (10.0, 5.0), (4.0, 2.0))
    wall.rotation_euler = (0.0, 0.0, np.pi / 2)            # its 4 m side now along y
    coll.objects.link(wall)
    ((name, hull),) = obstacle_footprints(coll, bpy.context.evaluated_depsgraph_get())
    assert name == "W" and len(hull) == 4
    np.testing.assert_allclose(hull.min(axis=0), (9.0, 3.0), atol=1e-5)
    np.testing.assert_allclose(hull.max(axis=0), (11.0, 7.0), atol=1e-5)
    path = make_path([(0, 0), (0, -10), (5, -20)])
    path.location = (1.0, 2.0, 0.0)
    bpy.context.evaluated_depsgraph_get()                  # as Follow Path does before reading
    ctrl = bezier_control_points(path)
    assert ctrl.shape == (7, 2)
    np.testing.assert_allclose(ctrl[::3], [(1, 2), (1, -8), (6, -18)], atol=1e-5)
