"""A figure that plays another's bake (Shared motion, docs/crowds.md) exports as a figure with a
bake of its own: for the length of an export its strip plays a copy of that bake, keyed on the
frames it plays them on and owned by it, then the shared bake again.

glTF's exporter (its default *Actions* mode) samples each action of an object as its active
action with the NLA off, over the action's own frames: the shared bake, sampled so, is the
other figure's motion (the strip's time shift lost), and the export hook
(:mod:`.export_gltf`) drops another figure's bake from a figure's animations, so the follower's
file would have none (and its keyed equipment, merged into an animation named after the shared
bake, would be an animation of its own).  With the copy the follower is, to every exporter and
to the hook, a figure with its own bake on its own strip (its tweak layer above, its
``delta_location`` as it is): what Blender shows, and only that figure's.  FBX's *NLA Strips*
takes sample every exported object with its strips playing (the shift kept); the copy changes
nothing there, and Export FBX with Tweaks (:mod:`.export_fbx`) flattens a follower's tweaks as
any figure's.
"""
from __future__ import annotations

from contextlib import contextmanager

import bpy
import numpy as np

from .. import compat
from . import bake, bake_layers


def _shift_keys(action, shift: float) -> None:
    """Move every key of ``action`` (and its manual frame range) ``shift`` frames later."""
    for fc in compat.all_fcurves(action):
        kp = fc.keyframe_points
        for prop in ("co", "handle_left", "handle_right"):
            buf = np.empty(2 * len(kp), np.float32)
            kp.foreach_get(prop, buf)
            buf[0::2] += shift
            kp.foreach_set(prop, buf)
        fc.update()
    if action.use_frame_range:
        action.frame_end += shift
        action.frame_start += shift


def _own_copy(fig, undo) -> None:
    """Let ``fig``'s strip play a copy of the shared bake keyed on the scene frames it plays it
    on; append to ``undo`` the function that gives the shared bake back (before any change)."""
    shared, strip = bake.shared_source(fig)
    slot = compat.strip_slot(strip)
    bounds = strip.frame_start, strip.frame_end, strip.action_frame_start, strip.action_frame_end
    shift = strip.frame_start - strip.action_frame_start        # a shared strip's scale is 1
    copy = shared.copy()

    def restore():
        strip.action = shared
        if slot is not None:
            strip.action_slot = slot
        strip.action_frame_start, strip.action_frame_end = bounds[2:]
        strip.frame_start, strip.frame_end = bounds[:2]
        bpy.data.actions.remove(copy)
    undo.append(restore)
    copy.name = fig.name
    copy[bake.OWNER] = fig
    copy.pop(bake.SHARED, None)
    _shift_keys(copy, shift)
    strip.action = copy
    if slot is not None:
        strip.action_slot = compat.slot_named(copy, slot.identifier)
    strip.action_frame_end = max(bounds[3] + shift, strip.action_frame_start + 1)
    strip.action_frame_start = bounds[2] + shift
    strip.action_frame_end = bounds[3] + shift
    strip.frame_start, strip.frame_end = bounds[:2]
    _merge_pieces(fig, shared.name, copy.name, undo)
    tweaks = bake_layers.tweak_layer(fig)[0]
    if tweaks is not None:          # the figure's frames, which its tweak layer spans: glTF
        #                             samples the tweak layer over the bake only when they match
        copy.use_frame_range = True
        copy.frame_end = max(tweaks.frame_range[1], copy.frame_start + 1)
        copy.frame_start, copy.frame_end = tweaks.frame_range


def _merge_pieces(fig, shared: str, own: str, undo) -> None:
    """The keyed equipment and state Empties of ``fig`` merge into its glTF animation, named
    after the bake it plays (:func:`.export_ready.key_in_place`): the copy's name for the
    export."""
    from .export_ready import equipment
    from .export_state import carriers
    for obj in equipment(fig) + carriers(fig):
        action = obj.animation_data.action if obj.animation_data else None
        if action is not None and action.get(bake.MERGE_INTO) == shared:
            action[bake.MERGE_INTO] = own
            undo.append(lambda action=action: action.__setitem__(bake.MERGE_INTO, shared))


def own_copies(figures) -> list:
    """Give each of ``figures`` that plays another's bake a copy of its own (see the module
    doc); returns the functions that undo it, to call in reverse order."""
    undo = []
    try:
        for fig in figures:
            if fig.type == "ARMATURE" and bake.shared_source(fig)[0] is not None:
                _own_copy(fig, undo)
    except Exception:
        restore_all(undo)
        raise
    return undo


def restore_all(undo) -> None:
    for restore in reversed(undo):
        restore()
    undo.clear()


@contextmanager
def unshared(figures):
    """Within the block each of ``figures`` that plays another's bake plays a copy of its own;
    everything is given back on leaving (also after an error), and the scene's frame evaluated
    again with the shared bake."""
    scene = bpy.context.scene
    frame = scene.frame_current, scene.frame_subframe
    undo = own_copies(figures)
    try:
        yield
    finally:
        restore_all(undo)
        scene.frame_set(frame[0], subframe=frame[1])
