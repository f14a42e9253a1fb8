"""The foot track drawn as a curve object: a poly spline through the foot's ground positions.

It is a guide for the animator, not part of the shot: it never renders (``hide_render``), the glTF
exporter leaves it out (it sits in glTF's ``glTF_not_exported`` collection as well), and the
figure's Show Foot Track setting hides it in the viewport (then FBX's "Visible Objects" leaves it
out too).  Each figure owns its track: the track points back at its figure, so a duplicated
figure (Shift+D copies the pointer, not the track) draws a track of its own and never redraws or
deletes the original's.
"""
from __future__ import annotations

import bpy
import numpy as np

MATERIAL = "Turning Foot Track"
#: ID property on the track object: the figure it belongs to (an ID pointer, remapped when both
#: are duplicated together).
OWNER = "turning_foot_track_of"
#: The collection the glTF exporter skips (io_scene_gltf2's BLENDER_GLTF_SPECIAL_COLLECTION).
GLTF_SKIPPED = "glTF_not_exported"


def owned_track(fig_obj):
    """The figure's own foot track object, or ``None`` (a track it shares with the figure it was
    duplicated from is that figure's)."""
    obj = fig_obj.turning.foot_track
    if obj is None:
        return None
    owner = obj.get(OWNER)
    if owner is None:
        # Drawn before owners were recorded: the figure's own unless another figure points at it
        # too (a duplicate), and then the one it is named after.
        shared = any(o != fig_obj and o.type == "ARMATURE" and o.turning.foot_track == obj
                     for o in bpy.data.objects)
        named = obj.name.startswith(f"{fig_obj.name} Foot Track")
        return obj if named or not shared else None
    return obj if owner == fig_obj else None


def _new_track(fig_obj, collection):
    name = f"{fig_obj.name} Foot Track"
    curve = bpy.data.curves.new(name, "CURVE")
    curve.dimensions = "3D"
    curve.bevel_depth = 0.03
    obj = bpy.data.objects.new(name, curve)
    colls = collection or (fig_obj.users_collection[0] if fig_obj.users_collection
                           else bpy.context.scene.collection)
    colls.objects.link(obj)
    skipped = bpy.data.collections.get(GLTF_SKIPPED)
    if skipped is None:
        skipped = bpy.data.collections.new(GLTF_SKIPPED)
        skipped.use_fake_user = True      # not in any scene: keep it on save
    skipped.objects.link(obj)
    obj.hide_select = True
    obj.hide_render = True
    obj[OWNER] = fig_obj
    mat = bpy.data.materials.get(MATERIAL) or bpy.data.materials.new(MATERIAL)
    mat.diffuse_color = (1.0, 0.55, 0.0, 1.0)
    curve.materials.append(mat)
    return obj


#: The track is drawn this far above the ground under the foot (m), so it is not hidden in it.
LIFT = 0.01


def write_foot_track(fig_obj, x, y, collection=None, z=None):
    """Create or refill the curve object showing the foot's path of ``fig_obj``; return it.
    ``z``: the ground's height under the foot on every point (default 0); the track is drawn
    :data:`LIFT` above it, on a Ground mesh on its surface."""
    obj = owned_track(fig_obj)
    if obj is None or obj.type != "CURVE":
        obj = _new_track(fig_obj, collection)
        fig_obj.turning.foot_track = obj
    obj.hide_viewport = not show_track(fig_obj)
    curve = obj.data
    curve.splines.clear()
    sp = curve.splines.new("POLY")
    n = len(x)
    sp.points.add(n - 1)
    lift = LIFT + (np.zeros(n) if z is None else np.asarray(z, float))
    co = np.column_stack([x, y, lift, np.ones(n)]).astype(np.float32)
    sp.points.foreach_set("co", co.ravel())
    curve.update_tag()
    return obj


def show_track(fig_obj) -> bool:
    return bool(getattr(fig_obj.turning, "show_foot_track", True))


def update_visibility(settings, _context=None) -> None:
    """``Show Foot Track`` changed: show or hide the figure's own track in the viewport."""
    fig_obj = settings.id_data
    obj = owned_track(fig_obj)
    if obj is not None:
        obj.hide_viewport = not show_track(fig_obj)


def remove_foot_track(fig_obj) -> None:
    """Delete the figure's own track; a track it only points at (another figure's) stays."""
    obj = owned_track(fig_obj)
    fig_obj.turning.foot_track = None
    if obj is None:
        return
    curve = obj.data
    mats = [m for m in curve.materials if m is not None] if curve is not None else []
    bpy.data.objects.remove(obj)
    if curve is not None and curve.users == 0:
        bpy.data.curves.remove(curve)
    for mat in mats:                      # what the first track made goes with the last one
        if mat.name == MATERIAL and mat.users == 0:
            bpy.data.materials.remove(mat)
    skipped = bpy.data.collections.get(GLTF_SKIPPED)
    if (skipped is not None and len(skipped.all_objects) == 0 and skipped.use_fake_user
            and skipped.users == 1):            # ours: only the fake user holds it
        bpy.data.collections.remove(skipped)
