"""The turn state per frame in an exported file: one Empty per state property, moved by it.

The bake keys the model's state on the armature as custom properties (``turn_lean`` and the
others of :data:`~blender_turning.mapping.base.STATE_PROPS`).  Neither of Blender's exporters
writes an animated custom property (FBX writes custom properties once, glTF as a node's static
``extras``), and neither importer reads one back, but both carry an object's animated transform.
With *Export Turn State* (Bake Turns, redo panel) :func:`bake_state` adds, as a child of the
figure, an Empty ``"<figure> turn_lean"`` (and one for each other property) whose X location is
driven by the property (its other channels stay at rest): the file then holds each property's
value on every frame as that Empty's X translation in its parent's frame.  The driver reads the
property as it plays, from the bake's NLA strip with the tweak layer above (docs/layers.md), so
the Empties follow every rebake and Live Preview.

As the equipment of a user's rig (:mod:`.export_ready`) each Empty also gets an action holding
its rest, so glTF samples it, and FBX's first take (the bake's NLA strip, with every exported
object sampled) carries it.  :func:`clear_state` deletes them (a bake without the option, Clear
Bake, Remove Figure).
"""
from __future__ import annotations

import bpy

from ...mapping.base import STATE_PROPS
from ..scene.retarget_adapter import _drive
from .export_ready import key_in_place

#: ID property on a state Empty: the figure (object) whose property moves it.
CARRIES = "turning_state_of"
#: Viewport size of a state Empty (m): a dot; the value is its position, not its size.
SIZE = 0.02


def carriers(fig) -> list:
    """The state Empties of ``fig`` (its children made by :func:`bake_state`)."""
    return [o for o in fig.children if o.get(CARRIES) == fig]


def bake_state(fig, frames) -> int:
    """Make ``fig``'s state Empties (one for each state property it has), keyed for the
    exporters on the first and last of ``frames``.  Returns the Empties made."""
    clear_state(fig)
    collection = fig.users_collection[0] if fig.users_collection \
        else bpy.context.scene.collection
    made = 0
    for prop in STATE_PROPS:
        if prop not in fig.keys():
            continue
        emp = bpy.data.objects.new(f"{fig.name} {prop}", None)
        emp.empty_display_type, emp.empty_display_size = "PLAIN_AXES", SIZE
        collection.objects.link(emp)
        emp.parent = fig                  # in the figure's frame, exported with it
        emp[CARRIES] = fig
        _drive(emp, "location", 0, fig, prop, 1.0)
        key_in_place(fig, emp, frames)
        made += 1
    return made


def clear_state(fig) -> None:
    """Delete ``fig``'s state Empties and their actions."""
    for emp in carriers(fig):
        action = emp.animation_data.action if emp.animation_data else None
        bpy.data.objects.remove(emp)
        if action is not None and action.users == 0:
            bpy.data.actions.remove(action)
