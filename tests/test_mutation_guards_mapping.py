"""Guards for mapping mutants that the rest of the suite let through: the ski
tilt's size and the direction of the skier's leg twist (Section 7), measured by forward
kinematics on the baked channels.  ``scripts/mutate.py`` holds the mutants."""
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.mapping.sports.skier import SkierOptions, ski_tilts

from test_mapping_skier import posed, run


@pytest.fixture(scope="module")
def skier():
    traj = run("skier")
    o = SkierOptions()
    return traj, o, posed("skier", traj, o)[3], posed("skier", traj,
                                                      replace(o, leg_twist_gain=0.0))[3]


def ski_roll(P, s):
    """Roll of ski ``s`` about its length (armature space; > 0 on its left edge)."""
    return np.arctan2(P[f"ski.{s}"][:, 2, 0], P[f"ski.{s}"][:, 0, 0])


def test_inside_ski_tilt_is_the_fitted_gain_times_C_f(skier):
    """Section 7: the tilt is linear in C_f with the constant "estimated from a plot like Fig. 5":
    the least-squares slope of theta_v on C_f, computed here independently.  The inside ski (L in
    a left turn) has exactly that tilt (round-off: measured 3e-16 rad), the outside one
    ``1 + outside_extra`` times it; so the inside ski follows the lean (rms 18% of the lean's,
    measured), where a halved tilt would miss it by more than half."""
    traj, o, P, _ = skier
    gain = float(np.dot(traj.theta_v, traj.C_f) / np.dot(traj.C_f, traj.C_f))
    want = gain * traj.C_f
    assert np.abs(want).max() < o.tilt_max            # the clip does not bind here
    left = traj.C_f > 0
    inside = np.where(left, ski_roll(P, "L"), ski_roll(P, "R"))
    outside = np.where(left, ski_roll(P, "R"), ski_roll(P, "L"))
    np.testing.assert_allclose(inside, want, rtol=0, atol=1e-12)
    np.testing.assert_allclose(outside, (1 + o.outside_extra) * want, rtol=0, atol=1e-12)
    rms = np.sqrt(np.mean((inside - traj.theta_v) ** 2) / np.mean(traj.theta_v ** 2))
    assert rms < 0.25


def test_an_explicit_tilt_gain_is_used_as_given():
    traj = run("skier", seconds=4.0)
    P = posed("skier", traj, SkierOptions(tilt_gain=3.0, outside_extra=0.0))[3]
    for s in "LR":
        np.testing.assert_allclose(ski_roll(P, s), 3.0 * traj.C_f, rtol=0, atol=1e-12)


def test_leg_twist_turns_the_knee_into_the_turn(skier):
    """Where the ski is on edge more than the body leans (tilt - theta_v > 0 in a left turn) the
    knee moves towards the turn's centre (left, -X in the rig, which faces +Y), and the other
    way where it is on edge less; the ankle stays on the ski.  Compared with the same pose
    without twist; the knee moves up to 5 cm (measured)."""
    traj, o, P, P0 = skier
    for s in "LR":
        diff = ski_tilts(traj, o)[s] - traj.theta_v
        dx = P[f"shin.{s}"][:, 0, 3] - P0[f"shin.{s}"][:, 0, 3]
        m = np.abs(diff) > 0.02
        assert m.sum() > 50
        assert np.all(np.sign(dx[m]) == -np.sign(diff[m])), s
        np.testing.assert_allclose(P[f"foot.{s}"][:, :3, 3], P0[f"foot.{s}"][:, :3, 3],
                                   rtol=0, atol=1e-12)
