"""What every operator shares: finding the figure in the context, and poll reasons."""
from __future__ import annotations

from .props import figure_settings


def context_figure(context):
    """The active figure's armature: the active object, or the armature its body belongs to."""
    obj = getattr(context, "active_object", None)
    if obj is not None and figure_settings(obj) is None and obj.parent is not None:
        obj = obj.parent
    return obj if figure_settings(obj) is not None else None


def poll_figure(cls, context) -> bool:
    """Poll for operators acting on the active figure; says why when it cannot."""
    if context.mode != "OBJECT":
        cls.poll_message_set("Switch to Object Mode first")
        return False
    if context_figure(context) is None:
        cls.poll_message_set("No figure selected: add one with Add Figure, or select one")
        return False
    return True
