"""The cyclist mapping (Section 7), checked with numpy forward kinematics on the baked channels."""
import math

import numpy as np
import pytest

from blender_turning.core import PhaseEllipse, preset, simulate
from blender_turning.mapping import map_trajectory
from blender_turning.mapping.sports.cyclist import CyclistOptions, steer_angle
from blender_turning.mapping.kinematics import Skeleton
from blender_turning.mapping.rig_spec import load_rig


def run(seconds=10.0, theta_max=23.0, period=2.0):
    fig = preset("cyclist")
    return simulate(fig, PhaseEllipse(fig.body, omega0=2 * math.pi / period,
                                      theta_max=math.radians(theta_max), heading=0.0),
                    duration=seconds).resample(24)


def posed(traj, options=None):
    track = map_trajectory("cyclist", traj, options)
    spec = load_rig("cyclist")
    sk = Skeleton.from_spec(spec)
    return track, spec, sk, sk.fk(track.bones, len(track))


@pytest.fixture(scope="module")
def cyclist():
    traj = run()
    return (traj,) + posed(traj)


def local_angle(q, axis):
    """Signed rotation angle of unit quaternions ``q`` about the unit local ``axis``."""
    return 2.0 * np.arctan2(q[:, 1:] @ np.asarray(axis, float), q[:, 0])


def test_crank_angle_is_distance_over_radius_and_gear(cyclist):
    traj, track, spec, sk, P = cyclist
    o = CyclistOptions()
    r = max(m.size[0] for m in spec.meshes_of("wheel.R"))
    # The crank arm's direction in the frame, unwrapped: the crank turns forwards (the right
    # pedal, ahead at rest, goes down first) by s / (r * gear_ratio).
    rel = np.linalg.inv(P["frame"]) @ np.concatenate(
        [sk.carry(P, "crank", spec.bone("pedal.R").head), np.ones((len(traj), 1))], 1)[..., None]
    rel = rel[:, :3, 0] - (np.linalg.inv(sk.rest_of("frame")) @ np.append(
        spec.bone("crank").head, 1))[:3]
    angle = np.unwrap(np.arctan2(-rel[:, 2], rel[:, 1]))
    expected = (traj.s - traj.s[0]) / (r * o.gear_ratio)
    assert np.allclose(angle - angle[0], expected, atol=1e-9)
    # and the wheels by s / r (local channel about the axle, the bones' Y)
    w = np.unwrap(local_angle(track.bones["wheel.R"].rotation, (0, 1, 0)))
    assert np.allclose(-(w - w[0]), (traj.s - traj.s[0]) / r, atol=1e-9)


def test_gear_ratio_and_radius_are_parameters():
    traj = run(seconds=2.0)
    a = posed(traj, CyclistOptions(gear_ratio=4.0, wheel_radius=0.5))[0]
    q = np.unwrap(local_angle(a.bones["crank"].rotation, (0, 1, 0)))
    assert np.allclose(-(q - q[0]), (traj.s - traj.s[0]) / (0.5 * 4.0), atol=1e-9)


def test_steer_angle_has_the_sign_of_cf(cyclist):
    traj, track, spec, sk, P = cyclist
    delta = local_angle(track.bones["fork"].rotation, (0, 1, 0))
    big = np.abs(traj.C_f) > 1e-3
    assert big.sum() > 100
    assert np.all(np.sign(delta[big]) == np.sign(traj.C_f[big]))
    # the wheel on the ground points where a bicycle of this wheelbase must steer
    wb = float(np.linalg.norm(np.subtract(spec.bone("wheel.F").head, spec.bone("wheel.R").head)))
    # The wheel rolls along its plane's intersection with the ground, a x z for the axle a:
    # that line is atan(a_y / a_x) off the frame's heading, whatever the lean.
    a = P["wheel.F"][:, :3, 1]
    assert np.allclose(a[:, 1] / a[:, 0], wb * traj.C_f, atol=1e-9)


def test_steer_angle_function():
    assert steer_angle(0.1, 0.0, 1.0, 1.0) == pytest.approx(math.atan(0.1))
    assert steer_angle(-0.1, 0.3, 1.0, 1.0) < 0
    assert steer_angle(10.0, 0.0, 1.0, 0.5) == pytest.approx(0.5)


def test_feet_on_pedals_and_hands_on_the_handlebar(cyclist):
    traj, track, spec, sk, P = cyclist
    for s in "LR":
        # the ball of the foot (the foot's tail) on the pedal over the 10 s run (IK onto the
        # pedal: round-off, measured <= 6.7e-16 m; the hands 7.8e-16 m)
        ball = P[f"foot.{s}"][:, :3, 3] + P[f"foot.{s}"][:, :3, 1] * spec.bone(f"foot.{s}").length
        on_pedal = sk.carry(P, f"pedal.{s}", spec.bone(f"foot.{s}").tail)
        assert np.abs(ball - on_pedal).max() < 1e-9
        # the hand grips the bar where it held it at rest (the hand's midpoint)
        mid = 0.5 * (np.add(spec.bone(f"hand.{s}").head, spec.bone(f"hand.{s}").tail))
        assert np.abs(sk.carry(P, f"hand.{s}", mid) - sk.carry(P, "fork", mid)).max() < 1e-9
        # the pedals stay level with the frame
        rel = np.linalg.inv(P["frame"]) @ P[f"pedal.{s}"]
        want = np.linalg.inv(sk.rest_of("frame")) @ sk.rest_of(f"pedal.{s}")
        assert np.allclose(rel[:, :3, :3], want[:3, :3], atol=1e-9)


def test_wheels_touch_the_ground(cyclist):
    traj, track, spec, sk, P = cyclist
    for wheel in ("wheel.F", "wheel.R"):
        r = max(m.size[0] for m in spec.meshes_of(wheel))
        a = P[wheel][:, :3, 1]
        low = P[wheel][:, 2, 3] - r * np.sqrt(1 - a[:, 2] ** 2)
        assert np.abs(low).max() < 1e-9
    # in the world too (the object only turns about Z and moves in x, y)
    c, s = np.cos(track.rotation[:, 2]), np.sin(track.rotation[:, 2])
    assert np.allclose(c ** 2 + s ** 2, 1) and np.allclose(track.location[:, 2], 0)


def test_bike_and_rider_lean_by_theta_v(cyclist):
    traj, track, spec, sk, P = cyclist
    for bone in ("frame", "spine"):
        z = P[bone][:, :3, :3] @ np.linalg.inv(sk.rest_of(bone)[:3, :3]) @ np.array([0, 0, 1.0])
        assert np.allclose(np.arctan2(-z[:, 0], z[:, 2]), traj.theta_v, atol=1e-9)


def test_options_are_validated():
    with pytest.raises(ValueError, match="gear_ratio"):
        CyclistOptions(gear_ratio=0.0)
    with pytest.raises(ValueError, match="wheel_radius"):
        CyclistOptions(wheel_radius=-1.0)


def test_the_fork_is_raked_with_trail():
    """A bicycle's steering axis leans back (head angle ~72 deg) and meets the ground ahead of the
    front tyre's contact (trail, which makes a real bike self-steer into its lean)."""
    spec = load_rig("cyclist")
    fork = spec.bone("fork")
    k = np.subtract(fork.tail, fork.head)
    k = k / np.linalg.norm(k)
    head_angle = math.degrees(math.atan2(k[2], -k[1]))
    assert 68.0 < head_angle < 76.0
    hub = np.asarray(spec.bone("wheel.F").head)
    ground = np.asarray(fork.head) - fork.head[2] / k[2] * k          # the axis at z = 0
    trail = ground[1] - hub[1]
    assert 0.03 < trail < 0.10


def test_a_part_of_a_run_turns_the_wheels_as_the_run_does(cyclist):
    """Live Preview maps a window of a run: with the run's first distance (meta ``s_start``) its
    rows are the whole run's rows, wheels and crank included (the rest of the mapping is frame
    by frame)."""
    traj, track, *_ = cyclist
    a, b = 100, 160
    part = type(traj)(traj.data[:, a:b], {**traj.meta, "s_start": float(traj.s[0])})
    window = map_trajectory("cyclist", part, frame_start=1 + a)
    np.testing.assert_array_equal(window.frames, track.frames[a:b])
    for name, ch in window.bones.items():
        if ch.rotation is not None:
            # the same rotations (a quaternion and its negative are one), to float round-off
            dots = np.abs(np.sum(ch.rotation * track.bones[name].rotation[a:b], axis=1))
            np.testing.assert_allclose(dots, 1.0, atol=1e-9, err_msg=name)
    # Without it the part's wheels start from where the part starts: not the run's.
    q = map_trajectory("cyclist", type(traj)(traj.data[:, a:b], traj.meta)).bones["wheel.F"]
    dots = np.abs(np.sum(q.rotation * track.bones["wheel.F"].rotation[a:b], axis=1))
    assert dots.min() < 0.99
