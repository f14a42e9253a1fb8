"""The user's own animation around a bake: the action the figure was playing (stashed on a muted
NLA track while baked, given back by Clear Bake with the keys the user set meanwhile), and the
transform and pose the bake overrode (put back bit for bit).

The stashed action is held by an ID-pointer property, not by name: the user may rename it while
it is stashed, and the pointer keeps it a user so it is never lost on save.
"""
from __future__ import annotations

import bpy
import numpy as np

from .. import compat

#: ID property on the armature object: the user's action the bake replaced (an ID pointer, so a
#: renamed action is still found and keeps a user while it is stashed; older files hold its name).
STASHED = "turning_stashed_action"
STASH_TRACK = "Turning: user action"
#: ID property on the armature object: its transform and pose before the bake, for Clear Bake.
REST = "turning_rest"
#: The F-curve group of the bake's state properties (and of copied curves that had none).
PROP_GROUP = "Turning state"

#: What a key is: ``(attribute, values per key, dtype)`` for ``foreach_get``/``foreach_set``.
_KEY_ATTRS = (("co", 2, np.float32), ("handle_left", 2, np.float32),
              ("handle_right", 2, np.float32), ("interpolation", 1, np.int32),
              ("handle_left_type", 1, np.int32), ("handle_right_type", 1, np.int32))


def fcurve_keys(fc) -> bytes:
    """Every key of ``fc`` (positions, handles, interpolation) as bytes, for comparing curves."""
    n = len(fc.keyframe_points)
    out = []
    for attr, width, dtype in _KEY_ATTRS:
        buf = np.empty(n * width, dtype)
        fc.keyframe_points.foreach_get(attr, buf)
        out.append(buf.tobytes())
    return b"".join(out)


def copy_fcurve(src, bag):
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


def stashed_action(obj):
    """The user's action a bake of ``obj`` replaced (kept on a muted NLA track), or ``None``."""
    ref = obj.get(STASHED)
    if isinstance(ref, str):                   # files saved before the reference was an ID
        return bpy.data.actions.get(ref)
    return ref if isinstance(ref, bpy.types.Action) else None


def stash_strip(obj, user):
    """``(track, strip)`` holding the stashed ``user`` action: on the add-on's track, else on a
    muted track (the user may rename it); ``(None, None)`` if the user took it off the NLA."""
    adt = obj.animation_data
    found = [(t, s) for t in (adt.nla_tracks if adt else ()) for s in t.strips if s.action == user]
    for rank in (lambda t: t.name == STASH_TRACK, lambda t: t.mute):
        for track, strip in found:
            if rank(track):
                return track, strip
    return None, None


def stash(obj, current):
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


def stashes(figs) -> dict:
    """Each of ``figs``' stashed user action (or ``None``) by name, before a bake: what
    :func:`stash_note` tells a new stash by."""
    return {f.name: stashed_action(f) for f in figs}


def stash_note(fig, before: dict) -> str | None:
    """What to tell the user when a bake has just stashed ``fig``'s action (``before``: from
    :func:`stashes`), or ``None``: its keys stop playing while the figure is baked, so the bake
    says where they are and how to get them back (docs/layers.md)."""
    user = stashed_action(fig)
    if user is None or user == before.get(fig.name):
        return None
    return (f"your action {user.name!r} no longer plays: it is kept, muted, on the NLA track "
            f"{STASH_TRACK!r}; Clear Bake plays it again, and keys set now go on the tweak layer "
            "above the bake")


def record_rest(obj) -> None:
    """Remember the transform and pose the bake is about to override (Clear Bake restores them
    bit for bit: recomputing them from the Start settings would not be exact)."""
    obj[REST] = {
        "mode": obj.rotation_mode, "location": tuple(obj.location),
        "rotation_euler": tuple(obj.rotation_euler),
        "bones": {pb.name: {"mode": pb.rotation_mode, "location": tuple(pb.location),
                            "rotation_quaternion": tuple(pb.rotation_quaternion),
                            "rotation_euler": tuple(pb.rotation_euler)}
                  for pb in obj.pose.bones}}


def restore_rest(obj) -> None:
    """Put back what :func:`record_rest` remembered (bones the user deleted since are skipped)."""
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


def give_back(curves, user_bag) -> None:
    """Put the user's keys ``curves`` (copied parameters, and anything keyed while baked) into the
    user's action, replacing only curves that differ."""
    if user_bag is None:
        return
    have = {(fc.data_path, fc.array_index): fc for fc in user_bag.fcurves}
    for fc in list(curves):
        old = have.get((fc.data_path, fc.array_index))
        if old is not None and fcurve_keys(old) == fcurve_keys(fc) and old.mute == fc.mute:
            continue
        if old is not None:
            user_bag.fcurves.remove(old)
        copy_fcurve(fc, user_bag)


def stashed_channels(obj, user):
    """The F-curve container of the stashed ``user`` action, through the slot it played with."""
    _, strip = stash_strip(obj, user)
    slot = compat.strip_slot(strip) if strip is not None else None
    if slot is None:
        slot = compat.slot_named(user, obj.get(STASHED + "_slot"))
    return compat.channelbag(user, slot)


def unstash(obj, user) -> None:
    """Take the stashed ``user`` action off its NLA track and assign it again (unless the user
    assigned another one); forget the stash."""
    adt = obj.animation_data
    if user is not None:
        track, strip = stash_strip(obj, user)
        slot = compat.strip_slot(strip) if strip is not None else None
        # The slot the stash played through: files from 4.2 recorded no slot name.
        name = slot.identifier if slot is not None else obj.get(STASHED + "_slot")
        if track is not None:
            adt.nla_tracks.remove(track)
        if adt.action is None:
            compat.restore_action(obj, user, name)
    for key in (STASHED, STASHED + "_slot"):
        if key in obj:
            del obj[key]
