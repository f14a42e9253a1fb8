"""The user's own rig as a figure, on the bpy wheel: a Rigify rig and a Mixamo-named
skeleton ski beside a built-in skier with the same settings, measured frame by frame."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning import blender as addon  # noqa: E402
from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from rig_fixtures import (activate, knee, lean, mixamo_skeleton, name, rigify_rig,  # noqa: E402
                          sample, state, world_head)

pytestmark = pytest.mark.blender
FRAMES = (1, 48)
SAME = ("mass", "com_height", "inertia", "speed", "period", "lean", "heading", "start_heading")


@pytest.fixture(scope="module")
def scene():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = FRAMES
    sc.render.fps = 24
    rigify = rigify_rig(location=(4.0, 0.0, 0.0))
    mixamo = mixamo_skeleton(location=(-4.0, 0.0, 0.0))
    for obj in (rigify, mixamo):
        obj.rotation_euler = (0.0, 0.0, math.pi)          # face +Y, as the built-in does
    sc.cursor.location = (0, 0, 0)
    assert bpy.ops.turning.add_figure(sport="SKIER") == {"FINISHED"}
    builtin = bpy.context.view_layer.objects.active
    yield {"builtin": builtin, "rigify": rigify, "mixamo": mixamo}
    addon.unregister()


@pytest.fixture(scope="module")
def figures(scene):
    before = {k: state(scene[k]) for k in ("rigify", "mixamo")}
    for key in ("rigify", "mixamo"):
        obj = scene[key]
        activate(obj)
        assert bpy.ops.turning.make_figure(sport="SKIER", bone_map="AUTO") == {"FINISHED"}
        assert obj.turning.rig.bone_map == key.upper()
    src = scene["builtin"].turning
    for key in ("rigify", "mixamo"):
        for name in SAME:
            setattr(scene[key].turning, name, getattr(src, name))
    for obj in scene.values():
        activate(obj)
        assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    return scene, before


@pytest.fixture(scope="module")
def sampled(figures):
    return sample(figures[0], FRAMES, {"ski.L": [("ankle", "L")], "ski.R": [("ankle", "R")]})


@pytest.mark.parametrize("key", ["rigify", "mixamo"])
def test_lean_follows_the_builtin_within_2_deg(sampled, key):
    """The issue asks 2 deg; measured 0.0002 deg (Rigify) and 0.0001 deg (Mixamo): the hips
    go on the built-in's lean line, so only float32 keys stand between them."""
    out = sampled[0]
    lb, lu = lean(out["builtin"]), lean(out[key])
    assert np.ptp(lb) > math.radians(15)
    assert np.max(np.abs(lu - lb)) < math.radians(0.02), np.degrees(np.max(np.abs(lu - lb)))


@pytest.mark.parametrize("key", ["rigify", "mixamo"])
def test_knee_flexion_follows_within_5_deg(sampled, key):
    """The issue asks 5 deg; measured 0.14 deg on Rigify (its IK solver, with the rig's
    ik_stretch at 0 while it is a figure: 5.0 deg with Rigify's 0.1) and 0.002 deg on Mixamo."""
    out = sampled[0]
    for s in "LR":
        kb, ku = knee(out["builtin"], s), knee(out[key], s)
        assert np.ptp(kb) > math.radians(3)
        assert np.max(np.abs(ku - kb)) < math.radians(0.5), np.degrees(np.max(np.abs(ku - kb)))


@pytest.mark.parametrize("key", ["rigify", "mixamo"])
def test_feet_on_the_skis_and_skis_on_the_snow(sampled, key):
    """Ankle to binding within 1 cm; no point of a ski below the snow, none 2 cm above it (the
    built-in's skis are on the snow on every frame)."""
    _, low, gap, _ = sampled
    low, gap = np.array(low[key]).min(axis=1), np.array(gap[key])
    assert np.all(low > -1e-3) and np.all(low < 0.02), (low.min(), low.max())
    assert np.all(gap < 0.01), gap.max()


@pytest.mark.parametrize("key", ["rigify", "mixamo"])
def test_deforming_bones_all_move_none_sheared(sampled, key):
    """Every deforming bone moves in the armature's own space (not only with the object), and
    no bone's world matrix is non-finite or sheared (its axes stay perpendicular)."""
    frames = sampled[3][key]
    names = list(frames[0])
    assert len(names) > (100 if key == "rigify" else 20)
    for n in names:
        arm = np.array([f[n][0] for f in frames])                 # (frames, 4, 4)
        world = np.array([f[n][1] for f in frames])
        assert np.all(np.isfinite(world)), n
        cols = world[:, :3, :3] / np.linalg.norm(world[:, :3, :3], axis=1, keepdims=True)
        shear = np.abs(np.einsum("fki,fkj->fij", cols, cols) - np.eye(3)).max()
        assert shear < 1e-3, (n, shear)
        assert np.ptp(arm.reshape(len(arm), -1), axis=0).max() > 1e-3, n


def test_rigify_controls_carry_the_keys(figures):
    """The animator keeps editing with the rig's own controls: the keys are on them, none on
    the DEF or ORG bones."""
    obj = figures[0]["rigify"]
    paths = {fc.data_path for fc in bake.baked_channels(obj).fcurves}
    for b in ("torso", "hips", "chest", "head", "foot_ik.L", "foot_ik.R", "hand_ik.L",
              "hand_ik.R", "thigh_ik_target.L", "thigh_ik_target.R", "thigh_fk.L", "hand_fk.R"):
        assert f'pose.bones["{b}"].rotation_quaternion' in paths, b
    for b in ("torso", "foot_ik.L", "hand_ik.R", "thigh_ik_target.L"):
        assert f'pose.bones["{b}"].location' in paths, b
    assert not [p for p in paths if '"DEF-' in p or '"ORG-' in p or '"MCH-' in p]


def test_rigify_shoulders_and_wrists_are_where_the_retarget_puts_them(figures, monkeypatch):
    """Rigify turns its upper spine by halves of the chest control's turn, so the bake keys the
    spine's FK controls (``chest`` stays at rest): the evaluated shoulder and wrist joints are
    the retargeted ones (``solve_joints``), world space, every frame.  Keying ``chest`` put the
    shoulders 11-22 cm off and the arms then fell short of the poles' grips."""
    from blender_turning.blender.scene import retarget_adapter
    from blender_turning.mapping.retarget import retarget as R
    obj = figures[0]["rigify"]
    seen = []
    monkeypatch.setattr(retarget_adapter, "retarget",
                        lambda *a, **k: seen.append(a) or R.retarget(*a, **k))
    activate(obj)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    track, sport, rig, bm, fit = seen[-1]
    out = R.retarget(track, sport, rig, bm, fit)
    joints = R.solve_joints(R._Builtin(sport, track, fit), rig, bm, sport)
    turn = R._matrix_xyz(out.rotation)
    sc, worst = bpy.context.scene, {}
    for k, f in enumerate(range(FRAMES[0], FRAMES[1] + 1)):
        sc.frame_set(f)
        for j in ("upper_arm.L", "upper_arm.R", "hand.L", "hand.R"):
            want = out.location[k] + fit.scale * turn[k] @ joints[j][k, :3, 3]
            off = np.linalg.norm(world_head(obj, bm.bone(j)) - want)
            worst[j] = max(worst.get(j, 0.0), off)
    assert max(worst.values()) < 1e-3, worst          # measured: 0.06 mm


def test_rigify_fk_switch_still_shows_the_motion(figures, sampled):
    """IK/FK slider at FK: the FK controls carry the same motion (knees within 5 deg of the
    built-in's, ankles within 2 cm of where the IK put them)."""
    scene, _ = figures
    obj, out = scene["rigify"], sampled[0]
    sc = bpy.context.scene
    parents = ("thigh_parent.L", "thigh_parent.R", "upper_arm_parent.L", "upper_arm_parent.R")
    for p in parents:
        obj.pose.bones[p]["IK_FK"] = 1.0
    obj.update_tag()
    try:
        fk = {"p": [], "heading": out["rigify"]["heading"]}
        for f in range(FRAMES[0], FRAMES[1] + 1):
            sc.frame_set(f)
            fk["p"].append({(w, s): world_head(obj, name("rigify", w, s))
                            for w in ("ankle", "knee", "hip") for s in "LR"})
    finally:
        for p in parents:
            obj.pose.bones[p]["IK_FK"] = 0.0
        obj.update_tag()
    for s in "LR":
        diff = np.abs(knee(fk, s) - knee(out["builtin"], s))
        assert np.max(diff) < math.radians(5), np.degrees(diff.max())
        moved = [np.linalg.norm(a["ankle", s] - b["ankle", s])
                 for a, b in zip(fk["p"], out["rigify"]["p"])]
        assert max(moved) < 0.02, max(moved)


def test_a_rig_lacking_joints_is_refused_with_the_list(scene):
    arm = bpy.data.armatures.new("Stub")
    obj = bpy.data.objects.new("Stub", arm)
    bpy.context.scene.collection.objects.link(obj)
    activate(obj)
    bpy.ops.object.mode_set(mode="EDIT")
    for n in ("mixamorig:Hips", "mixamorig:Spine2", "mixamorig:LeftUpLeg"):
        arm.edit_bones.new(n).tail = (0, 0, 1)
    bpy.ops.object.mode_set(mode="OBJECT")
    before = state(obj)
    n_objects = len(bpy.data.objects)
    with pytest.raises(RuntimeError, match=r"lacks 12 bone\(s\).*spine.006 -> 'mixamorig:Head'"):
        bpy.ops.turning.make_figure(sport="SKIER", bone_map="MIXAMO")
    with pytest.raises(RuntimeError, match="matches none of the bone maps"):
        bpy.ops.turning.make_figure(sport="SKIER", bone_map="AUTO")
    assert state(obj) == before and not obj.turning.is_figure
    assert len(bpy.data.objects) == n_objects
    obj.scale = (1, 2, 1)
    with pytest.raises(RuntimeError, match="one positive scale"):
        bpy.ops.turning.make_figure(sport="SKIER", bone_map="MIXAMO")
    bpy.data.objects.remove(obj)


@pytest.mark.parametrize("key", ["rigify", "mixamo"])
def test_remove_figure_gives_the_rig_back_exactly(figures, key):
    scene, before = figures
    obj = scene[key]
    coll = obj.turning.rig.equipment.name
    activate(obj)
    assert bpy.ops.turning.remove_figure() == {"FINISHED"}
    assert state(obj) == before[key]
    assert coll not in bpy.data.collections
    assert not [o for o in bpy.data.objects if o.name.startswith(obj.name + " ")]
    assert "turning" not in obj.keys()
