"""A figure made from the user's own rig, baked and tweaked, taken apart in every order: Remove
Figure straight away, after Clear Bake, after the tweak layer was deleted, or the rig deleted
while still a figure.  Each leaves no ``Turning: tweaks`` NLA track and no action of the
add-on's behind; the one thing kept on purpose is a tweak layer holding the animator's keys, in
its action with a fake user (docs/own-rigs.md).  The rig's own action comes back as it was."""
import os
import tempfile

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from rig_fixtures import activate, mixamo_skeleton, state  # noqa: E402

from blender_turning.blender.anim import bake, bake_layers  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]
HEAD = "mixamorig:Head"


@pytest.fixture
def scene(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, 24
    return sc


def keys(action) -> dict:
    """``{(data_path, index): keyframe points}`` of every curve of ``action`` (all slots)."""
    out = {}
    for bag in _bags(action):
        for fc in bag.fcurves:
            out[fc.data_path, fc.array_index] = [tuple(k.co) for k in fc.keyframe_points]
    return out


def _bags(action):
    if hasattr(action, "layers") and len(action.layers):
        return [bag for layer in action.layers for strip in layer.strips
                for bag in strip.channelbags]
    return [action]                       # bpy 4.2: the action holds its curves


def figure(with_action: bool, tweak: bool):
    """The rig (with an action of its own, keyed, or none), made a figure and baked; with
    ``tweak`` the animator keys the head on the tweak layer.  Returns the rig, its state and its
    action's keys before Make Figure."""
    rig = mixamo_skeleton()
    if with_action:
        rig.pose.bones[0].location = (0.0, 0.0, 2.0)
        rig.pose.bones[0].keyframe_insert("location", frame=3)
    before = state(rig), {a.name: keys(a) for a in bpy.data.actions}
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER", bone_map="AUTO") == {"FINISHED"}
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert bake_layers.playing(rig, bake_layers.tweak_layer(rig)[0])
    if tweak:
        bpy.context.scene.frame_set(10)
        pb = rig.pose.bones[HEAD]
        pb.location = (pb.location[0] + 3.0, pb.location[1], pb.location[2])
        assert pb.keyframe_insert("location", frame=10)
    return rig, before


def no_tweak_tracks():
    left = [(o.name, t.name) for o in bpy.data.objects if o.animation_data
            for t in o.animation_data.nla_tracks if t.name == bake_layers.TWEAK_TRACK]
    assert not left, left


def check_actions(before_actions: dict, tweaked: bool):
    """The actions are those before Make Figure, with their keys, plus (``tweaked``) the tweak
    layer kept with a fake user holding the head's key; none of the add-on's bakes."""
    now = {a.name: a for a in bpy.data.actions}
    extra = sorted(set(now) - set(before_actions))
    assert sorted(set(before_actions) - set(now)) == []
    for name, want in before_actions.items():
        assert keys(now[name]) == want, name
    assert not [a for a in now.values() if bake.BAKED_PATHS in a], "a bake action is left"
    if not tweaked:
        assert extra == []
        return
    assert len(extra) == 1, extra
    kept = now[extra[0]]
    assert kept.use_fake_user and bake_layers.TWEAKS_OF in kept
    assert any(path == f'pose.bones["{HEAD}"].location' for path, _ in keys(kept))


def remove_figure(rig):
    activate(rig)
    assert bpy.ops.turning.remove_figure() == {"FINISHED"}


@pytest.mark.parametrize("with_action", [False, True])
@pytest.mark.parametrize("tweak", [False, True])
@pytest.mark.parametrize("order", ["figure first", "clear bake first", "tweak layer first"])
def test_remove_figure_in_any_order_leaves_only_the_kept_tweaks(scene, with_action, tweak,
                                                                 order):
    rig, (rig_before, actions_before) = figure(with_action, tweak)
    if order == "clear bake first":
        activate(rig)
        assert bpy.ops.turning.clear_bake() == {"FINISHED"}
    elif order == "tweak layer first":
        action, _ = bake_layers.tweak_layer(rig)
        rig.animation_data.action = None            # the animator unassigns and deletes it
        bpy.data.actions.remove(action)
    remove_figure(rig)
    assert state(rig) == rig_before
    no_tweak_tracks()
    check_actions(actions_before, tweak and order != "tweak layer first")
    bpy.data.objects.remove(rig)                     # then the rig itself
    no_tweak_tracks()
    check_actions(actions_before, tweak and order != "tweak layer first")


def test_the_kept_tweaks_play_again_when_the_rig_is_a_figure_again(scene):
    rig, _ = figure(with_action=False, tweak=True)
    tweaks = bake_layers.tweak_layer(rig)[0].name
    remove_figure(rig)
    assert rig.animation_data is None
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER", bone_map="AUTO") == {"FINISHED"}
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert rig.animation_data.action.name == tweaks
    no_tweak_tracks()


@pytest.mark.parametrize("tweak", [False, True])
def test_a_rig_deleted_while_a_figure_leaves_nothing_of_the_figure_after_a_save(scene, tmp_path,
                                                                              tweak):
    """The rig deleted first (the figure still on it): as for any deleted object, Blender
    keeps its actions until the file is saved (Undo brings the rig back with them) and drops
    the unused ones then.  After a save and a reload no bake, tweak layer or ``Turning:
    tweaks`` track of it is left."""
    rig, _ = figure(with_action=True, tweak=tweak)
    bpy.data.objects.remove(rig)
    path = tmp_path / "deleted.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.wm.open_mainfile(filepath=str(path))
    no_tweak_tracks()
    ours = [a.name for a in bpy.data.actions
            if bake.BAKED_PATHS in a or bake_layers.TWEAKS_OF in a]
    assert ours == []
