"""A comparable picture of everything in a .blend that an operator could change (for the
"a failed operator changes nothing" tests): every object (transform, parent, visibility, custom
properties, the figure's settings, pose, animation data with its NLA tracks and strips), every
action (users, custom properties, each F-curve's keys and handles), every curve's points, every
collection's objects, every material and mesh, and each scene's frame range.

Floats are compared exactly (as float32 bytes where Blender stores float32): a failed operator
must leave them bit for bit.
"""
from __future__ import annotations

import bpy
import numpy as np

from blender_turning.blender import compat


def _value(v):
    """An ID property or RNA value as plain, comparable Python."""
    if isinstance(v, bpy.types.ID):
        return ("ID", type(v).__name__, v.name)
    if hasattr(v, "to_dict"):
        return {k: _value(x) for k, x in v.to_dict().items()}
    if hasattr(v, "to_list"):
        return tuple(v.to_list())
    if isinstance(v, float):
        return repr(v)                    # NaN equals NaN here: a NaN setting left alone is equal
    if isinstance(v, (str, int, bool)) or v is None:
        return v
    try:
        return tuple(_value(x) for x in v)
    except TypeError:
        return repr(v)


def _props(idblock) -> dict:
    """Custom properties; the storage of registered properties (``turning``, which 4.2 creates on
    first read) is compared through RNA instead."""
    rna = idblock.bl_rna.properties
    return {k: _value(idblock[k]) for k in idblock.keys() if k not in rna}


def _rna(struct) -> dict:
    """Every RNA property of a property group (the figure's ``turning`` settings)."""
    out = {}
    for prop in struct.bl_rna.properties:
        if prop.identifier == "rna_type":
            continue
        out[prop.identifier] = _value(getattr(struct, prop.identifier))
    return out


def _keys(fc) -> tuple:
    kp = fc.keyframe_points
    n = len(kp)
    parts = []
    for attr, width, dtype in (("co", 2, np.float32), ("handle_left", 2, np.float32),
                               ("handle_right", 2, np.float32), ("interpolation", 1, np.int32)):
        buf = np.empty(n * width, dtype)
        kp.foreach_get(attr, buf)
        parts.append(buf.tobytes())
    group = fc.group.name if fc.group else None
    return (group, fc.mute, fc.extrapolation, *parts)


def _anim(obj):
    adt = obj.animation_data
    if adt is None:
        return None
    tracks = [(t.name, t.mute, [(s.name, s.action.name if s.action else None, s.frame_start,
                                 s.frame_end, s.action_frame_start, s.action_frame_end, s.mute)
                                for s in t.strips]) for t in adt.nla_tracks]
    return (adt.action.name if adt.action else None, compat.slot_identifier(obj), tracks)


def _transform(obj) -> bytes:
    return np.array(obj.matrix_basis, np.float32).tobytes()


def snapshot() -> dict:
    out = {}
    for sc in bpy.data.scenes:
        out["scene", sc.name] = (sc.frame_start, sc.frame_end, sc.frame_current,
                                 sc.render.fps, sc.render.fps_base)
    for o in bpy.data.objects:
        rec = {"type": o.type, "data": o.data.name if o.data else None,
               "parent": o.parent.name if o.parent else None, "matrix": _transform(o),
               "rotation_mode": o.rotation_mode,
               "hide": (o.hide_viewport, o.hide_render, o.hide_select),
               "collections": sorted(c.name for c in o.users_collection),
               "props": _props(o), "anim": _anim(o)}
        if getattr(o, "turning", None) is not None:
            rec["turning"] = _rna(o.turning)
        if o.pose is not None:
            rec["pose"] = {pb.name: (pb.rotation_mode, tuple(pb.location),
                                     tuple(pb.rotation_quaternion), tuple(pb.rotation_euler),
                                     tuple(pb.scale)) for pb in o.pose.bones}
        out["object", o.name] = rec
    for a in bpy.data.actions:
        out["action", a.name] = {"users": a.users, "fake": a.use_fake_user, "props": _props(a),
                                 "fcurves": {(fc.data_path, fc.array_index): _keys(fc)
                                             for fc in compat.all_fcurves(a)}}
    for c in bpy.data.curves:
        splines = []
        for sp in c.splines:
            pts = sp.bezier_points if sp.type == "BEZIER" else sp.points
            width = 3 if sp.type == "BEZIER" else 4
            co = np.empty(width * len(pts), np.float32)
            pts.foreach_get("co", co)
            splines.append((sp.type, sp.use_cyclic_u, co.tobytes()))
        out["curve", c.name] = (c.users, splines)
    for coll in bpy.data.collections:
        out["collection", coll.name] = (sorted(o.name for o in coll.objects),
                                        sorted(ch.name for ch in coll.children), coll.users)
    for kind in ("meshes", "materials", "armatures"):
        out[kind] = sorted((d.name, d.users) for d in getattr(bpy.data, kind))
    for arm in bpy.data.armatures:
        out["bones", arm.name] = sorted(b.name for b in arm.bones)
    return out


def diff(before: dict, after: dict) -> list:
    """The keys whose values differ (for a readable assertion message)."""
    return sorted((str(k) for k in set(before) | set(after) if before.get(k) != after.get(k)))
