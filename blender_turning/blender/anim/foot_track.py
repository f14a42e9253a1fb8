"""The foot track drawn as a curve object: a poly spline through the foot's ground positions.

It is a guide for the animator, not part of the shot: it never renders (``hide_render``) and is
not exported.  Tracks live in a collection of their own, *Turning Guides*, a child of the scene
collection; a hidden track (the figure's *Show Foot Track* off, the default) sits in its child
*Turning Guides Hidden*, which every view layer of the scene excludes (``LayerCollection.exclude``,
the outliner's checkbox).  An excluded collection's objects are not in the view layer, and the
exporters take the view layer's objects (FBX: ``context.view_layer.objects``; glTF: the
evaluated scene), so a default FBX or glTF export leaves a hidden track out.  Showing it moves it
into *Turning Guides*, drawn in the viewport; it is then in the view layer, so FBX's defaults
export it (glTF still skips it: every track is also in glTF's ``glTF_not_exported`` collection).
Each figure owns its track: the track points back at its figure, so a duplicated figure (Shift+D
copies the pointer, not the track) draws a track of its own and never redraws or deletes the
original's.
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
#: Shown tracks; its child :data:`HIDDEN` (excluded from every view layer) holds hidden ones.
GUIDES = "Turning Guides"
HIDDEN = "Turning Guides Hidden"


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


def _collection(name, parent):
    coll = bpy.data.collections.get(name)
    if coll is None:
        coll = bpy.data.collections.new(name)
    if parent is not None and coll.name not in parent.children:
        parent.children.link(coll)
    return coll


def _find_layer(layer, coll):
    if layer.collection == coll:
        return layer
    for child in layer.children:
        found = _find_layer(child, coll)
        if found is not None:
            return found
    return None


def _guide_collections(fig_obj):
    """``(shown, hidden)``: the guide collections, linked under every scene the figure is in,
    the hidden one excluded from each of their view layers."""
    # Object.users_scene lists every object of every scene, O(objects) a call and O(N^2) over a
    # crowd's bake; with one scene the answer is that scene either way.
    scenes = list(bpy.data.scenes) if len(bpy.data.scenes) == 1 else \
        fig_obj.users_scene or (bpy.context.scene,)
    shown = _collection(GUIDES, None)
    hidden = _collection(HIDDEN, shown)
    for scene in scenes:
        if shown.name not in scene.collection.children:
            scene.collection.children.link(shown)
        for view_layer in scene.view_layers:
            layer = _find_layer(view_layer.layer_collection, hidden)
            if layer is not None and not layer.exclude:
                layer.exclude = True
    return shown, hidden


def guide_collections():
    """``(shown, hidden)`` for :func:`write_foot_track` of several figures of the one scene
    there is (``None`` with several scenes: each figure's are its scenes'): read once, as
    reading the view layers after a new object costs a resync of the view layer (O(objects))."""
    return _guide_collections(None) if len(bpy.data.scenes) == 1 else None


def _place(fig_obj, obj, new: bool = False, guides=None) -> None:
    """Link the track into the guide collection its figure's Show Foot Track asks for (and
    glTF's skipped one), and out of every other (a track drawn by older versions sat in the
    figure's collection).  A ``new`` track is in no collection yet: nothing to look up (a
    lookup in a collection, and ``Object.users_collection``, cost O(objects)).  ``guides``:
    :func:`guide_collections`, when the caller has them."""
    shown, hidden = guides or _guide_collections(fig_obj)
    home = shown if show_track(fig_obj) else hidden
    skipped = bpy.data.collections.get(GLTF_SKIPPED)
    if skipped is None:
        skipped = bpy.data.collections.new(GLTF_SKIPPED)
        skipped.use_fake_user = True      # not in any scene: keep it on save
    for coll in (home, skipped):
        if new or obj.name not in coll.objects:
            coll.objects.link(obj)
    for coll in [] if new else list(obj.users_collection):
        if coll not in (home, skipped):
            coll.objects.unlink(obj)
    obj.hide_viewport = False             # older versions hid it per object


def _new_track(fig_obj):
    name = f"{fig_obj.name} Foot Track"
    curve = bpy.data.curves.new(name, "CURVE")
    curve.dimensions = "3D"
    curve.bevel_depth = 0.03
    obj = bpy.data.objects.new(name, curve)
    obj.hide_select = True
    obj.hide_render = True
    obj[OWNER] = fig_obj
    mat = bpy.data.materials.get(MATERIAL) or bpy.data.materials.new(MATERIAL)
    mat.diffuse_color = (1.0, 0.55, 0.0, 1.0)
    curve.materials.append(mat)
    return obj


#: The track is drawn this far above the ground under the foot (m), so it is not hidden in it.
LIFT = 0.01


def write_foot_track(fig_obj, x, y, z=None, guides=None):
    """Create or refill the curve object showing the foot's path of ``fig_obj``; return it.
    ``z``: the ground's height under the foot on every point (default 0); the track is drawn
    :data:`LIFT` above it, on a Ground mesh on its surface.  ``guides``: the guide collections
    (:func:`guide_collections`), when a crowd's bake has them."""
    obj = owned_track(fig_obj)
    new = obj is None or obj.type != "CURVE"
    if new:
        obj = _new_track(fig_obj)
        fig_obj.turning.foot_track = obj
    _place(fig_obj, obj, new, guides)
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
    return bool(getattr(fig_obj.turning, "show_foot_track", False))


def update_visibility(settings, _context=None) -> None:
    """``Show Foot Track`` changed: move the figure's own track into the shown or the hidden
    (excluded) guide collection."""
    fig_obj = settings.id_data
    obj = owned_track(fig_obj)
    if obj is not None:
        _place(fig_obj, obj)


def _remove_if_ours_and_empty(name, fake_user):
    coll = bpy.data.collections.get(name)
    if coll is None or len(coll.all_objects) or len(coll.children) or \
            coll.use_fake_user != fake_user or (fake_user and coll.users != 1):
        return
    bpy.data.collections.remove(coll)


def remove_foot_track(fig_obj) -> None:
    """Delete the figure's own track; a track it only points at (another figure's) stays.  The
    guide collections go with the last track."""
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
    _remove_if_ours_and_empty(HIDDEN, False)
    _remove_if_ours_and_empty(GUIDES, False)
    _remove_if_ours_and_empty(GLTF_SKIPPED, True)     # ours: only the fake user holds it
