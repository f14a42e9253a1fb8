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


#: On an export's copy: the shared bake it stands in for (``of``), the strip's frames before the
#: copy (``strip``: start, end, action start, action end) and its slot's identifier (``slot``).
#: :func:`restore_copies` finds the copies by it in the file, so no list of them can outlive the
#: data it names (a file loaded after a failed export frees them).
COPY = "turn_export_copy"


def _own_copy(fig) -> None:
    """Let ``fig``'s strip play a copy of the shared bake keyed on the scene frames it plays it
    on, marked with what gives the shared bake back (:data:`COPY`)."""
    shared, strip = bake.shared_source(fig)
    slot = compat.strip_slot(strip)
    bounds = strip.frame_start, strip.frame_end, strip.action_frame_start, strip.action_frame_end
    shift = strip.frame_start - strip.action_frame_start        # a shared strip's scale is 1
    copy = shared.copy()
    copy[COPY] = {"of": shared, "strip": list(bounds),
                  "slot": slot.identifier if slot is not None else ""}
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
    _merge_pieces(fig, shared.name, copy.name)
    tweaks = bake_layers.tweak_layer(fig)[0]
    if tweaks is not None:          # the figure's frames, which its tweak layer spans: glTF
        #                             samples the tweak layer over the bake only when they match
        copy.use_frame_range = True
        copy.frame_end = max(tweaks.frame_range[1], copy.frame_start + 1)
        copy.frame_start, copy.frame_end = tweaks.frame_range


def _give_back(fig, strip, copy) -> None:
    """``fig``'s ``strip`` plays the shared bake ``copy`` stands in for, on its frames."""
    mark = copy[COPY]
    shared, bounds = mark["of"], list(mark["strip"])
    strip.action = shared
    slot = compat.slot_named(shared, mark["slot"])
    if slot is not None:
        strip.action_slot = slot
    strip.action_frame_start, strip.action_frame_end = bounds[2:]
    strip.frame_start, strip.frame_end = bounds[:2]
    _merge_pieces(fig, copy.name, shared.name)


def _merge_pieces(fig, merged: str, into: str) -> None:
    """The keyed equipment and state Empties of ``fig`` that merge into its glTF animation named
    ``merged`` (:func:`.export_ready.key_in_place`) merge into ``into``'s: the copy's for the
    export, the shared bake's again after it."""
    from .export_ready import equipment
    from .export_state import carriers
    for obj in equipment(fig) + carriers(fig):
        action = obj.animation_data.action if obj.animation_data else None
        if action is not None and action.get(bake.MERGE_INTO) == merged:
            action[bake.MERGE_INTO] = into


def own_copies(figures) -> None:
    """Give each of ``figures`` that plays another's bake a copy of its own (see the module
    doc), after giving back any copies an export left (:func:`restore_copies`)."""
    restore_copies()
    try:
        for fig in figures:
            if fig.type == "ARMATURE" and bake.shared_source(fig)[0] is not None:
                _own_copy(fig)
    except Exception:
        restore_copies()
        raise


def restore_copies() -> None:
    """Every figure playing an export's copy plays the shared bake again, on the frames it
    played it on, and the copies are gone: the scene as it was before the export."""
    copies = [a for a in bpy.data.actions if COPY in a]
    if not copies:
        return
    for fig in bpy.data.objects:
        adt = fig.animation_data
        for strip in (s for t in (adt.nla_tracks if adt else ()) for s in t.strips):
            if strip.action in copies:
                _give_back(fig, strip, strip.action)
    for copy in copies:
        bpy.data.actions.remove(copy)


@contextmanager
def unshared(figures):
    """Within the block each of ``figures`` that plays another's bake plays a copy of its own;
    everything is given back on leaving (also after an error), and the scene's frame evaluated
    again with the shared bake."""
    scene = bpy.context.scene
    frame = scene.frame_current, scene.frame_subframe
    own_copies(figures)
    try:
        yield
    finally:
        restore_copies()
        scene.frame_set(frame[0], subframe=frame[1])
