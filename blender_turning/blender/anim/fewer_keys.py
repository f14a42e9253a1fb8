"""Fewer Keys: a figure's every-frame bake thinned to the keys :mod:`..mapping.keys` picks,
per F-curve, with smooth (Bezier) handles carrying the every-frame motion's slope.

The object's and the bones' locations and rotations are thinned, and the state read-outs
but ``turn_phase`` (it wraps every turn: a key on every frame).  A re-bake (or Live Preview)
writes every frame again.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import bpy
import numpy as np

from ...mapping import keys
from . import bake, bake_layers

_KINDS = {"location": "location", "rotation_euler": "euler", "rotation_quaternion": "quaternion"}
#: Per kind: the factor from the largest component error to the bound on the whole channel
#: (the module docstring of :mod:`..mapping.keys`).
_WHOLE = {"location": math.sqrt(3.0), "euler": 3.0, "quaternion": 4.0, "angle": 1.0}


@dataclass(frozen=True)
class KeyReport:
    """What :func:`reduce_bake` did to one figure's bake."""

    keys: int
    """Keys kept, over all the bake's F-curves."""
    every_frame: int
    """Keys of the every-frame bake."""
    angle_error: float
    """Largest rotation error of the reduced curves against the every-frame bake (``turn_lean``
    too), rad."""
    length_error: float
    """Largest position error, m."""

    def summary(self) -> str:
        return (f"{self.keys:,} of {self.every_frame:,} keys "
                f"({100.0 * self.keys / max(self.every_frame, 1):.0f}%), within "
                f"{math.degrees(self.angle_error):.3f} deg and {1e3 * self.length_error:.2f} mm")


def channel_kind(data_path: str) -> str | None:
    """The kind of a baked curve (:data:`..mapping.keys.KINDS`), ``None``: keyed every frame."""
    if data_path.startswith('["') and data_path.endswith('"]'):
        return keys.READOUTS.get(data_path[2:-2])
    return _KINDS.get(data_path.rpartition(".")[2])


def write_hermite_keys(fc, frames, values, slope) -> None:
    """Replace ``fc``'s keys by Bezier keys at ``frames`` whose handles sit a third of the way to
    the neighbouring keys with the given slopes (``(k, 2)``, arriving and leaving, d value /
    d frame): each segment is the cubic Hermite interpolant of its two keys
    (:func:`..mapping.keys.hermite`).  Handles are Aligned, so an animator's edit keeps the
    curve smooth, except at a corner of the motion (two slopes): Free there."""
    f, v, d = (np.asarray(a, float) for a in (frames, values, slope))
    n = len(f)
    h = np.diff(f) / 3.0 if n > 1 else np.ones(1)
    hl, hr = np.r_[h[:1], h], np.r_[h, h[-1:]]
    enum = bpy.types.Keyframe.bl_rna.properties
    bezier = enum["interpolation"].enum_items["BEZIER"].value
    aligned = enum["handle_left_type"].enum_items["ALIGNED"].value
    free = enum["handle_left_type"].enum_items["FREE"].value
    kind = np.where(d[:, 0] == d[:, 1], aligned, free).astype(np.int32)
    kp = fc.keyframe_points
    kp.clear()
    kp.add(n)
    kp.foreach_set("co", np.column_stack([f, v]).ravel())
    kp.foreach_set("handle_left", np.column_stack([f - hl, v - d[:, 0] * hl]).ravel())
    kp.foreach_set("handle_right", np.column_stack([f + hr, v + d[:, 1] * hr]).ravel())
    kp.foreach_set("interpolation", np.full(n, bezier, np.int32))
    kp.foreach_set("handle_left_type", kind)
    kp.foreach_set("handle_right_type", kind)
    fc.update()


def reduce_bake(fig, tolerance: keys.KeyTolerance = keys.DEFAULT_TOLERANCE) -> KeyReport:
    """Thin the every-frame bake of ``fig`` (just written by :func:`.bake.bake_pose_track`) to
    the keys within ``tolerance`` of it; returns the counts and the largest errors."""
    action = bake.figure_action(fig)
    bag = bake.baked_channels(fig)
    if action is None or bag is None:
        raise ValueError(f"figure {fig.name!r} has no bake to reduce")
    paths = set(action.get(bake.BAKED_PATHS, "").splitlines())
    kept = total = 0
    worst = {"angle": 0.0, "length": 0.0}
    for fc in [fc for fc in bag.fcurves if fc.data_path in paths]:
        n = len(fc.keyframe_points)
        total += n
        kind = channel_kind(fc.data_path)
        if kind is None:
            kept += n
            continue
        co = np.empty(2 * n, np.float32)
        fc.keyframe_points.foreach_get("co", co)
        f, v = co[0::2].astype(float), co[1::2].astype(float)
        bound = keys.channel_tolerance(kind, tolerance, v)
        d = keys.key_slopes(f, v, bound)
        idx = keys.reduce_keys(f, v, bound, d)
        err = float(np.max(np.abs(keys.hermite(f[idx], v[idx], d[idx], f) - v)))
        if kind != "readout":
            which = "length" if kind == "location" else "angle"
            worst[which] = max(worst[which], _WHOLE[kind] * err)
        write_hermite_keys(fc, f[idx], v[idx], d[idx])
        kept += len(idx)
    bake_layers.fingerprint(action, bag)      # the bake's own keys now, not the user's edits
    return KeyReport(kept, total, worst["angle"], worst["length"])
