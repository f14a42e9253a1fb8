"""Bone names, in one place (docs/ARCHITECTURE.md Section 7, rule 6).

Human bones carry Rigify's metarig names so animators know them; equipment bones are named after
the equipment.  ``root`` stays on the ground under the foot point (the object carries position
and heading); ``lean`` pivots about the line of the foot (the travel line, the rig's +Y axis).
"""
from __future__ import annotations

from ..core.registry import SPORTS

class MissingBoneError(KeyError, ValueError):
    """A bone a rig or a mapping needs is not there; the message names it.

    A ``KeyError`` (a failed lookup) that is also a ``ValueError``, so the Blender operators'
    ``except ValueError`` reports it instead of raising a traceback.
    """

    def __str__(self):
        return str(self.args[0]) if self.args else ""


ROOT = "root"
LEAN = "lean"

HIPS, SPINE, SPINE_2, CHEST, NECK, NECK_2, HEAD = (
    "spine", "spine.001", "spine.002", "spine.003", "spine.004", "spine.005", "spine.006")
SPINE_CHAIN = (HIPS, SPINE, SPINE_2, CHEST, NECK, NECK_2, HEAD)


def side(base: str, s: str) -> str:
    """``side("thigh", "L") -> "thigh.L"``."""
    if s not in ("L", "R"):
        raise ValueError(f"side = {s!r} is not 'L' or 'R'")
    return f"{base}.{s}"


def mirror(name: str) -> str:
    """``thigh.L <-> thigh.R``; names without a side are returned unchanged."""
    if name.endswith(".L"):
        return name[:-2] + ".R"
    if name.endswith(".R"):
        return name[:-2] + ".L"
    return name


SIDED_HUMAN = ("shoulder", "upper_arm", "forearm", "hand", "thigh", "shin", "foot", "toe")
HUMAN = SPINE_CHAIN + tuple(side(b, s) for b in SIDED_HUMAN for s in ("L", "R"))

SKI = ("ski.L", "ski.R")
POLE = ("pole.L", "pole.R")
BOARD = "board"
FRAME, FORK, WHEEL_F, WHEEL_R, CRANK = "frame", "fork", "wheel.F", "wheel.R", "crank"
PEDAL = ("pedal.L", "pedal.R")

#: Bones each sport's rig must have (checked when a mapping starts): the sport records'
#: ``bones``, a live view of the sport registry.
REQUIRED = SPORTS.view("bones")


def require(names, wanted, rig: str = "rig") -> None:
    """Raise :class:`MissingBoneError` naming the first bone of ``wanted`` not in ``names``."""
    have = set(names)
    for b in wanted:
        if b not in have:
            raise MissingBoneError(f"bone {b!r} is missing from {rig}")
