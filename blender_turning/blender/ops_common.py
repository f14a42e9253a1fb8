"""What every operator shares: finding the figure in the context, and poll reasons."""
from __future__ import annotations

from .props import figure_settings


def context_figure(context):
    """The active figure's armature: the active object, or the armature its body belongs to."""
    obj = getattr(context, "active_object", None)
    if obj is not None and figure_settings(obj) is None and obj.parent is not None:
        obj = obj.parent
    return obj if figure_settings(obj) is not None else None


def selected_figures(context) -> list:
    """Every selected figure (a selected body mesh counts for its armature), the active one
    first, the others by name; each once."""
    active = context_figure(context)
    found = {}
    for obj in getattr(context, "selected_objects", ()) or ():
        if figure_settings(obj) is None and obj.parent is not None:
            obj = obj.parent
        if figure_settings(obj) is not None:
            found[obj.name] = obj
    rest = [found[name] for name in sorted(found) if active is None or name != active.name]
    return ([active] if active is not None else []) + rest


def poll_figure(cls, context) -> bool:
    """Poll for operators acting on the active figure; says why when it cannot."""
    if context.mode != "OBJECT":
        cls.poll_message_set("Switch to Object Mode first")
        return False
    if context_figure(context) is None:
        cls.poll_message_set("No figure selected: add one with Add Figure, or select one")
        return False
    return True
