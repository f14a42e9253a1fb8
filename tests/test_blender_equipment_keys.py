"""A user rig's equipment keyed in closed form (``export_ready.closed_form``): the transforms it
writes are the ones Blender evaluates through the rig's IK and the equipment's constraints, on a
Rigify rig and a Mixamo-like one, and a bake reads Blender's evaluation on three frames only for
those pieces (Rigify's hands are not where the retarget solves them: its poles are read frame by
frame)."""
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from rig_fixtures import activate, mixamo_skeleton, rigify_rig  # noqa: E402

from blender_turning.blender.anim import export_ready  # noqa: E402

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]
FRAMES = 48
#: Measured: the Mixamo-like rig 2.0e-6 m and 1.2e-6 (rotation, unit-column matrix entries),
#: float32 keys; Rigify's feet 6.8e-5 m and 8.6e-7, where its IK solver stops short of the
#: target.  export_ready.CHECK_M / CHECK_RAD (1e-4) bound both.
TOL_M, TOL_RAD = export_ready.CHECK_M, export_ready.CHECK_RAD
#: The pieces whose closed form holds on each rig.
CLOSED = {"rigify": {"ski.L", "ski.R"}, "mixamo": {"ski.L", "ski.R", "pole.L", "pole.R"}}
RIGS = {"rigify": lambda: rigify_rig("Rob", location=(1.0, 2.0, 0.0)),
        "mixamo": lambda: mixamo_skeleton("Ann", location=(1.0, 2.0, 0.0))}


@pytest.fixture
def scene(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end, sc.render.fps = 1, FRAMES, 24
    yield sc


def baked(monkeypatch, kind):
    """A skier made from the ``kind`` rig and baked (export-ready): the figure, its equipment,
    the track the bake keyed them from and the frames Blender evaluated for them."""
    rig = RIGS[kind]()
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIER") == {"FINISHED"}
    seen, evaluated = {}, []
    closed, sample = export_ready.closed_form, export_ready._sample

    def spy_closed(fig, objs, track):
        seen["track"] = track
        return closed(fig, objs, track)

    def spy_sample(scene, objs, frames):
        evaluated.extend(frames)
        return sample(scene, objs, frames)

    monkeypatch.setattr(export_ready, "closed_form", spy_closed)
    monkeypatch.setattr(export_ready, "_sample", spy_sample)
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    monkeypatch.undo()
    return rig, list(rig.turning.rig.equipment.objects), seen["track"], evaluated


def errors(got, want):
    """Largest location (m) and rotation (matrix entry, unit columns) differences."""
    unit = lambda m: m[..., :3, :3] / np.linalg.norm(m[..., :3, :3], axis=-2, keepdims=True)  # noqa: E731
    return (np.abs(got[..., :3, 3] - want[..., :3, 3]).max(),
            np.abs(unit(got) - unit(want)).max())


@pytest.mark.parametrize("kind", sorted(RIGS))
def test_the_closed_form_is_what_blender_evaluates(scene, monkeypatch, kind):
    rig, gear, track, evaluated = baked(monkeypatch, kind)
    assert len(gear) == 4                               # skis and poles
    closed = np.array([o["turning_equipment"] in CLOSED[kind] for o in gear])
    # The check's three frames, and every frame for the pieces it turned down.
    assert len(evaluated) == 3 + (FRAMES if not closed.all() else 0)
    keyed = export_ready._sample(scene, gear, track.frames)      # the keys, as played
    export_ready.clear_equipment(rig)                   # the constraints place it again
    mats, tied = export_ready.closed_form(rig, gear, track)
    assert tied.all()
    live = export_ready._sample(scene, gear, track.frames)
    loc, rot = errors(mats[:, closed], live[:, closed])
    assert loc <= TOL_M and rot <= TOL_RAD, (loc, rot)
    loc, rot = errors(keyed, live)
    assert loc <= TOL_M and rot <= TOL_RAD, (loc, rot)
    ride = np.linalg.norm(live[-1, :, :3, 3] - live[0, :, :3, 3], axis=1)
    assert ride.min() > 3.0                             # it moves: 2 s at 10 m/s


def test_a_rig_moved_by_a_tweak_is_read_frame_by_frame(scene, monkeypatch):
    """A key of the user's on a bone (the tweak layer) moves the rig otherwise than the bake's
    keys: the closed form stands aside and every frame is evaluated."""
    rig, gear, track, _ = baked(monkeypatch, "mixamo")
    pb = rig.pose.bones["mixamorig:LeftFoot"]
    pb.rotation_quaternion = (0.9, 0.3, 0.0, 0.0)
    assert pb.keyframe_insert("rotation_quaternion", frame=20)
    export_ready.clear_equipment(rig)
    assert not export_ready.closed_form(rig, gear, track)[1].any()
    evaluated = []
    sample = export_ready._sample
    monkeypatch.setattr(export_ready, "_sample",
                        lambda sc, objs, frames: evaluated.extend(frames) or sample(sc, objs,
                                                                                      frames))
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert len(evaluated) == FRAMES
