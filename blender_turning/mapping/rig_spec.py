"""The four figures as data: ``rigs/<name>.json``, loaded and validated into frozen dataclasses.

File format (JSON; armature space, metres; the figure faces +Y with Z up and stands with its feet
on z = 0 around the origin, the foot point of the physical model)::

    {
      "name": "skier", "sport": "skier",
      "bones": [
        {"name": "root", "head": [x, y, z], "tail": [x, y, z], "roll": 0.0,
         "parent": null, "connected": false, "deform": false},
        ...
      ],
      "meshes": [
        {"name": "thigh.L", "bone": "thigh.L", "shape": "capsule", "size": [0.07, 0.46],
         "offset": [0, 0.22, 0], "rotation": [1, 0, 0, 0], "material": "suit"},
        ...
      ]
    }

Bones
    ``head``/``tail``/``roll`` are edit-bone values: the rest frame is Blender's (Y from head to
    tail, X and Z from the roll by ``vec_roll_to_mat3``).  ``roll`` is in radians.  A bone's
    parent comes before it; a ``connected`` bone's head equals its parent's tail.  ``deform``
    bones carry body meshes; helpers (``root``, ``lean``) do not.
Meshes
    Primitives skinned rigidly to one bone (vertex group weight 1).  ``offset`` is the primitive's
    centre and ``rotation`` (w, x, y, z; optional, identity by default) its orientation, both in
    the bone's rest frame measured from the head.  ``size`` by ``shape``:

    * ``box``: ``[sx, sy, sz]``, full extents along the (rotated) X, Y, Z axes;
    * ``cylinder``: ``[radius, length]``, axis along the (rotated) Y;
    * ``capsule``: ``[radius, length]``, axis along Y, ``length`` end to end including the caps.

    ``material`` is one of ``MATERIALS``.
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from .bones import REQUIRED, MissingBoneError

__all__ = ["BoneSpec", "MeshSpec", "RigSpec", "RIGS_DIR", "RIG_NAMES", "MATERIALS", "SHAPES",
           "load_rig", "parse_rig"]

# The repository's and the Blender extension's top-level rigs/, or blender_turning/rigs in a pip
# install (pyproject.toml maps one onto the other).
_PACKAGE, _TOP = Path(__file__).resolve().parents[1], Path(__file__).resolve().parents[2]
RIGS_DIR = _PACKAGE / "rigs" if (_PACKAGE / "rigs").is_dir() else _TOP / "rigs"
RIG_NAMES = ("skier", "snowboarder", "telemark", "cyclist")
MATERIALS = ("skin", "suit", "equipment", "metal", "rubber")
SHAPES = {"box": 3, "cylinder": 2, "capsule": 2}


@dataclass(frozen=True)
class BoneSpec:
    name: str
    head: tuple
    """(3,) rest head, m, armature space."""
    tail: tuple
    """(3,) rest tail, m, armature space."""
    roll: float = 0.0
    """Edit-bone roll, rad."""
    parent: str | None = None
    connected: bool = False
    deform: bool = True

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.subtract(self.tail, self.head)))


@dataclass(frozen=True)
class MeshSpec:
    name: str
    bone: str
    shape: str
    size: tuple
    """Extents, m (see the module docstring)."""
    offset: tuple = (0.0, 0.0, 0.0)
    """(3,) centre in the bone's rest frame from its head, m."""
    rotation: tuple = (1.0, 0.0, 0.0, 0.0)
    """(w, x, y, z) orientation in the bone's rest frame."""
    material: str = "suit"


@dataclass(frozen=True)
class RigSpec:
    name: str
    sport: str
    bones: tuple
    meshes: tuple

    def bone(self, name: str) -> BoneSpec:
        for b in self.bones:
            if b.name == name:
                return b
        raise MissingBoneError(f"bone {name!r} is not in rig {self.name!r}")

    @property
    def bone_names(self) -> tuple:
        return tuple(b.name for b in self.bones)

    def meshes_of(self, bone: str) -> tuple:
        return tuple(m for m in self.meshes if m.bone == bone)


def _vec(where: str, value, n: int) -> tuple:
    try:
        v = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        raise ValueError(f"{where} = {value!r} is not a list of {n} numbers") from None
    if len(v) != n or not all(math.isfinite(x) for x in v):
        raise ValueError(f"{where} = {value!r} is not a list of {n} finite numbers")
    return v


def parse_rig(doc: dict, source: str = "rig") -> RigSpec:
    """Validate a rig document (the parsed JSON) and build a :class:`RigSpec`."""
    for key in ("name", "sport", "bones", "meshes"):
        if key not in doc:
            raise ValueError(f"{source}: missing key {key!r}")
    sport = doc["sport"]
    if sport not in REQUIRED:
        raise ValueError(f"{source}: sport = {sport!r} is not one of {', '.join(REQUIRED)}")
    bones, seen = [], {}
    for k, b in enumerate(doc["bones"]):
        name = b.get("name")
        if not isinstance(name, str) or not name:
            raise ValueError(f"{source}: bone #{k} has no name")
        if name in seen:
            raise ValueError(f"{source}: bone {name!r} appears twice")
        where = f"{source}: bone {name!r}"
        head = _vec(f"{where} head", b.get("head"), 3)
        tail = _vec(f"{where} tail", b.get("tail"), 3)
        if np.linalg.norm(np.subtract(tail, head)) < 1e-4:
            raise ValueError(f"{where}: head and tail coincide (length < 0.1 mm)")
        parent = b.get("parent")
        if parent is not None and parent not in seen:
            raise ValueError(f"{where}: parent {parent!r} is not a bone defined before it")
        connected = bool(b.get("connected", False))
        if connected:
            if parent is None:
                raise ValueError(f"{where}: connected but has no parent")
            gap = np.linalg.norm(np.subtract(head, seen[parent].tail))
            if gap > 1e-6:
                raise ValueError(f"{where}: connected but its head is {gap:.3g} m from the "
                                 f"tail of {parent!r}")
        bone = BoneSpec(name, head, tail, float(b.get("roll", 0.0)), parent, connected,
                        bool(b.get("deform", True)))
        seen[name] = bone
        bones.append(bone)
    missing = [n for n in REQUIRED[sport] if n not in seen]
    if missing:
        raise MissingBoneError(f"{source}: bone {missing[0]!r} is missing (a {sport} rig needs it)")
    meshes = []
    for k, m in enumerate(doc["meshes"]):
        where = f"{source}: mesh {m.get('name', '#' + str(k))!r}"
        if m.get("bone") not in seen:
            raise ValueError(f"{where}: bone {m.get('bone')!r} is not in the rig")
        shape = m.get("shape")
        if shape not in SHAPES:
            raise ValueError(f"{where}: shape = {shape!r} is not one of {', '.join(SHAPES)}")
        size = _vec(f"{where} size", m.get("size"), SHAPES[shape])
        if min(size) <= 0:
            raise ValueError(f"{where}: size = {list(size)} must be positive")
        rot = _vec(f"{where} rotation", m.get("rotation", (1, 0, 0, 0)), 4)
        if abs(np.linalg.norm(rot) - 1.0) > 1e-3:
            raise ValueError(f"{where}: rotation = {list(rot)} is not a unit quaternion")
        material = m.get("material", "suit")
        if material not in MATERIALS:
            raise ValueError(f"{where}: material = {material!r} is not one of "
                             f"{', '.join(MATERIALS)}")
        meshes.append(MeshSpec(str(m.get("name", m["bone"])), m["bone"], shape, size,
                               _vec(f"{where} offset", m.get("offset", (0, 0, 0)), 3),
                               rot, material))
    return RigSpec(str(doc["name"]), sport, tuple(bones), tuple(meshes))


@lru_cache(maxsize=None)
def load_rig(name: str) -> RigSpec:
    """The rig ``rigs/<name>.json`` (one of ``RIG_NAMES``), validated."""
    if name not in RIG_NAMES:
        raise ValueError(f"rig = {name!r} is not one of {', '.join(RIG_NAMES)}")
    path = RIGS_DIR / f"{name}.json"
    with open(path) as fh:
        return parse_rig(json.load(fh), str(path.name))
