"""The body of a posed built-in figure: its centre of mass and roll inertia from segment data
(the telemark skier's own body).  numpy only.

Segment masses, centres of mass and radii of gyration are Dempster's cadaver data as tabulated by
D. A. Winter, *Biomechanics and Motor Control of Human Movement*, 4th ed. (Wiley 2009), Table
4.1.  The figure is twelve segments between its joints: per side the upper arm (shoulder to
elbow), forearm (elbow to wrist), hand (wrist to the hand bone's tail, Winter's knuckle II),
thigh (hip to knee), leg (knee to ankle) and foot (ankle to the ball of the foot, Winter's
metatarsal II head); and trunk-head-neck (Winter's "trunk head neck", greater trochanter to
glenohumeral joint: here the hip joints' midpoint to the shoulder joints' midpoint).  The
fractions sum to 1.  Each segment is a slender rod for its own inertia: ``m (rho L)^2`` about
an axis through its centre across it, ``(rho L)^2 m sin^2`` of the angle to an oblique axis.

The model's body (Section 2) is an inverted pendulum rolling about the line of travel: ``l`` is
the distance from the foot point to the centre of mass in the plane across the travel, and
``I_v`` the roll inertia about the centre of mass (docs: ``I_v`` is about the COM, Eq. 13).
"""
from __future__ import annotations

import numpy as np

from .kinematics import dot, norm, stack_dot

__all__ = ["SEGMENTS", "segment_ends", "centre_and_roll_inertia"]

#: Winter (2009) Table 4.1: segment -> (mass fraction, COM from the proximal end as a fraction
#: of the segment length, radius of gyration about the COM as a fraction of the length).
SEGMENTS = {
    "upper_arm": (0.028, 0.436, 0.322),
    "forearm": (0.016, 0.430, 0.303),
    "hand": (0.006, 0.506, 0.297),
    "thigh": (0.100, 0.433, 0.323),
    "leg": (0.0465, 0.433, 0.302),
    "foot": (0.0145, 0.50, 0.475),
    "trunk_head_neck": (0.578, 0.66, 0.503),
}


def _tail(P, skel, bone):
    return P[bone][:, :3, 3] + skel.length(bone) * P[bone][:, :3, 1]


def segment_ends(P, skel) -> list:
    """``[(segment, proximal (n, 3), distal (n, 3)), ...]`` of a posed built-in skeleton:
    ``P`` its armature-space bone poses (``Skeleton.fk``), ``skel`` with bone lengths."""
    head = lambda b: P[b][:, :3, 3]                    # noqa: E731
    out = [("trunk_head_neck", 0.5 * (head("thigh.L") + head("thigh.R")),
            0.5 * (head("upper_arm.L") + head("upper_arm.R")))]
    for s in "LR":
        out += [("upper_arm", head(f"upper_arm.{s}"), head(f"forearm.{s}")),
                ("forearm", head(f"forearm.{s}"), head(f"hand.{s}")),
                ("hand", head(f"hand.{s}"), _tail(P, skel, f"hand.{s}")),
                ("thigh", head(f"thigh.{s}"), head(f"shin.{s}")),
                ("leg", head(f"shin.{s}"), head(f"foot.{s}")),
                ("foot", head(f"foot.{s}"), head(f"toe.{s}"))]
    return out


def centre_and_roll_inertia(P, skel, mass: float, axis=(0.0, 1.0, 0.0)):
    """``(com (n, 3), I (n,))``: the centre of mass (armature space, m) and the moment of
    inertia (kg m^2) about the line through it along ``axis`` (the travel, the rig's +Y) of a
    body of ``mass`` kg posed as ``P`` (see :func:`segment_ends`)."""
    e = np.asarray(axis, float) / np.linalg.norm(axis)
    parts = []
    for name, a, b in segment_ends(P, skel):
        frac, at, rg = SEGMENTS[name]
        seg = b - a
        length = norm(seg)
        u = seg / length[:, None]
        own = (rg * length) ** 2 * (1.0 - stack_dot(u, e) ** 2)   # a rod about a parallel axis
        parts.append((frac * mass, a + at * seg, frac * mass * own))
    m = sum(p[0] for p in parts)
    com = sum(p[0] * p[1] for p in parts) / m
    inertia = np.zeros(len(com))
    for mi, c, own in parts:
        d = c - com
        inertia += mi * (dot(d, d) - stack_dot(d, e) ** 2) + own
    return com, inertia
