"""Building blocks shared by the sport mappings (Section 7): leaning, springs, IK limbs, gluing a
bone to equipment, and putting equipment on the ground.

All functions work on a :class:`~.kinematics.PoseBuilder` over ``n`` frames at once; points and
rotations are in armature space (the rig's frame: travel along +Y, Z up, foot point at the
origin).  The object transform (position and heading) is applied by Blender on top.
"""
from __future__ import annotations

import math

import numpy as np

from .. import bones as B
from ..kinematics import (PoseBuilder, cross, dot, frame_from_yx, norm, quat_from_axis_angle,
                          quat_mul, quat_to_matrix, rigid_inverse, stack_dot, two_bone_ik)

__all__ = ["rot_y", "rot_z", "rotate_about", "smoothstep", "phase_window", "static_force",
           "add_local_rotation", "lean", "carried", "limb_frames", "ik_limb", "place_on_ground",
           "body_axes", "mesh_points", "leg_lengths", "height_on_ground"]


def _about(angle, axis: int) -> np.ndarray:
    """(..., 3, 3) rotations by ``angle`` about the coordinate axis ``axis`` (right-handed)."""
    a = np.asarray(angle, float)
    m = np.zeros(a.shape + (3, 3))
    i, j = (axis + 1) % 3, (axis + 2) % 3
    c, s = np.cos(a), np.sin(a)
    m[..., axis, axis] = 1.0
    m[..., i, i], m[..., i, j], m[..., j, i], m[..., j, j] = c, -s, s, c
    return m


def rot_y(angle) -> np.ndarray:
    """(n, 3, 3) rotations about +Y (the travel line)."""
    return _about(angle, 1)


def rot_z(angle) -> np.ndarray:
    """(n, 3, 3) rotations about +Z (yaw, counter-clockwise seen from above)."""
    return _about(angle, 2)


def rotate_about(v, axis, angle):
    """Rodrigues: rotate vectors ``v`` (n, 3) about unit ``axis`` (n, 3) by ``angle`` (n,)."""
    k = axis / norm(axis, keepdims=True)
    a = np.asarray(angle, float)[..., None]
    return (v * np.cos(a) + cross(k, v) * np.sin(a)
            + k * dot(k, v, keepdims=True) * (1.0 - np.cos(a)))


def smoothstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def phase_window(phi, centre, hold, ramp):
    """1 within ``hold`` of the phase ``centre`` (rad, wrapped), 0 beyond ``hold + ramp``."""
    d = np.abs((np.asarray(phi) - centre + math.pi) % (2.0 * math.pi) - math.pi)
    return 1.0 - smoothstep((d - hold) / ramp)


def static_force(traj) -> float:
    """``m g``, the leg force of an upright figure at rest (from the trajectory's body)."""
    m, g = traj.meta.get("body.m"), traj.meta.get("body.g")
    if m is not None and g is not None:
        return float(m) * float(g)
    return float(np.median(traj.F_leg))


def body_axes(skel):
    """The figure's (right, forward, up) in armature space: right is the hips bone's rest X."""
    right = skel.rest_of(B.HIPS)[:3, 0].copy()
    right[2] = 0.0
    right /= np.linalg.norm(right)
    up = np.array([0.0, 0.0, 1.0])
    return right, cross(up, right), up


def add_local_rotation(b: PoseBuilder, bone: str, axis_rest, angle):
    """Compose a rotation by ``angle`` about the armature-space rest direction ``axis_rest`` (as
    carried by the parent's pose) after the bone's current local rotation."""
    axis_local = b.skel.rest_of(bone)[:3, :3].T @ np.asarray(axis_rest, float)
    q = quat_from_axis_angle(np.broadcast_to(axis_local, (b.n, 3)), angle)
    cur = b.rot.get(bone)
    b.set_local(bone, rotation=q if cur is None else quat_mul(q, cur))


def lean(b: PoseBuilder, theta_v):
    """Lean the body about the line of the foot (the rig's Y axis at z = 0).

    ``theta_v > 0`` leans left of travel (docs/ARCHITECTURE.md Section 4), i.e. a rotation by
    ``-theta_v`` about +Y.
    """
    add_local_rotation(b, B.LEAN, (0.0, 1.0, 0.0), -np.asarray(theta_v, float))


def carried(b: PoseBuilder, bone: str, carrier: str) -> np.ndarray:
    """The pose ``bone`` would have if rigidly attached to ``carrier`` as in the rest pose."""
    return stack_dot(b.pose(carrier), b.skel.rest_in(bone, carrier))


def leg_lengths(skel, upper: str, lower: str):
    """Rest lengths (m) of a two-bone chain ``upper -> lower`` (head to head, head to the
    connected child's head)."""
    return (float(np.linalg.norm(skel.rest_of(lower)[:3, 3] - skel.rest_of(upper)[:3, 3])),
            _length(skel, lower))


def _length(skel, bone):
    """Rest distance from ``bone``'s head to its connected child's head (its tail), m."""
    for i, p in enumerate(skel.parents):
        if p == bone and skel.connected[i]:
            return float(np.linalg.norm(skel.rest[i][:3, 3] - skel.rest_of(bone)[:3, 3]))
    raise ValueError(f"bone {bone!r} has no connected child to measure its length")


def limb_frames(root, hinge_x, target, pole, l1, l2, twist=None, reach=0.9999):
    """Two-bone IK (analytic) without touching a pose: the armature-space rotations (n, 3, 3) of
    the upper and lower bones whose chain from ``root`` (n, 3) reaches ``target``, bending
    towards ``pole`` rotated by ``twist`` (n,) rad about the root-target line, with the hinge
    (each bone's X) on the side of ``hinge_x`` (the upper bone's unposed X).  The lengths
    ``l1``, ``l2`` (m) are numbers or (n, 1) per frame.  Returns ``(upper_rot, lower_rot,
    end)``, ``end`` the point reached."""
    pole = np.asarray(pole, float)
    if pole.shape != root.shape:
        pole = np.broadcast_to(pole, root.shape)
    if twist is not None:
        pole = rotate_about(pole, target - root, twist)
    mid, end = two_bone_ik(root, target, l1, l2, pole, reach)
    n = cross(end - root, pole)
    n /= norm(n, keepdims=True)
    n[dot(n, hinge_x) < 0] *= -1.0
    return frame_from_yx(mid - root, n), frame_from_yx(end - mid, n), end


def ik_limb(b: PoseBuilder, upper: str, lower: str, target, pole, twist=None, reach=0.9999):
    """Two-bone IK (analytic): pose ``upper`` and ``lower`` so that ``lower``'s tail reaches
    ``target`` (n, 3), bending towards ``pole`` (n, 3) rotated by ``twist`` (n,) rad about the
    root-target line.  The hinge is each bone's X axis (the rigs' limbs hinge about X).
    Returns the point reached (n, 3)."""
    base = b.unposed(upper)
    r_up, r_low, end = limb_frames(base[:, :3, 3], base[:, :3, 0], target, pole,
                                   *leg_lengths(b.skel, upper, lower), twist, reach)
    b.set_pose(upper, r_up)
    b.set_pose(lower, r_low)
    return end


#: (id(spec), bone, shapes) -> (spec, corner points): :func:`mesh_points` once per rig (the spec
#: is kept, so its id is not reused while the entry stands).
_CORNERS = {}


def mesh_points(spec, bone: str, shapes=("box",)):
    """Corner points (k, 3) of ``bone``'s box meshes, in the bone's rest frame (from its head);
    computed once per rig and shared, read-only."""
    hit = _CORNERS.get((id(spec), bone, shapes))
    if hit is not None and hit[0] is spec:
        return hit[1]
    pts = []
    for m in spec.meshes_of(bone):
        if m.shape not in shapes:
            continue
        half = np.asarray(m.size) / 2.0
        signs = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)], float)
        pts.append(np.asarray(m.offset) + (signs * half) @ quat_to_matrix(m.rotation).T)
    if not pts:
        raise ValueError(f"bone {bone!r} has no box mesh to put on the ground")
    pts = np.concatenate(pts)
    pts.setflags(write=False)
    if len(_CORNERS) >= 256:                           # specs made on the fly (tests, rigs)
        _CORNERS.clear()
    _CORNERS[(id(spec), bone, shapes)] = (spec, pts)
    return pts


def place_on_ground(b: PoseBuilder, spec, bone: str, rotation, anchor_rest, anchor_xy):
    """Pose equipment ``bone`` with armature-space ``rotation`` (n, 3, 3) so that its lowest box
    corner touches z = 0 and the rest point ``anchor_rest`` lands at ``anchor_xy`` (n, 2)."""
    anchor, lowest = _grounded(b, spec, bone, rotation, anchor_rest)
    head = np.empty((b.n, 3))
    head[:, :2] = anchor_xy - stack_dot(rotation, anchor)[:, :2]
    head[:, 2] = -lowest
    b.set_pose(bone, rotation, head)
    return head


def height_on_ground(b: PoseBuilder, spec, bone: str, rotation, anchor_rest) -> np.ndarray:
    """The height (n,) of the rest point ``anchor_rest`` of equipment ``bone`` that
    :func:`place_on_ground` puts on the ground with ``rotation`` (n, 3, 3), m."""
    anchor, lowest = _grounded(b, spec, bone, rotation, anchor_rest)
    return stack_dot(rotation, anchor)[:, 2] - lowest


def _grounded(b, spec, bone, rotation, anchor_rest):
    """``(anchor in the bone's frame (3,), the lowest box corner's height (n,) from the head)``
    of ``bone`` rotated by ``rotation``."""
    rest = b.skel.rest_of(bone)
    corners = mesh_points(spec, bone)                           # bone frame
    anchor = rest[:3, :3].T @ (np.asarray(anchor_rest, float) - rest[:3, 3])
    return anchor, (rotation[:, 2, :] @ corners.T).min(axis=1)   # the corners' heights (n, k)


def tyre_radius(spec, bone: str = B.WHEEL_R) -> float:
    """The largest cylinder radius on the wheel ``bone`` of the rig ``spec`` (its tyre), m."""
    radii = [m.size[0] for m in spec.meshes_of(bone) if m.shape == "cylinder"]
    if not radii:
        raise ValueError(f"bone {bone!r} has no cylinder mesh (the tyre)")
    return float(max(radii))
