"""The glTF exporter's user extension (Blender's ``io_scene_gltf2`` calls it for an enabled add-on
that offers ``glTF2ExportUserExtension``): each exported figure carries its own animation only.

With one armature in the export the exporter, by default, takes every action in the file that
animates bones as one of that armature's animations: a glTF of one figure would hold every
figure's bake (on import, the skier plays the cyclist's motion).  Every bake action records its
owner (``bake.OWNER``) and every tweak layer its figure (``bake_layers.TWEAKS_OF``), so
:meth:`glTF2ExportUserExtension.gather_actions_hook` drops, from an object's actions, the bakes
and tweak layers of other objects.  The keyed equipment of a user's rig
(:mod:`.export_ready`) is merged into its figure's animation (one glTF animation per figure,
which an importer plays as one).

The exporter (its default *Actions* mode) samples each action as the object's active action with
the NLA off, so a figure's tweak layer (docs/layers.md), sampled alone, would put its offsets on
the rest pose.  The tweak layer is sampled with the NLA on instead
(:meth:`glTF2ExportUserExtension.post_animation_switch_hook`): every bone, and each transform of
the armature object the layer keys, as Blender plays them, the bake's strip under the tweaks.
The bake's own animation keeps only the channels the tweak layer's leaves out (the armature
object's travel: :meth:`glTF2ExportUserExtension.pre_gather_animation_hook`), and the two merge
into the figure's one animation.

A figure that plays another's bake (Shared motion) plays a copy of its own for the length of the
export (:mod:`.export_shared`; :func:`glTF2_pre_export_callback` and
:func:`glTF2_post_export_callback`, and after a failed export the timer and handler there), and
exports as a figure with its own bake.
"""
from __future__ import annotations

import bpy

from .. import compat
from . import bake, bake_layers, export_shared

MERGE_INTO = bake.MERGE_INTO


def glTF2_pre_export_callback(export_settings):  # noqa: N802 (the name the exporter looks for)
    """Before the exporter gathers anything: each figure playing another's bake plays a copy of
    its own (:mod:`.export_shared`).  The exporter skips :func:`glTF2_post_export_callback` when
    the export fails: then the timer gives the scene back as soon as the failed export returns
    (in Blender's window), and a save (:func:`restore_before_save`) or the next export before
    it, should it come first."""
    export_shared.own_copies(list(bpy.context.scene.objects))
    if not bpy.app.timers.is_registered(restore_after_export):
        bpy.app.timers.register(restore_after_export, first_interval=0.0)


def glTF2_post_export_callback(export_settings):  # noqa: N802
    export_shared.restore_copies()


def restore_after_export():
    """The timer of :func:`glTF2_pre_export_callback` (returns ``None``: runs once)."""
    export_shared.restore_copies()


@bpy.app.handlers.persistent
def restore_before_save(*_args):
    """A ``save_pre`` handler: no file is saved with an export's copies."""
    export_shared.restore_copies()


def _foreign(action, obj) -> bool:
    """A bake of another object (a figure or a piece of equipment)."""
    owner = action.get(bake.OWNER) if action is not None else None
    return owner is not None and owner != obj


def _sampled_tweaks(obj):
    """The tweak layer ``obj`` plays over its bake's NLA strip, sampled for the figure's bones
    (over its own frame range, the bake's: ``bake_layers.span_tweaks``), or ``None``: none, or
    one whose range leaves out some of the bake's frames (then the file has the bake alone)."""
    baked, strip = bake.find_bake(obj)
    tweaks, _ = bake_layers.tweak_layer(obj)
    if strip is None or not bake_layers.playing(obj, tweaks):
        return None
    (lo, hi), (start, end) = tweaks.frame_range, baked.frame_range
    return tweaks if lo <= start and hi >= end else None


def _kept(action, obj, tweaks) -> bool:
    """Exported as an animation of ``obj``: not another object's bake, not a tweak layer other
    than the one ``obj`` plays (``tweaks``)."""
    if _foreign(action, obj):
        return False
    return bake_layers.TWEAKS_OF not in action or action == tweaks


#: glTF's target path of each transform property an action may key on an object.
_PATHS = {"location": "translation", "rotation_quaternion": "rotation",
          "rotation_euler": "rotation", "rotation_axis_angle": "rotation", "scale": "scale"}


def _object_paths(action) -> set:
    """The glTF paths of the armature object's own transform that ``action`` keys."""
    return {_PATHS[fc.data_path] for fc in compat.all_fcurves(action) if fc.data_path in _PATHS}


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
    def __init__(self):
        self.tweaks = {}      # object name: the tweak layer it plays, before any switch

    def gather_actions_hook(self, blender_object, actions, export_settings):
        tweaks = _sampled_tweaks(blender_object)
        if tweaks is not None:
            self.tweaks[blender_object.name] = tweaks
        if hasattr(actions, "actions"):                   # 4.4+: ActionsData of ActionData
            for key in list(actions.actions):
                kept = [a for a in actions.actions[key] if _kept(a.action, blender_object, tweaks)]
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
        keep = [a for a in actions.blender_actions if _kept(a, blender_object, tweaks)]
        actions.blender_actions = keep
        for act in keep:
            name = _merge_name(act, blender_object)
            if name is not None:
                actions.blender_tracks[act.name] = name
            elif act.get(bake.OWNER) == blender_object and (
                    tweaks is not None or _has_keyed_pieces(blender_object)):
                actions.blender_tracks[act.name] = act.name

    def post_animation_switch_hook(self, blender_object, blender_action, *args):
        """The exporter made ``blender_action`` active with the NLA off (``args``: its slot on
        4.4+, the NLA track's name, the target type, the settings); a figure's tweak layer is
        sampled with the NLA on, over the bake's strip, as Blender plays it."""
        if args[-2] == "OBJECT":
            blender_object.animation_data.use_nla = \
                self.tweaks.get(blender_object.name) == blender_action

    def pre_gather_animation_hook(self, animation, blender_action, *args):
        """An armature's sampled animation (``animation``: its channels on 4.4+; ``args``: the
        slot on 4.4+, the object, the settings): a figure's bake, when its tweak layer is
        exported too, keeps only the channels the tweak layer's animation leaves out (the merge
        keeps the first animation's channel of a target, and the bake's name sorts first)."""
        obj = args[-2]
        tweaks = self.tweaks.get(obj.name)
        if tweaks is None or blender_action is None or blender_action.get(bake.OWNER) != obj:
            return
        channels = getattr(animation, "channels", animation)
        bones = {id(n.node) for n in args[-1]["vtree"].nodes.values()
                 if getattr(n, "blender_bone", None) is not None}
        keyed = _object_paths(tweaks)
        channels[:] = [c for c in channels if id(c.target.node) not in bones
                       and c.target.path not in keyed]

def _has_keyed_pieces(obj) -> bool:
    """Keyed equipment or state Empties, whose animations merge into ``obj``'s."""
    from .export_ready import equipment, KEYED
    from .export_state import carriers
    return any(KEYED in e for e in equipment(obj)) or bool(carriers(obj))
