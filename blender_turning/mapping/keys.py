"""Fewer keys: the frames of a channel an animator needs to key to stay within a tolerance of
the every-frame bake, with smooth in-betweens.

Each kept key carries the slope of the every-frame motion (:func:`slopes`: one slope, or at a
corner of the motion one arriving and one leaving); between two keys the curve is their cubic
Hermite interpolant (:func:`hermite`), which is exactly a Bezier segment whose handles sit at a
third of the way to the neighbouring key along the frame axis (what
``blender/fewer_keys.write_hermite_keys`` writes).  :func:`reduce_keys` keeps the
first and last frame and every extremum (a turn's apex stays a key an animator can grab), then
adds, in every segment still off by more than the tolerance, the frame where it is off most,
until every frame is within it.

Tolerances are per channel kind (:class:`KeyTolerance`): a location component within
``length / sqrt(3)`` (the point within ``length``), an Euler component within ``angle / 3``
(the rotation within ``angle``: the rotation distance is invariant, so the three errors add at
most), a quaternion component within ``angle / 4`` (a rotation of ``2 |dq| <= 4 max|dq_i|``).
The state read-outs (:data:`READOUTS`): ``turn_lean`` within ``angle``, the curvature, leg
force and speed within ``readout`` of their range over the bake; ``turn_phase`` wraps from
2 pi to 0 every turn and keeps a key on every frame.
The keys are stored as 32-bit floats, so a channel whose values are so large that float
rounding takes a fair share of the tolerance keeps a tighter one (:func:`reduce_keys`).
numpy only.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .base import STATE_PROPS

__all__ = ["KeyTolerance", "DEFAULT_TOLERANCE", "KINDS", "READOUTS", "channel_tolerance",
           "slopes", "key_slopes", "hermite", "reduce_keys"]

KINDS = ("location", "euler", "quaternion", "angle", "readout")
#: The kind of each state read-out that is thinned (``turn_phase`` is not: it wraps).
READOUTS = {"turn_lean": "angle", "turn_curvature": "readout", "turn_leg_force": "readout",
            "turn_speed": "readout", "turn_skid": "angle"}
assert set(READOUTS) | {"turn_phase"} == set(STATE_PROPS)


@dataclass(frozen=True)
class KeyTolerance:
    """How far a reduced curve may stray from the every-frame bake."""

    angle: float = math.radians(0.1)
    """Rotation of a bone or the object, rad (default 0.1 deg)."""
    length: float = 1e-3
    """Position of a bone or the object, m (default 1 mm)."""
    readout: float = 1e-3
    """A state read-out other than an angle, as a fraction of its range over the bake (default
    0.1 %)."""

    def __post_init__(self):
        for name, value, hi in (("angle", self.angle, math.pi), ("length", self.length, 1.0),
                                ("readout", self.readout, 1.0)):
            if not (isinstance(value, (int, float)) and 0.0 < value <= hi):
                raise ValueError(f"{name} tolerance = {value!r} is outside the allowed range "
                                 f"(0, {hi:g}]")


DEFAULT_TOLERANCE = KeyTolerance()


def channel_tolerance(kind: str, tol: KeyTolerance, values=None) -> float:
    """The bound on one component of a channel of ``kind`` (the module docstring); a
    ``"readout"`` needs its ``values``."""
    if kind == "readout":
        v = np.asarray(values, float)
        scale = float(np.ptp(v)) or float(np.max(np.abs(v)))
        return tol.readout * scale if scale > 0.0 else 1.0     # all zero: any bound holds
    if kind == "angle":
        return tol.angle
    if kind == "location":
        return tol.length / math.sqrt(3.0)
    if kind == "euler":
        return tol.angle / 3.0
    if kind == "quaternion":
        return tol.angle / 4.0
    raise ValueError(f"channel kind = {kind!r} is not one of {', '.join(KINDS)}")


def slopes(frames, values, kink: float = math.inf) -> np.ndarray:
    """d value / d frame of the every-frame motion at every frame, arriving and leaving:
    shape ``(n, 2)``.  Both are the central second-order difference (one-sided at the ends),
    except at a kink -- where the backward and forward second-order differences differ by more
    than ``kink`` (value per frame): a bone's rotation where a joint reaches its limit -- there
    the arriving slope is the backward difference and the leaving one the forward difference,
    so a key there carries the corner (broken handles) instead of rounding it off."""
    f, v = np.asarray(frames, float), np.asarray(values, float)
    n = len(f)
    if n < 3:
        d = np.gradient(v, f) if n == 2 else np.zeros_like(v)
        return np.column_stack([d, d])
    central = np.gradient(v, f, edge_order=2)
    out = np.column_stack([central, central])
    if n >= 5 and kink < math.inf:
        h = np.diff(f)
        back = (3 * v[2:] - 4 * v[1:-1] + v[:-2]) / (h[1:] + h[:-1])       # frames 2..n-1
        ahead = (-3 * v[:-2] + 4 * v[1:-1] - v[2:]) / (h[1:] + h[:-1])     # frames 0..n-3
        i = np.arange(2, n - 2)
        corner = i[np.abs(back[i - 2] - ahead[i]) > kink]
        out[corner, 0] = back[corner - 2]
        out[corner, 1] = ahead[corner]
    return out


def hermite(key_frames, key_values, slope_pairs, frames) -> np.ndarray:
    """The curve through the keys (cubic Hermite segments, each leaving its first key with that
    key's leaving slope and arriving at the next with its arriving slope; ``key_slopes`` of
    shape ``(k, 2)``), at ``frames`` (inside the keys' range)."""
    kf, kv, kd = (np.asarray(a, float) for a in (key_frames, key_values, slope_pairs))
    f = np.asarray(frames, float)
    if len(kf) == 1:
        return np.full(f.shape, kv[0])
    j = np.clip(np.searchsorted(kf, f, side="right") - 1, 0, len(kf) - 2)
    h = kf[j + 1] - kf[j]
    u = (f - kf[j]) / h
    u2, u3 = u * u, u * u * u
    return ((2 * u3 - 3 * u2 + 1) * kv[j] + (u3 - 2 * u2 + u) * h * kd[j, 1]
            + (3 * u2 - 2 * u3) * kv[j + 1] + (u3 - u2) * h * kd[j + 1, 0])


def key_slopes(frames, values, bound: float) -> np.ndarray:
    """:func:`slopes` with a kink where the slope jumps by more than ``bound`` per frame: a
    corner that the central difference would round off by about the bound in the frames beside
    it."""
    step = float(np.median(np.diff(np.asarray(frames, float)))) if len(frames) > 1 else 1.0
    return slopes(frames, values, bound / step)


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
    ``slope`` (``(n, 2)``; default :func:`key_slopes`), is within ``bound`` of ``values`` at
    every frame.

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
    slope = key_slopes(frames, values, bound) if slope is None else np.asarray(slope, float)
    bound = bound - _float32_margin(values)
    if n <= 2 or bound <= 0.0:
        return np.arange(n)
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
