"""numpy FK/IK in Blender's conventions (mapping/kinematics.py)."""
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from blender_turning.mapping.base import BoneChannels
from blender_turning.mapping.kinematics import (PoseBuilder, Skeleton, cross, quat_continuous,
                                                quat_from_axis_angle, quat_from_matrix,
                                                quat_mul, quat_to_matrix, rest_matrix,
                                                rigid_inverse, two_bone_ik, vec_roll_to_mat3)

unit = st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1)


def test_vec_roll_known_frames():
    # Blender: a bone along +Y with roll 0 has the identity frame; along -Z, X stays +X and Z
    # becomes +Y; along +X, X becomes -Y.  (Values checked against bpy 5.0.1 bone.matrix_local,
    # together with 30 random bones with random rolls, to 2e-6 = float32 precision.)
    assert np.allclose(vec_roll_to_mat3((0, 1, 0), 0.0), np.eye(3))
    assert np.allclose(vec_roll_to_mat3((0, 0, -1), 0.0), [[1, 0, 0], [0, 0, 1], [0, -1, 0]])
    assert np.allclose(vec_roll_to_mat3((1, 0, 0), 0.0), [[0, 1, 0], [-1, 0, 0], [0, 0, 1]])
    # The singular direction -Y: Blender's symmetric fallback.
    assert np.allclose(vec_roll_to_mat3((0, -1, 0), 0.0), np.diag([-1, -1, 1]))
    # Roll rotates X and Z about the bone axis (right-handed).
    m = vec_roll_to_mat3((0, 1, 0), math.pi / 2)
    assert np.allclose(m[:, 0], (0, 0, -1)) and np.allclose(m[:, 2], (1, 0, 0))


@settings(max_examples=200, deadline=None)
@given(unit, st.floats(-math.pi, math.pi))
def test_vec_roll_is_a_rotation_with_y_along_the_bone(v, roll):
    m = vec_roll_to_mat3(v, roll)
    # Within 6e-3 of -Y Blender replaces 1 + y by a two-term series, which leaves the frame
    # orthonormal only to ~1e-5, and within 2.5e-4 of -Y it snaps Y to exactly -Y (Blender's
    # own float32 matrices do the same).
    assert np.allclose(m @ m.T, np.eye(3), atol=1e-4)
    assert np.isclose(np.linalg.det(m), 1.0, atol=1e-4)
    assert np.allclose(m[:, 1], np.asarray(v) / np.linalg.norm(v), atol=3e-4)


@settings(max_examples=200, deadline=None)
@given(unit, st.floats(-2 * math.pi, 2 * math.pi))
def test_quaternion_matrix_round_trip(axis, angle):
    q = quat_from_axis_angle(np.asarray(axis), angle)
    back = quat_from_matrix(quat_to_matrix(q))
    assert np.allclose(back, q * np.sign(q[0] if q[0] != 0 else 1), atol=1e-9) or \
        np.allclose(back, -q, atol=1e-9)
    # Composition matches matrix products.
    q2 = quat_from_axis_angle(np.array([0.3, -0.2, 0.9]), 0.7)
    assert np.allclose(quat_to_matrix(quat_mul(q2, q)), quat_to_matrix(q2) @ quat_to_matrix(q),
                       atol=1e-12)


def test_quat_continuous_removes_sign_flips():
    q = quat_from_axis_angle(np.tile([0.0, 0.0, 1.0], (50, 1)), np.linspace(0, 4 * math.pi, 50))
    q[::3] *= -1
    c = quat_continuous(q)
    assert np.all(np.sum(c[1:] * c[:-1], axis=1) >= 0)
    assert np.allclose(quat_to_matrix(c), quat_to_matrix(q))


@settings(max_examples=100, deadline=None)
@given(st.tuples(*[st.floats(-0.7, 0.7)] * 3), unit)
def test_two_bone_ik_reaches_reachable_targets(target, pole):
    root = np.zeros(3)
    t = np.asarray(target)
    if not 0.05 < np.linalg.norm(t) < 0.75 or np.linalg.norm(np.cross(t, pole)) < 1e-3:
        return
    mid, end = two_bone_ik(root, t, 0.45, 0.4, np.asarray(pole))
    assert np.allclose(end, t, atol=1e-9)
    assert np.isclose(np.linalg.norm(mid - root), 0.45)
    assert np.isclose(np.linalg.norm(end - mid), 0.4)
    # The joint bends towards the pole side of the root-target line.
    assert np.dot(mid - root, np.asarray(pole) - np.dot(pole, t) / np.dot(t, t) * t) > -1e-9


def chain():
    """A three-bone chain with a rolled, unconnected middle bone."""
    heads = [(0, 0, 0), (0, 0, 1), (0.2, 0.1, 1.5)]
    tails = [(0, 0, 1), (0.2, 0.1, 1.5), (0.5, 0.4, 1.2)]
    rest = [rest_matrix(h, t, r) for h, t, r in zip(heads, tails, (0.0, 0.4, -1.0))]
    return Skeleton(["a", "b", "c"], [None, "a", "b"], rest, [False, True, True])


def test_fk_composition_matches_blender_formula():
    sk = chain()
    n = 5
    rng = np.random.default_rng(0)
    q = {k: quat_from_axis_angle(rng.normal(size=(n, 3)), rng.normal(size=n)) for k in "abc"}
    loc = rng.normal(size=(n, 3))
    ch = {"a": BoneChannels(loc, q["a"]), "b": BoneChannels(None, q["b"]),
          "c": BoneChannels(None, q["c"])}
    P = sk.fk(ch, n)
    for k in range(n):
        def T(v):
            m = np.eye(4)
            m[:3, 3] = v
            return m

        def R(qq):
            m = np.eye(4)
            m[:3, :3] = quat_to_matrix(qq)
            return m
        pa = sk.rest[0] @ T(loc[k]) @ R(q["a"][k])
        pb = pa @ np.linalg.inv(sk.rest[0]) @ sk.rest[1] @ R(q["b"][k])
        pc = pb @ np.linalg.inv(sk.rest[1]) @ sk.rest[2] @ R(q["c"][k])
        assert np.allclose(P["a"][k], pa) and np.allclose(P["b"][k], pb)
        assert np.allclose(P["c"][k], pc)
    # Connected bones stay attached: b's head is a's tail.
    assert np.allclose(P["b"][:, :3, 3], P["a"][:, :3, 3] + P["a"][:, :3, 1] * 1.0)


def test_set_pose_inverts_fk():
    sk = chain()
    n = 4
    rng = np.random.default_rng(1)
    b = PoseBuilder(sk, n)
    b.set_local("a", quat_from_axis_angle(rng.normal(size=(n, 3)), rng.normal(size=n)),
                rng.normal(size=(n, 3)))
    want = quat_to_matrix(quat_from_axis_angle(rng.normal(size=(n, 3)), rng.normal(size=n)))
    b.set_pose("b", want)
    assert np.allclose(b.pose("b")[:, :3, :3], want)
    ch = {k: BoneChannels(b.loc.get(k), b.rot.get(k)) for k in "ab"}
    assert np.allclose(sk.fk(ch, n)["b"], b.pose("b"))


def test_set_pose_with_a_head_puts_the_bone_there():
    """set_pose's closed form (the rigid inverse of the unposed bone times the target) gives the
    bone the rotation and head asked, for a bone under a posed parent."""
    c = chain()
    sk = Skeleton(c.names, c.parents, c.rest, [False, False, True])     # b has a location
    n = 50
    rng = np.random.default_rng(4)
    b = PoseBuilder(sk, n)
    b.set_local("a", quat_from_axis_angle(rng.normal(size=(n, 3)), rng.normal(size=n)),
                rng.normal(size=(n, 3)))
    want = quat_to_matrix(quat_from_axis_angle(rng.normal(size=(n, 3)), rng.normal(size=n)))
    head = rng.normal(size=(n, 3))
    b.set_pose("b", want, head)
    # Measured: 1e-15 (rotation), 2.4e-15 m (head).
    assert np.max(np.abs(b.pose("b")[:, :3, :3] - want)) < 1e-14
    assert np.max(np.abs(b.pose("b")[:, :3, 3] - head)) < 1e-14
    with pytest.raises(ValueError, match="connected"):
        b.set_pose("c", want, head)


def test_cached_poses_follow_every_change_of_an_ancestor():
    """PoseBuilder caches poses: a change of a bone's (or an ancestor's) channels must reach
    every descendant's pose, and read-outs must not alias the cache."""
    sk = chain()
    n = 3
    rng = np.random.default_rng(2)
    b = PoseBuilder(sk, n)
    b.pose("c")
    b.pose("c")[:] = 0.0                      # a caller scribbling on what the cache handed out
    np.testing.assert_allclose(b.pose("c"), sk.fk({}, n)["c"], atol=1e-12)
    for step in range(3):
        bone = "abc"[step]
        b.set_local(bone, quat_from_axis_angle(rng.normal(size=(n, 3)), rng.normal(size=n)))
        ch = {k: BoneChannels(b.loc.get(k), b.rot.get(k)) for k in "abc"}
        want = sk.fk(ch, n)
        for k in "abc":
            np.testing.assert_allclose(b.pose(k), want[k], atol=1e-12)
    b.set_pose("b", quat_to_matrix(quat_from_axis_angle(rng.normal(size=(n, 3)),
                                                        rng.normal(size=n))))
    ch = {k: BoneChannels(b.loc.get(k), b.rot.get(k)) for k in "abc"}
    np.testing.assert_allclose(b.pose("c"), sk.fk(ch, n)["c"], atol=1e-12)


def test_rigid_inverse_equals_the_general_inverse():
    rng = np.random.default_rng(3)
    m = np.zeros((50, 4, 4))
    m[:, :3, :3] = quat_to_matrix(quat_from_axis_angle(rng.normal(size=(50, 3)),
                                                       rng.normal(size=50)))
    m[:, :3, 3] = rng.normal(size=(50, 3))
    m[:, 3, 3] = 1.0
    np.testing.assert_allclose(rigid_inverse(m), np.linalg.inv(m), atol=1e-12)


def test_missing_bone_is_named():
    with pytest.raises(KeyError, match="'nope'"):
        chain().i("nope")


# bone.matrix_local (rotation part) read back from bpy 5.0.1 for edit bones (head, tail, roll);
# the second is within 1e-3 of -Y, on Blender's series-expansion branch.
BLENDER_REST = [
    (((0.1, -0.2, 0.3), (0.4, 0.1, -0.2), 0.7),
     [[0.500821, 0.457496, 0.734763], [-0.841123, 0.457496, 0.28846],
      [-0.204182, -0.762493, 0.613934]]),
    (((0, 0, 1), (0.001, -0.5, 1.0), -2.0),
     [[0.416146, 0.002, 0.909296], [0.000832, -0.999998, 0.001819], [0.909297, 0.0, -0.416147]]),
    (((-0.3, 0.2, 0.9), (-0.1, 0.25, 0.5), 1.3),
     [[-0.122655, 0.444445, 0.88737], [-0.975385, 0.111111, -0.190471],
      [-0.183251, -0.888889, 0.419876]]),
]


@pytest.mark.parametrize("bone, want", BLENDER_REST)
def test_rest_matrix_matches_blender(bone, want):
    head, tail, roll = bone
    m = rest_matrix(head, tail, roll)
    assert np.allclose(m[:3, :3], want, atol=2e-6)     # Blender stores float32
    assert np.allclose(m[:3, 3], head)


def test_cross_is_numpys_cross_to_the_last_bit():
    rng = np.random.default_rng(7)
    a, b = rng.normal(size=(73, 3)), rng.normal(size=(73, 3))
    np.testing.assert_array_equal(cross(a, b), np.cross(a, b))
    np.testing.assert_array_equal(cross(a, b[0]), np.cross(a, b[0]))        # broadcast
    np.testing.assert_array_equal(cross([0.0, 0.0, 1.0], a), np.cross([0.0, 0.0, 1.0], a))
    np.testing.assert_array_equal(cross([1.0, 0.0, 0.0], [0.0, 1.0, 0.0]), [0.0, 0.0, 1.0])
