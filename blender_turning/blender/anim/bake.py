"""Write a :class:`~blender_turning.mapping.base.PoseTrack` into F-curves, whole curves at once.

One action per figure, named after the figure's armature and tagged as the add-on's, played
from an NLA track of its own; the figure's active action is the animator's tweak layer above it
(:mod:`.bake_layers`, docs/layers.md).  Each animated channel becomes one F-curve filled by
``keyframe_points.add(n)`` and two ``foreach_set`` calls (no ``bpy.ops``, no ``frame_set``, no
mode switch).  Baking again replaces exactly the F-curves the previous bake wrote, and refuses
when the user keyed one of them in the bake layer.  If the figure was playing an action of the
user's, that action is kept on a muted NLA track and comes back on :func:`clear_bake`
(:mod:`.user_action`).  The action belongs to its figure (an ID pointer on it), so a duplicate
bakes its own; a bake the user moved to another NLA track is re-baked and cleared in place.

Figures whose motion is another's, moved and later by whole frames (:mod:`...mapping.shared_motion`:
a crowd's followers strung out along the leader's track), play that figure's action instead of
one of their own (:func:`share_bake`): an NLA strip on their own bake track, shifted, and the
translation in their ``delta_location``.  The action stays its figure's; when that figure
re-bakes or clears its bake while others play it, it leaves them the action as it is and makes
a new one (:func:`_give_up`), so no figure's motion changes because another's did.
"""
from __future__ import annotations

from dataclasses import dataclass

import bpy
import numpy as np

from .. import compat
from . import bake_layers, key_crc, user_action
from .user_action import PROP_GROUP, REST, STASHED
from ...mapping.base import PoseTrack

#: ID property on an action made by :func:`bake_pose_track`: the paths it wrote, one per line.
BAKED_PATHS = "turning_baked_paths"
#: ID property on that action: the figure (object) it belongs to.  An ID pointer, so a duplicated
#: figure's copied action points at the copy, and an action shared by two figures is the owner's.
OWNER = "turning_figure"
#: ID property on a bake action that other figures play too (:func:`share_bake`); once its figure
#: gives it up (or is deleted) it is nobody's own.
SHARED = "turning_shared"
#: ID property on a figure playing another's bake: the translation it plays it with (its
#: ``delta_location``, put back to zero when it stops).
SHARE_OFFSET = "turning_share_offset"
#: Parameter F-curves (``Object.turning.*``) the user keys; a bake copies them, never drops them.
PARAM_PREFIX = bake_layers.PARAM_PREFIX


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


#: Custom properties a bake keys but never creates on an object (``export_ready.TAKE``): their
#: F-curves resolve on no object, so FBX's *All Actions* (which exports an action as a take of
#: every object all of its F-curves resolve on) finds no object the bake's action fits, and the
#: bake's only take is its NLA strip's (docs/export.md).  Blender skips a curve that resolves on
#: nothing when it plays the action.
KEY_ONLY = "turn_take "

#: ID property on an equipment object's action: the name of its figure's action (the glTF
#: animation its keys merge into; export_ready.py writes it, export_gltf.py reads it).
MERGE_INTO = "turning_export_merge"


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
    """Raise :class:`BakeError` if ``track`` names a bone ``obj`` lacks or holds a non-finite value,
    or ``obj``'s bake layer holds keys of the user's (:func:`.bake_layers.check_unedited`).

    Called before anything is written, so a bad track leaves the scene untouched.
    """
    _check_values(obj, track)
    action, strip = find_bake(obj)
    if action is not None:
        _check_unedited(obj, action, _bag(obj, action, strip))


def _check_unedited(obj, action, bag, keys=None) -> None:
    try:
        bake_layers.check_unedited(obj, action, bag, keys)
    except bake_layers.EditedBakeError as exc:
        raise BakeError(str(exc)) from None


def _check_values(obj, track: PoseTrack) -> None:
    _check_rig(obj, track)
    arrays = [track.frames, track.location, track.rotation, *track.props.values()]
    for ch in track.bones.values():
        arrays += [a for a in (ch.location, ch.rotation) if a is not None]
    if not all(np.all(np.isfinite(a)) for a in arrays):
        raise BakeError("the pose track holds a value that is not a finite number")


def _check_rig(obj, track: PoseTrack) -> None:
    if obj is None or obj.type != "ARMATURE":
        raise BakeError("the figure must be an armature object")
    missing = [b for b in track.bones if b not in obj.pose.bones]
    if missing:
        raise BakeError(f"armature {obj.name!r} has no bone {missing[0]!r}")
    if len(track) == 0:
        raise BakeError("the pose track has no frames")


def _is_ours(action, obj) -> bool:
    """Is ``action`` a bake of the figure ``obj`` (not a user's, not another figure's)?"""
    if action is None or BAKED_PATHS not in action:
        return False
    owner = action.get(OWNER)
    if owner is None:             # made before owners were recorded; or shared and given up
        return SHARED not in action
    return owner == obj


def shared_elsewhere(action) -> bool:
    """Do figures other than its own play the bake ``action`` (each of their strips is a user;
    its own figure's strip is one)?"""
    return action.get(SHARED) is not None and action.users > 1 + int(action.use_fake_user)


def _give_up(obj, action, strip) -> None:
    """Leave the bake ``action`` to the other figures that play it, exactly as it is: ``obj``
    stops playing it, and it is nobody's own (renamed: ``obj``'s next bake takes the name)."""
    if strip is not None:
        _drop_strip(obj.animation_data, strip)
    else:
        obj.animation_data.action = None
    del action[OWNER]
    action.name = f"{obj.name} (shared)"


def _drop_inherited(obj, track) -> None:
    """Take ``obj`` off another figure's bake playing on ``track``: the translation it played a
    shared bake with goes too, and a shared action nobody plays any more is deleted."""
    actions = [s.action for s in track.strips if s.action is not None]
    obj.animation_data.nla_tracks.remove(track)
    if SHARE_OFFSET in obj:
        obj.delta_location = (0.0, 0.0, 0.0)
        del obj[SHARE_OFFSET]
    for action in actions:
        if SHARED in action and action.get(OWNER) is None and action.users == 0:
            bpy.data.actions.remove(action)


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


def inherited_bakes(obj) -> list:
    """Bake tracks of ``obj`` playing another figure's bake: a duplicate's copies of its
    template's tracks (Shift+D shares NLA strips' actions).  A bake of ``obj`` replaces them."""
    adt = obj.animation_data if obj is not None else None
    return [t for t in (adt.nla_tracks if adt else ()) if t.name == bake_layers.BAKE_TRACK
            and any(s.action is not None and BAKED_PATHS in s.action and not _is_ours(s.action, obj)
                    for s in t.strips)]


def _bag(obj, action, strip):
    if strip is None:
        return compat.channels(obj, action)
    return compat.channelbag(action, compat.strip_slot(strip))


def _figure_action(obj):
    """``(action, strip, keep)``: the figure's own action and strip (see :func:`find_bake`), made
    and assigned when there is none, and the curves ``keep`` the tweak layer takes over (the
    user's keyed parameters).  A user's action is stashed, not touched; a bake other figures
    play too is left to them (:func:`_give_up`) and a new one made."""
    action, strip = find_bake(obj)
    given_up = action is not None and shared_elsewhere(action)
    if given_up:
        _give_up(obj, action, strip)
        action = strip = None
    if action is not None and _bag(obj, action, strip) is not None:
        keep = []
        current = obj.animation_data.action
        if strip is None:                 # assigned (an older bake): what is not baked moves up
            paths = set(action.get(BAKED_PATHS, "").splitlines())
            keep = [fc for fc in _bag(obj, action, None).fcurves if fc.data_path not in paths]
        elif current is not None and not bake_layers.is_tweaks(current, obj):
            keep = _stash_users(obj, current)   # the user plays an action of theirs over the bake
        return action, strip, keep
    params = _make_way(obj)
    if not given_up:                      # a figure that gave its bake up is still baked
        user_action.record_rest(obj)
    # An earlier bake the user unassigned (unused, ours), found by the name it was made with: a
    # look at every action's properties costs O(actions) a figure, 30 ms at 20,000 actions.
    old = bpy.data.actions.get(obj.name)
    if old is not None and old.get(OWNER) == obj and old.users == 0:
        bpy.data.actions.remove(old)
    action = compat.assign_new_action(obj, obj.name)
    action[BAKED_PATHS] = ""
    action[OWNER] = obj
    return action, None, params


def _make_way(obj) -> list:
    """Clear ``obj``'s animation for a bake of its own or another's: another figure's bake it
    played goes, its tweak layer stops being the active action (it plays again above the bake)
    and a user's action is stashed.  The user's keyed parameter curves, for the tweak layer."""
    adt = obj.animation_data
    current = adt.action if adt else None
    for inherited in inherited_bakes(obj):
        _drop_inherited(obj, inherited)
    if bake_layers.is_tweaks(current, obj):
        adt.action = None
    elif current is not None:
        return _stash_users(obj, current)
    return []


def _stash_users(obj, current) -> list:
    """Stash the user's ``current`` action; return its keyed parameter curves."""
    bag = compat.channels(obj)
    params = [fc for fc in (bag.fcurves if bag else ()) if fc.data_path.startswith(PARAM_PREFIX)]
    user_action.stash(obj, current)
    obj.animation_data.action = None
    return params


def _remove_baked(bag, action) -> None:
    paths = set(action.get(BAKED_PATHS, "").splitlines())
    for fc in [fc for fc in bag.fcurves if fc.data_path in paths]:
        bag.fcurves.remove(fc)
    for grp in [g for g in bag.groups if len(g.channels) == 0]:
        bag.groups.remove(grp)
    action[BAKED_PATHS] = ""


def _make_props(obj, track: PoseTrack) -> None:
    """The custom properties ``track`` keys, made on ``obj``; ``KEY_ONLY`` ones not (and removed
    from a figure baked when they were made)."""
    for prop, values in track.props.items():
        if prop.startswith(KEY_ONLY):
            obj.pop(prop, None)
        elif prop not in obj.keys():
            obj[prop] = float(values[0])


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
    action, strip, keep = _figure_action(obj)
    for name, ch in track.bones.items():
        if ch.rotation is not None:
            obj.pose.bones[name].rotation_mode = "QUATERNION"
    obj.rotation_mode = "XYZ"
    _make_props(obj, track)
    bag = _bag(obj, action, strip)
    action[bake_layers.FINGERPRINTS] = ""     # a bake cut short must not read as the user's edits
    _remove_baked(bag, action)
    # Tagged before writing: curves of a bake cut short (an exception, a crash) are still known as
    # the bake's, so the next bake or Clear Bake removes them instead of colliding with them.
    action[BAKED_PATHS] = "\n".join(sorted({c[0] for c in chans}))
    count = write_channels(bag, chans, np.asarray(track.frames, float))
    bake_layers.fingerprint(action, bag)
    first, last = float(track.frames[0]), float(track.frames[-1])
    since = held_from(obj, first)
    action.use_frame_range = since < first     # held from the scene's first frame
    if since < first:
        action.frame_end = last
        action.frame_start = since
    if strip is not None:
        _fit_strip(strip, action)
    else:
        bake_layers.push_bake(obj, action)
    _play_tweaks(obj, keep, bag)
    bake_layers.span_tweaks(obj, action.frame_range)
    return BakeResult(action, count, len(track))


#: A window of fewer keys than 1/WINDOW_KEYS of a curve's is written key by key (a key costs ~4 us,
#: a whole curve's ``foreach_set`` ~0.1 us a key: measured on a 1,441-key bake).
WINDOW_KEYS = 40
#: ``action.as_pointer() -> (its fingerprints, {(data_path, index): keys (2 n,) float32},
#: {(data_path, index): crc})``: the keys the last rewrite in place (a Live Preview drag step,
#: or the release before a drag) left and their fingerprints, so a window rewrite reads only the
#: window's keys back from Blender (whole curves cost ~70 us each to read: 12 ms a step on a
#: Rigify rig's 60 s) and updates the fingerprints from the keys it changes
#: (:func:`.key_crc.crc_after_change`; a whole curve's CRC costs with its length).  Any other
#: write drops it; it holds while the action's fingerprints are the ones written with it.
_WINDOW_KEYS: dict = {}


def _read_keys(todo, total: int) -> dict:
    keys = {}
    for fc, _, _ in todo:
        buf = np.empty(2 * total, np.float32)
        fc.keyframe_points.foreach_get("co", buf)
        keys[(fc.data_path, fc.array_index)] = buf
    return keys


def _window_points(todo, i0: int, n: int) -> list:
    """Per curve of ``todo``, the ``co`` of its keys ``i0:i0 + n`` (written through)."""
    out = []
    for fc, _, _ in todo:
        kp = fc.keyframe_points
        out.append([kp[j].co for j in range(i0, i0 + n)])
    return out


def _kept_keys(action, todo, total: int, frames):
    """``(keys, crcs, points)``: what :data:`_WINDOW_KEYS` holds for ``action`` when it is still
    good and Blender's keys on ``frames`` (the window about to be written) are its own, with
    those keys' ``co`` (:func:`_window_points`); else ``None``.  A key the user changed outside
    the window is found by the next whole rewrite (a release), which reads every key; this
    window write leaves it as it is."""
    kept = _WINDOW_KEYS.get(action.as_pointer())
    if kept is None or kept[0] != action.get(bake_layers.FINGERPRINTS):
        return None
    keys = kept[1]
    first = keys.get((todo[0][0].data_path, todo[0][0].array_index))
    if first is None:
        return None
    i0, n = int(np.searchsorted(first[0::2], frames[0])), len(frames)
    if i0 + n > total or any(len(keys.get((fc.data_path, fc.array_index), ())) != 2 * total
                             for fc, _, _ in todo):
        return None
    points = _window_points(todo, i0, n)
    for (fc, _, _), cos in zip(todo, points):
        buf = keys[(fc.data_path, fc.array_index)][2 * i0:2 * (i0 + n)].tolist()
        if [v for co in cos for v in co] != buf:
            return None
    return keys, kept[2], points


def held_from(obj, first: float) -> float:
    """The frame a figure's bake starts on: the scene's first frame when the figure's motion
    starts later (a follower waiting at the start), its first pose held until then (the bake
    action's manual frame range, a shared bake's strip from before the action's first key).
    Blender's FBX exporter at its defaults writes each NLA strip and each action (*All
    Actions*) as a take from its first frame as time 0: a bake starting at the figure's first
    frame would come back that many frames early."""
    scenes = obj.users_scene
    start = (scenes[0] if scenes else bpy.context.scene).frame_start
    return float(min(first, start))


def can_share(obj) -> bool:
    """May ``obj`` play another figure's bake, or be played by others (:func:`share_bake`)?
    Not with a ``delta_location`` of the user's (sharing sets it), nor with a bake of the kind
    older versions left assigned (played from an NLA strip, it is shared)."""
    action, strip = find_bake(obj)
    return (SHARE_OFFSET in obj or not any(obj.delta_location)) and \
        (action is None or strip is not None)


def share_bake(obj, source, track: PoseTrack, shift: int, translation) -> BakeResult:
    """Let ``obj`` play ``source``'s bake instead of one of its own: a strip on its own bake
    track, ``shift`` frames later, and ``translation`` (m) its ``delta_location``.  ``track`` is
    what its own bake would write (:func:`...mapping.shared_motion.shares` found it to be
    ``source``'s, moved and later).  Its own earlier bake goes (left to any figure playing it),
    a user's action is stashed and its tweak layer plays above, as :func:`bake_pose_track`
    does.  (Its values are the source's, which were checked finite.)"""
    _check_rig(obj, track)
    action, source_strip = find_bake(source)
    if action is None or source_strip is None or not can_share(obj):
        raise BakeError(f"{obj.name!r} cannot play the bake of {source.name!r}")
    own, strip = find_bake(obj)
    if own is not None:
        if shared_elsewhere(own):
            _give_up(obj, own, strip)
        else:
            _drop_strip(obj.animation_data, strip)
            bpy.data.actions.remove(own)
    adt = obj.animation_data or obj.animation_data_create()
    params = _make_way(obj)
    if REST not in obj:
        user_action.record_rest(obj)
    for name, ch in track.bones.items():
        if ch.rotation is not None:
            obj.pose.bones[name].rotation_mode = "QUATERNION"
    obj.rotation_mode = "XYZ"
    _make_props(obj, track)
    first, last = float(track.frames[0]), float(track.frames[-1])
    since = held_from(obj, first)
    nla = adt.nla_tracks.new()
    nla.name = bake_layers.BAKE_TRACK
    played = nla.strips.new(action.name, int(since), action)
    if compat.SLOTTED_ACTIONS:
        played.action_slot = source_strip.action_slot
    played.action_frame_end = last - shift       # the strip ends on the figure's last frame
    played.action_frame_start = since - shift    # (before the action's first key: held)
    action[SHARED] = True
    obj.delta_location = translation
    obj[SHARE_OFFSET] = list(translation)
    bake_layers.start_tweaks(obj)
    bake_layers.take_parameters(obj, params)
    bake_layers.span_tweaks(obj, (since, last))
    return BakeResult(action, 0, len(track))


def shared_source(obj):
    """``(action, strip)`` of the other figure's bake ``obj`` plays (:func:`share_bake`), or
    ``(None, None)``."""
    if SHARE_OFFSET not in obj:
        return None, None
    for track in inherited_bakes(obj):
        return track.strips[0].action, track.strips[0]
    return None, None


def rewrite_pose_track(obj, track: PoseTrack) -> BakeResult | None:
    """Write ``track``'s values into the F-curves the last bake made, in place: the same
    channels, keyed on the same frames or on a run of them (a window of the range; the keys
    around it stay).  ``None`` (nothing written) when they differ; then :func:`bake_pose_track`
    makes the curves anew.  A window's quaternions take the sign of the keys they replace, so
    a bone does not spin the long way round into the keys beside the window.

    Removing and adding F-curves makes Blender rebuild the depsgraph's relations (27 ms next to
    a Rigify rig, measured); writing the keys' values costs a few ms and only tags the action.
    A short window is written key by key (:data:`WINDOW_KEYS`), and a window following another
    in the same action reads back only its own keys (:data:`_WINDOW_KEYS`).
    """
    _check_values(obj, track)
    action, strip = find_bake(obj)
    bag = None if action is None else _bag(obj, action, strip)
    if bag is None or shared_elsewhere(action):     # others play it: a new bake, not in place
        return None
    chans = _channel_list(obj, track)
    if set(action.get(BAKED_PATHS, "").splitlines()) != {c[0] for c in chans}:
        return None
    curves = {(fc.data_path, fc.array_index): fc for fc in bag.fcurves}
    todo = [(curves.get((path, index)), path, values) for path, index, _, values in chans]
    if any(fc is None for fc, _, _ in todo):
        return None
    total = len(todo[0][0].keyframe_points)
    if any(len(fc.keyframe_points) != total for fc, _, _ in todo):
        return None
    frames, n = np.asarray(track.frames, np.float32), len(track)
    by_key = n * WINDOW_KEYS < total
    kept = _kept_keys(action, todo, total, frames) if by_key else None
    _WINDOW_KEYS.pop(action.as_pointer(), None)
    # Each curve's keys are read once (unless kept): the user's edits are checked on them, the
    # window goes into them and their fingerprint is taken from what is written.
    keys, crcs, points = (_read_keys(todo, total), None, None) if kept is None else kept
    co = keys[(todo[0][0].data_path, todo[0][0].array_index)]
    i0 = int(np.searchsorted(co[0::2], frames[0]))
    if i0 + n > total or not np.array_equal(co[0::2][i0:i0 + n], frames):
        return None
    if kept is None:
        _check_unedited(obj, action, bag, keys)
    old = {fc: keys[(fc.data_path, fc.array_index)] for fc, _, _ in todo}
    signs = {}
    for fc, path, values in todo:   # w, x, y, z of one bone: the dot with the keys replaced
        if n < total and path.endswith(".rotation_quaternion"):
            signs[path] = signs.get(path, 0.0) + float(old[fc][2 * i0 + 1]) * float(values[0])
    window = slice(2 * i0, 2 * (i0 + n))
    before = None if kept is None else np.stack([old[fc][window] for fc, _, _ in todo])
    if by_key and points is None:
        points = _window_points(todo, i0, n)
    for k, (fc, path, values) in enumerate(todo):   # frames stay; LINEAR keys ignore handles
        buf = old[fc]
        buf[2 * i0 + 1:2 * (i0 + n):2] = -values if signs.get(path, 0.0) < 0 else values
        if by_key:
            for point, v in zip(points[k], buf[2 * i0 + 1:2 * (i0 + n):2].tolist()):
                point.y = v                 # (2 us a key; point[1] = v takes 5)
        else:
            fc.keyframe_points.foreach_set("co", buf)
    _make_props(obj, track)
    # The bake's own keys now, not the user's edits.
    if kept is None:
        crcs = bake_layers.fingerprint(action, bag, keys)
    else:                   # the fingerprints of the keys written, from the ones before
        ids = [(fc.data_path, fc.array_index) for fc, _, _ in todo]
        after = np.stack([old[fc][window] for fc, _, _ in todo])
        crcs.update(zip(ids, key_crc.crc_after_change([crcs[i] for i in ids], before, after,
                                                       4 * 2 * (total - i0 - n)).tolist()))
        bake_layers.keep_fingerprints(action, crcs)
    _WINDOW_KEYS[action.as_pointer()] = (action[bake_layers.FINGERPRINTS], keys, crcs)
    action.update_tag()                 # re-evaluate the animation, relations unchanged
    return BakeResult(action, len(todo), n)


def _play_tweaks(obj, keep, bake_bag) -> None:
    """The tweak layer above the bake, holding the user's keyed parameters (``keep``: copies of
    the stashed action's, or curves moved out of an older bake that was the active action)."""
    bake_layers.start_tweaks(obj)
    bake_layers.take_parameters(obj, keep)
    for fc in [fc for fc in bake_bag.fcurves if fc in keep]:
        bake_bag.fcurves.remove(fc)       # moved, not copied, out of an older assigned bake


def baked_channels(obj):
    """The F-curve container of ``obj``'s bake layer, or ``None`` when it is not baked."""
    action, strip = find_bake(obj)
    return None if action is None else _bag(obj, action, strip)


def _fit_strip(strip, action) -> None:
    """Let a pushed-down strip play the whole re-baked range (it keeps its scale and repeats)."""
    lo, hi = action.frame_range
    if (strip.action_frame_start, strip.action_frame_end) != (lo, hi):
        strip.action_frame_end = max(hi, strip.action_frame_start + 1)
        strip.action_frame_start = lo
        strip.action_frame_end = hi


def figure_action(obj):
    """The add-on's action of ``obj`` (assigned or on one of its NLA strips), or ``None``; a
    duplicate playing its template's bake: that bake."""
    action = find_bake(obj)[0]
    if action is None:
        for track in inherited_bakes(obj):
            return track.strips[0].action
    return action


def _drop_strip(adt, strip) -> None:
    for track in adt.nla_tracks:
        if any(s == strip for s in track.strips):
            track.strips.remove(strip)
            if len(track.strips) == 0:
                adt.nla_tracks.remove(track)
            return


def clear_bake(obj) -> bool:
    """Remove what the bakes wrote and give the user's action back as it was (with any keys the
    user set while baked), and the transform and pose the first bake overrode; a tweak layer
    that holds keys is parked (:func:`.bake_layers.park_tweaks`).  ``False`` if nothing was
    baked.

    The figure's action is deleted, unless it holds keys of the user's and there is no user action
    to give them back to: then it stays, as the user's (no longer tagged as a bake).
    """
    action, strip = find_bake(obj)
    inherited = inherited_bakes(obj)
    if action is None and not inherited:
        return False
    if action is not None and shared_elsewhere(action):    # theirs to keep playing
        _give_up(obj, action, strip)
        action = None
    for track in inherited:       # another figure's bake (shared, or a duplicate's copy): not ours
        _drop_inherited(obj, track)
    user = user_action.stashed_action(obj)
    user_bag = user_action.stashed_channels(obj, user) if user is not None else None
    if action is not None:
        _remove_bake_action(obj, action, strip, user is not None, user_bag)
    bake_layers.park_tweaks(obj, user is not None, user_bag)   # frees the active slot
    if STASHED in obj:
        user_action.unstash(obj, user)
    for prop in [p for p in obj.keys() if p.startswith("turn_")]:
        del obj[prop]
    if REST in obj:
        user_action.restore_rest(obj)
    adt = obj.animation_data
    if adt.action is None and len(adt.nla_tracks) == 0 and len(adt.drivers) == 0:
        obj.animation_data_clear()        # the bake made it; nothing of the user's is in it
    return True


def _remove_bake_action(obj, action, strip, has_user: bool, user_bag) -> None:
    bag = _bag(obj, action, strip)
    if bag is not None:
        _remove_baked(bag, action)
    if user_bag is not None and bag is not None:
        user_action.give_back(bag.fcurves, user_bag)
    if has_user or bag is None or len(bag.fcurves) == 0:
        if strip is not None:
            _drop_strip(obj.animation_data, strip)
        else:
            obj.animation_data.action = None
        bpy.data.actions.remove(action)
    else:                                 # only the user's keys are left: it is their action now
        for key in (BAKED_PATHS, OWNER):
            del action[key]


def layers(obj) -> list:
    """``[(kind, name, state)]`` of ``obj``'s layers, top first, for the panel: kind is
    ``'TWEAKS'``, ``'BAKE'`` or ``'USER'``."""
    out = []
    tweaks, parked = bake_layers.tweak_layer(obj)
    if tweaks is not None:
        bag = bake_layers.tweak_channels(obj)
        n = sum(len(fc.keyframe_points) for fc in bag.fcurves) if bag else 0
        out.append(("TWEAKS", tweaks.name, f"{n} keys" + (", parked (muted)" if parked else "")))
    action, strip = find_bake(obj)
    shared, played = shared_source(obj)
    if action is not None:
        where = "NLA strip" if strip is not None else "active action"
        lo, hi = action.frame_range
        out.append(("BAKE", action.name, f"{where}, frames {lo:g}-{hi:g}"))
    elif shared is not None:
        owner = shared.get(OWNER)
        whose = f"{owner.name}'s" if owner is not None else "shared"
        out.append(("BAKE", shared.name, f"{whose} bake, frames {played.frame_start:g}-"
                                         f"{played.frame_end:g} (moved by Delta Transform)"))
    user = user_action.stashed_action(obj)
    if user is not None:
        out.append(("USER", user.name, "kept for Clear Bake (muted)"))
    return out
