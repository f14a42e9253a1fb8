"""The layers of a baked figure: the bake on an NLA track of its own, the animator's tweaks above.

A figure's animation, bottom to top (docs/layers.md):

- ``Turning: user action`` (muted NLA track): the action the figure played before its first
  bake, kept untouched for Clear Bake (:mod:`.user_action`).
- ``Turning: bake`` (NLA track): the baked action as one strip.  Every rebake rewrites the
  curves in it and nothing else.
- the tweak layer: the figure's *active* action, tagged as its tweaks, blended in Combine mode.
  Keys the animator sets in the viewport land here as offsets on top of the bake (Blender keys a
  Combine layer relative to the NLA below it), so they survive every rebake.  Clear Bake parks a
  tweak layer that holds keys on the muted track ``Turning: tweaks``; the next bake plays it
  again.

The controller's keyed parameters (``turning.*``) live in the tweak layer while baked: a property
whose default is not zero is blended by replacement there, so the keyed value is the value.

A key of the user's on a baked channel inside the bake layer (set in the NLA's tweak mode on the
bake strip) is never lost silently: each baked curve's keys are fingerprinted when written, and a
rebake of a figure whose bake layer was edited is refused before anything changes, naming the
channel (:func:`check_unedited`).
"""
from __future__ import annotations

import zlib

import bpy
import numpy as np

from .. import compat

BAKE_TRACK = "Turning: bake"
TWEAK_TRACK = "Turning: tweaks"
#: ID property on the tweak action: the figure (object) whose tweaks it holds.
TWEAKS_OF = "turning_tweaks_of"
#: ID property on the figure: its ``action_blend_type`` before the tweak layer took over.
BLEND_BEFORE = "turning_blend_before"
#: ID property on the bake action: ``"data_path|index|crc"`` per baked curve, one a line.
FINGERPRINTS = "turning_baked_keys"
#: F-curves of the controller's parameters (``Object.turning.*``).
PARAM_PREFIX = "turning."


class EditedBakeError(ValueError):
    """The bake layer holds keys of the user's that a rebake would delete (names the channel)."""


# -- the bake layer ------------------------------------------------------------------------------

def push_bake(obj, action):
    """Put the assigned bake ``action`` on an NLA track of its own (on top), none assigned;
    return its strip.  The strip spans the action's keys."""
    adt = obj.animation_data
    track = adt.nla_tracks.new()
    track.name = BAKE_TRACK
    strip = compat.nla_strip_new(track, action.name, int(action.frame_range[0]), action)
    adt.action = None
    return strip


def _key_crc(fc, keys=None) -> int:
    """The fingerprint of ``fc``'s key positions; ``keys``: ``{(data_path, index): co}`` of
    curves already read (float32, as ``foreach_get`` gives them), taken from there."""
    co = None if keys is None else keys.get((fc.data_path, fc.array_index))
    if co is None:
        co = np.empty(2 * len(fc.keyframe_points), np.float32)
        fc.keyframe_points.foreach_get("co", co)
    return zlib.crc32(co.tobytes())


def fingerprint(action, bag, keys=None) -> dict:
    """Remember the keys of every curve the bake wrote (positions only: a stepped bake sets the
    handles afterwards, and a user's key always moves or adds a position); ``keys`` as in
    :func:`_key_crc`.  Returns ``{(data_path, index): crc}`` as :func:`keep_fingerprints`
    takes it."""
    paths = set(action.get("turning_baked_paths", "").splitlines())
    crcs = {(fc.data_path, fc.array_index): _key_crc(fc, keys)
            for fc in bag.fcurves if fc.data_path in paths}
    keep_fingerprints(action, crcs)
    return crcs


def keep_fingerprints(action, crcs: dict) -> None:
    """Store the fingerprints ``{(data_path, index): crc}`` of the bake's curves on ``action``
    (:func:`.key_crc.crc_after_change` updates them for a few keys written)."""
    action[FINGERPRINTS] = "\n".join(f"{path}|{index}|{crc}" for (path, index), crc in crcs.items())


def edited_curves(action, bag, keys=None) -> list:
    """``[(data_path, index)]`` of the baked curves whose keys changed since the bake wrote them
    (``[]`` for a bake written before fingerprints were kept: nothing to compare with);
    ``keys`` as in :func:`_key_crc`."""
    known = {}
    for line in action.get(FINGERPRINTS, "").splitlines():
        path, index, crc = line.rsplit("|", 2)
        known[(path, int(index))] = int(crc)
    if not known or bag is None:
        return []
    have = {(fc.data_path, fc.array_index): fc for fc in bag.fcurves}
    return [key for key, crc in known.items()
            if key not in have or _key_crc(have[key], keys) != crc]


def check_unedited(obj, action, bag, keys=None) -> None:
    """Raise :class:`EditedBakeError` if the user keyed (or deleted) a baked curve of ``obj``'s
    bake layer since the bake: a rebake or Clear Bake would delete those keys (``keys`` as in
    :func:`_key_crc`)."""
    edited = edited_curves(action, bag, keys)
    if edited:
        path, index = edited[0]
        more = f" (and {len(edited) - 1} more channels)" if len(edited) > 1 else ""
        raise EditedBakeError(
            f"the bake layer holds keys of yours on {path}[{index}]{more}, set after "
            "the bake; rebaking would delete them.  Key tweaks on the tweak layer (the figure's "
            f"active action, Start Tweak Layer) instead; to discard the edits, Clear Bake first")


# -- the tweak layer -----------------------------------------------------------------------------

def is_tweaks(action, obj) -> bool:
    return action is not None and action.get(TWEAKS_OF) == obj


def tweak_layer(obj):
    """``(action, parked_strip)``: ``obj``'s tweak layer, playing or parked on the muted
    ``Turning: tweaks`` track, or unassigned (the user played another action over it; strip
    ``None``; found by the name it was made with); ``(None, None)`` when it has none."""
    adt = obj.animation_data
    if adt is None:
        return None, None
    if is_tweaks(adt.action, obj):
        return adt.action, None
    for track in adt.nla_tracks:
        for strip in track.strips:
            if is_tweaks(strip.action, obj):
                return strip.action, strip
    # Unassigned: by the name it was made with (a look at every action costs O(actions) a figure).
    old = bpy.data.actions.get(_tweaks_name(obj))
    return (old if is_tweaks(old, obj) else None), None


def _tweaks_name(obj) -> str:
    return f"{obj.name} Tweaks"


def playing(obj, action) -> bool:
    adt = obj.animation_data
    return action is not None and adt is not None and adt.action == action


def _assign(obj, action) -> None:
    slots = getattr(action, "slots", None)
    compat.restore_action(obj, action, slots[0].identifier if slots else None)


def start_tweaks(obj):
    """Play ``obj``'s tweak layer (made if it has none, brought back if parked) as its active
    action in Combine mode; return it.  The figure must have no other active action."""
    adt = obj.animation_data or obj.animation_data_create()
    action, strip = tweak_layer(obj)
    if playing(obj, action):
        return action
    if adt.action is not None:
        raise ValueError(f"{obj.name} plays the action {adt.action.name!r}; a tweak layer "
                         "needs the active action slot")
    if BLEND_BEFORE not in obj:
        obj[BLEND_BEFORE] = adt.action_blend_type
    if action is None:
        action = compat.assign_new_action(obj, _tweaks_name(obj))
        action[TWEAKS_OF] = obj
    else:
        if strip is not None:
            _drop_track_of(adt, strip)
        _assign(obj, action)
    adt.action_blend_type = "COMBINE"     # keys are offsets on top of the bake
    return action


def span_tweaks(obj, frame_range) -> None:
    """Give ``obj``'s playing tweak layer the bake's frame range as its own (Manual Frame Range):
    an exporter that plays each action over its range (FBX's *All Actions*) then plays the
    figure with its tweaks over the whole bake, not over the keys the layer happens to hold (an
    empty one: none)."""
    action, _ = tweak_layer(obj)
    if playing(obj, action):
        action.use_frame_range = True
        action.frame_start, action.frame_end = frame_range


def tweak_channels(obj):
    """The F-curve container of ``obj``'s tweak layer (its one slot), or ``None``."""
    action, _ = tweak_layer(obj)
    if action is None:
        return None
    slots = getattr(action, "slots", None)
    return compat.channelbag(action, slots[0] if slots else None)


def take_parameters(obj, curves) -> None:
    """Copy the controller's keyed parameter curves ``curves`` into the playing tweak layer
    (replacing its own of the same path)."""
    from .user_action import copy_fcurve
    bag = compat.channels(obj)
    for fc in curves:
        old = next((c for c in bag.fcurves if (c.data_path, c.array_index)
                    == (fc.data_path, fc.array_index)), None)
        if old is not None:
            bag.fcurves.remove(old)
        copy_fcurve(fc, bag)


def keep_in_file(obj) -> str | None:
    """Remove Figure's part, after Clear Bake: take a tweak layer that holds keys (parked on the
    muted ``Turning: tweaks`` track, or unassigned) off the rig and keep its action in the file
    with a fake user, so the animator's keys are not lost and the rig carries nothing of the
    figure's; still tagged as the rig's tweaks, it plays again on Start Tweak Layer once the rig
    is a figure again.  Returns the action's name, or ``None`` when there is none (or it became
    the user's action: :func:`park_tweaks`)."""
    action, strip = tweak_layer(obj)
    if action is None or playing(obj, action):
        return None
    adt = obj.animation_data
    if strip is not None:
        _drop_track_of(adt, strip)
    action.use_fake_user = True
    if adt is not None and adt.action is None and len(adt.nla_tracks) == 0 and \
            len(adt.drivers) == 0:
        obj.animation_data_clear()        # the tweak track was all the figure left in it
    return action.name


def _drop_track_of(adt, strip) -> None:
    for track in adt.nla_tracks:
        if any(s == strip for s in track.strips):
            adt.nla_tracks.remove(track)
            return


def park_tweaks(obj, has_user: bool, user_bag) -> str | None:
    """Clear Bake's part: give the keyed parameters back to the user's action (``user_bag``; kept
    in the layer when the figure had no action of the user's), then park a tweak layer that still
    holds keys on the muted ``Turning: tweaks`` track and delete an empty one.  Returns the name
    of the action the tweaks are kept in, or ``None``."""
    from .user_action import give_back
    action, strip = tweak_layer(obj)
    adt = obj.animation_data
    if action is None:
        if adt is not None and BLEND_BEFORE in obj:
            adt.action_blend_type = obj[BLEND_BEFORE]
            del obj[BLEND_BEFORE]
        return None
    bag = tweak_channels(obj)
    params = [fc for fc in bag.fcurves if fc.data_path.startswith(PARAM_PREFIX)] if bag else []
    if has_user:
        give_back(params, user_bag)
        for fc in params:
            bag.fcurves.remove(fc)
    for grp in [g for g in (bag.groups if bag else ()) if len(g.channels) == 0]:
        bag.groups.remove(grp)
    left = len(bag.fcurves) if bag else 0
    if playing(obj, action):
        adt.action = None
        if BLEND_BEFORE in obj:
            adt.action_blend_type = obj[BLEND_BEFORE]
    if BLEND_BEFORE in obj:
        del obj[BLEND_BEFORE]
    if left == 0:
        if strip is not None:
            _drop_track_of(adt, strip)
        bpy.data.actions.remove(action)
        return None
    if not has_user and left == len(params):
        del action[TWEAKS_OF]              # only keyed parameters: the user's action now
        _assign(obj, action)
        return action.name
    if strip is None:
        track = adt.nla_tracks.new()
        track.name = TWEAK_TRACK
        slot = compat.slot_named(action, action.slots[0].identifier) \
            if compat.SLOTTED_ACTIONS and len(action.slots) else None
        new = track.strips.new(action.name, int(action.frame_range[0]), action)
        if slot is not None:
            new.action_slot = slot
        new.blend_type = "COMBINE"
        track.mute = True
    return action.name
