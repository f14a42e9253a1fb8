"""An export-ready bake: the equipment of a figure made from the user's rig keyed on the baked
range, so glTF and FBX carry it with their default settings.

On a user's rig the skis, poles and bicycle are objects of their own that follow the rig through
Child Of and Damped Track constraints and drivers (:func:`.retarget_adapter.build_equipment`).
Both exporters sample each object's evaluated transform frame by frame (``matrix_world``, so
what its constraints and drivers make of it), but only of objects they see as animated:

- glTF samples an object with an action; one without stays where it stands.
- FBX, by default (*NLA Strips* and *All Actions* on), writes one take per unmuted NLA strip of
  the exported objects, sampling every exported object with that strip playing and every active
  action removed, then one take per action that fits an object.  The figure's bake plays from
  its NLA strip (docs/layers.md), so the bake's take is the first in the file (the one an
  importer plays) and carries whatever follows the rig live; equipment moved by keys of its own
  would stand still in it.

So :func:`bake_equipment` leaves the constraints and drivers on and gives each piece an action
holding the transform it already has (its rest under the constraints, on the first and last
baked frames): glTF then samples it, FBX's bake take samples it as it follows the rig, and in
Blender nothing moves differently.  Nothing steps the scene.  :func:`clear_equipment` removes
those actions (Clear Bake, a re-bake, a Live Preview re-bake, Remove Figure).

A built-in figure needs none of this: its equipment is part of its skinned mesh and moves with
the bones the bake keys.
"""
from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix

from .. import compat
from . import bake
from ..scene.retarget_adapter import is_user_rig, rig_settings

#: ID property on an equipment object keyed by :func:`bake_equipment`: its transform
#: (``matrix_basis``, row by row) before, given back exactly by :func:`clear_equipment` (the keys
#: hold it as float32).
KEYED = "turning_export_keys"


def equipment(fig) -> list:
    """The equipment objects of a user's rig (an empty list for a built-in figure)."""
    if not is_user_rig(fig) or rig_settings(fig).equipment is None:
        return []
    return list(rig_settings(fig).equipment.objects)


#: The rotation property of each rotation mode (an Euler order otherwise).
_ROTATION = {"QUATERNION": "rotation_quaternion", "AXIS_ANGLE": "rotation_axis_angle"}


def _basis_channels(obj) -> list:
    """``[(data_path, index, value)]`` of ``obj``'s own transform in its rotation mode."""
    rot = _ROTATION.get(obj.rotation_mode, "rotation_euler")
    return [(path, i, float(v)) for path in ("location", rot, "scale")
            for i, v in enumerate(getattr(obj, path))]


#: Custom property each bake's action keys (``"turn_take <name>"``, value 0) and no object has
#: (``bake.KEY_ONLY``): FBX exports, as a take of an object, every action all of whose F-curves
#: resolve on it, and figures of a sport share their bones (equipment objects share location,
#: rotation, scale); with this curve a bake's action fits no object, and plays only where the
#: add-on put it (the figure's NLA strip, a piece's active action).
TAKE = bake.KEY_ONLY


def with_take(fig, track):
    """``track`` with the figure's own take property (see ``TAKE``)."""
    from ...mapping.base import PoseTrack
    props = {**track.props, TAKE + fig.name: np.zeros(len(track))}
    return PoseTrack(track.frames, track.location, track.rotation, track.bones, props)


def own_take(obj, bag, frames) -> None:
    """Key an equipment object's own take property in ``bag`` on ``frames``."""
    obj.pop(TAKE + obj.name, None)            # made on a piece baked when it was made
    path = f'["{bpy.utils.escape_identifier(TAKE + obj.name)}"]'
    frames = np.asarray(frames, float)
    bake.write_channels(bag, [(path, 0, "Turning", np.zeros(len(frames)))], frames)


def bake_equipment(fig, frames) -> int:
    """Key a user rig's equipment with the transform it holds (constraints and drivers stay
    on and move it) on the first and last of ``frames`` (the figure's baked frames, ascending).
    Returns the objects keyed."""
    clear_equipment(fig)
    objs = equipment(fig)
    for obj in objs:
        key_in_place(fig, obj, frames)
    return len(objs)


def key_in_place(fig, obj, frames) -> None:
    """Give ``obj`` an action of its own that holds its transform on the first and last of
    ``frames``, merged into ``fig``'s glTF animation (see the module doc)."""
    ends = np.unique(np.asarray(frames, float)[[0, -1]])
    obj[KEYED] = [float(v) for row in obj.matrix_basis for v in row]
    keyed = compat.assign_new_action(obj, obj.name)
    keyed[bake.OWNER] = obj
    keyed[bake.MERGE_INTO] = bake.figure_action(fig).name        # one glTF animation
    bag = compat.channels(obj)
    bake.write_channels(bag, [(path, i, "Object Transforms", np.full(len(ends), v))
                              for path, i, v in _basis_channels(obj)], ends)
    own_take(obj, bag, ends)


def clear_equipment(fig) -> None:
    """Remove the keys :func:`bake_equipment` wrote and give each piece its transform back."""
    for obj in equipment(fig):
        if KEYED not in obj:
            continue
        adt = obj.animation_data
        action = adt.action if adt else None
        if action is not None and action.get(bake.OWNER) == obj:
            adt.action = None
            bpy.data.actions.remove(action)
        obj.matrix_basis = Matrix(np.reshape(obj[KEYED], (4, 4)).tolist())
        del obj[KEYED]


# -- root motion --------------------------------------------------------------------------------

#: The bone that carries the motion with Root Motion: the built-in figures' and Rigify's.
ROOT_BONE = "root"


def root_motion(fig, track, bone: str = ROOT_BONE):
    """``track`` with the armature object's motion moved onto its ``bone`` (for engines that
    take the character's travel from its root bone): the object keeps its transform of the first
    frame on every frame, and the bone's pose ``B'`` is chosen so that every bone stays where it
    was in the world: ``O_0 R B'(f) = O(f) R B(f)`` with ``O`` the object's transform, ``R`` the
    bone's rest matrix in the armature and ``B`` its own pose (identity when not animated)."""
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
    return PoseTrack(track.frames, np.tile(track.location[0], (n, 1)),
                     np.tile(track.rotation[0], (n, 1)), bones, dict(track.props))
