"""Skidding on the rig (mapping/sports/skid_pose.py, docs/skidding.md Section 8): the skis and board
yaw from the travel by the skid angle, the chest faces down the travel, a wedge's tips come
together with the skis edged inward, a hockey stop's skis go across on their uphill edges, and a
carved run maps bit for bit as a run without skidding."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start
from blender_turning.core.physics.model import RESISTANCE
from blender_turning.core.physics.skidding import STOP_EDGE, WEDGE_EDGE, Skidding
from blender_turning.core.ground.terrain import Plane
from blender_turning.core.physics.trajectory import Trajectory
from blender_turning.mapping import bones as B
from blender_turning.mapping import map_trajectory
from blender_turning.mapping.sports import skid_pose
from blender_turning.mapping.kinematics import Skeleton
from blender_turning.mapping.rig_spec import load_rig

FALL = -math.pi / 2


def run(sport, slope_deg, duration, V0=None, target=None, **skid):
    fig = preset(sport)
    if V0 is not None:
        fig = replace(fig, body=replace(fig.body, V_cm=V0))
    ground = Plane(math.radians(slope_deg), FALL)
    ctl = PhaseEllipse(fig.body, math.pi, math.radians(23), heading=FALL)
    ctl.begin_run(fig.limits)
    s0 = slalom_start(fig.body, *ctl.target(0.0), FALL)
    traj = simulate(fig, ctl, duration, 0.02, s0, ground=ground, resistance=RESISTANCE[sport],
                    target_speed=target, skidding=Skidding(**skid))
    return traj.resample(24, ground=ground)


def posed(sport, traj):
    track = map_trajectory(sport, traj)
    sk = Skeleton.from_spec(load_rig(sport))
    return track, sk.fk(track.bones, len(track))


def yaw_of(P, bone, axis=1):
    """The yaw of the bone's axis ``axis`` (Y: from the travel, armature +Y; X: from the right,
    armature +X) projected on the ground, rad (counter-clockwise positive)."""
    a = P[bone][:, :3, axis]
    return np.arctan2(-a[:, 0], a[:, 1]) if axis == 1 else np.arctan2(a[:, 1], a[:, 0])


def tilt_of(P, bone):
    """How far the bone's X axis (across the ski) dips: positive when its left edge is down."""
    return np.arcsin(np.clip(P[bone][:, 2, 0], -1, 1))


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


@pytest.fixture(scope="module")
def skidded():
    """Skidded turns at a 10 m/s target on 25 deg, then a hockey stop at 6 s."""
    traj = run("skier", 25, 9.0, target=10.0, style="skid", stop_at=6.0)
    return (traj,) + posed("skier", traj)


def test_the_skis_yaw_from_the_travel_by_the_skid_angle(skidded):
    traj, _, P = skidded
    assert np.abs(traj.skid).max() > math.radians(30)       # it does skid, then stops
    for s in ("L", "R"):
        # The ski's long axis is yawed by rot_z(skid) and tilted about itself: its ground
        # projection's yaw is the skid to round-off (measured 4e-16 rad).
        assert np.allclose(wrap(yaw_of(P, f"ski.{s}") - traj.skid), 0.0, atol=1e-9)


def test_the_board_yaws_by_the_skid_angle():
    traj = run("snowboarder", 15, 4.0, V0=10.0, stop_at=1.0, stop_side="toe")
    _, P = posed("snowboarder", traj)
    assert np.abs(traj.skid).max() > math.radians(60)
    assert np.allclose(wrap(yaw_of(P, "board") - traj.skid), 0.0, atol=1e-9)


def test_the_chest_faces_down_the_travel_while_the_skis_skid(skidded):
    """Counter-rotation: the chest turns CHEST_SHARE of the skid, the pelvis HIP_SHARE, while
    the skis turn all of it (the turn's own counter-twist, 12 deg at most, comes on top)."""
    traj, _, P = skidded
    big = np.abs(traj.skid) > math.radians(45)
    assert big.sum() > 10
    # About the body's up: in the frame of the lean (which leans back against the brake too).
    lean = P[B.LEAN][:, :3, :3]
    body = {k: np.einsum("nji,njk->nik", lean, P[k][:, :3, :3]) for k in ("spine.003", "spine")}
    chest = yaw_of(body, "spine.003", axis=0)         # the chest's X: to the right
    hips = yaw_of(body, "spine", axis=0)
    assert np.all(np.abs(chest[big]) < np.abs(hips[big]))
    assert np.all(np.abs(hips[big]) < np.abs(traj.skid[big]))


def test_the_stop_puts_the_skis_on_their_uphill_edges(skidded):
    traj, _, P = skidded
    late = traj.t > 6.0 + skid_pose.STOP_RAMP
    for s in ("L", "R"):
        # Uphill: the ski's left edge down when it turned left (skid > 0), for the whole stop.
        side = np.sign(traj.skid[late].sum())
        assert np.all(side * traj.skid[late] >= 0.0)
        assert np.allclose(tilt_of(P, f"ski.{s}")[late], side * STOP_EDGE, atol=1e-9)


@pytest.mark.parametrize("sport, within", [("skier", 2.5), ("snowboarder", 5.5)])
def test_the_body_leans_back_against_the_braking_force(sport, within, monkeypatch):
    """Skidded turns on 25 deg, a hockey stop at 6 s: the posed centre of mass (Winter's
    segments) leans back from where it is without the pitch by the angle of the snow's force,
    ``atan(m brake / F_leg)`` lagged by STOP_RAMP: up to 40 deg in the stop, 10-12 deg on average
    in the skidded turns; within 2.5 deg for the skier (measured 2.0: the centre is not exactly
    on the lean's axis), 5.5 deg for the snowboarder (measured 2.6 in the turns, 4.9 in the stop:
    its legs lean to keep the centre's roll, seen along the travel, on theta_v, 54 deg in the
    stop; under 40 deg of pitch that lean differs from the unpitched pose's and moves the
    centre's height, so its pitch seen across the travel)."""
    from blender_turning.mapping.anthropometry import centre_and_roll_inertia
    traj = run(sport, 25, 9.0, target=10.0, style="skid", stop_at=6.0)
    sk = Skeleton.from_spec(load_rig(sport))

    def back():
        com, _ = centre_and_roll_inertia(posed(sport, traj)[1], sk, 1.0)
        return np.arctan2(-com[:, 1], com[:, 2])

    leaning = back()
    pitch = skid_pose.back_pitch(traj)
    pitched = skid_pose.back_pitch
    monkeypatch.setattr(skid_pose, "back_pitch", lambda tr: np.zeros(len(tr)))
    upright = back()
    monkeypatch.setattr(skid_pose, "back_pitch", pitched)
    assert np.abs(leaning - upright - pitch).max() < math.radians(within)
    stop = traj.t >= 6.0
    assert math.radians(35) < pitch[stop].max() < math.radians(45)
    # The lag: a constant brake is taken in over STOP_RAMP, to 95% after three of it.
    m = traj.meta["body.m"]
    want = np.arctan2(m * traj.brake, traj.F_leg)
    const = Trajectory.from_columns(dict(traj.columns(), brake=np.full(len(traj), 5.0),
                                         F_leg=np.full(len(traj), m * 9.81)), traj.meta)
    p = skid_pose.back_pitch(const)
    i = int(np.searchsorted(const.t, 3 * skid_pose.STOP_RAMP))
    assert p[0] == 0.0 and 0.94 < p[i] / math.atan(5.0 / 9.81) < 0.96
    assert np.all(np.abs(p[-10:] - math.atan(5.0 / 9.81)) < 1e-9)
    assert np.all(want[traj.brake == 0.0] == 0.0)


def test_a_wedge_points_the_tips_together_edged_inward():
    traj = run("skier", 18, 6.0, V0=6.0, target=5.0, style="wedge")
    track, P = posed("skier", traj)
    half = np.abs(traj.skid)
    wide = half > math.radians(5)
    assert wide.sum() > 10
    assert np.allclose(yaw_of(P, "ski.L")[wide], -half[wide], atol=1e-9)
    assert np.allclose(yaw_of(P, "ski.R")[wide], half[wide], atol=1e-9)
    # Inward: the right ski's left edge down and the left ski's right edge, by WEDGE_EDGE more
    # than a parallel turn's tilt would give; measured on the difference of the two skis.
    assert np.all(tilt_of(P, "ski.R")[wide] - tilt_of(P, "ski.L")[wide] > WEDGE_EDGE)
    # The tips stay apart by the gap (not crossed); the tails are wider.
    spec = load_rig("skier")
    from blender_turning.mapping.sports.common import mesh_points
    c = mesh_points(spec, "ski.L")
    tip = np.array([0.0, c[:, 1].max(), 0.0])
    tail = np.array([0.0, c[:, 1].min(), 0.0])
    gap_tip = (P["ski.R"][:, :3, :3] @ tip + P["ski.R"][:, :3, 3]
               - P["ski.L"][:, :3, :3] @ tip - P["ski.L"][:, :3, 3])[:, 0]
    gap_tail = (P["ski.R"][:, :3, :3] @ tail + P["ski.R"][:, :3, 3]
                - P["ski.L"][:, :3, :3] @ tail - P["ski.L"][:, :3, 3])[:, 0]
    assert np.all(gap_tip[wide] > 0.0)
    assert np.all(gap_tail[wide] > gap_tip[wide] + 0.3)


def _carved():
    fig = preset("skier")
    return simulate(fig, PhaseEllipse(fig.body, omega0=math.pi, theta_max=math.radians(23),
                                      heading=0.0), duration=4.0).resample(24)


def test_a_carved_run_maps_bit_for_bit_through_the_skid_pose(monkeypatch):
    """The skid pose's arithmetic with a skid of 0 everywhere (forced on) gives the carved pose
    exactly: the carved model is its zero-skid case."""
    traj = _carved()
    carved = map_trajectory("skier", traj)
    monkeypatch.setattr(skid_pose.SkidPose, "__init__", _forced_on)
    forced = map_trajectory("skier", traj)
    assert set(forced.bones) >= set(carved.bones)
    for name, ch in forced.bones.items():
        was = carved.bones.get(name)
        # A channel the carved pose leaves unset is the rest one: (1, 0, 0, 0) exactly.
        rot = np.tile([1.0, 0.0, 0.0, 0.0], (len(traj), 1)) if was is None or \
            was.rotation is None else was.rotation
        assert ch.rotation is None or np.array_equal(ch.rotation, rot), name
        assert np.array_equal(ch.location, None if was is None else was.location), name


def _forced_on(self, traj):
    n = len(traj)
    self.skid, self.stop, self.pitch = np.zeros(n), np.zeros(n), np.zeros(n)
    self.stopping = self.wedge = np.zeros(n, bool)
    self.active = True


@pytest.mark.parametrize("sport", ["skier", "snowboarder", "telemark"])
def test_zero_skid_columns_leave_the_carved_pose(sport):
    """A carved run written with the skidding columns and meta (style skid, no stop) maps as
    the same run without them."""
    fig = preset(sport)
    traj = simulate(fig, PhaseEllipse(fig.body, omega0=math.pi, theta_max=math.radians(23),
                                      heading=0.0), duration=3.0).resample(24)
    cols = {k: v for k, v in traj.columns().items() if k not in ("skid", "ski_heading", "brake")}
    bare = Trajectory.from_columns(cols, {k: v for k, v in traj.meta.items()})
    tagged = Trajectory(traj.data, dict(traj.meta, style="skid", grip="snow"))
    a, b = map_trajectory(sport, bare), map_trajectory(sport, tagged)
    for name, ch in a.bones.items():
        assert np.array_equal(ch.rotation, b.bones[name].rotation) or ch.rotation is None


def test_a_goofy_rider_turns_the_board_the_same_way():
    """The goofy rider is the mirror image of a regular one on the mirrored run: its board too
    yaws by the run's own skid (the mirrored run's skid is the negative)."""
    from blender_turning.mapping.retarget.stance import goofy_track, mirrored_trajectory
    traj = run("snowboarder", 15, 3.0, V0=10.0, stop_at=1.0, stop_side="heel")
    mirrored = mirrored_trajectory(traj)
    assert np.array_equal(mirrored.skid, -traj.skid)
    track = goofy_track("snowboarder", map_trajectory("snowboarder", mirrored))
    P = Skeleton.from_spec(load_rig("snowboarder")).fk(track.bones, len(track))
    assert np.abs(traj.skid).max() > math.radians(60)
    # Through quaternions and back (goofy_track's local channels): measured 2e-15 rad.
    assert np.allclose(wrap(yaw_of(P, "board") - traj.skid), 0.0, atol=1e-9)


def test_the_skid_is_baked_as_a_state_property(skidded):
    traj, track, _ = skidded
    assert np.array_equal(track.props["turn_skid"], traj.skid)


def test_a_skidding_ski_brushes_a_band_its_length_times_sin_skid():
    from blender_turning.mapping.sports.skid_pose import brushed_half_width, equipment_length
    assert equipment_length(load_rig("skier")) == pytest.approx(1.65)
    assert equipment_length(load_rig("cyclist")) == 0.0
    skid = np.radians([0.0, 1.0, 30.0, -90.0])
    half = brushed_half_width(0.045, 1.65, skid)
    # Carved and barely skidded: the groove; 30 deg: half of 1.65 sin 30; across: the length.
    np.testing.assert_allclose(half, [0.045, 0.045, 0.4125, 0.825], rtol=1e-12)
