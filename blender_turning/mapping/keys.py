"""Fewer keys: the frames of a channel an animator needs to key to stay within a tolerance of
the every-frame bake, with smooth in-betweens.

Each kept key carries the slope of the every-frame motion (:func:`slopes`); between two keys
the curve is their cubic Hermite interpolant (:func:`hermite`), which is exactly a Bezier
segment whose handles sit at a third of the way to the neighbouring key along the frame axis
(what ``blender/figure_bake.set_hermite_handles`` writes).  :func:`reduce_keys` keeps the
first and last frame and every extremum (a turn's apex stays a key an animator can grab), then
adds, in every segment still off by more than the tolerance, the frame where it is off most,
until every frame is within it.

Tolerances are per channel kind (:class:`KeyTolerance`): a location component within
``length / sqrt(3)`` (the point within ``length``), an Euler component within ``angle / 3``
(the rotation within ``angle``: the rotation distance is invariant, so the three errors add at
most), a quaternion component within ``angle / 4`` (a rotation of ``2 |dq| <= 4 max|dq_i|``).
The keys are stored as 32-bit floats, so a channel whose values are so large that float
rounding takes a fair share of the tolerance keeps a tighter one (:func:`reduce_keys`).
numpy only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["KeyTolerance", "DEFAULT_TOLERANCE", "KINDS", "channel_tolerance", "slopes",
           "hermite", "reduce_keys"]

KINDS = ("location", "euler", "quaternion")


@dataclass(frozen=True)
class KeyTolerance:
    """How far a reduced curve may stray from the every-frame bake."""

    angle: float = math.radians(0.1)
    """Rotation of a bone or the object, rad (default 0.1 deg)."""
    length: float = 1e-3
    """Position of a bone or the object, m (default 1 mm)."""

    def __post_init__(self):
        for name, value, hi in (("angle", self.angle, math.pi), ("length", self.length, 1.0)):
            if not (isinstance(value, (int, float)) and 0.0 < value <= hi):
                raise ValueError(f"{name} tolerance = {value!r} is outside the allowed range "
                                 f"(0, {hi:g}]")


DEFAULT_TOLERANCE = KeyTolerance()


def channel_tolerance(kind: str, tol: KeyTolerance) -> float:
    """The bound on one component of a channel of ``kind`` (the module docstring)."""
    if kind == "location":
        return tol.length / math.sqrt(3.0)
    if kind == "euler":
        return tol.angle / 3.0
    if kind == "quaternion":
        return tol.angle / 4.0
    raise ValueError(f"channel kind = {kind!r} is not one of {', '.join(KINDS)}")


def slopes(frames, values) -> np.ndarray:
    """d value / d frame of the every-frame motion (second-order differences, one-sided at the
    ends)."""
    frames, values = np.asarray(frames, float), np.asarray(values, float)
    if len(frames) < 3:
        return np.gradient(values, frames) if len(frames) == 2 else np.zeros_like(values)
    return np.gradient(values, frames, edge_order=2)


def hermite(key_frames, key_values, key_slopes, frames) -> np.ndarray:
    """The curve through the keys (cubic Hermite segments), at ``frames`` (inside the keys'
    range)."""
    kf, kv, kd = (np.asarray(a, float) for a in (key_frames, key_values, key_slopes))
    f = np.asarray(frames, float)
    if len(kf) == 1:
        return np.full(f.shape, kv[0])
    j = np.clip(np.searchsorted(kf, f, side="right") - 1, 0, len(kf) - 2)
    h = kf[j + 1] - kf[j]
    u = (f - kf[j]) / h
    u2, u3 = u * u, u * u * u
    return ((2 * u3 - 3 * u2 + 1) * kv[j] + (u3 - 2 * u2 + u) * h * kd[j]
            + (3 * u2 - 2 * u3) * kv[j + 1] + (u3 - u2) * h * kd[j + 1])


def _float32_margin(values: np.ndarray) -> float:
    """What storing the keys as 32-bit floats and evaluating them costs: two units in the last
    place at the channel's largest magnitude."""
    top = float(np.max(np.abs(values))) if len(values) else 0.0
    return 2.0 * float(np.spacing(np.float32(top)))


def _extrema(values: np.ndarray, bound: float) -> np.ndarray:
    """Indices of the turning points of ``values``: where it stops rising and starts falling or
    the reverse, across plateaus, steps of less than ``bound / 1000`` counting as flat (a
    channel constant up to round-off has none)."""
    step = np.diff(values)
    moving = np.flatnonzero(np.abs(step) > 1e-3 * bound)
    if len(moving) < 2:
        return moving[:0]
    up = step[moving] > 0
    flip = np.flatnonzero(up[1:] != up[:-1])            # moving[flip] ends a rise or a fall
    return moving[flip] + 1


def reduce_keys(frames, values, bound: float, slope=None) -> np.ndarray:
    """Indices (ascending) of the frames to key so that :func:`hermite` through them, with
    ``slope`` (default :func:`slopes`), is within ``bound`` of ``values`` at every frame.

    ``bound`` is first lowered by the 32-bit rounding of the channel (:func:`_float32_margin`),
    so that the curve Blender stores stays within it; a channel where that leaves nothing keeps
    every frame."""
    frames, values = np.asarray(frames, float), np.asarray(values, float)
    n = len(frames)
    if frames.shape != values.shape or frames.ndim != 1:
        raise ValueError(f"frames {frames.shape} and values {values.shape} must be two (n,) "
                         "arrays")
    if not bound > 0.0:
        raise ValueError(f"bound = {bound!r} is outside the allowed range (0, inf)")
    bound = bound - _float32_margin(values)
    if n <= 2 or bound <= 0.0:
        return np.arange(n)
    slope = slopes(frames, values) if slope is None else np.asarray(slope, float)
    keep = np.zeros(n, bool)
    keep[[0, -1]] = True
    keep[_extrema(values, bound)] = True
    fixed = keep.copy()
    while True:
        idx = np.flatnonzero(keep)
        err = np.abs(hermite(frames[idx], values[idx], slope[idx], frames) - values)
        if not np.any(err > bound):
            return _pruned(frames, values, slope, bound, keep, fixed)
        worst = np.maximum.reduceat(err, idx[:-1])       # per segment [idx[j], idx[j+1])
        seg = np.searchsorted(idx, np.arange(n), side="right") - 1
        seg = np.minimum(seg, len(idx) - 2)
        at = np.flatnonzero((err > bound) & (err == worst[seg]))
        first = at[np.unique(seg[at], return_index=True)[1]]   # one new key per bad segment
        keep[first] = True


def _pruned(frames, values, slope, bound, keep, fixed) -> np.ndarray:
    """Drop the keys (not in ``fixed``) whose two segments, merged, stay within ``bound``: every
    other key at a time (their neighbours stay, so each merge is judged alone), both parities,
    until none goes."""
    n = len(frames)
    for _ in range(16):
        dropped = False
        for parity in (1, 0):
            idx = np.flatnonzero(keep)
            m = np.arange(parity or 2, len(idx) - 1, 2)         # interior keys, every other
            m = m[~fixed[idx[m]]]
            if not len(m):
                continue
            trial = keep.copy()
            trial[idx[m]] = False
            tidx = np.flatnonzero(trial)
            err = np.abs(hermite(frames[tidx], values[tidx], slope[tidx], frames) - values)
            worst = np.maximum.reduceat(err, tidx[:-1])
            seg = np.searchsorted(tidx, idx[m]) - 1             # the merged segment of each
            ok = worst[seg] <= bound
            keep[idx[m[ok]]] = False
            dropped |= bool(np.any(ok))
        if not dropped:
            break
    return np.flatnonzero(keep)
