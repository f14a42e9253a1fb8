"""The animator's tweaks in an FBX file: the bake and its tweak layer flattened into one take for
the length of an export, then put back as they were.

FBX's exporter, at its defaults (*NLA Strips* and *All Actions* on), writes one take for each
unmuted NLA strip of the exported objects, that strip alone playing and no active action, then
one take for each action that fits an object (all of its F-curves resolve on it), over the NLA.
The first take is the one an importer plays: the figure's bake strip (docs/layers.md), without
the tweak layer above it.  No setting of the exporter plays a strip with the active action over
it, so :func:`flattened` does it for one export (Export FBX with Tweaks, docs/export.md):

- the figure's evaluated channels (every curve of its bake and of its tweak layer) are read frame
  by frame as Blender plays them, over the bake strip's frames, into a new action that plays
  from the bake's strip in the bake's place: the strip's take is the bake with the tweaks;
- every tweak layer of the file gets a curve of a property no object has (``bake.KEY_ONLY``), so
  it fits no object and makes no take: the figure's own would play its tweaks twice, over the
  flattened strip, and another figure's (the same bones) would play that figure's tweaks on this
  one;

and on leaving (also after an error) the strip plays the bake again, the tweak layer is the
active action again, the tweak layers lose that curve, the flattened action is deleted and the
scene is on its frame again.
"""
from __future__ import annotations

from contextlib import contextmanager

import bpy
import numpy as np

from .. import compat
from . import bake, bake_layers


def tweaked(obj) -> bool:
    """``obj`` plays a tweak layer that holds keys over its bake's NLA strip."""
    if obj.type != "ARMATURE" or bake.find_bake(obj)[1] is None:
        return False
    action, _ = bake_layers.tweak_layer(obj)
    bag = bake_layers.tweak_channels(obj)
    return bake_layers.playing(obj, action) and bag is not None and \
        any(len(fc.keyframe_points) for fc in bag.fcurves)


@contextmanager
def flattened(figures):
    """Within the block each of ``figures`` that plays tweaks (:func:`tweaked`) has its bake
    strip play the bake and the tweaks as one action, and its tweak layer fits no object (see
    the module doc); everything is given back on leaving."""
    scene = bpy.context.scene
    frame = scene.frame_current, scene.frame_subframe
    undo = []
    try:
        figs = [f for f in figures if tweaked(f)]
        for fig in figs:
            _flatten(fig, scene, undo)
        for action in [a for a in bpy.data.actions if bake_layers.TWEAKS_OF in a]:
            undo.append(_fit_nothing(action))
        scene.frame_set(frame[0], subframe=frame[1])
        yield len(figs)
    finally:
        for restore in reversed(undo):
            restore()
        scene.frame_set(frame[0], subframe=frame[1])


def _curves(action, slot) -> list:
    bag = compat.channelbag(action, slot)
    return list(bag.fcurves) if bag is not None else []


def _frames(strip) -> tuple:
    """``(action frames, scene frames)``: the whole frames of the strip's action and the scene
    frames it plays them on (its first repeat)."""
    lo, hi = strip.action_frame_start, strip.action_frame_end
    local = np.arange(np.ceil(lo), np.floor(hi) + 1.0)
    return local, strip.frame_start + (local - lo) * strip.scale


def _sample(fig, scene, strip, curves) -> tuple:
    """``(action frames, [(data_path, index, group, values)])``: each channel of ``curves`` as
    Blender plays it on the strip's frames (a curve that resolves on nothing, the bake's take
    property: its keys)."""
    local, frames = _frames(strip)
    paths = {}
    for fc in curves:
        key = (fc.data_path, fc.array_index)
        if key not in paths:
            paths[key] = (fc.group.name if fc.group else "Turning", fc)
    values = {key: np.empty(len(frames)) for key in paths}
    for i, f in enumerate(frames):
        scene.frame_set(int(np.floor(f)), subframe=float(f - np.floor(f)))
        for (path, index), (_, fc) in paths.items():
            try:
                value = fig.path_resolve(path)
            except ValueError:                       # resolves on no object
                values[(path, index)][i] = fc.evaluate(local[i])
                continue
            values[(path, index)][i] = value[index] if hasattr(value, "__len__") else value
    return local, [(path, index, group, values[(path, index)])
                   for (path, index), (group, _) in paths.items()]


def _flatten(fig, scene, undo) -> None:
    """Flatten ``fig``'s bake and tweaks into its bake strip; append to ``undo`` the function
    that gives everything back (before changing anything)."""
    adt = fig.animation_data
    baked, strip = bake.find_bake(fig)
    tweaks = adt.action
    tweak_slot = compat.slot_identifier(fig)
    strip_slot = compat.strip_slot(strip)
    curves = _curves(baked, strip_slot) + list(bake_layers.tweak_channels(fig).fcurves)
    local, channels = _sample(fig, scene, strip, curves)
    bounds = strip.frame_start, strip.frame_end, strip.action_frame_start, strip.action_frame_end
    flat = None

    def restore():
        if strip.action != baked:
            strip.action = baked
            if strip_slot is not None:
                strip.action_slot = strip_slot
        if (strip.frame_start, strip.frame_end, strip.action_frame_start,
                strip.action_frame_end) != bounds:
            strip.action_frame_start, strip.action_frame_end = bounds[2:]
            strip.frame_start, strip.frame_end = bounds[:2]
        if flat is not None:
            bpy.data.actions.remove(flat)
        compat.restore_action(fig, tweaks, tweak_slot)
    undo.append(restore)
    adt.action = None
    flat = compat.assign_new_action(fig, f"{fig.name} with tweaks")
    bake.write_channels(compat.channels(fig), channels, local)
    flat_slot = compat.slot_named(flat, compat.slot_identifier(fig))
    adt.action = None
    strip.action = flat
    if flat_slot is not None:
        strip.action_slot = flat_slot


def _fit_nothing(action):
    """Give ``action`` (a tweak layer) a curve of a property no object has, for FBX's *All
    Actions*; return the function that removes it."""
    owner = action[bake_layers.TWEAKS_OF]
    slots = getattr(action, "slots", None)
    bag = compat.channelbag(action, slots[0] if slots else None)
    if bag is None:
        return lambda: None
    name = owner.name if owner is not None else action.name
    path = f'["{bpy.utils.escape_identifier(bake.KEY_ONLY + name)}"]'
    had_group = bag.groups.get("Turning") is not None
    curve = compat.new_fcurve(bag, path, 0, "Turning")
    curve.keyframe_points.insert(0.0, 0.0)

    def restore():
        bag.fcurves.remove(curve)
        group = bag.groups.get("Turning")
        if not had_group and group is not None:          # 4.2 keeps an emptied group
            bag.groups.remove(group)
    return restore
