"""Skidding on the rig (docs/skidding.md Section 8): the skis and the board pivot across the
travel by the trajectory's ``skid`` angle, the body counter-rotates, a wedge's skis point their
tips together, a hockey stop's skis go across the travel on their uphill edges.  numpy only.

The armature faces the travel (``theta_dir``); a ski's yaw from it is ``skid`` (its heading is
``ski_heading = theta_dir + skid``), positive counter-clockwise seen from above, about the
ankle (the board: about the midpoint of the boots).  The pelvis turns ``HIP_SHARE`` of the skid
with the skis and the chest ``CHEST_SHARE``: the upper body faces down the travel while the
legs follow the skis, as a skier's does in a skidded turn and a hockey stop.

- **Wedge** (``meta["style"] == "wedge"``): the ``skid`` column is the wedge's half-angle; the
  left ski yaws by ``-|skid|``, the right by ``+|skid|`` (tips together), both edged inward by
  :data:`..core.physics.skidding.WEDGE_EDGE` on top of the turn's tilt (the knees turn in by the leg
  twist the skier's mapping gives a ski edged more than the body leans); the boots spread so
  that the tips stay :data:`TIP_GAP` apart.
- **Stop** (from ``meta["stop_at"]``): both skis (the board) yaw by ``skid`` (up to 90 deg, and
  across the fall line when the figure stands), edged uphill by
  :data:`..core.physics.skidding.STOP_EDGE`, ramped in over :data:`STOP_RAMP`.
- **Leaning back against the brake** (any braking: a skid, a wedge, a stop): the snow's force on
  the figure is the leg force ``F_leg`` (the resultant of the normal and lateral forces, along
  which the pendulum leans ``theta_v``) and the braking force ``m F_brake / m`` against the
  travel.  A body that does not pitch has its centre of mass on the line of that force through
  the foot, as the lean in a turn does: it leans back (uphill in a stop) by
  ``atan(m brake / F_leg)`` about the line across the travel through the foot, taken in over
  :data:`STOP_RAMP` (a first-order lag: the body cannot pitch at once).

A carved run (``skid`` 0 on every frame, no wedge, no stop) is left exactly as it was: every
function returns its input (tested bit for bit).
"""
from __future__ import annotations

import numpy as np

from ...core.physics.skidding import STOP_EDGE, WEDGE_EDGE
from .. import bones as B
from .common import add_local_rotation, mesh_points, smoothstep, static_force

__all__ = ["SkidPose", "HIP_SHARE", "CHEST_SHARE", "TIP_GAP", "STOP_RAMP", "back_pitch",
           "knee_direction", "ski_front", "equipment_length", "brushed_half_width"]

HIP_SHARE = 0.5
"""The share of the skid the pelvis turns with the skis."""
CHEST_SHARE = 0.2
"""The share of the skid the chest turns with the skis (it faces down the travel by the rest)."""
TIP_GAP = 0.08
"""The gap between a wedge's ski tips, m."""
STOP_RAMP = 0.3
"""How long the skis take to go onto their uphill edges in a stop, s."""


class SkidPose:
    """The skid of one trajectory as the mapping poses it."""

    def __init__(self, traj):
        self.skid = np.asarray(traj.skid, float)
        meta = traj.meta
        stop_at = meta.get("stop_at")
        t = np.asarray(traj.t, float)
        self.stop = (np.zeros(len(t)) if stop_at is None
                     else smoothstep((t - float(stop_at)) / STOP_RAMP))
        self.stopping = self.stop > 0.0
        self.wedge = (meta.get("style") == "wedge") & ~self.stopping
        self.pitch = back_pitch(traj)
        self.active = bool(np.any(self.skid) or np.any(self.wedge) or np.any(self.stopping)
                           or np.any(self.pitch))

    def lean_back(self, b) -> None:
        """The body leans back by :attr:`pitch` about the line across the travel through the
        foot (after the lean ``theta_v``, before the legs are placed)."""
        if self.active:
            add_local_rotation(b, B.LEAN, (1.0, 0.0, 0.0), self.pitch)

    def yaw(self, s: str | None = None) -> np.ndarray:
        """The yaw from the travel (n,) of ski ``s`` (``None``: the board), rad."""
        if s is None:
            return self.skid
        half = np.abs(self.skid) * (1.0 if s == "R" else -1.0)
        return np.where(self.wedge, half, self.skid)

    def turn_hips(self, b, up) -> None:
        """The pelvis turns ``HIP_SHARE`` of the skid with the skis (about the body's up)."""
        if self.active:
            add_local_rotation(b, B.HIPS, up, HIP_SHARE * self.body_skid())

    def counter_rotate(self, b, up) -> None:
        """The upper body turns back to ``CHEST_SHARE`` of the skid, spread over the spine."""
        if self.active:
            for bone in (B.SPINE, B.SPINE_2, B.CHEST):
                add_local_rotation(b, bone, up, (CHEST_SHARE - HIP_SHARE) / 3.0 * self.body_skid())

    def body_skid(self) -> np.ndarray:
        """The skid the body follows: the skis' mean yaw (0 in a wedge)."""
        return np.where(self.wedge, 0.0, self.skid)

    def layout(self, layout: dict) -> dict:
        """The skier's ski layout (``{side: (fore-aft, yaw, heel)}``) with the skid's yaw."""
        if not self.active:
            return layout
        return {s: (dy, yaw + self.yaw(s), heel) for s, (dy, yaw, heel) in layout.items()}

    def tilts(self, tilts: dict) -> dict:
        """The skis' edge tilts (``{side: (n,)}``, positive: the left edge down) with a wedge's
        inward edging and a stop's uphill edging."""
        if not self.active:
            return tilts
        return {s: self.tilt(tilt, s) for s, tilt in tilts.items()}

    def tilt(self, tilt, s: str | None = None) -> np.ndarray:
        """One ski's (``s``; ``None``: the board's) tilt with the wedge and the stop."""
        if not self.active:
            return tilt
        inward = WEDGE_EDGE * (1.0 if s == "R" else -1.0) if s is not None else 0.0
        tilt = np.where(self.wedge, tilt + inward, tilt)
        # Across the travel the ski's left edge is the uphill one when it turned left (skid > 0):
        # the side the stop's skid takes (one side for the whole stop, as the core's).
        side = 1.0 if np.sum(self.skid[self.stopping]) >= 0.0 else -1.0
        return (1.0 - self.stop) * tilt + self.stop * side * STOP_EDGE

    def spread(self, front: float, half_width: float) -> dict:
        """How far (n,) each boot moves outward (m, +x for the right one) so that the wedge's
        tips, ``front`` m ahead of the ankles, stay :data:`TIP_GAP` apart; the ankles are
        ``half_width`` m either side of the body's axis."""
        out = np.where(self.wedge, np.maximum(
            front * np.sin(np.abs(self.skid)) + 0.5 * TIP_GAP - half_width, 0.0), 0.0)
        return {"L": -out, "R": out}


def back_pitch(traj) -> np.ndarray:
    """How far the body leans back against the braking force (n,), rad: ``atan(m brake /
    F_leg)`` (module docstring), lagged by :data:`STOP_RAMP`; 0 where nothing brakes."""
    brake = np.asarray(traj.brake, float)
    if not np.any(brake):
        return np.zeros(len(brake))
    m = traj.meta.get("body.m")
    m = float(m) if m is not None else static_force(traj) / 9.81
    want = np.arctan2(m * brake, np.maximum(np.asarray(traj.F_leg, float), 1e-9))
    t = np.asarray(traj.t, float)
    out = np.empty_like(want)
    p = 0.0
    for i, w in enumerate(want):
        dt = t[i] - t[i - 1] if i else 0.0
        p += (1.0 - np.exp(-dt / STOP_RAMP)) * (w - p)
        out[i] = p
    return out


def knee_direction(fwd, yaw) -> np.ndarray:
    """The armature-space forward ``fwd`` turned by ``yaw`` (n,) about +Z: where the knees
    point over skis turned by the skid."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([c * fwd[..., 0] - s * fwd[..., 1], s * fwd[..., 0] + c * fwd[..., 1],
                     np.broadcast_to(fwd[..., 2], c.shape)], -1)


def ski_front(skel, spec, ski: str, anchor_rest) -> float:
    """How far the ski's tip reaches ahead of the rest point ``anchor_rest`` (its boot), m."""
    rest = skel.rest_of(ski)
    tips = mesh_points(spec, ski) @ rest[:3, :3].T + rest[:3, 3]
    return float(tips[:, 1].max() - float(anchor_rest[1]))


def equipment_length(spec) -> float:
    """The length of the rig ``spec``'s ski (its left one) or board, tip to tail, m; 0 for a rig
    with neither (a bicycle does not skid)."""
    for bone in ("ski.L", B.BOARD):
        if bone in spec.bone_names:
            y = mesh_points(spec, bone)[:, 1]
            return float(y.max() - y.min())
    return 0.0


def brushed_half_width(groove_half: float, length: float, skid) -> np.ndarray:
    """Half the width (n,) of the track a ski (board) of ``length`` m leaves at the skid angle
    ``skid`` (n,) rad: a carved ski cuts a groove ``2 groove_half`` wide; a skidding one sweeps
    the snow across the travel over ``length |sin skid|`` and brushes a band that wide."""
    return np.maximum(groove_half, 0.5 * length * np.abs(np.sin(np.asarray(skid, float))))
