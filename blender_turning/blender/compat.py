"""Every Blender-version difference the add-on meets, in one place (Blender 4.2 LTS to 5.0).

Each guard carries a one-line reason.  The rest of ``blender/`` calls these helpers and never
tests ``bpy.app.version`` itself.
"""
from __future__ import annotations

import bpy

VERSION = bpy.app.version

# Slotted (layered) actions arrived in 4.4; 5.0 removed Action.fcurves/groups/id_root.
SLOTTED_ACTIONS = VERSION >= (4, 4, 0)
# Before 5.0 an add-on's registered properties live among the object's ID properties, and reading
# one that was never set (``obj.turning.is_figure``) creates the group there: look at the keys.
SETTINGS_IN_IDPROPS = VERSION < (5, 0, 0)

# EEVEE's engine id was 'BLENDER_EEVEE_NEXT' in 4.2-4.5 and is 'BLENDER_EEVEE' again in 5.0.
_ENGINES = {e.identifier for e in bpy.types.RenderSettings.bl_rna.properties["engine"].enum_items}
EEVEE_ENGINE = "BLENDER_EEVEE" if "BLENDER_EEVEE" in _ENGINES else "BLENDER_EEVEE_NEXT"

# Before 5.0 add-on (bpy.props) values are stored as the ID's custom properties (obj["turning"]),
# and reading obj.turning creates that group; 5.0 keeps them apart from obj.keys().
ADDON_PROPS_IN_ID_PROPERTIES = VERSION < (5, 0, 0)

_LINEAR = None


def linear_interpolation_value() -> int:
    """The enum value of ``'LINEAR'`` for ``Keyframe.interpolation`` (for ``foreach_set``)."""
    global _LINEAR
    if _LINEAR is None:
        _LINEAR = bpy.types.Keyframe.bl_rna.properties["interpolation"].enum_items["LINEAR"].value
    return _LINEAR


def assign_new_action(id_data, name: str):
    """Create the action ``name`` and assign it to ``id_data``; return the action.

    On 4.4+ the action gets one slot for ``id_data`` and a layer/strip/channelbag holding it.
    """
    adt = id_data.animation_data or id_data.animation_data_create()
    action = bpy.data.actions.new(name)
    if SLOTTED_ACTIONS:
        # 4.4+: F-curves live in a channelbag per slot; create the slot first, then assign both.
        slot = action.slots.new(id_type=id_data.id_type, name=id_data.name)
        layer = action.layers.new("Layer")
        strip = layer.strips.new(type="KEYFRAME")
        strip.channelbags.new(slot)
        adt.action = action
        adt.action_slot = slot
    else:
        # 4.2/4.3: the action holds its F-curves directly.
        adt.action = action
    return action


def channels(id_data, action=None):
    """The F-curve/group container (``.fcurves``, ``.groups``) of ``id_data``'s animation.

    ``action`` defaults to the assigned one.  Returns ``None`` when there is none (no action, or on
    4.4+ no channelbag for the assigned slot).
    """
    adt = id_data.animation_data
    if action is None:
        action = adt.action if adt else None
    if action is None:
        return None
    slot = adt.action_slot if SLOTTED_ACTIONS and adt and adt.action == action else None
    return channelbag(action, slot)


def channelbag(action, slot):
    """The F-curve container of ``action`` for ``slot`` (an NLA strip's or the assigned one)."""
    if not SLOTTED_ACTIONS:
        return action                     # 4.2/4.3: Action.fcurves and Action.groups
    if slot is None:
        return None
    for layer in action.layers:           # 4.4+: anim_utils' helper, inlined (not in 4.2)
        for strip in layer.strips:
            bag = strip.channelbag(slot)
            if bag:
                return bag
    return None


def strip_slot(strip):
    """The slot an NLA strip animates through (``None`` before 4.4)."""
    return strip.action_slot if SLOTTED_ACTIONS else None


def new_fcurve(bag, data_path: str, index: int, group: str):
    """A new F-curve in ``bag`` (see :func:`channels`), in the group ``group`` (made if needed)."""
    grp = bag.groups.get(group) or bag.groups.new(group)
    if SLOTTED_ACTIONS:
        # Channelbag.fcurves.new has no group argument; set it afterwards.
        fc = bag.fcurves.new(data_path, index=index)
        fc.group = grp
        return fc
    return bag.fcurves.new(data_path, index=index, action_group=group)


def all_fcurves(action):
    """Every F-curve of ``action`` over all slots (for inspection and snapshots)."""
    if not SLOTTED_ACTIONS:
        return list(action.fcurves)
    out = []
    for layer in action.layers:
        for strip in layer.strips:
            for bag in getattr(strip, "channelbags", ()):
                out.extend(bag.fcurves)
    return out


def nla_strip_new(track, name: str, frame: int, action):
    """Put ``action`` on an NLA ``track`` keeping the slot it was assigned with (4.4+)."""
    adt = track.id_data.animation_data
    slot = adt.action_slot if SLOTTED_ACTIONS else None
    strip = track.strips.new(name, int(frame), action)
    if SLOTTED_ACTIONS and slot is not None:
        strip.action_slot = slot          # 4.4+: a strip animates through a slot too
    return strip


def slot_named(action, identifier: str | None):
    """The slot of ``action`` with ``identifier`` (``None`` before 4.4 or when there is none)."""
    if not SLOTTED_ACTIONS or not identifier:
        return None
    return next((slot for slot in action.slots if slot.identifier == identifier), None)


def restore_action(id_data, action, slot_name: str | None = None):
    """Assign ``action`` back to ``id_data`` (on 4.4+ with the slot named ``slot_name``)."""
    adt = id_data.animation_data or id_data.animation_data_create()
    adt.action = action
    slot = slot_named(action, slot_name) if action is not None else None
    if slot is not None:
        adt.action_slot = slot


def slot_identifier(id_data) -> str | None:
    """The identifier of the slot ``id_data`` is animated through (``None`` before 4.4)."""
    adt = id_data.animation_data
    if not SLOTTED_ACTIONS or adt is None or adt.action_slot is None:
        return None
    return adt.action_slot.identifier


def set_base_color(mat, rgba, roughness: float, metallic: float) -> None:
    """Colour a material's Principled BSDF (for EEVEE and Cycles renders)."""
    if mat.node_tree is None:
        # Before 5.0 a new material has no node tree until use_nodes is set (deprecated in 5.0).
        mat.use_nodes = True
    bsdf = next((n for n in mat.node_tree.nodes if n.type == "BSDF_PRINCIPLED"), None)
    if bsdf is not None:
        bsdf.inputs["Base Color"].default_value = rgba
        bsdf.inputs["Roughness"].default_value = roughness
        bsdf.inputs["Metallic"].default_value = metallic


def set_output_format(scene, kind: str) -> None:
    """``kind``: 'PNG' frames or 'VIDEO' (H.264 in an MP4 container)."""
    image = scene.render.image_settings
    if kind == "VIDEO":
        if hasattr(image, "media_type"):
            image.media_type = "VIDEO"      # 5.0: video output is chosen by media type first
        image.file_format = "FFMPEG"
        scene.render.ffmpeg.format = "MPEG4"
        scene.render.ffmpeg.codec = "H264"
    else:
        if hasattr(image, "media_type"):
            image.media_type = "IMAGE"
        image.file_format = "PNG"


def temp_override(context, **kwargs):
    """``Context.temp_override`` (3.2+), for the one edit-mode switch of the rig builder."""
    return context.temp_override(**kwargs)
