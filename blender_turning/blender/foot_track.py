"""The foot track drawn as a curve object: a poly spline through the foot's ground positions."""
from __future__ import annotations

import bpy
import numpy as np

MATERIAL = "Turning Foot Track"


def write_foot_track(fig_obj, x, y, collection=None):
    """Create or refill the curve object showing the foot's path of ``fig_obj``; return it."""
    settings = fig_obj.turning
    obj = settings.foot_track
    name = f"{fig_obj.name} Foot Track"
    if obj is None or obj.type != "CURVE":
        curve = bpy.data.curves.new(name, "CURVE")
        curve.dimensions = "3D"
        curve.bevel_depth = 0.03
        obj = bpy.data.objects.new(name, curve)
        colls = collection or (fig_obj.users_collection[0] if fig_obj.users_collection
                               else bpy.context.scene.collection)
        colls.objects.link(obj)
        obj.hide_select = True
        settings.foot_track = obj
        mat = bpy.data.materials.get(MATERIAL) or bpy.data.materials.new(MATERIAL)
        mat.diffuse_color = (1.0, 0.55, 0.0, 1.0)
        curve.materials.append(mat)
    curve = obj.data
    curve.splines.clear()
    sp = curve.splines.new("POLY")
    n = len(x)
    sp.points.add(n - 1)
    co = np.column_stack([x, y, np.full(n, 0.01), np.ones(n)]).astype(np.float32)
    sp.points.foreach_set("co", co.ravel())
    curve.update_tag()
    return obj


def remove_foot_track(fig_obj) -> None:
    obj = fig_obj.turning.foot_track
    if obj is None:
        return
    curve = obj.data
    fig_obj.turning.foot_track = None
    bpy.data.objects.remove(obj)
    if curve is not None and curve.users == 0:
        bpy.data.curves.remove(curve)
