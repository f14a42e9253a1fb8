"""The armature standing on the ground (docs/TERRAIN.md Section 1): where its origin is and how
it is turned, per frame.  numpy only.

The object's origin is the foot point ``(x, y, z)`` (``z`` the trajectory's ground height).  On
flat ground the object only turns about +Z by ``theta_dir - 90 deg`` (the rig faces +Y).  On
terrain it also tilts with the surface: its +Z is the surface normal ``n`` at the foot and its +Y
the heading lifted into the surface, the core's track tangent
``t = (cos d, sin d, p) / sqrt(1 + p^2)`` with ``t . n = 0``
(:func:`..core.ground.terrain.surface_frame`).
Everything the sport mappings pose in the armature's own space then lies in the local surface:
the skis, the board and the wheels sit on the armature's XY plane, and the body's lean
``theta_v``, which the mappings apply about the armature's +Y, is the model's lean from the
surface normal (docs/TERRAIN.md Section 2), so relative to gravity the body leans by the plumb
lean plus ``theta_v``.  In the pitch plane the body stands square to the surface, as a skier
stands square to the skis (the roll model does not include pitch).
"""
from __future__ import annotations

import math

import numpy as np

from .kinematics import norm
from .sports.common import rot_z

__all__ = ["Placement", "surface_axes", "euler_xyz"]


def surface_axes(theta_dir, normal) -> np.ndarray:
    """(n, 3, 3) rotations whose columns are the armature's axes in world space: X right, Y the
    heading lifted into the surface, Z the unit surface ``normal`` ((n, 3), upward)."""
    d = np.asarray(theta_dir, float)
    nrm = np.asarray(normal, float)
    nrm = nrm / norm(nrm, keepdims=True)
    if np.any(nrm[:, 2] <= 0.0):
        raise ValueError("the surface normal must point up (n_z > 0) on every frame")
    c, s = np.cos(d), np.sin(d)
    p = -(c * nrm[:, 0] + s * nrm[:, 1]) / nrm[:, 2]     # the slope along the heading: t . n = 0
    t = np.stack([c, s, p], 1) / np.sqrt(1.0 + p * p)[:, None]
    x = np.cross(t, nrm)
    return np.stack([x, t, nrm], 2)


def euler_xyz(R, yaw_near) -> np.ndarray:
    """Blender's Euler XYZ ``(a, b, c)`` of rotations ``R = Rz(c) Ry(b) Rx(a)`` ((n, 3, 3)), with
    ``c`` taken within pi of ``yaw_near`` (so a figure turning round and round keeps turning
    instead of jumping by 2 pi in its F-curve)."""
    a = np.arctan2(R[:, 2, 1], R[:, 2, 2])
    b = -np.arcsin(np.clip(R[:, 2, 0], -1.0, 1.0))
    c = np.arctan2(R[:, 1, 0], R[:, 0, 0])
    c = c + 2 * math.pi * np.round((np.asarray(yaw_near, float) - c) / (2 * math.pi))
    return np.stack([a, b, c], 1)


class Placement:
    """Armature space <-> world for every frame of ``traj``; ``normal`` ((n, 3), or ``None`` for
    flat ground) the surface normal at the foot; ``surface``: the ground's height under world
    points, ``surface(x, y) -> z`` (arrays; ``None``: the plane through the foot, normal to
    ``normal``), where what touches the snow away from the foot (a pole's tip) goes."""

    def __init__(self, traj, normal=None, surface=None):
        n = len(traj)
        self.surface = surface
        z = np.asarray(getattr(traj, "z", np.zeros(n)), float)
        self.origin = np.stack([traj.x, traj.y, z], 1)
        yaw = np.asarray(traj.theta_dir, float) - math.pi / 2
        if normal is None:
            self.R = rot_z(yaw)
            self.euler = np.stack([np.zeros(n), np.zeros(n), yaw], 1)
        else:
            if np.shape(normal) != (n, 3):
                raise ValueError(f"normal must have shape ({n}, 3), not {np.shape(normal)}")
            self.R = surface_axes(traj.theta_dir, normal)
            self.euler = euler_xyz(self.R, yaw)

    def to_world(self, p, i):
        return self.origin[i] + self.R[i] @ p

    def to_world_many(self, p, idx):
        """Armature-space points ``p`` (k, 3) of frames ``idx`` to world."""
        return self.origin[idx] + np.einsum("nij,nj->ni", self.R[idx], p)

    def to_local(self, p_world, idx):
        return np.einsum("nji,nj->ni", self.R[idx], p_world - self.origin[idx])
