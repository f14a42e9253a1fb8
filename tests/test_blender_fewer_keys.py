"""Bake Turns with Fewer Keys: every F-curve of the motion, evaluated by Blender at every frame,
within the tolerance of the every-frame bake; far fewer keys; the count and the error reported."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender.anim import bake, fewer_keys  # noqa: E402
from blender_turning.mapping import keys  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]

@pytest.fixture
def skier(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 12 * 24 + 1        # 12 s at 24 fps
    scene.render.fps = 24
    assert bpy.ops.turning.add_figure(sport="SKIER") == {"FINISHED"}
    return bpy.context.view_layer.objects.active


def curves(fig):
    return {(fc.data_path, fc.array_index): fc for fc in bake.baked_channels(fig).fcurves}


def evaluated(fig, frames):
    return {k: np.array([fc.evaluate(f) for f in frames]) for k, fc in curves(fig).items()}


def test_fewer_keys_stay_within_the_tolerance_at_every_frame(skier):
    scene = bpy.context.scene
    frames = range(scene.frame_start, scene.frame_end + 1)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    full = evaluated(skier, frames)
    every = sum(len(fc.keyframe_points) for fc in curves(skier).values())
    tol = keys.KeyTolerance(angle=math.radians(0.1), length=0.001)
    assert bpy.ops.turning.bake_turns(fewer_keys=True, key_angle=tol.angle,
                                      key_length=tol.length) == {"FINISHED"}
    reduced = evaluated(skier, frames)
    assert reduced.keys() == full.keys()
    kept = 0
    for key, fc in curves(skier).items():
        kept += len(fc.keyframe_points)
        kind = fewer_keys.channel_kind(key[0])
        if kind is None:                  # turn_phase (it wraps), the take: every frame
            np.testing.assert_array_equal(reduced[key], full[key])
            continue
        # Blender's own evaluation (float32 keys and handles, the Bezier solved in float32)
        # within the bound: measured at most 0.999 of it (mapping/keys.py keeps a float32
        # margin).
        err = np.max(np.abs(reduced[key] - full[key]))
        assert err <= keys.channel_tolerance(kind, tol, full[key]), (key, err)
        assert {k.interpolation for k in fc.keyframe_points} == {"BEZIER"}
    # Whole rotations: each bone's quaternion (normalised, as Blender poses it) within the angle.
    for path in {k[0] for k in full if k[0].endswith("rotation_quaternion")}:
        q = np.column_stack([full[(path, i)] for i in range(4)])
        r = np.column_stack([reduced[(path, i)] for i in range(4)])
        r /= np.linalg.norm(r, axis=1, keepdims=True)
        q /= np.linalg.norm(q, axis=1, keepdims=True)
        angle = 2 * np.arccos(np.clip(np.abs(np.sum(q * r, axis=1)), 0, 1))
        assert np.max(angle) <= tol.angle, path
    assert fewer_keys.channel_kind('["turn_phase"]') is None
    assert fewer_keys.channel_kind('["turn_lean"]') == "angle"
    assert kept < 0.3 * every                   # measured 0.21 over 12 s (a start's transient)


def test_the_report_says_the_keys_and_the_error_and_a_rebake_keys_every_frame(skier):
    assert bpy.ops.turning.bake_turns(fewer_keys=True) == {"FINISHED"}
    report = fewer_keys.reduce_bake(skier)           # again: a reduced bake is its own reference
    assert report.keys <= report.every_frame
    assert report.angle_error <= math.radians(0.1) and report.length_error <= 0.001
    assert "keys (" in report.summary() and " deg and " in report.summary()
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}      # not taken for the user's edits
    n = bpy.context.scene.frame_end
    assert {len(fc.keyframe_points) for fc in curves(skier).values()} == {n}


def test_fewer_keys_with_a_step_is_refused_and_leaves_the_bake(skier):
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    before = {k: len(fc.keyframe_points) for k, fc in curves(skier).items()}
    with pytest.raises(RuntimeError, match="Fewer Keys picks the frames to key; Step = 3"):
        bpy.ops.turning.bake_turns(fewer_keys=True, step=3)
    assert {k: len(fc.keyframe_points) for k, fc in curves(skier).items()} == before
