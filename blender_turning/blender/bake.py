"""Write a :class:`~blender_turning.mapping.base.PoseTrack` into F-curves, whole curves at once.

One action per figure, named after the figure's armature and tagged as the add-on's.  Each
animated channel becomes one F-curve filled by ``keyframe_points.add(n)`` and two ``foreach_set``
calls (no ``bpy.ops``, no ``frame_set``, no mode switch).  Baking again replaces exactly the
F-curves the previous bake wrote; everything else in that action (the user's own keys, e.g. on
the controller's ``turning.*`` parameters) stays.  If the figure was playing an action of the
user's, that action is kept on a muted NLA track and comes back on :func:`clear_bake`.
"""
from __future__ import annotations

from dataclasses import dataclass

import bpy
import numpy as np

from . import compat
from ..mapping.base import PoseTrack

#: ID property on an action made by :func:`bake_pose_track`: the paths it wrote, one per line.
BAKED_PATHS = "turning_baked_paths"
#: ID property on the armature object: the identifier of the action the bake replaced.
STASHED = "turning_stashed_action"
STASH_TRACK = "Turning: user action"
PROP_GROUP = "Turning state"
#: Parameter F-curves (``Object.turning.*``) the user keys; a bake copies them, never drops them.
PARAM_PREFIX = "turning."


class BakeError(ValueError):
    """A pose track that does not fit the armature (names the bone or property)."""


@dataclass(frozen=True)
class BakeResult:
    action: object
    """The figure's action (``bpy.types.Action``)."""
    fcurves: int
    """F-curves written."""
    frames: int
    """Keys per F-curve."""


def _channel_list(obj, track: PoseTrack):
    """``[(data_path, index, group, values (n,)), ...]`` for every channel of ``track``."""
    out = []
    for i in range(3):
        out.append(("location", i, "Object Transforms", track.location[:, i]))
    for i in range(3):
        out.append(("rotation_euler", i, "Object Transforms", track.rotation[:, i]))
    for name, ch in track.bones.items():
        base = f'pose.bones["{bpy.utils.escape_identifier(name)}"]'
        if ch.location is not None:
            out.extend((base + ".location", i, name, ch.location[:, i]) for i in range(3))
        if ch.rotation is not None:
            out.extend((base + ".rotation_quaternion", i, name, ch.rotation[:, i])
                       for i in range(4))
    for prop, values in track.props.items():
        out.append((f'["{bpy.utils.escape_identifier(prop)}"]', 0, PROP_GROUP, np.asarray(values)))
    return out


def check_track(obj, track: PoseTrack) -> None:
    """Raise :class:`BakeError` if ``track`` names a bone ``obj`` lacks or holds a non-finite value.

    Called before anything is written, so a bad track leaves the scene untouched.
    """
    if obj is None or obj.type != "ARMATURE":
        raise BakeError("the figure must be an armature object")
    missing = [b for b in track.bones if b not in obj.pose.bones]
    if missing:
        raise BakeError(f"armature {obj.name!r} has no bone {missing[0]!r}")
    if len(track) == 0:
        raise BakeError("the pose track has no frames")
    arrays = [track.frames, track.location, track.rotation, *track.props.values()]
    for ch in track.bones.values():
        arrays += [a for a in (ch.location, ch.rotation) if a is not None]
    if not all(np.all(np.isfinite(a)) for a in arrays):
        raise BakeError("the pose track holds a value that is not a finite number")


def _is_ours(action) -> bool:
    return action is not None and BAKED_PATHS in action


def _copy_fcurve(src, bag):
    """Copy the F-curve ``src`` (keys, interpolation, handles) into ``bag``."""
    grp = src.group.name if src.group else PROP_GROUP
    dst = compat.new_fcurve(bag, src.data_path, src.array_index, grp)
    n = len(src.keyframe_points)
    dst.keyframe_points.add(n)
    for attr, width, dtype in (("co", 2, np.float32), ("handle_left", 2, np.float32),
                               ("handle_right", 2, np.float32), ("interpolation", 1, np.int32),
                               ("handle_left_type", 1, np.int32),
                               ("handle_right_type", 1, np.int32)):
        buf = np.empty(n * width, dtype)
        src.keyframe_points.foreach_get(attr, buf)
        dst.keyframe_points.foreach_set(attr, buf)
    dst.update()


def _figure_action(obj):
    """The figure's own action, assigned to ``obj``; a user's action is stashed, not touched."""
    adt = obj.animation_data
    current = adt.action if adt else None
    if _is_ours(current) and compat.channels(obj) is not None:
        return current
    params = []
    if current is not None:
        # The user's action: keep it (muted, on its own NLA track) and remember it for Clear Bake.
        bag = compat.channels(obj)
        params = [fc for fc in (bag.fcurves if bag else ())
                  if fc.data_path.startswith(PARAM_PREFIX)]
        track = adt.nla_tracks.new()
        track.name = STASH_TRACK
        compat.nla_strip_new(track, current.name, int(current.frame_range[0]), current)
        track.mute = True
        obj[STASHED] = current.name
        obj[STASHED + "_slot"] = compat.slot_identifier(obj) or ""
    action = compat.assign_new_action(obj, obj.name)
    action[BAKED_PATHS] = ""
    bag = compat.channels(obj)
    for fc in params:                     # the controller's keyed parameters stay with the figure
        _copy_fcurve(fc, bag)
    return action


def _remove_baked(bag, action) -> None:
    paths = set(action.get(BAKED_PATHS, "").splitlines())
    for fc in [fc for fc in bag.fcurves if fc.data_path in paths]:
        bag.fcurves.remove(fc)
    for grp in [g for g in bag.groups if len(g.channels) == 0]:
        bag.groups.remove(grp)
    action[BAKED_PATHS] = ""


def write_channels(bag, channels, frames) -> int:
    """Write each ``(data_path, index, group, values)`` as one whole F-curve; return the count."""
    n = len(frames)
    co = np.empty(2 * n, np.float32)
    co[0::2] = frames
    ipo = np.full(n, compat.linear_interpolation_value(), np.int32)
    for data_path, index, group, values in channels:
        fc = compat.new_fcurve(bag, data_path, index, group)
        co[1::2] = values
        kp = fc.keyframe_points
        kp.add(n)
        kp.foreach_set("co", co)
        kp.foreach_set("interpolation", ipo)
        fc.update()                       # handles and the cached range; keys are already sorted
    return len(channels)


def bake_pose_track(obj, track: PoseTrack) -> BakeResult:
    """Bake ``track`` into ``obj``'s figure action (created or reused); see the module doc."""
    check_track(obj, track)
    for name, ch in track.bones.items():
        if ch.rotation is not None:
            obj.pose.bones[name].rotation_mode = "QUATERNION"
    obj.rotation_mode = "XYZ"
    for prop, values in track.props.items():
        if prop not in obj.keys():
            obj[prop] = float(values[0])
    action = _figure_action(obj)
    bag = compat.channels(obj)
    _remove_baked(bag, action)
    chans = _channel_list(obj, track)
    count = write_channels(bag, chans, np.asarray(track.frames, float))
    action[BAKED_PATHS] = "\n".join(sorted({c[0] for c in chans}))
    return BakeResult(action, count, len(track))


def figure_action(obj):
    """The add-on's action on ``obj``, or ``None``."""
    adt = obj.animation_data if obj is not None else None
    action = adt.action if adt else None
    return action if _is_ours(action) else None


def clear_bake(obj) -> bool:
    """Remove what the bakes wrote; restore a stashed user action.  ``False`` if nothing baked.

    The figure's action is deleted when nothing of the user's (parameter keys) is left in it.
    """
    action = figure_action(obj)
    if action is None:
        return False
    bag = compat.channels(obj)
    if bag is not None:
        _remove_baked(bag, action)
    keep = bag is not None and len(bag.fcurves) > 0
    stashed = obj.get(STASHED)
    if not keep:
        obj.animation_data.action = None
        bpy.data.actions.remove(action)
    if stashed and not keep:
        adt = obj.animation_data
        for track in list(adt.nla_tracks):
            if track.name == STASH_TRACK:
                adt.nla_tracks.remove(track)
        user = bpy.data.actions.get(stashed)
        if user is not None:
            compat.restore_action(obj, user, obj.get(STASHED + "_slot"))
        del obj[STASHED]
        del obj[STASHED + "_slot"]
    for prop in [p for p in obj.keys() if p.startswith("turn_")]:
        del obj[prop]
    return True
