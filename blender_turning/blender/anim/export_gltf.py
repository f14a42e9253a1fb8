"""The glTF exporter's user extension (Blender's ``io_scene_gltf2`` calls it for an enabled add-on
that offers ``glTF2ExportUserExtension``): each exported figure carries its own animation only.

With one armature in the export the exporter, by default, takes every action in the file that
animates bones as one of that armature's animations: a glTF of one figure would hold every
figure's bake (on import, the skier plays the cyclist's motion).  Every bake action records its
owner (``bake.OWNER``), so :meth:`glTF2ExportUserExtension.gather_actions_hook` drops, from an
object's actions, the bakes of other objects.  The keyed equipment of a user's rig
(:mod:`.export_ready`) is merged into its figure's animation (one glTF animation per figure,
which an importer plays as one).
"""
from __future__ import annotations

from .. import compat
from . import bake, bake_layers

MERGE_INTO = bake.MERGE_INTO


def _foreign(action, obj) -> bool:
    """A bake of another object (a figure or a piece of equipment)."""
    owner = action.get(bake.OWNER) if action is not None else None
    return owner is not None and owner != obj


def _empty_tweaks(action, obj) -> bool:
    """The figure's tweak layer (docs/layers.md) without a key: nothing of its own to export."""
    return bake_layers.is_tweaks(action, obj) and \
        not any(len(fc.keyframe_points) for fc in compat.all_fcurves(action))


def _merge_name(action, obj):
    """The glTF animation ``action`` joins: a piece of equipment's, its figure's; the figure's
    tweak layer, its bake's (one animation per figure); ``None``: its own."""
    if MERGE_INTO in action:
        return action[MERGE_INTO]
    if bake_layers.is_tweaks(action, obj):
        baked = bake.figure_action(obj)
        return None if baked is None else baked.name
    return None


class glTF2ExportUserExtension:  # noqa: N801 (the name the exporter looks for)
    def gather_actions_hook(self, blender_object, actions, export_settings):
        if hasattr(actions, "actions"):                   # 4.4+: ActionsData of ActionData
            for key in list(actions.actions):
                kept = [a for a in actions.actions[key] if not _foreign(a.action, blender_object)
                        and not _empty_tweaks(a.action, blender_object)]
                for data in kept:
                    name = _merge_name(data.action, blender_object)
                    if name is not None:
                        data.force_name(name)
                if kept:
                    actions.actions[key] = kept
                else:
                    del actions.actions[key]
            return
        # 4.2/4.3: parallel lists of actions, NLA track names and target types; animations
        # merge by track name.
        keep = [a for a in actions.blender_actions if not _foreign(a, blender_object)
                and not _empty_tweaks(a, blender_object)]
        actions.blender_actions = keep
        for act in keep:
            name = _merge_name(act, blender_object)
            if name is not None:
                actions.blender_tracks[act.name] = name
            elif act.get(bake.OWNER) == blender_object and _has_keyed_pieces(blender_object):
                actions.blender_tracks[act.name] = act.name


def _has_keyed_pieces(obj) -> bool:
    """Keyed equipment or state Empties, whose animations merge into ``obj``'s."""
    from .export_ready import equipment, KEYED
    from .export_state import carriers
    return any(KEYED in e for e in equipment(obj)) or bool(carriers(obj))
