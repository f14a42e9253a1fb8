"""The telemark mapping (Section 7), checked with numpy forward kinematics."""

import numpy as np
import pytest

from blender_turning.mapping.sports.telemark import TelemarkOptions
from test_mapping_skier import knee, lowest_box_z, posed, run


@pytest.fixture(scope="module")
def tele():
    traj = run("telemark")
    return (traj,) + posed("telemark", traj)


def test_skis_separate_and_angle_to_give_cf(tele):
    traj, track, spec, sk, P = tele
    o = TelemarkOptions()
    ahead = P["ski.R"][:, 1, 3] - P["ski.L"][:, 1, 3]          # R ahead of L, m
    big = np.abs(traj.C_f) > o.lead_curvature
    assert big.sum() > 50
    # the outside ski leads: the right one in a left turn
    assert np.all(np.sign(ahead[big]) == np.sign(traj.C_f[big]))
    assert np.abs(ahead).max() > 0.8 * o.separation
    # each ski is tangent to the foot's circle of curvature: relative yaw = C_f * separation
    yaw = {s: np.arctan2(-P[f"ski.{s}"][:, 0, 1], P[f"ski.{s}"][:, 1, 1]) for s in "LR"}
    # (1e-3 rad: the ski heads sit a few mm off the boots' fore-aft offsets once yawed and
    # tilted, the boots are what is placed exactly)
    assert np.allclose(yaw["R"] - yaw["L"], traj.C_f * ahead, atol=1e-3)


def test_skis_on_the_ground_and_boots_on_the_skis(tele):
    traj, track, spec, sk, P = tele
    for s in "LR":
        assert np.abs(lowest_box_z(spec, P, f"ski.{s}")).max() < 1e-9
        # the ball of the foot (the toe's head) stays on the binding point of the ski
        ball = sk.carry(P, f"ski.{s}", spec.bone(f"toe.{s}").head)
        # On the binding by construction: measured <= 4.8e-16 m, 8.9e-16.
        assert np.abs(ball - P[f"toe.{s}"][:, :3, 3]).max() < 1e-9
        rel = np.linalg.inv(P[f"ski.{s}"]) @ P[f"toe.{s}"]
        ref = np.linalg.inv(sk.rest_of(f"ski.{s}")) @ sk.rest_of(f"toe.{s}")
        assert np.allclose(rel[:, :3, :3], ref[:3, :3], atol=1e-9)


def test_trailing_heel_lifts(tele):
    traj, track, spec, sk, P = tele
    heel_L = P["foot.L"][:, 2, 3] - sk.carry(P, "ski.L", sk.rest_of("foot.L")[:3, 3])[:, 2]
    behind_L = P["ski.L"][:, 1, 3] < P["ski.R"][:, 1, 3] - 0.3
    assert np.all(heel_L[behind_L] > 0.03)


def test_knees_follow_leg_force(tele):
    """(Its poles plant as the skier's: tests/test_mapping_skier.py runs the pole tests on both.)"""
    traj, track, spec, sk, P = tele
    assert np.corrcoef(knee(P, "L") + knee(P, "R"), traj.F_leg)[0, 1] > 0.9


def test_options_are_validated():
    with pytest.raises(ValueError, match="separation"):
        TelemarkOptions(separation=5.0)
    with pytest.raises(ValueError, match="k_s"):
        TelemarkOptions(k_s=-1.0)
