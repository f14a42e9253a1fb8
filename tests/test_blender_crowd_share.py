"""Shared motion: a crowd's followers whose motion is the leader's, moved, play the leader's baked
action from an NLA strip (moved by their Delta Transform) instead of baking their own, and move
as their own bake would; a re-bake, Clear Bake, a tweak or Live Preview of one figure never
changes another's motion."""
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from test_blender_operators import add, scene  # noqa: E402,F401

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake, bake_layers, foot_track  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]
FRAMES = (1, 13, 40, 72)


def crowd(count=3, **kw):
    """The leader and ``count`` followers strung out on its track, 1.5 m to its left."""
    lead = add("SKIER")
    assert bpy.ops.turning.add_crowd(formation="FOLLOW_LEADER", count=count, gap_time=1.0,
                                     lateral=1.5, **kw) == {"FINISHED"}
    return [lead] + [bpy.data.objects[f"Skier {k}"] for k in range(1, count + 1)]


def select(figs):
    for o in bpy.context.selected_objects:
        o.select_set(False)
    for f in figs:
        f.select_set(True)
    bpy.context.view_layer.objects.active = figs[0]


def motion(figs) -> dict:
    """Each figure's world matrix, every bone's pose and its lean on :data:`FRAMES`."""
    out = {}
    for f in FRAMES:
        bpy.context.scene.frame_set(f)
        for fig in figs:
            out[fig.name, f] = (np.array(fig.matrix_world),
                                np.array([np.array(pb.matrix_basis) for pb in fig.pose.bones]),
                                fig.get("turn_lean"))
    return out


def assert_same_motion(a: dict, b: dict, figs=None):
    # Blender plays the leader's float32 location key plus the float32 Delta Transform: within
    # two units in the last place of positions under 64 m (7.6e-6 m; measured 3.8e-6 over 10 s
    # and 100 m); the bones' and the lean's keys are the same float32 values (measured: 1e-15
    # in the pose matrices, the lean equal).
    for key in a:
        if figs is None or key[0] in figs:
            np.testing.assert_allclose(a[key][0], b[key][0], atol=8e-6, err_msg=str(key))
            np.testing.assert_allclose(a[key][1], b[key][1], atol=1e-7, err_msg=str(key))
            assert abs(a[key][2] - b[key][2]) <= 1e-7, key


def bake_actions() -> list:
    return [a for a in bpy.data.actions if bake.BAKED_PATHS in a]


@pytest.mark.installed
def test_followers_play_the_leaders_bake_and_move_as_their_own_bake_does(scene):
    figs = crowd()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    lead, followers = figs[0], figs[1:]
    action = bake.find_bake(lead)[0]
    assert bake_actions() == [action]                       # one bake for four figures
    for f in followers:
        assert bake.find_bake(f) == (None, None)            # none of its own...
        assert bake.figure_action(f) == action              # ...it plays the leader's
        assert f.delta_location.length > 1.0
        assert foot_track.owned_track(f) is not None        # its own foot track
        assert bake_layers.playing(f, bake_layers.tweak_layer(f)[0])    # and tweak layer
        kind, name, state = bake.layers(f)[1]               # the Bake panel's Layers
        assert (kind, name) == ("BAKE", "Skier") and state.startswith("Skier's bake, frames 1-72")
    shared = motion(figs)
    assert bpy.ops.turning.bake_turns(share=False) == {"FINISHED"}
    assert len(bake_actions()) == 4                         # the shared one went with its users
    for f in followers:
        assert tuple(f.delta_location) == (0.0, 0.0, 0.0)
        assert bake.find_bake(f)[0] is not None
    assert_same_motion(shared, motion(figs))
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}     # and back
    assert len(bake_actions()) == 1
    assert_same_motion(shared, motion(figs))


def test_figures_with_differences_bake_their_own(scene):
    crowd(body_jitter=0.05)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert len(bake_actions()) == 4
    assert not any(bake.SHARE_OFFSET in o for o in bpy.data.objects)


def test_a_delta_transform_of_the_users_is_kept_and_the_figure_bakes_its_own(scene):
    figs = crowd(count=2)
    figs[2].delta_location = (0.0, 0.0, 0.25)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert bake.find_bake(figs[2])[0] is not None
    assert tuple(figs[2].delta_location) == (0.0, 0.0, 0.25)
    assert bake.figure_action(figs[1]) == bake.find_bake(figs[0])[0]


@pytest.mark.installed
def test_rebaking_the_leader_alone_leaves_the_followers_as_they_were(scene):
    figs = crowd()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    before = motion(figs)
    lead = figs[0]
    lead.turning.lean *= 0.8
    select([lead])
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    after = motion(figs)
    assert_same_motion(before, after, {f.name for f in figs[1:]})
    assert not np.allclose(before[lead.name, 40][0], after[lead.name, 40][0])
    old = bake.figure_action(figs[1])
    assert old.name == "Skier (shared)" and old.get(bake.OWNER) is None
    assert bake.find_bake(lead)[0].name == "Skier" and bake.find_bake(lead)[0] != old
    # the followers' own bakes later take them off it; the last one deletes it
    select(figs[1:])
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert "Skier (shared)" not in bpy.data.actions


def test_clear_bake_of_one_figure_leaves_the_others(scene):
    figs = crowd()
    rest = [tuple(f.location) for f in figs]
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    before = motion(figs)
    select([figs[0]])
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert bake.figure_action(figs[0]) is None
    assert_same_motion(before, motion(figs), {f.name for f in figs[1:]})
    select([figs[2]])
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    f = figs[2]
    assert bake.figure_action(f) is None and f.animation_data is None
    assert tuple(f.delta_location) == (0.0, 0.0, 0.0) and bake.SHARE_OFFSET not in f
    assert tuple(f.location) == rest[2]
    assert_same_motion(before, motion(figs), {figs[1].name, figs[3].name})
    select(figs)
    assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    assert bake_actions() == []
    assert [tuple(f.location) for f in figs] == rest


def test_a_tweak_on_one_follower_moves_only_it(scene):
    figs = crowd()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    before = motion(figs)
    f = figs[2]
    bag = bake_layers.tweak_channels(f)
    fc = compat.new_fcurve(bag, "location", 2, "Object Transforms")
    fc.keyframe_points.insert(1, 0.5)                   # Combine: 0.5 m up on the bake
    after = motion(figs)
    assert_same_motion(before, after, {o.name for o in figs if o is not f})
    assert after[f.name, 40][0][2, 3] == pytest.approx(before[f.name, 40][0][2, 3] + 0.5)
    # it survives a re-bake of the whole crowd, still sharing
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert len(bake_actions()) == 1
    assert motion(figs)[f.name, 40][0][2, 3] == pytest.approx(after[f.name, 40][0][2, 3])


def test_live_preview_of_one_follower_gives_it_a_bake_of_its_own(scene):
    figs = crowd()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    before = motion(figs)
    f = figs[1]
    f.turning.live = True
    f.turning.lean *= 0.9
    assert bpy.ops.turning.refresh_preview() == {"FINISHED"}
    assert bake.find_bake(f)[0] is not None and tuple(f.delta_location) == (0.0, 0.0, 0.0)
    after = motion(figs)
    assert_same_motion(before, after, {o.name for o in figs if o is not f})
    assert not np.allclose(before[f.name, 40][0], after[f.name, 40][0])
    # Live Preview of the leader: a new bake of its own, the followers keep the old one
    f.turning.live = False
    figs[0].turning.live = True
    figs[0].turning.lean *= 0.9
    assert bpy.ops.turning.refresh_preview() == {"FINISHED"}
    assert_same_motion(before, motion(figs), {figs[2].name, figs[3].name})


def test_fewer_keys_thins_the_shared_bake_once(scene):
    figs = crowd()
    assert bpy.ops.turning.bake_turns(fewer_keys=True) == {"FINISHED"}
    (action,) = bake_actions()
    keys = sum(len(fc.keyframe_points) for fc in compat.all_fcurves(action))
    assert keys < 0.5 * 72 * len(compat.all_fcurves(action))
    assert all(bake.figure_action(f) == action for f in figs)
