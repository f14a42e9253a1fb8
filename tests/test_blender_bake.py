"""Bake on the bpy wheel: whole F-curves, read back equal to the pose track; re-bake and clear
touch only what the bake wrote."""
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake, bake_layers  # noqa: E402
from blender_turning.blender.scene import rig_builder  # noqa: E402
from blender_turning.mapping.base import BoneChannels, PoseTrack  # noqa: E402

pytestmark = pytest.mark.blender

#: A small rig in the agreed spec format: hips -> thigh -> shin, and a ski on the shin.
SPEC = {
    "name": "tiny", "sport": "skier",
    "bones": [
        {"name": "hips", "head": [0, 0, 0.9], "tail": [0, 0, 1.1], "roll": 0.0, "parent": None,
         "connected": False, "deform": True},
        {"name": "thigh.L", "head": [0.1, 0, 0.9], "tail": [0.1, 0, 0.5], "roll": 0.0,
         "parent": "hips", "connected": False, "deform": True},
        {"name": "shin.L", "head": [0.1, 0, 0.5], "tail": [0.1, 0, 0.05], "roll": 0.0,
         "parent": "thigh.L", "connected": True, "deform": True},
    ],
    "meshes": [
        {"name": "pelvis", "bone": "hips", "shape": "box", "size": [0.3, 0.2, 0.2],
         "offset": [0, 0.1, 0], "material": "suit"},
        {"name": "thigh", "bone": "thigh.L", "shape": "capsule", "size": [0.07, 0.4],
         "offset": [0, 0.2, 0], "material": "suit"},
        {"name": "shin", "bone": "shin.L", "shape": "cylinder", "size": [0.05, 0.45],
         "offset": [0, 0.22, 0], "rotation": [1, 0, 0, 0], "material": "skin"},
    ],
}


def synthetic_track(n=240, frame_start=1, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 24.0
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return PoseTrack(
        frames=frame_start + np.arange(n, dtype=float),
        location=np.column_stack([10 * t, np.sin(t), np.zeros(n)]),
        rotation=np.column_stack([np.zeros(n), 0.2 * np.sin(t), 0.1 * t]),
        bones={"hips": BoneChannels(location=rng.normal(size=(n, 3)) * 0.1, rotation=q),
               "shin.L": BoneChannels(rotation=q[::-1].copy())},
        props={"turn_phase": np.mod(t, 6.28), "turn_lean": 0.3 * np.sin(t),
               "turn_curvature": 0.1 * np.sin(t), "turn_leg_force": 700 + 10 * t,
               "turn_speed": np.full(n, 10.0)})


def read_fcurve(fc):
    co = np.empty(2 * len(fc.keyframe_points), np.float32)
    fc.keyframe_points.foreach_get("co", co)
    return co[0::2].astype(float), co[1::2].astype(float)


def fcurve_map(obj, bag=None):
    bag = bag or bake.baked_channels(obj)
    return {(fc.data_path, fc.array_index): fc for fc in bag.fcurves}


@pytest.fixture(scope="module")
def scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return bpy.context.scene


@pytest.fixture
def figure(scene):
    obj = rig_builder.build_figure(bpy.context, SPEC, "Tiny")
    yield obj
    rig_builder.remove_figure(obj)
    for a in list(bpy.data.actions):
        bpy.data.actions.remove(a)


def test_rig_built_from_spec(figure):
    arm = figure.data
    assert [b.name for b in arm.bones] == ["hips", "thigh.L", "shin.L"]
    assert arm.bones["shin.L"].parent.name == "thigh.L" and arm.bones["shin.L"].use_connect
    np.testing.assert_allclose(arm.bones["shin.L"].head_local, [0.1, 0, 0.5], atol=1e-6)
    body = figure.children[0]
    assert {g.name for g in body.vertex_groups} == {"hips", "thigh.L", "shin.L"}
    assert body.modifiers[0].type == "ARMATURE" and body.modifiers[0].object == figure
    # The shin part (bone pointing down) is centred 0.22 m below the knee, in armature space.
    vg = body.vertex_groups["shin.L"].index
    co = np.array([v.co for v in body.data.vertices if any(g.group == vg for g in v.groups)])
    np.testing.assert_allclose(co.mean(axis=0), [0.1, 0, 0.5 - 0.22], atol=1e-5)
    assert bpy.context.object is None or bpy.context.object.mode == "OBJECT"


def test_bad_spec_names_the_bone(scene):
    bad = dict(SPEC, meshes=[dict(SPEC["meshes"][0], bone="nope")])
    with pytest.raises(rig_builder.RigSpecError, match="nope"):
        rig_builder.build_figure(bpy.context, bad, "Bad")
    assert "Bad" not in bpy.data.objects


def test_bake_reads_back_equal(figure):
    track = synthetic_track()
    res = bake.bake_pose_track(figure, track)
    assert res.action.name == figure.name and bake.figure_action(figure) == res.action
    adt = figure.animation_data                  # the bake plays from its own NLA track
    assert [(t.name, [s.action for s in t.strips]) for t in adt.nla_tracks] == \
        [(bake_layers.BAKE_TRACK, [res.action])]
    assert bake_layers.is_tweaks(adt.action, figure) and adt.action_blend_type == "COMBINE"
    fcs = fcurve_map(figure)
    expect = {("location", i): track.location[:, i] for i in range(3)}
    expect.update({("rotation_euler", i): track.rotation[:, i] for i in range(3)})
    for i in range(3):
        expect[('pose.bones["hips"].location', i)] = track.bones["hips"].location[:, i]
    for i in range(4):
        expect[('pose.bones["hips"].rotation_quaternion', i)] = track.bones["hips"].rotation[:, i]
        expect[('pose.bones["shin.L"].rotation_quaternion', i)] = \
            track.bones["shin.L"].rotation[:, i]
    for p, v in track.props.items():
        expect[(f'["{p}"]', 0)] = v
    assert set(fcs) == set(expect) and res.fcurves == len(expect)
    for key, values in expect.items():
        frames, got = read_fcurve(fcs[key])
        np.testing.assert_array_equal(frames, track.frames)        # a key on every frame
        np.testing.assert_allclose(got, values, rtol=1e-6, atol=1e-6, err_msg=str(key))
    # Evaluation at a frame gives the pose (linear keys): the depsgraph sees the baked values.
    bpy.context.scene.frame_set(11)
    ev = figure.evaluated_get(bpy.context.evaluated_depsgraph_get())
    np.testing.assert_allclose(ev.location, track.location[10], atol=1e-5)
    np.testing.assert_allclose(ev.pose.bones["shin.L"].rotation_quaternion,
                               track.bones["shin.L"].rotation[10], atol=1e-5)
    assert ev["turn_leg_force"] == pytest.approx(track.props["turn_leg_force"][10], rel=1e-6)


def test_rebake_replaces_only_the_baked_curves(figure):
    # The user keys a custom channel on the figure's action after a first bake.
    bake.bake_pose_track(figure, synthetic_track(seed=1))
    figure["user_thing"] = 1.0
    figure.keyframe_insert('["user_thing"]', frame=5)
    other = bpy.data.actions.new("UserWalk")
    other.use_fake_user = True
    track = synthetic_track(n=100, seed=2)
    res = bake.bake_pose_track(figure, track)
    fcs = fcurve_map(figure)
    assert ('["user_thing"]', 0) in fcurve_map(figure, compat.channels(figure))  # in the tweaks
    _, got = read_fcurve(fcs[("location", 0)])
    np.testing.assert_allclose(got, track.location[:, 0], atol=1e-6)
    assert len(bpy.data.actions) == 3 and bpy.data.actions["UserWalk"] == other
    assert res.action == bake.figure_action(figure)
    # Twice = once.
    snap = {k: read_fcurve(v) for k, v in fcurve_map(figure).items()}
    bake.bake_pose_track(figure, track)
    again = {k: read_fcurve(v) for k, v in fcurve_map(figure).items()}
    assert snap.keys() == again.keys()
    for k in snap:
        np.testing.assert_array_equal(snap[k][1], again[k][1])


def test_user_action_is_stashed_and_restored(figure):
    figure.location = (1, 2, 3)
    figure.keyframe_insert("location", frame=1)
    user = figure.animation_data.action
    user_curves = len(compat.all_fcurves(user))
    bake.bake_pose_track(figure, synthetic_track(n=20))
    assert figure.animation_data.action != user
    assert len(compat.all_fcurves(user)) == user_curves               # untouched
    assert bake.clear_bake(figure)
    assert figure.animation_data.action == user
    assert len(figure.animation_data.nla_tracks) == 0
    assert not [k for k in figure.keys() if k.startswith(("turn_", "turning_stash"))]
    assert set(bpy.data.actions) == {user}


def test_missing_bone_writes_nothing(figure):
    track = synthetic_track(n=10)
    bad = PoseTrack(track.frames, track.location, track.rotation,
                    {"spine": BoneChannels(rotation=track.bones["hips"].rotation)})
    with pytest.raises(bake.BakeError, match="spine"):
        bake.bake_pose_track(figure, bad)
    assert figure.animation_data is None and len(bpy.data.actions) == 0
