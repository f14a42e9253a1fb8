"""Live Preview's drag step on a user's own rig (blender/jobs/live.py, docs/live-preview.md): the
window it keys is the one a whole bake keys there, on a 60 s run, the mapping's context around
the window mapped and only the window retargeted."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning.blender.jobs import live, pipeline  # noqa: E402
from blender_turning.blender.scene.scene_adapters import FrameRange  # noqa: E402
from blender_turning.mapping.sports import snow  # noqa: E402
from rig_fixtures import activate, mixamo_skeleton  # noqa: E402
from test_blender_live import baked, fresh_bake  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]

#: 60 s at 24 fps; the frame on screen 30 s in.
END, NOW = 24 * 60 + 1, 1 + 24 * 30


@pytest.fixture
def scene(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, END
    sc.render.fps = 24
    return sc


def users_figure(sport):
    rig = mixamo_skeleton("Ann")
    activate(rig)
    assert bpy.ops.turning.make_figure(sport=sport, bone_map="AUTO") == {"FINISHED"}
    rig.turning.live = True
    assert bpy.ops.turning.refresh_preview() == {"FINISHED"}
    return rig


@pytest.mark.parametrize("sport", ["CYCLIST", "SKIER"])
def test_a_drag_step_on_a_users_rig_keys_the_whole_bakes_window(scene, sport, monkeypatch):
    monkeypatch.setattr(live, "PREVIEW_STEPS", math.inf)     # the step integrates as the bake
    rig = users_figure(sport)
    before = baked(rig)
    scene.frame_set(NOW)
    rig.turning.lean += math.radians(1.0)
    if sport == "SKIER":
        # The skis' edge tilt as the whole run fits it (a drag step fits it over the part
        # simulated, Section 7): what is left is the window's own.
        whole = pipeline.simulate_figure(rig, FrameRange.of_scene(scene), ground=None)
        gain = snow.tilt_gain(whole, None)
        monkeypatch.setattr(live, "tilt_gain", lambda traj, _: gain)
    live.schedule()                                 # a drag step
    assert live.is_pending(rig) and rig.name not in live.FAILURES
    step = baked(rig)
    full = fresh_bake(rig)
    w = slice(2 * (NOW - live.WINDOW - 1), 2 * (NOW + live.WINDOW))
    assert step.keys() == full.keys() == before.keys()
    assert ('["turn_distance"]', 0) in step if sport == "CYCLIST" else True
    quats = {}
    for k, v in step.items():
        np.testing.assert_array_equal(v[:w.start], before[k][:w.start], err_msg=str(k))
        np.testing.assert_array_equal(v[w.stop:], before[k][w.stop:], err_msg=str(k))
        np.testing.assert_array_equal(v[w][0::2], full[k][w][0::2], err_msg=str(k))  # frames
        if k[0].endswith("rotation_quaternion"):
            quats.setdefault(k[0], {})[k[1]] = (v[w][1::2], full[k][w][1::2])
            continue
        # The same values as the whole bake's, to the keys' float32 (the wheels' distance
        # travelled, 300 m and more on: 3e-5 apart in float32).
        np.testing.assert_allclose(v[w][1::2], full[k][w][1::2], rtol=1e-6, atol=2e-6,
                                   err_msg=str(k))
    assert len(quats) > 5
    for path, comps in quats.items():
        new, whole = (np.stack([comps[i][j] for i in range(4)], axis=1) for j in range(2))
        # The same rotations (q and -q are one), to the keys' float32.
        assert np.abs(np.sum(new * whole, axis=1)).min() > 1 - 1e-6, path
    assert any(not np.array_equal(step[k][w], before[k][w]) for k in step)


def test_a_drag_reads_the_users_rig_once_and_again_when_its_map_changes(scene, monkeypatch):
    from blender_turning.blender.scene import retarget_adapter as ra
    scene.frame_end = 240
    rig = users_figure("SKIER")
    scene.frame_set(100)
    reads, read = [], ra.user_rig
    monkeypatch.setattr(ra, "user_rig", lambda obj: reads.append(1) or read(obj))
    for k in range(3):                              # three steps of a drag: one read
        rig.turning.lean += math.radians(0.5)
        live.schedule()
        assert rig.name not in live.FAILURES
    assert len(reads) == 1
    # The map changed between two steps (a joint left unmapped): the next step sees it.
    ra.fill_custom_map(rig, ra.figure_bone_map(rig))
    rig.turning.rig.bone_map = "CUSTOM"
    next(r for r in rig.turning.rig.custom_map if r.name == "thigh.L").bone = ""
    rig.turning.lean += math.radians(0.5)
    live.schedule()                                 # refused before a read
    assert "thigh.L" in live.FAILURES[rig.name].message and len(reads) == 1
    rig.turning.rig.bone_map = "MIXAMO"
    live._state["last_change"] -= live.SETTLE       # the drag ended: the release reads it anew
    assert live._tick() is None and not live.is_pending(rig)
    # The timer's drag step (the map changed back) and the release: one read each.
    assert len(reads) == 3 and rig.name not in live._RIGS
