"""An export-ready bake: the equipment of a figure made from the user's rig keyed on every baked
frame, so glTF and FBX carry it with their default settings.

On a user's rig the skis, poles and bicycle are objects of their own that follow the rig through
Child Of and Damped Track constraints and drivers (:func:`.retarget_adapter.build_equipment`).
The exporters write an object's keyed transform, not what its constraints and drivers make of
it, so without keys the equipment stays where it stood while the rider rides on.  After the
armature is baked, :func:`bake_equipment` works out every equipment object's transform on each
baked frame, writes whole F-curves of it (``foreach_set``, one action per object, owned by it as
the figure's action is by the figure), and turns the constraints and drivers off, so the keys
alone move the equipment, the same at every frame as before.

The transforms come in closed form where they can (:func:`closed_form`): a piece tied to a bone
by the add-on's Child Of alone sits at ``O(f) P(f) I B``, Child Of's own product (Blender's
``childof_evaluate``: the target bone's world matrix, the constraint's inverse matrix ``I``, the
object's basis ``B``), with ``O(f)`` the armature object's keyed transform and ``P(f)`` the
bone's pose, which the retarget solved (:attr:`.PoseTrack.joints`).  Blender evaluates the
scene on three frames to check each piece: a tweak, an NLA strip or a constraint of the user's
may move the rig otherwise, and a rig's own mechanism may not put the bone where the retarget
solved it (Rigify's feet land within 7e-5 m, its hands 2-13 cm off: its spine does not bend as
the retarget's joints do, measured).  Any other piece (a wheel on its hub, a driven or tracked
piece), a rig that moves otherwise and a failed check step the scene through every frame and
read what Blender evaluates (:func:`_sample`), the one place the add-on does.
:func:`clear_equipment` undoes all of it (Clear Bake, a re-bake, a Live Preview re-bake, Remove
Figure).

A built-in figure needs none of this: its equipment is part of its skinned mesh and moves with
the bones the bake keys.
"""
from __future__ import annotations

import dataclasses

import bpy
import numpy as np
from mathutils import Euler, Matrix, Vector

from .. import compat
from . import bake
from ..scene.retarget_adapter import is_user_rig, rig_settings

#: ID property on an equipment object keyed by :func:`bake_equipment`: its rotation mode and
#: transform (``matrix_basis``, row by row) before, given back by :func:`clear_equipment`.
KEYED = "turning_export_keys"


def equipment(fig) -> list:
    """The equipment objects of a user's rig (an empty list for a built-in figure)."""
    if not is_user_rig(fig) or rig_settings(fig).equipment is None:
        return []
    return list(rig_settings(fig).equipment.objects)


#: How far the closed form may lie from Blender's evaluation on the checked frames (m, and unit
#: rotation-matrix entries): measured 2e-6 through float32 keys on an FK rig, 6.8e-5 m where
#: Rigify's IK solver stops short of its target (``test_blender_equipment_keys.py``); a tenth of
#: a millimetre.
CHECK_M, CHECK_RAD = 1e-4, 1e-4
#: Object transforms and pose channels: an action or NLA strip keying one of them moves the rig
#: otherwise than the bake's keys do (the rig's drivers are its own machinery, which the retarget
#: solved through: Rigify drives its finger mechanisms' rotations).
_MOVES = ("location", "rotation_euler", "rotation_quaternion", "rotation_axis_angle", "scale",
          "delta_location", "delta_rotation_euler", "delta_rotation_quaternion", "delta_scale")


def _moves_rig(path: str) -> bool:
    return path in _MOVES or (path.startswith("pose.bones[") and path.rsplit(".", 1)[-1] in _MOVES)


def _moved_otherwise(fig) -> bool:
    """Whether anything but the bake's keys moves ``fig`` or its bones: a parent, an object
    constraint, a delta transform, or an active action or unmuted NLA strip other than the bake
    with a transform curve."""
    if fig.parent is not None or fig.rotation_mode != "XYZ":
        return True
    if any(c.enabled and c.influence > 0.0 for c in fig.constraints):
        return True
    if any(tuple(getattr(fig, d)) != _REST[d] for d in _DELTAS):
        return True
    adt = fig.animation_data
    if adt is None:
        return False
    baked = bake.figure_action(fig)
    actions = [adt.action] + [s.action for t in adt.nla_tracks if not t.mute for s in t.strips]
    curves = [fc for a in actions if a is not None and a != baked for fc in compat.all_fcurves(a)]
    return any(_moves_rig(fc.data_path) for fc in curves)


def _tie(obj, fig, joints):
    """The add-on's Child Of tying ``obj`` to a bone of ``fig`` whose pose ``joints`` holds, when
    that constraint alone places ``obj`` (no parent, no other constraint, action or driver); else
    ``None``."""
    adt = obj.animation_data
    if obj.parent is not None or (adt and (adt.action or len(adt.drivers)
                                           or any(not t.mute for t in adt.nla_tracks))):
        return None
    cons = [c for c in obj.constraints if c.enabled and c.influence > 0.0]
    if len(cons) != 1:
        return None
    c = cons[0]
    if (c.type != "CHILD_OF" or c.target != fig or c.subtarget not in joints
            or c.influence != 1.0 or c.owner_space != "WORLD" or c.target_space != "WORLD"
            or not all(getattr(c, f"use_{k}_{a}") for k in ("location", "rotation", "scale")
                       for a in "xyz")):
        return None
    return c


def _object_matrices(fig, track) -> np.ndarray:
    """(n, 4, 4) the armature object's transform the bake keys on each frame of ``track``."""
    scale = Vector(fig.scale)
    return np.array([Matrix.LocRotScale(Vector(loc), Euler(rot), scale)
                     for loc, rot in zip(track.location.tolist(), track.rotation.tolist())])


def closed_form(fig, objs, track):
    """``(mats, tied)``: ``(n_frames, n_objects, 4, 4)`` the transforms of ``objs`` on the frames
    of ``track`` from the poses the track carries (see the module doc), and which objects that
    holds for (``tied[j]``; ``mats[:, j]`` is undefined where it does not).  Nothing is
    evaluated."""
    mats = np.empty((len(track), len(objs), 4, 4))
    tied = np.zeros(len(objs), bool)
    if not track.joints or _moved_otherwise(fig):
        return mats, tied
    O = None
    for j, obj in enumerate(objs):
        con = _tie(obj, fig, track.joints)
        if con is None:
            continue
        O = _object_matrices(fig, track) if O is None else O
        rest = np.array(con.inverse_matrix) @ np.array(obj.matrix_basis)
        mats[:, j] = O @ track.joints[con.subtarget] @ rest
        tied[j] = True
    return mats, tied


def _agreeing(scene, objs, frames, mats) -> np.ndarray:
    """Per object of ``objs``: whether its closed-form ``mats`` are what Blender evaluates on the
    first, middle and last of ``frames``, within ``CHECK_M`` and ``CHECK_RAD``."""
    idx = sorted({0, len(frames) // 2, len(frames) - 1})
    got, want = _sample(scene, objs, frames[idx]), mats[idx]
    unit = lambda m: m[..., :3, :3] / np.linalg.norm(m[..., :3, :3], axis=-2, keepdims=True)  # noqa: E731
    return ((np.abs(got[..., :3, 3] - want[..., :3, 3]).max(axis=(0, 2)) <= CHECK_M)
            & (np.abs(unit(got) - unit(want)).max(axis=(0, 2, 3)) <= CHECK_RAD))


def _transforms(scene, fig, objs, frames, track) -> np.ndarray:
    """``_sample``'s transforms, from :func:`closed_form` for each object it holds for and
    Blender's evaluation agrees with on the checked frames, the others read frame by frame."""
    if track is None:
        return _sample(scene, objs, frames)
    mats, tied = closed_form(fig, objs, track)
    if tied.any():
        tied[tied] = _agreeing(scene, [o for o, t in zip(objs, tied) if t], frames,
                               mats[:, tied])
    if not tied.all():
        mats[:, ~tied] = _sample(scene, [o for o, t in zip(objs, tied) if not t], frames)
    return mats


def _sample(scene, objs, frames) -> np.ndarray:
    """``(n_frames, n_objects, 4, 4)`` transforms of ``objs`` relative to their parents (their
    ``matrix_basis`` once constraints are off), as evaluated on each of ``frames``."""
    out = np.empty((len(frames), len(objs), 4, 4))
    for i, f in enumerate(frames):
        scene.frame_set(int(f))
        for j, obj in enumerate(objs):
            world = obj.matrix_world
            if obj.parent is not None:
                world = (obj.parent.matrix_world @ obj.matrix_parent_inverse).inverted() @ world
            out[i, j] = np.array(world)
    return out


def _channels(mats, mode: str) -> dict:
    """``{data_path: (n, k) values}`` of ``(n, 4, 4)`` rigid-and-scale transforms, the rotation
    in the object's own ``mode``: Euler angles unwrapped from frame to frame (a wheel's spin
    keeps counting), quaternions kept on one side (q and -q are the same turn)."""
    loc = mats[:, :3, 3]
    scale = np.linalg.norm(mats[:, :3, :3], axis=1)                   # column lengths
    rot = [Matrix((m[:3, :3] / s[None, :]).tolist()) for m, s in zip(mats, scale)]
    if mode in ("QUATERNION", "AXIS_ANGLE"):
        quats = np.array([np.array(r.to_quaternion()) for r in rot])
        for i in range(1, len(quats)):
            if np.dot(quats[i], quats[i - 1]) < 0.0:
                quats[i] = -quats[i]
        return {"location": loc, "rotation_quaternion": quats, "scale": scale}
    eulers, prev = [], None
    for r in rot:
        prev = r.to_euler(mode) if prev is None else r.to_euler(mode, prev)
        eulers.append(tuple(prev))
    return {"location": loc, "rotation_euler": np.array(eulers), "scale": scale}


#: An object's transforms that are not its basis, held at rest while it is keyed.
_DELTAS = ("delta_location", "delta_rotation_euler", "delta_rotation_quaternion", "delta_scale")
_REST = {"delta_location": (0.0, 0.0, 0.0), "delta_rotation_euler": (0.0, 0.0, 0.0),
         "delta_rotation_quaternion": (1.0, 0.0, 0.0, 0.0), "delta_scale": (1.0, 1.0, 1.0)}


#: Custom property each bake's action keys on its own object only (``"turn_take <name>"``,
#: value 0): FBX exports, as a take of an object, every action all of whose F-curves resolve on
#: it, and figures of a sport share their bones (equipment objects share location, rotation,
#: scale).  On a figure it is one of the bake's state properties (Clear Bake removes those).
TAKE = "turn_take "


def with_take(fig, track):
    """``track`` with the figure's own take property (see ``TAKE``)."""
    props = {**track.props, TAKE + fig.name: np.zeros(len(track))}
    return dataclasses.replace(track, props=props)


def own_take(obj, bag, frames) -> None:
    """Key an equipment object's own take property in ``bag`` on ``frames``."""
    prop = TAKE + obj.name
    obj[prop] = 0.0
    path = f'["{bpy.utils.escape_identifier(prop)}"]'
    frames = np.asarray(frames, float)
    bake.write_channels(bag, [(path, 0, "Turning", np.zeros(len(frames)))], frames)


def drop_take(obj) -> None:
    for prop in [p for p in obj.keys() if p.startswith(TAKE)]:
        del obj[prop]


def bake_equipment(fig, frames, track=None) -> int:
    """Key a user rig's equipment on ``frames`` (the figure's baked frames, ascending), then
    turn its constraints and drivers off (and its delta transforms to rest).  ``track``: the
    pose track just baked on those frames, whose joint poses give the keys in closed form where
    they can (see the module doc); without it Blender evaluates every frame.  Returns the
    objects keyed.  The scene ends on the frame it was on."""
    clear_equipment(fig)                     # evaluate with the constraints on
    objs = equipment(fig)
    if not objs:
        return 0
    scene = bpy.context.scene
    current = scene.frame_current
    frames = np.asarray(frames, float)
    try:
        mats = _transforms(scene, fig, objs, frames, track)
    finally:
        scene.frame_set(current)
    for j, obj in enumerate(objs):
        before = {"mode": obj.rotation_mode,
                  "basis": [float(v) for row in obj.matrix_basis for v in row],
                  **{d: list(getattr(obj, d)) for d in _DELTAS}}
        keyed = compat.assign_new_action(obj, obj.name)
        keyed[bake.OWNER] = obj
        keyed[bake.MERGE_INTO] = bake.figure_action(fig).name    # one glTF animation
        obj[KEYED] = before
        _switch(obj, on=False)
        for d in _DELTAS:
            setattr(obj, d, _REST[d])
        values = _channels(mats[:, j], obj.rotation_mode)
        obj_bag = compat.channels(obj)
        bake.write_channels(obj_bag, [(path, i, "Object Transforms", v[:, i])
                                      for path, v in values.items() for i in range(v.shape[1])],
                            frames)
        own_take(obj, obj_bag, frames)
    scene.frame_set(current)
    return len(objs)


def _switch(obj, on: bool) -> None:
    """The add-on's constraints and drivers of an equipment object on or off."""
    for con in obj.constraints:
        if con.name.startswith("Turning:"):
            con.enabled = on
    adt = obj.animation_data
    for fc in (adt.drivers if adt else ()):
        fc.mute = not on


def clear_equipment(fig) -> None:
    """Remove the keys :func:`bake_equipment` wrote and turn the constraints and drivers back
    on: the equipment follows the rig again."""
    for obj in equipment(fig):
        if KEYED not in obj:
            continue
        adt = obj.animation_data
        action = adt.action if adt else None
        if action is not None and action.get(bake.OWNER) == obj:
            adt.action = None
            bpy.data.actions.remove(action)
        before = obj[KEYED]
        obj.rotation_mode = before["mode"]
        obj.matrix_basis = Matrix(np.reshape(before["basis"], (4, 4)).tolist())
        for d in _DELTAS:
            setattr(obj, d, before[d])
        del obj[KEYED]
        drop_take(obj)
        _switch(obj, on=True)


# -- root motion --------------------------------------------------------------------------------

#: The bone that carries the motion with Root Motion: the built-in figures' and Rigify's.
ROOT_BONE = "root"


def root_motion(fig, track, bone: str = ROOT_BONE):
    """``track`` with the armature object's motion moved onto its ``bone`` (for engines that
    take the character's travel from its root bone): the object keeps its transform of the first
    frame on every frame, and the bone's pose ``B'`` is chosen so that every bone stays where it
    was in the world: ``O_0 R B'(f) = O(f) R B(f)`` with ``O`` the object's transform, ``R`` the
    bone's rest matrix in the armature and ``B`` its own pose (identity when not animated); the
    joint poses the track carries become ``O_0^-1 O(f) P(f)``, where the bones now are in the
    armature."""
    from ...mapping.base import BoneChannels, PoseTrack
    from mathutils import Euler, Quaternion, Vector
    if bone not in fig.data.bones:
        raise bake.BakeError(f"{fig.name!r} has no bone {bone!r} to carry the root motion: "
                             "Root Motion needs the root bone of a Rigify rig or of a built-in "
                             "figure; turn it off for this rig")
    rest = fig.data.bones[bone].matrix_local
    rest_inv = rest.inverted()
    scale = Vector(fig.scale)
    n = len(track)
    own = track.bones.get(bone, BoneChannels())
    loc = np.zeros((n, 3)) if own.location is None else own.location
    rot = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)) if own.rotation is None else own.rotation
    first = Matrix.LocRotScale(Vector(track.location[0]), Euler(track.rotation[0]), scale)
    first_inv = first.inverted()
    out_loc, out_rot = np.empty((n, 3)), np.empty((n, 4))
    for i in range(n):
        obj = Matrix.LocRotScale(Vector(track.location[i]), Euler(track.rotation[i]), scale)
        basis = Matrix.LocRotScale(Vector(loc[i]), Quaternion(rot[i]), None)
        m = rest_inv @ first_inv @ obj @ rest @ basis
        out_loc[i] = m.to_translation()
        q = np.array(m.to_quaternion())
        out_rot[i] = -q if i and np.dot(q, out_rot[i - 1]) < 0.0 else q
    bones = dict(track.bones)
    bones[bone] = BoneChannels(out_loc, out_rot)
    moved = np.array(first_inv) @ _object_matrices(fig, track) if track.joints else None
    return PoseTrack(track.frames, np.tile(track.location[0], (n, 1)),
                     np.tile(track.rotation[0], (n, 1)), bones, dict(track.props),
                     {b: moved @ pose for b, pose in track.joints.items()})
