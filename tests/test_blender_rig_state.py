"""The user's rig keeps its state, on the bpy wheel: Undo restores it after Make Figure
and after Remove Figure (Blender's memfile undo runs headless), and the action it was playing
survives a bake.  Operators called from Python push no undo step of
their own here, so the test pushes one after each, as the window manager does after an operator
with the UNDO flag: what is checked is that everything they change is undoable data."""
import os
import tempfile

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender import compat  # noqa: E402
from rig_fixtures import activate, mixamo_skeleton, state  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]


@pytest.mark.installed
def test_undo_make_figure_and_remove_figure():
    obj = mixamo_skeleton("Bob")
    activate(obj)
    before = state(obj)
    objects = sorted(o.name for o in bpy.data.objects)
    bpy.ops.ed.undo_push(message="the rig")
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    bpy.ops.ed.undo_push(message="Make Figure")
    assert len(bpy.data.objects) == len(objects) + 4            # skis and poles
    bpy.ops.ed.undo()
    obj = bpy.data.objects["Bob"]
    assert sorted(o.name for o in bpy.data.objects) == objects
    assert state(obj) == before
    assert not obj.turning.is_figure
    bpy.ops.ed.redo()
    obj = bpy.data.objects["Bob"]
    assert obj.turning.is_figure and obj.turning.rig.equipment is not None
    activate(obj)
    assert bpy.ops.turning.remove_figure() == {"FINISHED"}
    bpy.ops.ed.undo_push(message="Remove Figure")
    assert sorted(o.name for o in bpy.data.objects) == objects
    bpy.ops.ed.undo()
    obj = bpy.data.objects["Bob"]
    assert obj.turning.is_figure and len(obj.turning.rig.equipment.objects) == 4


def test_the_users_action_is_kept_and_given_back():
    """The bake's guarantees on a user's rig: the action the rig was playing goes onto a muted
    NLA track, untouched; Clear Bake gives it back; Remove Figure leaves the rig as it was."""
    obj = mixamo_skeleton("Ann")
    pb = obj.pose.bones["mixamorig:Head"]
    for f, z in ((1, 0.0), (10, 0.2)):
        pb.rotation_quaternion = (1.0, 0.0, 0.0, z)
        pb.keyframe_insert("rotation_quaternion", frame=f)
    mine = obj.animation_data.action
    keys = [tuple(k.co) for fc in compat.channels(obj).fcurves for k in fc.keyframe_points]
    activate(obj)
    before = state(obj)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = 1, 24
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert obj.animation_data.action is not mine
    assert [t.name for t in obj.animation_data.nla_tracks if t.mute]
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert obj.animation_data.action is mine
    assert [tuple(k.co) for fc in compat.channels(obj).fcurves
            for k in fc.keyframe_points] == keys
    assert bpy.ops.turning.remove_figure() == {"FINISHED"}
    assert state(obj) == before


def test_clear_bake_puts_the_rig_back_where_its_run_started():
    """Moved after Make Figure, then baked: Clear Bake puts the rig where the run started (its
    Start, as for a built-in figure) with the pose it had."""
    obj = mixamo_skeleton("Cid")
    activate(obj)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    obj.location = (3.0, -2.0, 0.0)
    obj.rotation_euler[2] = 0.5
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = 1, 24
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    bpy.context.scene.frame_set(20)
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert tuple(obj.location) == pytest.approx((3.0, -2.0, 0.0), abs=1e-6)
    assert obj.rotation_euler[2] == pytest.approx(0.5, abs=1e-6)
    assert all(tuple(pb.rotation_quaternion) == (1.0, 0.0, 0.0, 0.0) for pb in obj.pose.bones)
