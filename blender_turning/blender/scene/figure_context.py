"""What every operator shares: finding the figure in the context, poll reasons, and the checks
that a figure's rig can carry its sport's bake (run before anything is written)."""
from __future__ import annotations

import re
import traceback

from ...core.errors import TurningError
from ...mapping.rig_spec import load_rig
from ..props.figure import figure_settings
from ..registry_items import sport_label
from .rig_builder import RIG_TAG


def context_figure(context):
    """The active figure's armature: the active object, or the armature its body belongs to."""
    obj = getattr(context, "active_object", None)
    if obj is not None and figure_settings(obj) is None and obj.parent is not None:
        obj = obj.parent
    return obj if figure_settings(obj) is not None else None


#: Custom property of a collection made by Add Crowd (:mod:`.ops_crowd`): a crowd's figures.
CROWD_TAG = "turning_crowd"


def crowd_collection(context):
    """The active collection when it is a crowd (made by Add Crowd), else ``None``."""
    coll = getattr(context, "collection", None)
    return coll if coll is not None and coll.get(CROWD_TAG) else None


def collection_figures(coll) -> list:
    """The figures of a collection (and its children), by name."""
    return sorted((o for o in coll.all_objects if figure_settings(o) is not None),
                  key=lambda o: o.name)


def selected_figures(context) -> list:
    """Every selected figure (a selected body mesh counts for its armature), the active one
    first, the others by name; each once.  With no figure selected and a Crowd collection
    active (clicked in the Outliner): its figures."""
    active = context_figure(context)
    found = {}
    for obj in getattr(context, "selected_objects", ()) or ():
        if figure_settings(obj) is None and obj.parent is not None:
            obj = obj.parent
        if figure_settings(obj) is not None:
            found[obj.name] = obj
    if not found and crowd_collection(context) is not None:
        figs = collection_figures(crowd_collection(context))
        if figs:
            return figs
    rest = [found[name] for name in sorted(found) if active is None or name != active.name]
    return ([active] if active is not None else []) + rest


def poll_figure(cls, context) -> bool:
    """Poll for operators acting on the active figure; says why when it cannot."""
    if context.mode != "OBJECT":
        cls.poll_message_set("Switch to Object Mode first")
        return False
    fig = context_figure(context)
    if fig is None:
        figs = selected_figures(context)          # a Crowd collection's, when it is active
        fig = figs[0] if figs else None
    if fig is None:
        cls.poll_message_set("No figure selected: add one with Add Figure, or select one")
        return False
    if not fig.is_editable:
        # Python may still write to linked data; the keys would be lost on save, silently.
        cls.poll_message_set(f"{fig.name} is linked from another file: make it local "
                             "(Object > Relations > Make Local) or a library override first")
        return False
    adt = fig.animation_data
    if adt is not None and adt.use_tweak_mode:
        cls.poll_message_set(f"{fig.name}'s NLA is in tweak mode: leave it first (Tab in the "
                             "NLA editor)")
        return False
    return True


def rig_bones(sport: str) -> tuple:
    """The bones the ``sport``'s mapping keys (every bone of its rig spec; the loader caches the
    spec by its file)."""
    return load_rig(sport.lower()).bone_names


class RigMismatch(ValueError):
    """A figure's armature that cannot carry its sport's motion; the message says what to do."""


def check_figure(obj) -> None:
    """Raise :class:`RigMismatch` when ``obj``'s armature lacks a bone its sport's mapping keys,
    or its Sport was switched away from the sport the rig was built for."""
    sport = obj.turning.sport
    built = obj.get(RIG_TAG)
    if isinstance(built, str) and built.upper() != sport:
        raise RigMismatch(
            f"the rig was built for the {sport_label(built)} but Sport is {sport_label(sport)}: "
            f"choose the {sport_label(built)} preset again, or add a new figure with "
            f"Add Figure > {sport_label(sport)}")
    from . import retarget_adapter                   # a user's rig: its bone map's joints
    if retarget_adapter.is_user_rig(obj):
        from ...mapping.retarget.bone_map import require_joints
        try:
            require_joints(retarget_adapter.figure_bone_map(obj), obj.data.bones.keys(),
                           f"armature {obj.data.name!r}")
        except ValueError as exc:
            raise RigMismatch(f"{exc}: undo the change, or map the joints again in Your Rig") \
                from None
        return
    missing = [b for b in rig_bones(sport) if b not in obj.data.bones]
    if missing:
        more = f" (and {len(missing) - 1} more)" if len(missing) > 1 else ""
        raise RigMismatch(
            f"armature {obj.data.name!r} has no bone {missing[0]!r}{more}, which the "
            f"{sport_label(sport)} needs: undo its removal, or add a new figure with "
            f"Add Figure > {sport_label(sport)}")


#: Which setting holds each of the core's bounds (the names its messages and scene files use).
BOUND_SETTING = {"C_f_max": "Limits > Max Curvature", "dC_f_max": "Limits > Max Curvature Rate",
                 "theta_fall": "Limits > Fall Angle", "physical branch": "Body > COM Height"}
_BOUND_NAMES = re.compile(r"\b(dC_f_max|C_f_max|theta_fall)\b")


def in_settings(msg: str) -> str:
    """``msg`` (a core error's text) with each bound it names followed by the setting that holds
    it, as the panels label it: ``C_f_max (Limits > Max Curvature) = 0.5 1/m``."""
    return _BOUND_NAMES.sub(lambda m: f"{m[1]} ({BOUND_SETTING[m[1]]})", msg)


def report_error(op, title: str, fig_name: str, exc: BaseException, note: str = "") -> set:
    """Report ``exc`` as one line and cancel.  Bad input (``ValueError``, the core's errors) says
    what is wrong; anything else is a bug: its traceback goes to the console, the report says so.
    Callers report only before they write, so either way the scene is unchanged."""
    if isinstance(exc, (ValueError, TurningError)):
        msg = in_settings(str(exc))
    else:
        traceback.print_exception(type(exc), exc, exc.__traceback__)
        msg = (f"internal error ({type(exc).__name__}: {exc}); nothing was changed. Please "
               "report it with the traceback from the system console")
    op.report({"ERROR"}, f"{title}: {fig_name}: {msg}{note}")
    return {"CANCELLED"}


def end_modal(op, context) -> None:
    """Undo what a modal operator's ``invoke`` set up: its timer, the progress bar and the status
    text (the workspace is None while a file is being opened)."""
    wm = context.window_manager
    if op._timer is not None:
        wm.event_timer_remove(op._timer)
        op._timer = None
    wm.progress_end()
    if context.workspace is not None:
        context.workspace.status_text_set(None)
