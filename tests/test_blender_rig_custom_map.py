"""A rig no shipped map fits, made a figure through a custom bone map edited as a list, saved
as a preset and loaded back."""
import os
import tempfile

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake  # noqa: E402
from blender_turning.blender.ops import bone_map as ops_bone_map  # noqa: E402
from blender_turning.core.physics.params import PRESETS  # noqa: E402
from rig_fixtures import PREFIX, activate, mixamo_skeleton  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]


def renamed(name):
    """A Mixamo skeleton whose bones are called ``bob_<name>``: no shipped map fits."""
    obj = mixamo_skeleton(name)
    for b in obj.data.bones:
        b.name = "bob_" + b.name[len(PREFIX):]
    return obj


@pytest.mark.installed
def test_custom_map_edit_save_load_and_bake():
    obj = renamed("Bob")
    activate(obj)
    with pytest.raises(RuntimeError, match="matches none of the bone maps"):
        bpy.ops.turning.make_figure(sport="SKIER", bone_map="AUTO")
    assert bpy.ops.turning.custom_map_from(source="MIXAMO") == {"FINISHED"}
    rows = obj.turning.rig.custom_map
    assert {r.name for r in rows} >= {"spine", "foot.L", "hand.R"}
    with pytest.raises(RuntimeError, match="lacks 15 bone"):
        bpy.ops.turning.make_figure(sport="SKIER", bone_map="CUSTOM")
    for r in rows:                                   # the user picks their own bones
        if r.bone:
            r.bone = "bob_" + r.bone[len(PREFIX):]
    assert bpy.ops.turning.custom_map_save(name="Bob rig") == {"FINISHED"}
    assert (ops_bone_map.preset_dir() / "Bob rig.json").is_file()
    # Another armature of the same rig loads the preset and becomes a figure through it.
    other = renamed("Bob 2")
    activate(other)
    assert bpy.ops.turning.custom_map_load(preset="Bob rig") == {"FINISHED"}
    assert bpy.ops.turning.make_figure(sport="SKIER", bone_map="CUSTOM") == {"FINISHED"}
    assert other.turning.rig.bone_map == "CUSTOM"
    # The body defaults from the rig's proportions: COM height with the legs, mass with the
    # height squared (the skeleton's legs are 0.87 m against the built-in's 0.842 m).
    k = (0.430029 + 0.440256) / (0.431045 + 0.411096)
    assert other.turning.com_height == pytest.approx(PRESETS["skier"].body.l * k, rel=1e-3)
    assert other.turning.mass == pytest.approx(PRESETS["skier"].body.m * k * k, rel=1e-3)
    bpy.context.scene.frame_start, bpy.context.scene.frame_end = 1, 24
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    keyed = {fc.data_path.split('"')[1] for fc in bake.baked_channels(other).fcurves
             if fc.data_path.startswith("pose")}
    assert {"bob_Hips", "bob_LeftUpLeg", "bob_RightFoot", "bob_LeftHand"} <= keyed
    with pytest.raises(RuntimeError, match="must be a plain file name"):
        bpy.ops.turning.custom_map_save(name="../escape")
