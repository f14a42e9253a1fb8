"""Pieces shared by the snow sports (skier, telemark skier, snowboarder; Section 7).

* The legs act as a spring driven by ``F_leg``: the hip-to-ankle length along the body is
  ``L = L_static - (F_leg - m g) / k_s`` (Section 7: "Given the force at any instant and k_s,
  the leg length is determined and inverse kinematics is used to calculate the bend of the
  knees"); Fig. 5 shows ``F_leg`` swinging about +-30 % around ``m g``.  The force is the
  mean over the foot's travel along the equipment's length (a ski, a board): the equipment is
  stiff over its length and bridges a bump shorter than it, so the boot follows the ground's
  curvature (``F_leg``'s ``V_f^2 kappa_n``) averaged over that length.  On a Ground mesh the
  curvature sits in the creases between its faces (every cell, 1 m; half a second at 12 m/s
  is 2 frames): unaveraged, the force jumped 324-1237 N between frames and the legs and the
  waist bend with it (the chest by up to 38 deg in a frame).
* The pelvis is carried by the lean and slides along the leaned body axis to give that length.
* The equipment (skis, board) is tilted on edge linearly in ``C_f`` and set on the ground;
  the boots are glued to it and the legs reach them by two-bone IK.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.physics.params import check_range
from .. import bones as B
from ..anthropometry import SEGMENTS, segment_ends
from ..kinematics import PoseBuilder, dot, norm
from .common import (add_local_rotation, body_axes, carried, ik_limb, lean, leg_lengths,
                     static_force)

__all__ = ["SpringLegOptions", "AngulationOptions", "angulation_back", "centre_on_lean",
           "lean_on_spring_legs", "spring_length", "bridged_force",
           "tilt_gain", "set_pelvis", "hip_drop", "knee_flexion",
           "carry_vec", "bend_waist", "twist_upper_body", "level_head", "legs_step"]


@dataclass(frozen=True)
class SpringLegOptions:
    """Options every snow sport shares: spring legs, edge tilt, waist and head (SI, radians)."""

    k_s: float = 3000.0
    """Leg spring stiffness, N/m: the legs shorten by (F_leg - m g) / k_s."""
    stance: float = 0.94
    """Hip-to-ankle length at the static force m g, as a fraction of the full leg length."""
    leg_min: float = 0.62
    """Shortest hip-to-ankle length, fraction of the full leg length."""
    leg_max: float = 0.985
    """Longest hip-to-ankle length, fraction of the full leg length."""
    tilt_gain: float | None = None
    """Edge tilt per unit curvature, rad m (tilt = tilt_gain C_f); None fits theta_v ~ C_f."""
    tilt_max: float = math.radians(70.0)
    """Largest edge tilt, rad."""
    waist_ratio: float = 0.6
    """Forward bend at the waist per radian of knee bend, rad/rad."""
    head_level: float = 0.5
    """Fraction of the lean the neck takes back to keep the eyes level."""

    def __post_init__(self):
        check_range("k_s", self.k_s, 0.0, 1e7, lo_open=True)
        check_range("leg_min", self.leg_min, 0.2, 1.0)
        check_range("leg_max", self.leg_max, self.leg_min, 0.999)
        check_range("stance", self.stance, self.leg_min, self.leg_max)
        if self.tilt_gain is not None:
            check_range("tilt_gain", self.tilt_gain, 0.0, 1e3)
        check_range("tilt_max", self.tilt_max, 0.0, math.pi / 2, hi_open=True)
        check_range("waist_ratio", self.waist_ratio, 0.0, 3.0)
        check_range("head_level", self.head_level, 0.0, 1.0)


@dataclass(frozen=True)
class AngulationOptions(SpringLegOptions):
    """A snow sport's angulation on a preset's carving equipment (docs/racing.md)."""

    angulation: float = 1.5
    """On a preset's carving skis or board: how much more upright than the lean the pelvis and
    the upper body stand, per radian of the equipment's edge angle over the lean, rad/rad (the
    hips and knees angulate inside; 0: none).  1.5 puts Reid et al.'s 65 deg of edge on a 55 deg
    lean at about 20 deg between the legs' and the trunk's lines (docs/racing.md)."""
    angulation_max: float = math.radians(25.0)
    """The most the upper body stands more upright than the lean, rad: with the legs' line
    leaning further, the hip joints then take about 30 deg between legs and trunk, the hip's
    range of adduction (30 deg, AAOS normal ranges)."""

    def __post_init__(self):
        super().__post_init__()
        check_range("angulation", self.angulation, 0.0, 3.0)
        check_range("angulation_max", self.angulation_max, 0.0, math.radians(45.0))


def angulation_back(theta_v, edge, o) -> np.ndarray:
    """How far (n,) rad toward upright the pelvis and the upper body stand: ``o.angulation``
    times the edge angle's excess over the lean ``theta_v`` (none where the edge is the
    flatter), at most ``o.angulation_max``, signed as ``theta_v``."""
    th = np.asarray(theta_v, float)
    return np.sign(th) * np.minimum(o.angulation * np.maximum(np.abs(edge) - np.abs(th), 0.0),
                                    o.angulation_max)


#: Poses tried before the final one (:func:`centre_on_lean`): the first's step from the model of
#: :func:`legs_step`, then the secant's; after two the centre of mass leans theta_v within
#: 0.002 deg at every frame of a snowboarder's slalom, 0.001 deg of a racer's (measured,
#: tests/test_mapping_snowboarder.py, tests/test_mapping_racing.py).
COM_PASSES = 2
#: Winter's segments that lean with the legs (:func:`legs_step`) and the bones whose poses give
#: every segment's ends (:func:`..anthropometry.segment_ends`).
LEG_SEGMENTS = ("thigh", "leg", "foot")
SEGMENT_BONES = tuple(f"{bone}.{s}" for bone in ("thigh", "shin", "foot", "toe", "upper_arm",
                                                   "forearm", "hand") for s in "LR")
#: Newton steps on :func:`legs_step`'s model: the fourth and a sixth give the same pose to
#: 1e-14 deg of the centre's lean (measured on the carver).
MODEL_STEPS = 4


def centre_on_lean(b, theta_v, pose, passes: int = COM_PASSES) -> None:
    """Pose ``b`` by ``pose(builder, extra)``, the legs leaning ``extra`` (n,) rad beyond
    ``theta_v``, with the ``extra`` that puts the posed figure's centre of mass (Winter's
    segments, :mod:`..anthropometry`) on ``theta_v`` from the foot point.  From ``passes``
    trial poses (:data:`COM_PASSES`): the first step is the root of :func:`legs_step`'s model,
    the next ones the secant's through the last two trials' misses (the pose is not linear in
    ``extra``: the hips drop where a leg cannot reach, the waist bends with the knees)."""
    th = np.asarray(theta_v, float)
    extra, last = np.zeros_like(th), None
    for _ in range(passes):
        trial = PoseBuilder(b.skel, b.n)
        trial.placement = b.placement
        pose(trial, extra)
        miss, step = legs_step({name: trial.pose(name) for name in SEGMENT_BONES}, b.skel, th,
                               th + extra)
        if last is not None:
            moved, slope = extra - last[0], np.zeros_like(th)
            np.divide(miss - last[1], moved, out=slope, where=moved != 0.0)
            step = np.where(np.abs(slope) > 1e-3, -miss / np.where(slope == 0.0, 1.0, slope),
                            step)
        last = (extra, miss)
        extra = extra + step
    pose(b, extra)


def legs_step(P, skel, theta_v, legs_lean):
    """``(miss, step)`` (n,) rad of the pose ``P`` whose legs lean ``legs_lean`` (n,) rad: how
    far its centre of mass leans beyond ``theta_v`` from the foot point, and the legs' further
    lean ``d`` that puts it on ``theta_v`` in a model of how the pose moves.  Leaning the legs
    by ``d`` further turns them and the hip joints by ``d`` about the foot's line and carries
    the rest of the body (pelvis, trunk, arms: turned back about the hips) with the hip joints;
    and :func:`set_pelvis` keeps the ankles at their height ``a`` above the ground, so the whole
    figure slides out along the legs' line by ``a (1 / cos(legs_lean + d) - 1 / cos legs_lean)``.
    The centre's moment is then ``R(d) A + C + slide``: ``A`` the legs' moment plus the rest's
    mass at the hip joints, ``C`` the rest's moment about them; ``d`` is its root in
    :data:`MODEL_STEPS` Newton steps."""
    legs, rest, m_rest = 0.0, 0.0, 0.0
    for name, a, e in segment_ends(P, skel):
        frac, at, _ = SEGMENTS[name]
        if name in LEG_SEGMENTS:
            legs = legs + frac * (a + at * (e - a))
        else:
            rest, m_rest = rest + frac * (a + at * (e - a)), m_rest + frac
    com = (legs + rest)[:, ::2] * (-1.0, 1.0)
    hips = 0.5 * (P["thigh.L"][:, :3, 3] + P["thigh.R"][:, :3, 3])
    ankle_z = 0.5 * (P["foot.L"][:, 2, 3] + P["foot.R"][:, 2, 3])
    A = (legs + m_rest * hips)[:, ::2] * (-1.0, 1.0)     # (x, z) with x to the left
    C = (rest - m_rest * hips)[:, ::2] * (-1.0, 1.0)
    secant = 1.0 / np.cos(legs_lean)

    def miss(d):
        c, s = np.cos(d), np.sin(d)
        out = ankle_z * (1.0 / np.cos(legs_lean + d) - secant)
        x = c * A[:, 0] + s * A[:, 1] + C[:, 0] + out * np.sin(legs_lean + d)
        z = -s * A[:, 0] + c * A[:, 1] + C[:, 1] + out * np.cos(legs_lean + d)
        return np.arctan2(x, z) - theta_v

    d = np.zeros_like(theta_v)
    for _ in range(MODEL_STEPS):
        m = miss(d)
        d = d - m / ((miss(d + 1e-6) - m) / 1e-6)
    return np.arctan2(com[:, 0], com[:, 1]) - theta_v, d


def spring_length(traj, k_s: float, static: float, lo: float, hi: float,
                  span: float = 0.0) -> np.ndarray:
    """Hip-to-ankle length (n,), m: a spring of stiffness ``k_s`` (N/m) about ``static``,
    driven by :func:`bridged_force` over ``span`` m."""
    return np.clip(static - (bridged_force(traj, span) - static_force(traj)) / k_s, lo, hi)


def bridged_force(traj, span: float) -> np.ndarray:
    """``F_leg`` (n,) averaged over the foot's travel ``s`` within ``span / 2`` m either side
    of each frame (the module docstring): the exact mean of the force taken linear in ``s``
    between the frames (the run's ends cut the span short)."""
    F = np.asarray(traj.F_leg, float)
    s = np.asarray(traj.s, float)
    if span <= 0.0 or len(s) < 2 or s[-1] <= s[0]:
        return F
    # The integral of the force over s up to each frame, then up to any point between frames.
    ds = np.diff(s)
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (F[1:] + F[:-1]) * ds)])

    def integral(x):
        x = np.clip(x, s[0], s[-1])
        k = np.clip(np.searchsorted(s, x, side="right") - 1, 0, len(s) - 2)
        u = x - s[k]
        slope = (F[k + 1] - F[k]) / np.where(ds[k] > 0.0, ds[k], 1.0)
        return cum[k] + F[k] * u + 0.5 * slope * u * u

    lo, hi = np.maximum(s - 0.5 * span, s[0]), np.minimum(s + 0.5 * span, s[-1])
    width = hi - lo
    return np.where(width > 0.0, (integral(hi) - integral(lo)) / np.where(width > 0.0, width, 1.0),
                    F)


def lean_on_spring_legs(b, traj, o, span: float = 0.0):
    """Lean the body by ``theta_v`` and size the spring legs (Section 7) on equipment ``span``
    m long (:func:`bridged_force`).

    Returns ``(theta_v, (right, fwd, up) body axes, full leg length, hip-to-ankle length (n,))``.
    """
    skel = b.skel
    th = np.asarray(traj.theta_v, float)
    axes = body_axes(skel)
    lean(b, th)
    full = sum(leg_lengths(skel, "thigh.L", "shin.L"))
    length = spring_length(traj, o.k_s, o.stance * full, o.leg_min * full, o.leg_max * full,
                           span)
    return th, axes, full, length

def tilt_gain(traj, gain) -> float:
    """``gain`` or, if None, the least-squares slope of ``theta_v`` on ``C_f`` (rad m).

    Section 7: "A linear relationship is assumed between the curvature of the ski and the angle
    at which the ski is tilted.  The constant to use is easily estimated from a plot like the
    one in Fig. 5" -- this is that estimate, made from the trajectory itself.
    """
    if gain is not None:
        return float(gain)
    c = traj.C_f
    den = float(np.dot(c, c))
    return float(np.dot(traj.theta_v, c) / den) if den > 0 else 0.0


def carry_vec(b, bone: str, v) -> np.ndarray:
    """The armature-space rest direction ``v`` as carried by ``bone``'s current pose, (n, 3)."""
    p = b.pose(bone)[:, :3, :3] @ b.skel.rest_of(bone)[:3, :3].T
    return p @ np.asarray(v, float)


def set_pelvis(b, theta_v, length, ankle_z: float, drop=0.0):
    """Slide the hips along the leaned body axis so the hip joints sit ``length`` above the
    ankles measured along the body (ankles at height ``ankle_z``), lowered by ``drop`` (n,)."""
    skel = b.skel
    hip_z = 0.5 * (skel.rest_of("thigh.L")[2, 3] + skel.rest_of("thigh.R")[2, 3])
    h = length + ankle_z / np.cos(theta_v) - drop
    up_local = skel.rest_of(B.HIPS)[:3, :3].T @ np.array([0.0, 0.0, 1.0])
    b.set_local(B.HIPS, location=(h - hip_z)[:, None] * up_local)


def hip_drop(b, ankles: dict, reach: float) -> np.ndarray:
    """How far (n,) the hips must slide down the body axis for every leg to reach its ankle
    with at most ``reach`` of its full length."""
    up = carry_vec(b, B.LEAN, (0.0, 0.0, 1.0))
    drop = np.zeros(b.n)
    for s, ankle in ankles.items():
        l1, l2 = leg_lengths(b.skel, B.side("thigh", s), B.side("shin", s))
        v = b.unposed(B.side("thigh", s))[:, :3, 3] - ankle
        vu = dot(v, up)
        target = reach * (l1 + l2)
        disc = target * target - dot(v, v) + vu * vu
        need = vu - np.sqrt(np.maximum(disc, 0.0))
        drop = np.maximum(drop, np.where(norm(v) > target, need, 0.0))
    return drop


def knee_flexion(b, s: str) -> np.ndarray:
    """Angle (n,) between thigh and shin, rad (0 = straight leg)."""
    y1 = b.pose(B.side("thigh", s))[:, :3, 1]
    y2 = b.pose(B.side("shin", s))[:, :3, 1]
    return np.arccos(np.clip(dot(y1, y2), -1.0, 1.0))


def legs_to(b, ankles: dict, pole, twist: dict | None = None, carriers: dict | None = None):
    """IK both legs to their ankles and glue each foot to its carrier (ski, board)."""
    for s, ankle in ankles.items():
        ik_limb(b, B.side("thigh", s), B.side("shin", s), ankle, pole,
                None if twist is None else twist[s])
        if carriers:
            foot = B.side("foot", s)
            p = carried(b, foot, carriers[s])
            b.set_pose(foot, p[:, :3, :3])


def bend_waist(b, right, angle):
    """Bend forward at the waist by ``angle`` (n,) rad (Section 7: tied to the knee bend)."""
    add_local_rotation(b, B.SPINE, right, -np.asarray(angle))


def twist_upper_body(b, up, angle):
    """Twist the upper body about the body's up axis by ``angle`` (n,) rad (left positive),
    spread over the three spine segments above the hips."""
    for bone in (B.SPINE, B.SPINE_2, B.CHEST):
        add_local_rotation(b, bone, up, np.asarray(angle) / 3.0)


def level_head(b, theta_v, amount: float):
    """Turn the neck against the lean by ``amount * theta_v``, as people keep their eyes level."""
    add_local_rotation(b, B.NECK, (0.0, 1.0, 0.0), amount * np.asarray(theta_v))
