"""The user's armature at rest (read by the Blender side) and how it is measured against the
built-in figure: its facing, its size and where it stands.  numpy only."""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .bone_map import BoneMap, require_joints
from ..sports.common import rot_z
from .stance import builtin_skeleton

__all__ = ["UserRig", "RigFit", "fit_rig"]


@dataclass(frozen=True)
class UserRig:
    """The user's armature at rest, as Blender has it (armature space, the armature's units)."""

    names: tuple
    parents: tuple
    """Parent bone name (or ``None``) of each bone."""
    rest: np.ndarray
    """(k, 4, 4) ``bone.matrix_local``."""
    local_location: tuple = None
    """``bone.use_local_location`` of each bone (default all ``True``)."""
    scale: float = 1.0
    """The armature object's uniform scale (world metres per armature unit)."""
    name: str = "rig"

    def __post_init__(self):
        k = len(self.names)
        rest = np.asarray(self.rest, float)
        if rest.shape != (k, 4, 4) or len(self.parents) != k:
            raise ValueError(f"rig {self.name!r}: {k} names, {len(self.parents)} parents and "
                             f"rest matrices of shape {rest.shape} do not agree")
        if not np.all(np.isfinite(rest)):
            raise ValueError(f"rig {self.name!r}: a rest matrix is not finite")
        if not (math.isfinite(self.scale) and self.scale > 0):
            raise ValueError(f"rig {self.name!r}: scale = {self.scale!r} must be positive")
        object.__setattr__(self, "rest", rest)
        if self.local_location is None:
            object.__setattr__(self, "local_location", (True,) * k)
        object.__setattr__(self, "_index", {n: i for i, n in enumerate(self.names)})
        object.__setattr__(self, "_at_rest", {})     # the retarget's constants (retarget.py)

    def i(self, name: str) -> int:
        from ..bones import MissingBoneError
        try:
            return self._index[name]
        except KeyError:
            raise MissingBoneError(f"bone {name!r} is not in rig {self.name!r}") from None

    def rest_of(self, name: str) -> np.ndarray:
        return self.rest[self.i(name)]

    def head(self, name: str) -> np.ndarray:
        return self.rest[self.i(name)][:3, 3]


@dataclass(frozen=True)
class RigFit:
    """How the built-in rig's armature space sits in the user's (see the module doc)."""

    facing: float
    """Direction the user's rig faces in its armature space, rad, counter-clockwise from +X."""
    builtin_facing: float
    """Direction the built-in rig faces in its armature space (+Y = pi/2; the snowboarder
    stands side-on, facing +X = 0), rad."""
    k: float
    """Size of the user's figure over the built-in's (leg length ratio, world metres)."""
    origin: np.ndarray
    """(3,) the user's armature point that goes onto the foot point (ankle midpoint, z = 0)."""
    scale: float
    """World metres per user armature unit."""

    @cached_property
    def C(self) -> np.ndarray:
        """(3, 3) the built-in's axes -> the user's (turns the built-in's facing onto the
        user's)."""
        C = rot_z(self.facing - self.builtin_facing)
        C.setflags(write=False)
        return C

    @property
    def travel(self) -> float:
        """The direction of travel in the user's armature space (where the built-in's +Y goes),
        rad CCW from +X: the object turns it onto the heading."""
        return math.pi / 2 + self.facing - self.builtin_facing

    def point(self, p) -> np.ndarray:
        """Built-in armature-space points (..., 3) -> the user's armature space."""
        return self.origin + (self.k / self.scale) * np.asarray(p, float) @ self.C.T


def _leg_length(head):
    return sum(float(np.linalg.norm(head(b) - head(a)))
               for a, b in (("thigh.L", "shin.L"), ("shin.L", "foot.L")))


def fit_rig(rig: UserRig, bm: BoneMap, sport: str = "skier", mirror: bool = False) -> RigFit:
    """Measure the user's rig against the built-in figure of ``sport`` (facing, size, origin);
    ``mirror``: against its mirror image (a goofy snowboarder)."""
    require_joints(bm, rig.names, f"armature {rig.name!r}")
    head = lambda j: rig.head(bm.bone(j))            # noqa: E731
    fwd = _forward(head("thigh.L") - head("thigh.R"))
    if fwd is None:
        raise ValueError(f"armature {rig.name!r}: the hip joints coincide in plan (thigh.L -> "
                         f"{bm.bone('thigh.L')!r}, thigh.R -> {bm.bone('thigh.R')!r}); cannot "
                         f"tell which way it faces")
    toes = sum(rig.rest_of(bm.bone(f"foot.{s}"))[:3, 1] for s in ("L", "R"))
    if np.dot(toes[:2], fwd[:2]) < 0:
        raise ValueError(f"armature {rig.name!r}: its feet point backwards from the way its "
                         f"left and right hips say it faces (are .L and .R swapped?)")
    skel = builtin_skeleton(sport, mirror)
    b_head = lambda j: skel.rest_of(j)[:3, 3]        # noqa: E731
    b_fwd = _forward(b_head("thigh.L") - b_head("thigh.R"))
    k = rig.scale * _leg_length(head) / _leg_length(b_head)
    ankles = 0.5 * (head("foot.L") + head("foot.R"))
    return RigFit(float(math.atan2(fwd[1], fwd[0])), float(math.atan2(b_fwd[1], b_fwd[0])),
                  float(k), np.array([ankles[0], ankles[1], 0.0]), float(rig.scale))


def _forward(left):
    """The facing (unit, horizontal) of a body whose right-to-left hip vector is ``left``:
    ``left x up``; ``None`` if the hips coincide in plan."""
    left = np.array([left[0], left[1], 0.0])
    if np.linalg.norm(left) < 1e-9:
        return None
    fwd = np.cross(left, [0.0, 0.0, 1.0])
    return fwd / np.linalg.norm(fwd)
