"""Each rig built and baked for 10 s on the bpy wheel; F-curves read back equal the mapping's
arrays; then, on the depsgraph-evaluated pose of the baked scene (bone positions in world space),
the physical properties of Section 7."""
import math
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

from blender_turning import blender as addon  # noqa: E402
from blender_turning.blender import compat  # noqa: E402
from blender_turning.blender.anim import bake, export_ready  # noqa: E402
from blender_turning.blender.anim.figure_bake import apply_bake  # noqa: E402
from blender_turning.blender.jobs.pipeline import figure_pose_track  # noqa: E402
from blender_turning.blender.scene.scene_adapters import FrameRange  # noqa: E402

pytestmark = pytest.mark.blender
SPORTS = ("SKIER", "SNOWBOARDER", "TELEMARK", "CYCLIST")
SECONDS, FPS = 10, 24


def mapped_sports():
    try:
        from blender_turning.mapping import MAPPINGS
    except ImportError:
        return ()
    return tuple(s for s in SPORTS if s.lower() in MAPPINGS)


class Baked:
    """One figure baked in the shared scene: its trajectory, pose track and evaluated bones."""

    def __init__(self, obj, traj, track):
        self.obj, self.traj, self.track = obj, traj, track
        self.world = {}          # bone -> (n, 4, 4) evaluated world matrices
        self.tail = {}           # bone -> (n, 3) evaluated world tail positions

    def head(self, bone):
        return self.world[bone][:, :3, 3]

    def axis(self, bone, i):
        return self.world[bone][:, :3, i]


@pytest.fixture(scope="module")
def baked():
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    scene = bpy.context.scene
    scene.render.fps, scene.frame_start, scene.frame_end = FPS, 1, 1 + SECONDS * FPS
    frames = FrameRange.of_scene(scene)
    out = {}
    for i, sport in enumerate(mapped_sports()):
        scene.cursor.location = (6.0 * i, 0.0, 0.0)
        bpy.ops.turning.add_figure(sport=sport)
        obj = bpy.context.view_layer.objects.active
        traj, track = figure_pose_track(obj, frames)
        apply_bake(obj, traj, track)
        out[sport] = Baked(obj, traj, track)
    for f in range(frames.start, frames.end + 1):       # tests may step frames; the bake may not
        scene.frame_set(f)
        dg = bpy.context.evaluated_depsgraph_get()
        for b in out.values():
            ev = b.obj.evaluated_get(dg)
            mw = np.array(ev.matrix_world)
            for pb in ev.pose.bones:
                b.world.setdefault(pb.name, []).append(mw @ np.array(pb.matrix))
                b.tail.setdefault(pb.name, []).append((mw @ np.array([*pb.tail, 1.0]))[:3])
    for b in out.values():
        b.world = {k: np.array(v) for k, v in b.world.items()}
        b.tail = {k: np.array(v) for k, v in b.tail.items()}
    yield out
    addon.unregister()


def figure(baked, sport):
    if sport not in baked:
        pytest.skip(f"no {sport.lower()} mapping yet")
    return baked[sport]


@pytest.mark.parametrize("sport", SPORTS)
def test_fcurves_read_back_equal_to_mapping(baked, sport):
    b = figure(baked, sport)
    tr = b.track
    fcs = {(fc.data_path, fc.array_index): fc for fc in bake.baked_channels(b.obj).fcurves}
    expect = {("location", i): tr.location[:, i] for i in range(3)}
    expect.update({("rotation_euler", i): tr.rotation[:, i] for i in range(3)})
    for name, ch in tr.bones.items():
        for attr, arr in (("location", ch.location), ("rotation_quaternion", ch.rotation)):
            if arr is not None:
                expect.update({(f'pose.bones["{name}"].{attr}', i): arr[:, i]
                               for i in range(arr.shape[1])})
    expect.update({(f'["{p}"]', 0): v for p, v in tr.props.items()})
    # The figure's own take (export_ready.py: a constant that only its own object has, so FBX
    # gives no other object this action).
    expect[(f'["{export_ready.TAKE}{b.obj.name}"]', 0)] = np.zeros(len(tr))
    assert set(fcs) == set(expect)
    for key, values in expect.items():
        co = np.empty(2 * len(fcs[key].keyframe_points), np.float32)
        fcs[key].keyframe_points.foreach_get("co", co)
        np.testing.assert_array_equal(co[0::2], np.arange(1, 2 + SECONDS * FPS))  # every frame
        np.testing.assert_allclose(co[1::2], values, rtol=1e-6, atol=1e-5, err_msg=str(key))


def ground_tilt(b, bone):
    """Signed roll of ``bone`` about its own long axis relative to the ground (left = +)."""
    y, z = b.axis(bone, 1), b.axis(bone, 2)
    left = np.cross([0.0, 0.0, 1.0], y)
    left /= np.linalg.norm(left, axis=1)[:, None]
    return np.arctan2(np.sum(z * left, axis=1), z[:, 2])


@pytest.mark.parametrize("sport, bones", [("SKIER", ("ski.L", "ski.R")),
                                          ("TELEMARK", ("ski.L", "ski.R")),
                                          ("SNOWBOARDER", ("board",))])
def test_skis_and_board_on_the_ground(baked, sport, bones):
    b = figure(baked, sport)
    for bone in bones:
        ends = np.stack([b.head(bone)[:, 2], b.tail[bone][:, 2]])
        # The centre line never sinks below the snow and stays within an edge's height of it.
        assert ends.min() > -0.005, (bone, ends.min())
        assert ends.max() < 0.06, (bone, ends.max())


@pytest.mark.parametrize("sport", ["SKIER", "TELEMARK", "SNOWBOARDER"])
def test_edge_tilt_follows_curvature(baked, sport):
    b = figure(baked, sport)
    bones = ("board",) if sport == "SNOWBOARDER" else ("ski.L", "ski.R")
    for bone in bones:
        tilt = ground_tilt(b, bone)
        r = np.corrcoef(tilt, b.traj.C_f)[0, 1]
        assert abs(r) > 0.9, (bone, r)
        if sport != "SNOWBOARDER":        # skis tilt into the turn: left turn, left edge down
            assert r > 0.9, (bone, r)


def knee_bend(b):
    bends = [np.arccos(np.clip(np.sum(b.axis(f"thigh.{s}", 1) * b.axis(f"shin.{s}", 1), axis=1),
                               -1, 1)) for s in "LR"]
    return np.mean(bends, axis=0)


@pytest.mark.parametrize("sport", ["SKIER", "SNOWBOARDER"])
def test_knee_bend_rises_with_leg_force(baked, sport):
    b = figure(baked, sport)
    bend, F = knee_bend(b), b.traj.F_leg
    assert np.corrcoef(bend, F)[0, 1] > 0.7
    lo, hi = np.quantile(F, [1 / 3, 2 / 3])
    assert bend[F >= hi].mean() - bend[F <= lo].mean() > math.radians(5)


@pytest.mark.parametrize("sport", ["SKIER", "TELEMARK"])
def test_pole_tips_touch_the_ground_near_30_and_210_deg(baked, sport):
    b = figure(baked, sport)
    phi = np.degrees(b.traj.phi)
    for bone, plant in (("pole.L", 30.0), ("pole.R", 210.0)):
        tip = b.tail[bone][:, 2]
        signed = (phi - plant + 180.0) % 360.0 - 180.0
        off = np.abs(signed)
        near = (signed > -10.0) & (signed <= 0.0)       # touched down by the plant phase
        assert near.sum() >= 3, "the run passes the plant phase"
        assert np.all(tip[near] < 0.02), (bone, tip[near].max())      # planted
        # only around the plant: the hold (20 deg) and the frames the tip comes out of its hole
        # (after the first turn: while the controller converges the phase is no steady clock)
        settled = b.traj.t > 2.0
        assert np.all(off[(tip < 0.02) & settled] < 50.0), bone
        assert tip[off > 90.0].min() > 0.1, bone                        # lifted otherwise


def rest_matrix(b, bone):
    return np.array(b.obj.data.bones[bone].matrix_local)


def carried_point(b, point_rest, carrier):
    """Where a rest-pose point rigidly attached to ``carrier`` is now (world, per frame)."""
    local = np.linalg.inv(rest_matrix(b, carrier)) @ np.array([*point_rest, 1.0])
    return (b.world[carrier] @ local)[:, :3]


def test_crank_angle_proportional_to_distance(baked):
    b = figure(baked, "CYCLIST")
    # The left pedal's centre circles the crank axle; its angle, in the frame's own coordinates.
    frame_inv = np.linalg.inv(b.world["frame"])
    d = (frame_inv @ np.concatenate([b.head("pedal.L") - b.head("crank"),
                                     np.zeros((len(b.traj), 1))], axis=1)[..., None])[..., :3, 0]
    axle = np.linalg.svd(d - d.mean(axis=0))[2][-1]           # normal of the pedal's circle
    e1 = d[0] / np.linalg.norm(d[0])
    e2 = np.cross(axle, e1)
    angle = np.unwrap(np.arctan2(d @ e2, d @ e1))
    s = b.traj.s - b.traj.s[0]
    slope, icpt = np.polyfit(s, angle, 1)
    resid = angle - (slope * s + icpt)
    assert abs(slope) * s[-1] > 4 * math.pi                    # it really turns (> 2 turns)
    total = abs(angle[-1] - angle[0])
    assert np.abs(resid).max() < 0.005 * total and abs(icpt) < 0.005 * total


def test_steer_angle_has_the_sign_of_curvature(baked):
    b = figure(baked, "CYCLIST")
    fx = np.einsum("nji,nj->ni", b.world["frame"][:, :3, :3], b.axis("fork", 0))
    delta = np.arctan2(fx[:, 1], fx[:, 0])                      # about the frame's up axis
    cf = b.traj.C_f
    turning = np.abs(cf) > 0.02
    assert turning.sum() > 20
    assert np.all(np.sign(delta[turning]) == np.sign(cf[turning]))
    assert np.corrcoef(delta, cf)[0, 1] > 0.95


def test_feet_on_pedals_and_hands_on_handlebar_within_1cm(baked):
    b = figure(baked, "CYCLIST")
    bones = b.obj.data.bones
    for s in "LR":
        # The ball of the foot rests on the pedal; the wrist holds the grip on the fork.
        ball = carried_point(b, bones[f"foot.{s}"].tail_local, f"pedal.{s}")
        assert np.linalg.norm(b.tail[f"foot.{s}"] - ball, axis=1).max() < 0.01
        wrist = carried_point(b, bones[f"hand.{s}"].head_local, "fork")
        assert np.linalg.norm(b.head(f"hand.{s}") - wrist, axis=1).max() < 0.01
        # ...and the pedal really moves (the check is not vacuous).
        assert np.ptp(b.head(f"pedal.{s}")[:, 2]) > 0.1
