"""Guards for bake mutants that the rest of the suite let through: a pose track
holding NaN is refused before anything is written; Clear Bake keeps the user's keyed
``turning.*`` parameters; a re-bake starts from a moved Start.  Runs on bpy 5.0 and 4.2."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.jobs.pipeline import figure_pose_track  # noqa: E402
from blender_turning.blender.scene.scene_adapters import FrameRange  # noqa: E402
from blender_turning.mapping.base import BoneChannels, PoseTrack  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]


@pytest.fixture
def figure(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, 48
    sc.render.fps = 24
    sc.cursor.location = (0.0, 0.0, 0.0)
    assert bpy.ops.turning.add_figure(sport="SKIER") == {"FINISHED"}
    return bpy.context.view_layer.objects.active


def keys(obj, data_path):
    """``(frames, values)`` of the F-curve ``data_path`` on ``obj``'s current action, or None."""
    bag = compat.channels(obj)
    fc = next((f for f in (bag.fcurves if bag else ()) if f.data_path == data_path), None)
    if fc is None:
        return None
    co = np.empty(2 * len(fc.keyframe_points), np.float32)
    fc.keyframe_points.foreach_get("co", co)
    return co[0::2].tolist(), co[1::2].tolist()


def with_nan(track, where):
    """A copy of ``track`` with one NaN in the ``where`` channel."""
    loc, rot = track.location.copy(), track.rotation.copy()
    bones = {k: BoneChannels(None if v.location is None else v.location.copy(),
                             None if v.rotation is None else v.rotation.copy())
             for k, v in track.bones.items()}
    props = {k: np.array(v, float) for k, v in track.props.items()}
    if where == "location":
        loc[3, 0] = np.nan
    elif where == "bone":
        name = next(k for k, v in bones.items() if v.rotation is not None)
        bones[name].rotation[5, 1] = np.nan
    else:
        props[next(iter(props))][7] = np.nan
    return PoseTrack(track.frames, loc, rot, bones, props)


@pytest.mark.parametrize("where", ["location", "bone", "prop"])
def test_a_nan_pose_track_is_refused_and_nothing_written(figure, where):
    _, track = figure_pose_track(figure, FrameRange.of_scene(bpy.context.scene))
    actions = set(bpy.data.actions)
    with pytest.raises(bake.BakeError, match="finite"):
        bake.bake_pose_track(figure, with_nan(track, where))
    assert set(bpy.data.actions) == actions and bake.figure_action(figure) is None
    assert not [k for k in figure.keys() if k.startswith("turn_")]


def test_clear_bake_keeps_the_users_keyed_parameters(figure):
    figure.turning.period = 2.5
    figure.keyframe_insert("turning.period", frame=1)
    figure.turning.period = 1.8
    figure.keyframe_insert("turning.period", frame=48)
    before = keys(figure, "turning.period")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    figure.turning.lean = math.radians(18)                 # keyed after the bake, on its action
    figure.keyframe_insert("turning.lean", frame=10)
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert keys(figure, "turning.period") == before
    assert keys(figure, "turning.lean") == ([10.0], [pytest.approx(math.radians(18))])
    assert keys(figure, "location") is None and keys(figure, '["turn_lean"]') is None
    bpy.context.scene.frame_set(48)
    assert figure.turning.period == pytest.approx(1.8)     # the keys still drive the figure


def test_rebake_starts_from_a_moved_start(figure):
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    figure.turning.start = (10.0, 5.0, 0.0)
    figure.turning.start_heading = 1.0
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    first = figure.turning.foot_track.data.splines[0].points[0].co
    assert (first[0], first[1]) == pytest.approx((10.0, 5.0), abs=1e-5)
    bpy.context.scene.frame_set(1)
    assert tuple(figure.location)[:2] == pytest.approx((10.0, 5.0), abs=1e-5)
    # The rest pose faces +Y: heading 1.0 rad from +x is a yaw of 1.0 - pi / 2.
    assert figure.rotation_euler[2] == pytest.approx(1.0 - math.pi / 2, abs=1e-5)
