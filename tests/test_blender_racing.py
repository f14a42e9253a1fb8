"""A racer in Blender (docs/racing.md): the Sport Presets menu's Slalom Racer on a skier figure
bakes the racer's lean, stands the skis on the sidecut relation's edge angle and angulates."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender.jobs.pipeline import figure_pose_track  # noqa: E402
from blender_turning.blender.scene.scene_adapters import FrameRange  # noqa: E402
from blender_turning.core.equipment import carving_of  # noqa: E402
from blender_turning.mapping.kinematics import Skeleton  # noqa: E402
from blender_turning.mapping.rig_spec import load_rig  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]


@pytest.fixture
def racer(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end, sc.render.fps = 1, 96, 24
    assert bpy.ops.turning.add_figure(sport="SKIER") == {"FINISHED"}
    obj = bpy.context.view_layer.objects.active
    assert bpy.ops.turning.apply_figure_preset(sport="SLALOM_RACER") == {"FINISHED"}
    obj.turning.period, obj.turning.lean = 2.0, math.radians(60.0)
    return obj


def test_the_racer_bakes_its_lean_and_carving_skis(racer):
    traj, track = figure_pose_track(racer, FrameRange.of_scene(bpy.context.scene))
    assert traj.meta["preset"] == "slalom_racer"
    # The racer leans the 60 deg asked (the skier's preset: 36.7 deg at 10 m/s).
    assert math.degrees(np.abs(traj.theta_v).max()) == pytest.approx(60.0, abs=0.05)
    skel = Skeleton.from_spec(load_rig("skier"))
    P = skel.fk(track.bones, len(track))
    roll = np.arctan2(P["ski.L"][:, 2, 0], P["ski.L"][:, 0, 0])
    np.testing.assert_allclose(roll, carving_of("slalom_racer").edge_angle(traj.C_f), atol=1e-9)
    assert math.degrees(np.abs(roll).max()) > 65.0
    # It angulates (docs/racing.md): at its deepest lean the shins stand on the skis' edge
    # (measured 1e-12 deg) and the trunk, hips to shoulders, more upright than the lean.
    k = int(np.argmax(np.abs(traj.theta_v)))
    head = lambda b: P[b][k, :3, 3]                                     # noqa: E731
    for s in "LR":
        shin = head(f"shin.{s}") - head(f"foot.{s}")
        assert math.atan2(-shin[0], shin[2]) == pytest.approx(roll[k], abs=1e-4)
    trunk = (head("upper_arm.L") + head("upper_arm.R") - head("thigh.L") - head("thigh.R"))
    assert abs(math.atan2(-trunk[0], trunk[2])) < abs(traj.theta_v[k]) - math.radians(10.0)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}


def test_a_saved_preset_stores_and_restores_the_equipment(racer):
    """The "+" button's preset stores the racer's equipment with its body; applying it to a
    figure showing the sport's own skis brings the racer's back, and a saved preset of the
    sport's own figure takes them off again."""
    from blender_turning.blender.ui import presets
    assert racer.turning.equipment.preset == "slalom_racer"
    folder = os.path.join(bpy.utils.user_resource("SCRIPTS", path="presets"),
                          presets.PRESET_SUBDIR)
    assert bpy.ops.turning.figure_preset_add(name="My racer") == {"FINISHED"}
    saved = os.path.join(folder, "My_racer.py")
    assert bpy.ops.turning.apply_figure_preset(sport="SKIER") == {"FINISHED"}
    assert racer.turning.equipment.preset == ""
    assert bpy.ops.turning.figure_preset_add(name="My skier") == {"FINISHED"}
    own = os.path.join(folder, "My_skier.py")
    assert bpy.ops.turning.apply_figure_preset(filepath=saved) == {"FINISHED"}
    assert racer.turning.equipment.preset == "slalom_racer"
    assert racer.turning.mass == pytest.approx(85.0)
    traj, _ = figure_pose_track(racer, FrameRange.of_scene(bpy.context.scene))
    assert traj.meta["preset"] == "slalom_racer"
    assert bpy.ops.turning.apply_figure_preset(filepath=own) == {"FINISHED"}
    assert racer.turning.equipment.preset == ""
    for path in (saved, own):
        os.remove(path)
