"""Rebakes keep the animator's work: the bake plays from an NLA track of its own, the animator's
keys live on a tweak layer above it (the active action, Combine) and survive every rebake and
Clear Bake; a key of the user's inside the bake layer makes the rebake refuse, naming it."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from mathutils import Quaternion  # noqa: E402
from scene_snapshot import diff, snapshot  # noqa: E402
from test_blender_animator import LayoutStub  # noqa: E402
from test_blender_operators import add, scene  # noqa: E402,F401
from test_blender_robustness import settled, user_keys  # noqa: E402

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake, bake_layers  # noqa: E402
from blender_turning.blender.ui import panel  # noqa: E402

pytestmark = pytest.mark.blender

HEAD = "spine.004"                  # the neck: the highest spine bone the skier's bake keys
HEAD_PATH = f'pose.bones["{HEAD}"].rotation_quaternion'
TWEAK = Quaternion((0.0, 0.0, 1.0), math.radians(25.0))      # +25 deg about the bone's Z


def baked_head(obj, frame) -> Quaternion:
    """The head's rotation at ``frame`` on the bake layer alone (its keys, linear)."""
    fcs = {fc.array_index: fc for fc in bake.baked_channels(obj).fcurves
           if fc.data_path == HEAD_PATH}
    return Quaternion([fcs[i].evaluate(frame) for i in range(4)]).normalized()


def shown_head(obj, frame) -> Quaternion:
    """The head's rotation Blender shows at ``frame`` (NLA, tweak layer and all)."""
    bpy.context.scene.frame_set(frame)
    return Quaternion(obj.pose.bones[HEAD].rotation_quaternion).normalized()


def angle(a: Quaternion, b: Quaternion) -> float:
    return a.rotation_difference(b).angle


def key_head_tweak(obj, frame=50):
    """What an animator does: turn the head 25 deg further at ``frame`` and key it."""
    pb = obj.pose.bones[HEAD]
    bpy.context.scene.frame_set(frame)
    pb.rotation_quaternion = Quaternion(pb.rotation_quaternion) @ TWEAK
    assert pb.keyframe_insert("rotation_quaternion", frame=frame)


# Blender keys a Combine layer as the offset from the NLA below (to float32 round-off) and
# evaluates the head on the bake's linear keys: measured 2e-7 rad between the pose shown and
# bake @ tweak.  A tweak lost to a rebake is 25 deg (0.44 rad) off.
ANGLE_TOL = 1e-4


@pytest.mark.installed
def test_a_key_set_after_a_bake_survives_the_rebake(scene):
    obj = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert HEAD_PATH in {fc.data_path for fc in bake.baked_channels(obj).fcurves}
    key_head_tweak(obj)
    assert angle(shown_head(obj, 50), baked_head(obj, 50) @ TWEAK) < ANGLE_TOL
    obj.turning.lean = math.radians(15)                       # a different motion
    before_head = baked_head(obj, 50)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert angle(baked_head(obj, 50), before_head) > math.radians(0.5)   # the bake did change
    assert angle(shown_head(obj, 50), baked_head(obj, 50) @ TWEAK) < ANGLE_TOL
    # Away from the key the offset is the same (a one-key Combine layer holds it).
    assert angle(shown_head(obj, 20), baked_head(obj, 20) @ TWEAK) < ANGLE_TOL
    tweaks = compat.channels(obj)
    assert bake_layers.is_tweaks(obj.animation_data.action, obj)
    assert {fc.data_path for fc in tweaks.fcurves} == {HEAD_PATH}


@pytest.mark.installed
@pytest.mark.parametrize("how", ["bake_turns", "follow_path"])
def test_a_key_set_before_the_first_bake_is_kept_and_said(scene, capfd, how):
    """A key of the user's from before any bake stops playing under the bake (its action is
    stashed on a muted track): the bake says so, naming the action and the track, once."""
    obj = add("SKIER")
    if how == "follow_path":
        bpy.ops.curve.primitive_bezier_curve_add(location=(0, 0, 0))
        curve = bpy.context.view_layer.objects.active
        curve.scale = (10, 10, 1)
        obj.turning.path = curve
        for o in bpy.context.selected_objects:
            o.select_set(False)
        bpy.context.view_layer.objects.active = obj
        obj.select_set(True)
    bpy.context.scene.frame_set(50)
    obj.pose.bones[HEAD].rotation_quaternion = TWEAK
    assert obj.pose.bones[HEAD].keyframe_insert("rotation_quaternion", frame=50)
    user = obj.animation_data.action
    capfd.readouterr()
    op = getattr(bpy.ops.turning, how)
    assert op() == {"FINISHED"}
    out = capfd.readouterr().out
    said = [line for line in out.splitlines() if "no longer plays" in line]
    assert len(said) == 1, out
    assert user.name in said[0] and "Turning: user action" in said[0]
    assert "Clear Bake" in said[0]
    assert angle(shown_head(obj, 50), baked_head(obj, 50)) < ANGLE_TOL   # the bake plays
    assert op() == {"FINISHED"}                               # a rebake: already said
    assert "no longer plays" not in capfd.readouterr().out
    assert bake.clear_bake(obj) and obj.animation_data.action == user
    assert angle(shown_head(obj, 50), TWEAK) < ANGLE_TOL       # given back


def test_tweaks_survive_clear_bake_and_play_again_on_the_next_bake(scene):
    obj = add("SKIER")
    user = user_keys(obj)                     # the figure plays an action of the user's
    before = settled()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    key_head_tweak(obj)
    tweaks = obj.animation_data.action
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    # The user's action is back exactly; the tweaks wait on a muted track of their own.
    assert obj.animation_data.action == user
    parked = [t for t in obj.animation_data.nla_tracks if t.name == bake_layers.TWEAK_TRACK]
    assert len(parked) == 1 and parked[0].mute and parked[0].strips[0].action == tweaks
    after = settled()
    assert {fc.data_path for fc in compat.all_fcurves(tweaks)} == {HEAD_PATH}
    after.pop(("action", tweaks.name))
    after[("object", obj.name)]["anim"] = before[("object", obj.name)]["anim"] = None
    assert after == before, diff(before, after)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert obj.animation_data.action == tweaks
    assert angle(shown_head(obj, 50), baked_head(obj, 50) @ TWEAK) < ANGLE_TOL


def test_a_key_in_the_bake_layer_refuses_the_rebake_and_names_it(scene):
    obj = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    # A key set on the bake strip itself (the NLA's tweak mode): the value at frame 50 changes.
    fc = next(f for f in bake.baked_channels(obj).fcurves
              if f.data_path == HEAD_PATH and f.array_index == 3)
    fc.keyframe_points[49].co.y += 0.2
    fc.update()
    before = snapshot()
    with pytest.raises(RuntimeError, match=r"bake layer holds keys of yours on "
                                           r'pose\.bones\["spine\.004"\]\.rotation_quaternion\[3\]'):
        bpy.ops.turning.bake_turns()
    assert snapshot() == before, diff(before, snapshot())
    # Clear Bake is the way to discard them; then a bake goes through.
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}


def test_a_stepped_bake_is_not_taken_for_the_users_edits(scene):
    obj = add("SKIER")
    assert bpy.ops.turning.bake_turns(step=4) == {"FINISHED"}     # handles set after writing
    assert bpy.ops.turning.bake_turns(step=3) == {"FINISHED"}
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}


@pytest.mark.installed
def test_start_tweak_layer_and_the_panel_shows_the_layers(scene):
    obj = add("SKIER")
    user_keys(obj)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    obj.animation_data.action = None                  # the user unassigned the tweak layer
    calls = []
    panel.draw_layers(LayoutStub(calls), obj)
    labels = [c[2]["text"] for c in calls if c[0] == "label"]
    assert labels == ["Layers (top first)", "Tweaks: Skier Tweaks (2 keys)",  # the keyed period
                      "Bake: Skier (NLA strip, frames 1-72)",
                      "User: Mine (kept for Clear Bake (muted))"]
    assert ("operator", ("turning.start_tweaks",)) in [c[:2] for c in calls]
    assert bpy.ops.turning.start_tweaks() == {"FINISHED"}
    adt = obj.animation_data
    assert bake_layers.is_tweaks(adt.action, obj) and adt.action_blend_type == "COMBINE"
    with pytest.raises(RuntimeError, match="already the figure's active action"):
        bpy.ops.turning.start_tweaks()
    calls = []
    panel.draw_layers(LayoutStub(calls), obj)
    assert "operator" not in [c[0] for c in calls]
    # Another action of the user's in the active slot: refused, nothing changes.
    other = bpy.data.actions.new("Other")
    adt.action = other
    before = snapshot()
    with pytest.raises(RuntimeError, match="plays the action 'Other'"):
        bpy.ops.turning.start_tweaks()
    assert snapshot() == before


def test_the_bake_plays_from_its_own_track_below_the_tweaks(scene):
    obj = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    adt = obj.animation_data
    assert [t.name for t in adt.nla_tracks] == [bake_layers.BAKE_TRACK]
    strip = adt.nla_tracks[0].strips[0]
    assert strip.action == bake.figure_action(obj)
    assert (strip.frame_start, strip.frame_end) == (1.0, 72.0)
    # The rebake over a longer range lets the strip play all of it.
    scene.frame_end = 96
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert (strip.frame_start, strip.frame_end) == (1.0, 96.0)
    loc = {fc.array_index: fc for fc in bake.baked_channels(obj).fcurves
           if fc.data_path == "location"}
    scene.frame_set(90)                           # the figure moves on the new frames
    np.testing.assert_allclose(obj.location[:2], [loc[i].evaluate(90) for i in range(2)],
                               atol=1e-5)


def as_older_versions_left_it(obj):
    """The bake as the figure's active action (no bake track, no tweak layer)."""
    adt = obj.animation_data
    action, tweaks = bake.figure_action(obj), adt.action
    adt.action = None
    bpy.data.actions.remove(tweaks)
    adt.nla_tracks.remove(adt.nla_tracks[bake_layers.BAKE_TRACK])
    adt.action_blend_type = "REPLACE"
    slots = getattr(action, "slots", None)
    compat.restore_action(obj, action, slots[0].identifier if slots else None)
    return action


def test_an_older_bake_in_the_action_slot_keeps_the_users_keys(scene):
    obj = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    action = as_older_versions_left_it(obj)
    obj.keyframe_insert("turning.period", frame=1)          # the user's key, in the bake
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}     # ... stays, as the user's action
    assert obj.animation_data.action == action and bake.figure_action(obj) is None
    assert [fc.data_path for fc in compat.channels(obj).fcurves] == ["turning.period"]


def test_rebaking_an_older_bake_moves_the_users_keys_to_the_tweak_layer(scene):
    obj = add("SKIER")
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    action = as_older_versions_left_it(obj)
    obj.turning.period = 2.5
    obj.keyframe_insert("turning.period", frame=1)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert bake.figure_action(obj) == action                # rebaked in place, now on the NLA
    assert [t.name for t in obj.animation_data.nla_tracks] == [bake_layers.BAKE_TRACK]
    assert [fc.data_path for fc in compat.channels(obj).fcurves] == ["turning.period"]
    assert "turning.period" not in {fc.data_path for fc in bake.baked_channels(obj).fcurves}
