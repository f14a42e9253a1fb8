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
#: ID property on that action: the figure (object) it belongs to.  An ID pointer, so a duplicated
#: figure's copied action points at the copy, and an action shared by two figures is the owner's.
OWNER = "turning_figure"
#: ID property on the armature object: the user's action the bake replaced (an ID pointer, so a
#: renamed action is still found and keeps a user while it is stashed; older files hold its name).
STASHED = "turning_stashed_action"
STASH_TRACK = "Turning: user action"
#: ID property on the armature object: its transform and pose before the bake, for Clear Bake.
REST = "turning_rest"
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


def _is_ours(action, obj) -> bool:
    """Is ``action`` a bake of the figure ``obj`` (not a user's, not another figure's)?"""
    if action is None or BAKED_PATHS not in action:
        return False
    owner = action.get(OWNER)
    return owner is None or owner == obj       # None: made before owners were recorded


def _fcurve_keys(fc) -> bytes:
    n = len(fc.keyframe_points)
    out = []
    for attr, width, dtype in _KEY_ATTRS:
        buf = np.empty(n * width, dtype)
        fc.keyframe_points.foreach_get(attr, buf)
        out.append(buf.tobytes())
    return b"".join(out)


_KEY_ATTRS = (("co", 2, np.float32), ("handle_left", 2, np.float32),
              ("handle_right", 2, np.float32), ("interpolation", 1, np.int32),
              ("handle_left_type", 1, np.int32), ("handle_right_type", 1, np.int32))


def _copy_fcurve(src, bag):
    """Copy the F-curve ``src`` (keys, interpolation, handles, mute) into ``bag``."""
    grp = src.group.name if src.group else PROP_GROUP
    dst = compat.new_fcurve(bag, src.data_path, src.array_index, grp)
    n = len(src.keyframe_points)
    dst.keyframe_points.add(n)
    for attr, width, dtype in _KEY_ATTRS:
        buf = np.empty(n * width, dtype)
        src.keyframe_points.foreach_get(attr, buf)
        dst.keyframe_points.foreach_set(attr, buf)
    dst.mute, dst.extrapolation = src.mute, src.extrapolation
    dst.update()


def find_bake(obj):
    """``(action, nla_strip)`` of the figure's own action: assigned (strip ``None``) or pushed
    down onto an NLA strip; ``(None, None)`` when the figure is not baked."""
    adt = obj.animation_data if obj is not None else None
    if adt is None:
        return None, None
    if _is_ours(adt.action, obj):
        return adt.action, None
    for track in adt.nla_tracks:
        for strip in track.strips:
            if _is_ours(strip.action, obj):
                return strip.action, strip
    return None, None


def _bag(obj, action, strip):
    if strip is None:
        return compat.channels(obj, action)
    return compat.channelbag(action, compat.strip_slot(strip))


def stashed_action(obj):
    """The user's action a bake of ``obj`` replaced (kept on a muted NLA track), or ``None``."""
    ref = obj.get(STASHED)
    if isinstance(ref, str):                   # files saved before the reference was an ID
        return bpy.data.actions.get(ref)
    return ref if isinstance(ref, bpy.types.Action) else None


def _stash_strip(obj, user):
    """``(track, strip)`` holding the stashed ``user`` action: on the add-on's track, else on a
    muted track (the user may rename it); ``(None, None)`` if the user took it off the NLA."""
    adt = obj.animation_data
    found = [(t, s) for t in (adt.nla_tracks if adt else ()) for s in t.strips if s.action == user]
    for rank in (lambda t: t.name == STASH_TRACK, lambda t: t.mute):
        for track, strip in found:
            if rank(track):
                return track, strip
    return None, None


def _stash(obj, current):
    """Keep the user's ``current`` action on a muted NLA track of its own; remember it."""
    adt = obj.animation_data
    track = adt.nla_tracks.new()
    track.name = STASH_TRACK
    compat.nla_strip_new(track, current.name, int(current.frame_range[0]), current)
    track.mute = True
    # A second stash (the user assigned another action over a bake, then baked again): the first
    # stash stays on its own muted track, where it was before this bake; only this one is undone.
    obj[STASHED] = current
    obj[STASHED + "_slot"] = compat.slot_identifier(obj) or ""


def _record_rest(obj) -> None:
    """Remember the transform and pose the bake is about to override (Clear Bake restores them
    bit for bit: recomputing them from the Start settings would not be exact)."""
    obj[REST] = {
        "mode": obj.rotation_mode, "location": tuple(obj.location),
        "rotation_euler": tuple(obj.rotation_euler),
        "bones": {pb.name: {"mode": pb.rotation_mode, "location": tuple(pb.location),
                            "rotation_quaternion": tuple(pb.rotation_quaternion),
                            "rotation_euler": tuple(pb.rotation_euler)}
                  for pb in obj.pose.bones}}


def _restore_rest(obj) -> None:
    rest = obj[REST].to_dict()
    del obj[REST]
    obj.rotation_mode = rest["mode"]
    obj.location, obj.rotation_euler = rest["location"], rest["rotation_euler"]
    for name, b in rest["bones"].items():
        pb = obj.pose.bones.get(name)
        if pb is not None:
            pb.rotation_mode = b["mode"]
            pb.location = b["location"]
            pb.rotation_quaternion = b["rotation_quaternion"]
            pb.rotation_euler = b["rotation_euler"]


def _figure_action(obj):
    """The figure's own action and strip (see :func:`find_bake`); made and assigned when there is
    none.  A user's action is stashed, not touched."""
    action, strip = find_bake(obj)
    if action is not None and _bag(obj, action, strip) is not None:
        return action, strip
    adt = obj.animation_data
    current = adt.action if adt else None
    params = []
    if current is not None:
        bag = compat.channels(obj)
        params = [fc for fc in (bag.fcurves if bag else ())
                  if fc.data_path.startswith(PARAM_PREFIX)]
        _stash(obj, current)
    _record_rest(obj)
    for old in [a for a in bpy.data.actions if a.get(OWNER) == obj and a.users == 0]:
        bpy.data.actions.remove(old)          # an earlier bake the user unassigned: unused, ours
    action = compat.assign_new_action(obj, obj.name)
    action[BAKED_PATHS] = ""
    action[OWNER] = obj
    bag = compat.channels(obj)
    for fc in params:                     # the controller's keyed parameters stay with the figure
        _copy_fcurve(fc, bag)
    return action, None


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
    """Bake ``track`` into ``obj``'s figure action (created or reused; in place when the user
    pushed it down onto an NLA strip); see the module doc."""
    check_track(obj, track)
    chans = _channel_list(obj, track)
    action, strip = _figure_action(obj)
    for name, ch in track.bones.items():
        if ch.rotation is not None:
            obj.pose.bones[name].rotation_mode = "QUATERNION"
    obj.rotation_mode = "XYZ"
    for prop, values in track.props.items():
        if prop not in obj.keys():
            obj[prop] = float(values[0])
    bag = _bag(obj, action, strip)
    _remove_baked(bag, action)
    count = write_channels(bag, chans, np.asarray(track.frames, float))
    action[BAKED_PATHS] = "\n".join(sorted({c[0] for c in chans}))
    if strip is not None:
        _fit_strip(strip, action)
    return BakeResult(action, count, len(track))


def _fit_strip(strip, action) -> None:
    """Let a pushed-down strip play the whole re-baked range (it keeps its scale and repeats)."""
    lo, hi = action.frame_range
    if (strip.action_frame_start, strip.action_frame_end) != (lo, hi):
        strip.action_frame_end = max(hi, strip.action_frame_start + 1)
        strip.action_frame_start = lo
        strip.action_frame_end = hi


def figure_action(obj):
    """The add-on's action of ``obj`` (assigned or on one of its NLA strips), or ``None``."""
    return find_bake(obj)[0]


def _give_back(bag, user_bag) -> None:
    """Put what is left in the figure's action (the user's keys: copied parameters, and anything
    keyed while baked) into the user's action, replacing only curves that differ."""
    if user_bag is None:
        return
    have = {(fc.data_path, fc.array_index): fc for fc in user_bag.fcurves}
    for fc in bag.fcurves:
        old = have.get((fc.data_path, fc.array_index))
        if old is not None and _fcurve_keys(old) == _fcurve_keys(fc) and old.mute == fc.mute:
            continue
        if old is not None:
            user_bag.fcurves.remove(old)
        _copy_fcurve(fc, user_bag)


def _drop_strip(adt, strip) -> None:
    for track in adt.nla_tracks:
        if any(s == strip for s in track.strips):
            track.strips.remove(strip)
            if len(track.strips) == 0:
                adt.nla_tracks.remove(track)
            return


def clear_bake(obj) -> bool:
    """Remove what the bakes wrote and give the user's action back as it was (with any keys the
    user set while baked).  ``False`` if nothing was baked.

    The figure's action is deleted unless it holds keys of the user's and there is no user action
    to give them back to.
    """
    action, strip = find_bake(obj)
    if action is None:
        return False
    adt = obj.animation_data
    bag = _bag(obj, action, strip)
    if bag is not None:
        _remove_baked(bag, action)
    user = stashed_action(obj)
    slot = obj.get(STASHED + "_slot")
    if user is not None and bag is not None:
        _, stash = _stash_strip(obj, user)
        user_slot = compat.strip_slot(stash) if stash is not None else None
        _give_back(bag, compat.channelbag(user, user_slot))
    keep = bag is not None and len(bag.fcurves) > 0 and user is None
    if not keep:
        if strip is not None:
            _drop_strip(adt, strip)
        else:
            adt.action = None
        bpy.data.actions.remove(action)
    if STASHED in obj:
        track, _ = _stash_strip(obj, user) if user is not None else (None, None)
        if track is not None:
            adt.nla_tracks.remove(track)
        if user is not None and adt.action is None:
            compat.restore_action(obj, user, slot)
        del obj[STASHED]
        if STASHED + "_slot" in obj:
            del obj[STASHED + "_slot"]
    for prop in [p for p in obj.keys() if p.startswith("turn_")]:
        del obj[prop]
    if REST in obj:
        _restore_rest(obj)
    return True
