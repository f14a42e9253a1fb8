"""Bone maps as data: which bone of the user's rig plays each of our joints.

``rigs/bone_maps/<name>.json`` (numpy and stdlib only; loaded and validated here)::

    {
      "name": "mixamo", "label": "Mixamo (mixamorig:)", "description": "...",
      "joints": {"spine": "mixamorig:Hips", "thigh.L": "mixamorig:LeftUpLeg", ...},
      "controls": [{"bone": "torso", "joint": "spine", "parent": null}, ...],
      "rig_settings": [{"bone": "thigh_parent.L", "property": "pole_vector", "value": 1},
                       {"bone": "thigh_ik.L", "attribute": "ik_stretch", "value": 0.0}]
    }

Joints
    Our joints are the built-in figures' human bones (``bones.HUMAN``: Rigify's metarig names,
    ``spine`` is the pelvis, ``spine.003`` the chest, ``spine.006`` the head).  A map names the
    user's bone for each; ``REQUIRED_JOINTS`` must be there, the others are optional.
Controls (optional)
    For a rig animated through controls (Rigify), the bones the bake keys instead of the joints:
    each ``bone`` moves rigidly with ``joint`` from its rest pose, and its parent's frame moves
    rigidly with ``parent`` (a joint, or ``null``: the parent stays at rest).  The bake keys a
    control's rotation, and its location where the parent is ``null`` or ``"location": true``
    (an FK control whose parent chain does not carry it to its joint's place: Rigify's
    ``spine_fk.002`` hangs from the torso, the joint from the bent lower spine).  Without
    controls the bake keys the mapped joints themselves (FK).
Rig settings (optional)
    Pose-bone settings the figure needs on the rig, a custom ``property`` or an RNA
    ``attribute``: Rigify's ``pole_vector`` switch (so the knee and elbow poles the bake keys
    take effect) and ``ik_stretch`` = 0 on its IK chains (Blender's IK with stretch also
    shortens a chain within reach: measured, the knee bent up to 5.0 deg less than asked, 0.14
    deg without); set by Make Figure, restored by Remove Figure.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache

from .. import bones as B
from ..bones import MissingBoneError
from ..rig_spec import RIGS_DIR

__all__ = ["JOINTS", "REQUIRED_JOINTS", "JOINT_PARENT", "BONE_MAPS", "BoneMap", "Control",
           "parse_bone_map", "load_bone_map", "missing_joints", "require_joints", "auto_bone_map"]

BONE_MAPS_DIR = RIGS_DIR / "bone_maps"
#: The shipped maps, in the order AUTO tries them (the most specific names first).
BONE_MAPS = ("rigify", "mixamo", "builtin")

JOINTS = B.HUMAN
_SIDED_REQUIRED = ("upper_arm", "forearm", "hand", "thigh", "shin", "foot")
REQUIRED_JOINTS = (B.HIPS, B.CHEST, B.HEAD) + tuple(
    B.side(b, s) for b in _SIDED_REQUIRED for s in ("L", "R"))

#: Our joint tree (each joint's parent joint); optional joints are skipped over when absent.
JOINT_PARENT = {B.HIPS: None, B.SPINE: B.HIPS, B.SPINE_2: B.SPINE, B.CHEST: B.SPINE_2,
                B.NECK: B.CHEST, B.NECK_2: B.NECK, B.HEAD: B.NECK_2}
for _s in ("L", "R"):
    JOINT_PARENT.update({
        B.side("shoulder", _s): B.CHEST, B.side("upper_arm", _s): B.side("shoulder", _s),
        B.side("forearm", _s): B.side("upper_arm", _s), B.side("hand", _s): B.side("forearm", _s),
        B.side("thigh", _s): B.HIPS, B.side("shin", _s): B.side("thigh", _s),
        B.side("foot", _s): B.side("shin", _s), B.side("toe", _s): B.side("foot", _s)})


@dataclass(frozen=True)
class Control:
    bone: str
    """The rig's control bone the bake keys."""
    joint: str
    """The joint it moves rigidly with."""
    parent: str | None = None
    """The joint its parent frame moves rigidly with (``None``: the parent stays at rest)."""
    location: bool = False
    """Key its location too, under a parent (a root control's location is always keyed)."""


@dataclass(frozen=True)
class BoneMap:
    name: str
    label: str
    joints: dict
    """our joint -> the rig's bone (only the joints the rig has)."""
    controls: tuple = ()
    """:class:`Control` s keyed instead of the joints (empty: key the joints)."""
    rig_settings: tuple = ()
    """``(bone, 'property' | 'attribute', name, value)``: pose-bone settings the figure sets."""
    description: str = ""

    def bone(self, joint: str) -> str | None:
        return self.joints.get(joint)


def parse_bone_map(doc: dict, source: str = "bone map") -> BoneMap:
    """Validate a bone-map document (the parsed JSON) and build a :class:`BoneMap`."""
    if not isinstance(doc, dict):
        raise ValueError(f"{source}: not a JSON object")
    for key in ("name", "joints"):
        if key not in doc:
            raise ValueError(f"{source}: missing key {key!r}")
    joints = doc["joints"]
    if not isinstance(joints, dict):
        raise ValueError(f"{source}: 'joints' must map our joints to the rig's bones")
    for joint, bone in joints.items():
        if joint not in JOINTS:
            raise ValueError(f"{source}: joint {joint!r} is not one of ours "
                             f"({', '.join(JOINTS)})")
        if not isinstance(bone, str) or not bone:
            raise ValueError(f"{source}: joint {joint!r} maps to {bone!r}, not a bone name")
    used = {}
    for joint, bone in joints.items():
        if bone in used:
            raise ValueError(f"{source}: bone {bone!r} plays both {used[bone]!r} and {joint!r}")
        used[bone] = joint
    controls = []
    for k, c in enumerate(doc.get("controls", ())):
        where = f"{source}: control #{k}"
        if not isinstance(c, dict) or not isinstance(c.get("bone"), str):
            raise ValueError(f"{where} has no bone name")
        for key in ("joint", "parent"):
            j = c.get(key)
            if (key == "joint" or j is not None) and j not in joints:
                raise ValueError(f"{where} ({c['bone']!r}): {key} = {j!r} is not a mapped joint")
        if not isinstance(c.get("location", False), bool):
            raise ValueError(f"{where} ({c['bone']!r}): location = {c['location']!r} must be "
                             f"true or false")
        controls.append(Control(c["bone"], c["joint"], c.get("parent"),
                                c.get("location", False)))
    settings = []
    for k, s in enumerate(doc.get("rig_settings", ())):
        try:
            kind = "property" if "property" in s else "attribute"
            settings.append((str(s["bone"]), kind, str(s[kind]), float(s["value"])))
        except (KeyError, TypeError, ValueError):
            raise ValueError(f"{source}: rig setting #{k} needs bone, property (or attribute) "
                             f"and a number value") from None
    return BoneMap(str(doc["name"]), str(doc.get("label", doc["name"])), dict(joints),
                   tuple(controls), tuple(settings), str(doc.get("description", "")))


@lru_cache(maxsize=None)
def load_bone_map(name: str) -> BoneMap:
    """The shipped map ``rigs/bone_maps/<name>.json`` (one of ``BONE_MAPS``), validated."""
    if name not in BONE_MAPS:
        raise ValueError(f"bone_map = {name!r} is not one of {', '.join(BONE_MAPS)}")
    path = BONE_MAPS_DIR / f"{name}.json"
    with open(path) as fh:
        return parse_bone_map(json.load(fh), path.name)


def missing_joints(bone_map: BoneMap, bone_names) -> list:
    """``[(joint, bone or None), ...]``: required joints the map leaves out or whose bone the rig
    lacks, and the bones of its controls the rig lacks (``('control', bone)``)."""
    have = set(bone_names)
    out = [(j, bone_map.bone(j)) for j in REQUIRED_JOINTS
           if bone_map.bone(j) is None or bone_map.bone(j) not in have]
    out += [("control", c.bone) for c in bone_map.controls if c.bone not in have]
    return out


def _describe(missing) -> str:
    return ", ".join(f"{j} (no bone mapped)" if b is None else f"{j} -> {b!r}"
                     for j, b in missing)


def require_joints(bone_map: BoneMap, bone_names, rig: str = "the rig") -> None:
    """Raise :class:`MissingBoneError` listing everything of ``bone_map`` that ``rig`` lacks."""
    missing = missing_joints(bone_map, bone_names)
    if missing:
        raise MissingBoneError(f"{rig} lacks {len(missing)} bone(s) of the {bone_map.name!r} "
                               f"bone map: {_describe(missing)}")


def auto_bone_map(bone_names, rig: str = "the rig") -> BoneMap:
    """The first shipped map (``BONE_MAPS`` order) whose bones ``rig`` all has; else raise
    :class:`MissingBoneError` with what the nearest map misses."""
    names = set(bone_names)
    best = None
    for name in BONE_MAPS:
        bm = load_bone_map(name)
        missing = missing_joints(bm, names)
        if not missing:
            return bm
        if best is None or len(missing) < len(best[1]):
            best = (bm, missing)
    bm, missing = best
    raise MissingBoneError(f"{rig} matches none of the bone maps ({', '.join(BONE_MAPS)}); the "
                           f"nearest, {bm.name!r}, lacks {len(missing)}: {_describe(missing)}")
