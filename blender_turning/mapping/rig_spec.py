"""The figures as data: ``rigs/<name>.json``, loaded and validated into frozen dataclasses.

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

from ..core.ranges import RANGES, Range
from ..core.registry import SPORTS
from ..core.validate import FieldError, Fields, check, read_text
from .bones import REQUIRED, MissingBoneError

__all__ = ["BoneSpec", "MeshSpec", "RigSpec", "RIGS_DIR", "RIG_NAMES", "MATERIALS", "SHAPES",
           "load_rig", "parse_rig"]

# The repository's and the Blender extension's top-level rigs/, or blender_turning/rigs in a pip
# install (pyproject.toml maps one onto the other).
_PACKAGE, _TOP = Path(__file__).resolve().parents[1], Path(__file__).resolve().parents[2]
RIGS_DIR = _PACKAGE / "rigs" if (_PACKAGE / "rigs").is_dir() else _TOP / "rigs"
#: The rigs there are: one per registered sport (its record's ``rig_file``, by default
#: ``RIGS_DIR/<sport>.json``), a live view of the sport registry.
RIG_NAMES = SPORTS.view("rig_file")
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


_BONE_KEYS = {"name", "head", "tail", "roll", "parent", "connected", "deform"}
_MESH_KEYS = {"name", "bone", "shape", "size", "offset", "rotation", "material"}
_RIG_RANGES = {                       # rig data, armature space (see the module docstring)
    "point": RANGES["coordinate"],
    "roll": Range(-2 * math.pi, 2 * math.pi, "rad", "an edit bone's roll"),
    "size": Range(1e-4, 10.0, "m", "a primitive's extent"),
    "rotation": Range(-10.0, 10.0, "", "a quaternion component (then checked to be unit)"),
}


def _vec(f: Fields, key, n: int, kind: str, default=None) -> tuple:
    """``f[key]``: a list of ``n`` numbers, each in ``_RIG_RANGES[kind]``."""
    v = f.value(key, default)
    if not isinstance(v, (list, tuple)) or len(v) != n:
        f.fail(key, f"= {v!r} is not a list of {n} numbers")
    sub = Fields(list(v), f.source, f.name(key))
    return tuple(check(sub.name(i), x, _RIG_RANGES[kind], f.source) for i, x in enumerate(v))


def parse_rig(doc: dict, source: str = "rig") -> RigSpec:
    """Validate a rig document (the parsed JSON) and build a :class:`RigSpec`.  Errors name the
    source and the field (``skier.json: bones[3].head[0] = 'x' is not a number ...``)."""
    if not isinstance(doc, dict):
        raise FieldError(f"{source}: a rig must be a JSON object, not {type(doc).__name__}")
    top = Fields(doc, source).only({"name", "sport", "bones", "meshes"})
    rig_name = top.string("name")
    sport = top.string("sport", choices=tuple(REQUIRED))
    top.value("meshes")
    bones, seen = [], {}
    for b in top.tables("bones", _BONE_KEYS):
        name = b.string("name")
        if not name:
            b.fail("name", "is empty")
        if name in seen:
            b.fail("name", f"= {name!r}: bone {name!r} appears twice")
        head, tail = _vec(b, "head", 3, "point"), _vec(b, "tail", 3, "point")
        if np.linalg.norm(np.subtract(tail, head)) < 1e-4:
            b.fail("tail", f"= {list(tail)}: head and tail of bone {name!r} coincide "
                           "(length < 0.1 mm)")
        parent = b.string("parent", None)
        if parent is not None and parent not in seen:
            b.fail("parent", f"= {parent!r} is not a bone defined before {name!r}")
        connected = b.boolean("connected", False)
        if connected:
            if parent is None:
                b.fail("connected", f"is true but bone {name!r} has no parent")
            gap = np.linalg.norm(np.subtract(head, seen[parent].tail))
            if gap > 1e-6:
                b.fail("connected", f"is true but the head of {name!r} is {gap:.3g} m from "
                                    f"the tail of {parent!r}")
        roll = b.number("roll", _RIG_RANGES["roll"], 0.0)
        bone = BoneSpec(name, head, tail, roll, parent, connected, b.boolean("deform", True))
        seen[name] = bone
        bones.append(bone)
    missing = [n for n in REQUIRED[sport] if n not in seen]
    if missing:
        raise MissingBoneError(f"{source}: bone {missing[0]!r} is missing (a {sport} rig needs it)")
    meshes = []
    for m in top.tables("meshes", _MESH_KEYS):
        bone = m.string("bone", choices=None)
        if bone not in seen:
            m.fail("bone", f"= {bone!r} is not a bone of the rig")
        shape = m.string("shape", choices=tuple(SHAPES))
        size = _vec(m, "size", SHAPES[shape], "size")
        rot = _vec(m, "rotation", 4, "rotation", (1.0, 0.0, 0.0, 0.0))
        if abs(np.linalg.norm(rot) - 1.0) > 1e-3:
            m.fail("rotation", f"= {list(rot)} is not a unit quaternion")
        meshes.append(MeshSpec(m.string("name", bone), bone, shape, size,
                               _vec(m, "offset", 3, "point", (0.0, 0.0, 0.0)), rot,
                               m.string("material", "suit", choices=MATERIALS)))
    return RigSpec(rig_name, sport, tuple(bones), tuple(meshes))


def load_rig(name: str) -> RigSpec:
    """The rig of the sport ``name`` (one of ``RIG_NAMES``: ``rigs/<name>.json`` or its record's
    ``rig_file``), validated."""
    if name not in RIG_NAMES:
        raise ValueError(f"rig = {name!r} is not one of {', '.join(RIG_NAMES)}")
    return _load_rig_file(str(SPORTS[name].rig_path(RIGS_DIR)))


@lru_cache(maxsize=None)
def _load_rig_file(file: str) -> RigSpec:
    path = Path(file)
    try:
        doc = json.loads(read_text(path, "rig file"))
    except (json.JSONDecodeError, RecursionError) as exc:
        raise FieldError(f"rig file {str(path)!r} is not valid JSON ({exc})") from None
    return parse_rig(doc, str(path.name))
