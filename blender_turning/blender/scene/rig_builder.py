"""Build a figure from its rig spec (``rigs/<sport>.json``): an armature and one skinned mesh.

The spec (agreed with the mapping layer)::

    {"name": "skier", "sport": "skier",
     "bones": [{"name", "head": [x, y, z], "tail": [x, y, z], "roll", "parent", "connected",
                "deform"}, ...],              # armature space, m; the figure faces +Y, Z up
     "meshes": [{"name", "bone", "shape": "capsule" | "box" | "cylinder", "size": [...],
                 "offset": [x, y, z], "rotation": [w, x, y, z], "material": ...}, ...]}

Mesh parts are placed in the rest frame of their bone (origin at the head, +Y along the bone),
centred at ``offset`` and turned by the optional ``rotation``.  Sizes, in m: a capsule
``[radius, length]`` and a cylinder ``[radius, length]`` lie along the local Y axis (``length`` is
the whole length, caps included); a box is ``[x, y, z]`` full extents.  All parts become one mesh
object parented to the armature, with one vertex group per bone (weight 1) and an Armature
modifier, so the figure deforms rigidly per bone.  The only mode switch is the one edit-mode
visit that creates the bones.
"""
from __future__ import annotations

import dataclasses
import math

import bpy
import numpy as np
from mathutils import Matrix, Quaternion, Vector

from ...mapping.rig_spec import load_rig
from .. import compat

RIG_TAG = "turning_rig"

#: Material kind -> (RGBA viewport colour, roughness, metallic).
MATERIALS = {
    "skin": ((0.80, 0.58, 0.45, 1.0), 0.6, 0.0),
    "suit": ((0.10, 0.30, 0.75, 1.0), 0.5, 0.0),
    "equipment": ((0.85, 0.12, 0.10, 1.0), 0.4, 0.0),
    "metal": ((0.70, 0.70, 0.72, 1.0), 0.3, 1.0),
    "rubber": ((0.05, 0.05, 0.05, 1.0), 0.9, 0.0),
}
_SEGMENTS = 12


class RigSpecError(ValueError):
    """A rig spec that cannot be built (names the bone or mesh part)."""


def load_spec(sport: str) -> dict:
    """The shipped spec of ``sport`` (``rigs/``), validated by the mapping layer's loader, as a
    dict."""
    return as_dict(load_rig(sport.lower()))


def as_dict(spec) -> dict:
    """Accept the JSON dict or the mapping layer's ``RigSpec`` dataclass."""
    if isinstance(spec, dict):
        return spec
    if dataclasses.is_dataclass(spec):
        return dataclasses.asdict(spec)
    raise RigSpecError(f"cannot read a rig spec from {type(spec).__name__}")


# -- primitive meshes (numpy; local part frame) -----------------------------------------------

def _ring(radius, y, n=_SEGMENTS):
    a = np.arange(n) * (2 * math.pi / n)
    return np.column_stack([radius * np.cos(a), np.full(n, y), radius * np.sin(a)])


def _tube(rings, close_ends):
    """Vertices and faces of stacked rings (each ``_SEGMENTS`` long), optionally capped."""
    n = _SEGMENTS
    verts = np.vstack(rings)
    faces = []
    for r in range(len(rings) - 1):
        a, b = r * n, (r + 1) * n
        faces += [(a + i, a + (i + 1) % n, b + (i + 1) % n, b + i) for i in range(n)]
    if close_ends:
        last = (len(rings) - 1) * n
        faces.append(tuple(range(n - 1, -1, -1)))
        faces.append(tuple(range(last, last + n)))
    return verts, faces


def primitive(shape: str, size) -> tuple[np.ndarray, list]:
    """``(verts (k, 3), faces)`` of a primitive centred at the origin (see the module doc)."""
    size = [float(s) for s in size]
    if shape == "box":
        if len(size) != 3:
            raise RigSpecError(f"a box needs size [x, y, z], not {size}")
        h = np.array(size) / 2
        v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * h
        faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
        return v, faces
    if shape not in ("capsule", "cylinder") or len(size) != 2:
        raise RigSpecError(f"shape {shape!r} with size {size}: expected capsule or cylinder "
                           "[radius, length], or box [x, y, z]")
    r, length = size
    if shape == "cylinder":
        return _tube([_ring(r, -length / 2), _ring(r, length / 2)], True)
    half = max(length / 2 - r, 0.0)
    rings = []
    for k in range(3, -1, -1):                      # bottom cap, equator last
        a = k * math.pi / 8
        rings.append(_ring(r * math.cos(a), -half - r * math.sin(a)))
    for k in range(4):
        a = k * math.pi / 8
        rings.append(_ring(r * math.cos(a), half + r * math.sin(a)))
    return _tube(rings, True)


# -- materials -----------------------------------------------------------------------------------

def material(kind: str):
    """The shared material of ``kind`` (made once per file)."""
    if kind not in MATERIALS:
        raise RigSpecError(f"material {kind!r} is not one of {', '.join(MATERIALS)}")
    name = f"Turning {kind.title()}"
    mat = bpy.data.materials.get(name)
    if mat is None:
        rgba, rough, metal = MATERIALS[kind]
        mat = bpy.data.materials.new(name)
        mat.diffuse_color = rgba                   # Workbench / viewport colour
        mat.roughness, mat.metallic = rough, metal
        compat.set_base_color(mat, rgba, rough, metal)
    return mat


# -- building ------------------------------------------------------------------------------------

def _check(spec: dict) -> None:
    names = [b["name"] for b in spec.get("bones", ())]
    if not names:
        raise RigSpecError(f"rig {spec.get('name')!r} has no bones")
    if len(set(names)) != len(names):
        raise RigSpecError(f"rig {spec.get('name')!r} names a bone twice")
    for b in spec["bones"]:
        if b.get("parent") and b["parent"] not in names:
            raise RigSpecError(f"bone {b['name']!r}: parent {b['parent']!r} is not in the rig")
        if np.allclose(b["head"], b["tail"]):
            raise RigSpecError(f"bone {b['name']!r} has zero length")
    for m in spec.get("meshes", ()):
        if m["bone"] not in names:
            raise RigSpecError(f"mesh part {m.get('name')!r}: bone {m['bone']!r} is not in the rig")


def build_armature(context, spec: dict, name: str, collection=None):
    """The armature object ``name`` with the spec's bones (one edit-mode visit)."""
    arm = bpy.data.armatures.new(name)
    obj = bpy.data.objects.new(name, arm)
    (collection or context.scene.collection).objects.link(obj)
    view_layer = context.view_layer
    prev_active = view_layer.objects.active
    view_layer.objects.active = obj
    with compat.temp_override(context, active_object=obj, object=obj, edit_object=obj):
        bpy.ops.object.mode_set(mode="EDIT")
        try:
            ebs = arm.edit_bones
            for b in spec["bones"]:
                eb = ebs.new(b["name"])
                eb.head, eb.tail = Vector(b["head"]), Vector(b["tail"])
                eb.roll = float(b.get("roll", 0.0))
                eb.use_deform = bool(b.get("deform", True))
            for b in spec["bones"]:
                if b.get("parent"):
                    ebs[b["name"]].parent = ebs[b["parent"]]
                    ebs[b["name"]].use_connect = bool(b.get("connected", False))
        finally:
            bpy.ops.object.mode_set(mode="OBJECT")
    view_layer.objects.active = prev_active
    for pb in obj.pose.bones:
        pb.rotation_mode = "QUATERNION"
    return obj


def build_mesh(spec: dict, arm_obj, name: str, collection=None):
    """One mesh object holding every part, skinned to ``arm_obj`` (vertex group per bone)."""
    verts, faces, mat_idx, groups = [], [], [], {}
    kinds = []
    start = 0
    for part in spec.get("meshes", ()):
        v, f = primitive(part["shape"], part["size"])
        local = Matrix.Translation(Vector(part.get("offset", (0, 0, 0))))
        if part.get("rotation") is not None:
            local = local @ Quaternion(part["rotation"]).to_matrix().to_4x4()
        m = np.array(arm_obj.data.bones[part["bone"]].matrix_local @ local)
        verts.append(v @ m[:3, :3].T + m[:3, 3])
        faces += [tuple(i + start for i in face) for face in f]
        kind = part.get("material", "suit")
        if kind not in kinds:
            kinds.append(kind)
        mat_idx += [kinds.index(kind)] * len(f)
        groups.setdefault(part["bone"], []).extend(range(start, start + len(v)))
        start += len(v)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(np.vstack(verts).tolist() if verts else [], [], faces)
    for kind in kinds:
        mesh.materials.append(material(kind))
    if faces:
        mesh.polygons.foreach_set("material_index", np.array(mat_idx, np.int32))
        mesh.polygons.foreach_set("use_smooth", np.ones(len(faces), bool))
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    (collection or bpy.context.scene.collection).objects.link(obj)
    obj.parent = arm_obj
    for bone, idx in groups.items():
        obj.vertex_groups.new(name=bone).add(idx, 1.0, "REPLACE")
    mod = obj.modifiers.new("Armature", "ARMATURE")
    mod.object = arm_obj
    return obj


def build_figure(context, spec, name: str | None = None, location=(0.0, 0.0, 0.0),
                 collection=None):
    """Build the figure of ``spec`` at ``location``; return the armature object."""
    spec = as_dict(spec)
    _check(spec)
    name = name or spec["name"].title()
    arm_obj = build_armature(context, spec, name, collection)
    arm_obj.location = location
    arm_obj[RIG_TAG] = spec.get("sport", spec["name"])
    try:
        build_mesh(spec, arm_obj, f"{arm_obj.name} Body", collection)
    except BaseException:
        remove_figure(arm_obj)          # nothing half-built stays behind
        raise
    return arm_obj


def remove_figure(obj) -> None:
    """Delete a figure's armature, its mesh children and their data (for undoing a failed add)."""
    for child in list(obj.children):
        data = child.data
        bpy.data.objects.remove(child)
        if data is not None and data.users == 0:
            bpy.data.meshes.remove(data)
    arm = obj.data
    bpy.data.objects.remove(obj)
    if arm.users == 0:
        bpy.data.armatures.remove(arm)
