"""The user's own armature as a figure: read its rest pose for the mapping layer's
retargeting, build the sport's equipment tied to it, and keep what it was before.

Reads ``bone.matrix_local``, parents and ``use_local_location`` into a
:class:`~..mapping.retarget.user_rig.UserRig`; everything numerical happens in the mapping layer.
"""
from __future__ import annotations

import json
import math
from dataclasses import replace
from typing import NamedTuple

import bpy
import numpy as np
from mathutils import Matrix, Quaternion

from ...mapping import MAPPINGS, map_trajectory
from ...mapping.retarget.bone_map import (JOINTS, BoneMap, auto_bone_map, load_bone_map,
                                          parse_bone_map,
                                 require_joints)
from ...mapping.retarget.equipment import equipment_rest
from ...mapping.retarget.retarget import retarget
from ...mapping.rig_spec import load_rig
from ...mapping.retarget.stance import STANCES, goofy_track, mirrored_trajectory
from ...mapping.retarget.user_rig import UserRig, fit_rig
from .. import compat
from .rig_builder import material, primitive

#: Panel / operator choice -> shipped map name.
NAMED = {"RIGIFY": "rigify", "MIXAMO": "mixamo", "BUILTIN": "builtin"}


def rig_settings(obj):
    return obj.turning.rig


def is_figure(obj) -> bool:
    """Whether ``obj`` is a figure, read without leaving settings behind on an armature that
    is not one (see ``compat.ADDON_PROPS_IN_ID_PROPERTIES``)."""
    if obj is None or obj.type != "ARMATURE":
        return False
    if compat.ADDON_PROPS_IN_ID_PROPERTIES and "turning" not in obj.keys():
        return False
    return bool(obj.turning.is_figure)


def is_user_rig(obj) -> bool:
    """``True`` for a figure made from the user's armature by Make Figure."""
    return is_figure(obj) and bool(obj.turning.rig.is_user_rig)


#: Object constraints that set the object's location or rotation over its keys: the bake writes
#: keys the constraint then overrides (the figure would not move, or not as baked).
OVERRIDING_CONSTRAINTS = {"COPY_LOCATION", "COPY_ROTATION", "COPY_TRANSFORMS", "CHILD_OF",
                          "TRANSFORM", "FOLLOW_PATH", "CLAMP_TO", "TRACK_TO", "DAMPED_TRACK",
                          "LOCKED_TRACK", "PIVOT", "SHRINKWRAP", "FLOOR", "LIMIT_LOCATION",
                          "LIMIT_ROTATION", "LIMIT_DISTANCE", "ARMATURE", "ACTION",
                          "OBJECT_SOLVER", "FOLLOW_TRACK", "CAMERA_SOLVER"}


def check_transform(obj) -> None:
    """The object's transform must be a turn about Z and a uniform scale (the bake keys its
    location and its rotation about Z, and the ground is the armature's XY plane); the rig
    must be editable (not linked from a library) and free of object constraints that override
    the keys the bake writes."""
    for what, block in (("armature", obj), ("armature data", obj.data)):
        lib = getattr(block, "library", None)
        if lib is not None:
            raise ValueError(f"{what} {block.name!r} is linked from the library "
                             f"{lib.filepath!r}: the bake cannot key it; make it local "
                             "(Object > Relations > Make Local) or a library override first")
    for c in obj.constraints:
        if c.type in OVERRIDING_CONSTRAINTS and not c.mute and c.influence > 0.0:
            raise ValueError(f"armature {obj.name!r} has the constraint {c.name!r} ({c.type}), "
                             "which overrides the location and rotation keys the bake writes "
                             "(the figure would not move as baked): remove or mute it first")
    rx, ry = obj.rotation_euler[0], obj.rotation_euler[1]
    if obj.rotation_mode != "XYZ" or abs(rx) > 1e-6 or abs(ry) > 1e-6:
        m = obj.matrix_world.to_3x3().normalized()
        if abs(m[2][2] - 1.0) > 1e-6:
            deg = tuple(round(math.degrees(a), 2) for a in obj.matrix_world.to_euler())
            raise ValueError(f"armature {obj.name!r} is tilted (rotation {deg} deg); apply its "
                             f"rotation first (Object > Apply > Rotation)")
    sx, sy, sz = obj.scale
    if not (sx > 0 and abs(sx - sy) <= 1e-6 * sx and abs(sx - sz) <= 1e-6 * sx):
        scale = tuple(round(v, 6) for v in obj.scale)
        raise ValueError(f"armature {obj.name!r} has scale {scale}; a figure needs one positive "
                         f"scale on all axes (apply the scale)")
    if obj.parent is not None:
        raise ValueError(f"armature {obj.name!r} is parented to {obj.parent.name!r}; a figure "
                         f"moves on its own")


def user_rig(obj) -> UserRig:
    """``obj``'s armature at rest (read at every bake and every Live Preview step: the matrices
    in one ``foreach_get``, Blender's column-major floats turned row-major)."""
    bones = obj.data.bones
    n = len(bones)
    rest = np.empty(16 * n, np.float32)
    bones.foreach_get("matrix_local", rest)
    local = np.empty(n, bool)
    bones.foreach_get("use_local_location", local)
    parents = [b.parent for b in bones]
    return UserRig(tuple(bones.keys()), tuple(p.name if p else None for p in parents),
                   rest.reshape(n, 4, 4).transpose(0, 2, 1).astype(float),
                   tuple(bool(v) for v in local), float(obj.scale[0]), obj.name)


def resolve_bone_map(obj, choice: str) -> BoneMap:
    """The bone map ``choice`` ('AUTO', 'RIGIFY', 'MIXAMO', 'BUILTIN' or 'CUSTOM') for ``obj``,
    checked against its bones (raises naming everything missing)."""
    names = obj.data.bones.keys()
    where = f"armature {obj.name!r}"
    if choice == "AUTO":
        return auto_bone_map(names, where)
    if choice == "CUSTOM":
        rows = rig_settings(obj).custom_map
        bm = parse_bone_map({"name": "custom", "label": "Custom",
                             "joints": {r.name: r.bone for r in rows if r.bone}}, "custom map")
    elif choice in NAMED:
        bm = load_bone_map(NAMED[choice])
    else:
        raise ValueError(f"bone_map = {choice!r} is not one of AUTO, {', '.join(NAMED)}, CUSTOM")
    require_joints(bm, names, where)
    return bm


def figure_bone_map(obj) -> BoneMap:
    return resolve_bone_map(obj, rig_settings(obj).bone_map)


def fill_custom_map(obj, bm: BoneMap) -> None:
    """Start the custom list from ``bm`` (every joint, mapped or empty)."""
    rows = rig_settings(obj).custom_map
    rows.clear()
    for joint in JOINTS:
        row = rows.add()
        row.name = joint
        row.bone = bm.bone(joint) or ""


def mirrored(obj) -> bool:
    """A goofy snowboarder (built-in or the user's rig): the mirror image of the built-in's
    regular stance."""
    return (is_figure(obj) and obj.turning.sport.lower() in STANCES
            and obj.turning.rig.stance == "GOOFY")


def facing(obj) -> float:
    """The figure's direction of travel in its armature's axes, rad CCW from +X: measured for a
    user's rig, +Y (pi/2) for the built-in figures."""
    fitted = fitted_rig(obj)
    return math.pi / 2 if fitted is None else fitted.fit.travel


class FittedRig(NamedTuple):
    """What a bake reads of a user's rig: its armature at rest, its bone map, how it sits
    against the built-in figure and its arms' reach over the built-in's (:func:`arm_ratio`)."""

    rig: UserRig
    bone_map: BoneMap
    fit: object
    reach: float


def fitted_rig(obj) -> FittedRig | None:
    """``obj``'s :class:`FittedRig` when it is a user's rig, else ``None``."""
    if not is_user_rig(obj):
        return None
    sport, rig, bm = obj.turning.sport.lower(), user_rig(obj), figure_bone_map(obj)
    fit = fit_rig(rig, bm, sport, mirrored(obj))
    return FittedRig(rig, bm, fit, arm_ratio(rig, bm, sport, fit))


def figure_track(obj, traj, frames, options=None, normal=None, surface=None, rows=None,
                 fitted="read"):
    """The pose track of ``obj`` for ``traj`` (one sample per frame of ``frames``) when it is a
    user's rig or rides goofy: the built-in figure's Section 7 mapping (of the mirrored run for
    a goofy stance), retargeted onto the user's rig, or mirrored onto the built-in rig itself.
    ``normal`` ((n, 3)): the surface normal at the foot on a Ground mesh; the figure then stands
    in the local surface as the built-in figures do (:mod:`..mapping.surface`); ``surface``: the
    ground's height, where the built-in's poles are planted.  ``rows`` ``(a, b)``: only frames
    ``a:b`` of it (the rest mapped as their context); a part of a run (``traj.meta``
    ``"path_start"``: the foot point's path length at its first frame) turns the wheels on.
    ``fitted``: :func:`fitted_rig` of ``obj`` when already read."""
    sport, mirror = obj.turning.sport.lower(), mirrored(obj)
    fitted = fitted_rig(obj) if isinstance(fitted, str) else fitted
    if fitted is not None:
        options = plants_for(sport, options, fitted.fit.k, fitted.reach)
    track = map_trajectory(sport, mirrored_trajectory(traj) if mirror else traj, options,
                           frame_start=frames.start, normal=normal, surface=surface)
    if fitted is None:
        return goofy_track(sport, track if rows is None else track.rows(*rows))
    return retarget(track, sport, fitted.rig, fitted.bone_map, fitted.fit, mirror=mirror,
                    rows=rows, distance=float(traj.meta.get("path_start", 0.0)))


def plants_for(sport: str, options, k: float, reach: float = 1.0):
    """The sport's mapping options with the pole plants planned for a figure ``k`` times the
    built-in's size whose arms are ``reach`` times as long again (the retargeted rig), so its
    holes stay put and its hands can follow them; unchanged without poles."""
    opts = MAPPINGS[sport].Options() if options is None else options
    if not hasattr(opts, "plant_scale"):
        return options
    return replace(opts, plant_scale=k, plant_reach=reach)


def arm_ratio(rig: UserRig, bm: BoneMap, sport: str, fit) -> float:
    """The user's arm (shoulder to wrist, world metres) over ``k`` times the built-in's."""
    from ...mapping.retarget.stance import builtin_skeleton
    skel = builtin_skeleton(sport)
    joints = [bm.bone(j) for j in ("upper_arm.L", "forearm.L", "hand.L")]
    if any(b is None or b not in rig.names for b in joints):
        return 1.0
    h = [rig.head(b) for b in joints]
    user = fit.scale * float(np.linalg.norm(h[1] - h[0]) + np.linalg.norm(h[2] - h[1]))
    return user / (fit.k * (skel.length("upper_arm.L") + skel.length("forearm.L")))


# -- the rig as it was -------------------------------------------------------------------------

_OBJ = ("location", "rotation_mode", "rotation_euler", "rotation_quaternion",
        "rotation_axis_angle", "scale")


def _get(owner, attrs):
    return {a: (getattr(owner, a) if isinstance(getattr(owner, a), str)
                else list(getattr(owner, a))) for a in attrs}


def _set(owner, values):
    for a in ("rotation_mode",) + tuple(a for a in values if a != "rotation_mode"):
        if a in values:
            setattr(owner, a, values[a])


def keyed_bones(bm: BoneMap):
    return [c.bone for c in bm.controls] if bm.controls else [bm.bone(j) for j in bm.joints]


def save_state(obj, bm: BoneMap) -> None:
    """Remember the object transform, the channels of every bone the bake keys and the rig
    settings the map changes (JSON on the figure; :func:`restore_state` puts them back)."""
    props = []
    for bone, kind, prop, _ in bm.rig_settings:
        pb = obj.pose.bones.get(bone)
        if pb is None:
            continue
        if kind == "property":
            props.append([bone, kind, prop, prop in pb.keys(), pb.get(prop)])
        else:
            props.append([bone, kind, prop, True, getattr(pb, prop)])
    state = {"object": _get(obj, _OBJ),
             "bones": {b: _get(obj.pose.bones[b], _OBJ) for b in keyed_bones(bm)},
             "props": props,
             "state_props": [p for p in obj.keys() if p.startswith("turn_")]}
    rig_settings(obj).saved_state = json.dumps(state)


def restore_state(obj, pose_only: bool = False) -> None:
    """Put back what :func:`save_state` kept (with ``pose_only``: transforms and channels)."""
    raw = rig_settings(obj).saved_state
    if not raw:
        return
    state = json.loads(raw)
    _set(obj, state["object"])
    for name, values in state["bones"].items():
        pb = obj.pose.bones.get(name)
        if pb is not None:
            _set(pb, values)
    if pose_only:
        return
    for bone, kind, prop, had, old in state["props"]:
        pb = obj.pose.bones.get(bone)
        if pb is None:
            continue
        if kind == "attribute":
            setattr(pb, prop, old)
        elif had:
            pb[prop] = old
        elif prop in pb.keys():
            del pb[prop]
    obj.update_tag()


def reset_user_rig(obj) -> None:
    """Clear Bake on a user's rig: its channels as they were before it became a figure, the
    object at its Start, facing the Start direction (as a built-in figure is put back)."""
    restore_state(obj, pose_only=True)
    s = obj.turning
    obj.location = s.start
    if obj.rotation_mode == "XYZ":
        obj.rotation_euler[2] = s.start_heading - facing(obj)


def apply_rig_settings(obj, bm: BoneMap) -> None:
    for bone, kind, prop, value in bm.rig_settings:
        pb = obj.pose.bones.get(bone)
        if pb is None:
            continue
        if kind == "attribute":
            setattr(pb, prop, type(getattr(pb, prop))(value))
        else:
            old = pb.get(prop)
            pb[prop] = type(old)(value) if isinstance(old, (int, float)) else value
    obj.update_tag()          # the rig's drivers read these properties: evaluate them again


# -- equipment ---------------------------------------------------------------------------------

def _piece_mesh(spec, piece, name):
    verts, faces, kinds, mat_idx, start = [], [], [], [], 0
    for part in spec.meshes_of(piece.name):
        v, f = primitive(part.shape, part.size)
        m = np.array(Matrix.Translation(part.offset)
                     @ Quaternion(part.rotation).to_matrix().to_4x4())
        verts.append(piece.size * (v @ m[:3, :3].T + m[:3, 3]))
        faces += [tuple(i + start for i in face) for face in f]
        if part.material not in kinds:
            kinds.append(part.material)
        mat_idx += [kinds.index(part.material)] * len(f)
        start += len(v)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(np.vstack(verts).tolist(), [], faces)
    for kind in kinds:
        mesh.materials.append(material(kind))
    mesh.polygons.foreach_set("material_index", np.array(mat_idx, np.int32))
    mesh.update()
    return mesh


def build_equipment(context, obj, bm: BoneMap):
    """The sport's equipment as objects of their own collection, each tied to its bone by a
    Child Of constraint (placed at the rig's rest as on the built-in figure, sized to the
    character); a piece that faces another gets a Damped Track (the crank), one that rolls a
    hub empty tied to the bone and a driver on the distance travelled (the wheels).  Returns
    the collection."""
    sport = obj.turning.sport.lower()
    rig = user_rig(obj)
    spec = load_rig(sport)
    coll = bpy.data.collections.new(f"{obj.name} Equipment")
    parent = obj.users_collection[0] if obj.users_collection else context.scene.collection
    parent.children.link(coll)
    pieces = equipment_rest(sport, rig, bm, mirror=mirrored(obj))
    made = {}
    for piece in pieces:
        name = f"{obj.name} {piece.name}"
        eq = bpy.data.objects.new(name, _piece_mesh(spec, piece, name))
        coll.objects.link(eq)
        tied = eq
        if piece.spin:            # a wheel rolls about its axle on a hub tied to the rig
            tied = bpy.data.objects.new(name + " hub", None)
            coll.objects.link(tied)
            eq.parent = tied
            _drive_spin(eq, obj, piece.spin)
        rest = obj.data.bones[piece.bone].matrix_local
        tied.matrix_basis = rest.inverted() @ Matrix(piece.rest.tolist())
        if piece.slide:           # along the fork, in the bone's frame (armature units)
            prop, axis = piece.slide
            _drive_slide(tied, obj, prop, np.array(rest.to_3x3()).T @ axis / obj.scale[0])
        con = tied.constraints.new("CHILD_OF")
        con.name = "Turning: follows " + piece.bone
        con.target, con.subtarget = obj, piece.bone
        con.inverse_matrix = Matrix.Identity(4)
        eq["turning_equipment"] = piece.name
        made[piece.name] = eq
    for piece in pieces:          # the crank turns to face its pedal about its axle
        if piece.track:
            con = made[piece.name].constraints.new("DAMPED_TRACK")
            con.name = "Turning: faces " + piece.track
            con.target, con.track_axis = made[piece.track], "TRACK_" + piece.track_axis
    rig_settings(obj).equipment = coll
    return coll


def _drive(eq, path, index, obj, prop, factor: float) -> None:
    """``eq.<path>[index] = factor * obj[prop]`` (a simple expression: no Python)."""
    if prop not in obj.keys():
        obj[prop] = 0.0
    fc = eq.driver_add(path, index)
    drv = fc.driver
    drv.type = "SCRIPTED"
    var = drv.variables.new()
    var.name, var.type = "d", "SINGLE_PROP"
    var.targets[0].id = obj
    var.targets[0].data_path = f'["{prop}"]'
    drv.expression = f"{float(factor)!r} * d"


def _drive_spin(eq, obj, spin: float) -> None:
    """``eq.rotation_euler.y = spin * obj["turn_distance"]``: the wheel rolls."""
    _drive(eq, "rotation_euler", 1, obj, "turn_distance", spin)


def _drive_slide(eq, obj, prop: str, axis) -> None:
    """``eq.delta_location = axis * obj[prop]``: the piece slides along ``axis`` (its parent
    bone's frame, per unit of the property)."""
    for i in range(3):
        _drive(eq, "delta_location", i, obj, prop, axis[i])


def remove_equipment(obj) -> None:
    coll = rig_settings(obj).equipment
    if coll is None:
        return
    for eq in list(coll.objects):
        mesh = eq.data
        bpy.data.objects.remove(eq)
        if mesh is not None and mesh.users == 0:
            bpy.data.meshes.remove(mesh)
    bpy.data.collections.remove(coll)
    rig_settings(obj).equipment = None
