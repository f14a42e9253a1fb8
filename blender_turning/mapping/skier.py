"""The alpine skier (Section 7, Fig. 5 and Fig. 20 for the inputs).

Section 7: the legs act as a spring driven by ``F_leg`` (stiffness ``k_s``), the knee bend comes
from two-bone IK on the resulting leg length and the waist bend is tied to the knee bend; the
ski tilt is linear in ``C_f`` with the outside (weight-bearing) ski tilted slightly more; when
``theta_v`` and the ski tilt disagree the leg is twisted in or out; the poles are planted at
``phi`` = 30 and 210 deg, just before each turn; the upper body twists in phase with the turn.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..core.params import check_range
from . import bones as B
from .base import Mapping
from .common import carried, ik_limb, phase_window, place_on_ground, rot_y, rot_z
from .kinematics import frame_from_yx
from .snow import (SpringLegOptions, bend_waist, carry_vec, hip_drop, knee_flexion,
                   lean_on_spring_legs, legs_to, level_head, set_pelvis, tilt_gain,
                   twist_upper_body)

SIDES = (("L", -1.0), ("R", 1.0))

# Hand (wrist) targets from the shoulder in the chest's axes (outwards, forwards, up), m: held in
# front of the hips, reaching forwards and down for the plant.  The pole's tip points 15 deg out
# from straight ahead when planted and 150 deg (behind, outwards) when trailing.
HAND_NEUTRAL = (0.06, 0.30, -0.36)
HAND_PLANT = (0.10, 0.40, -0.33)
POLE_AIM_PLANT, POLE_AIM_TRAIL = math.radians(15.0), math.radians(150.0)


@dataclass(frozen=True)
class SkierOptions(SpringLegOptions):
    """Parameters of the skier mapping (SI units, angles in radians)."""

    outside_extra: float = 0.15
    """Extra tilt of the outside (weight-bearing) ski, fraction of the tilt."""
    leg_twist_gain: float = 0.8
    """Leg twist per radian of (ski tilt - theta_v), rad/rad (knee towards the turn)."""
    leg_twist_max: float = math.radians(25.0)
    """Largest leg twist, rad."""
    pole_plant_L: float = math.radians(30.0)
    """Phase of the left pole plant (before the left turn), rad."""
    pole_plant_R: float = math.radians(210.0)
    """Phase of the right pole plant (before the right turn), rad."""
    pole_hold: float = math.radians(20.0)
    """Half-width in phase of the pole's ground contact, rad."""
    pole_swing: float = math.radians(70.0)
    """Phase over which the pole swings between planted and trailing, rad."""
    pole_lift: float = 0.35
    """Height of the pole tip when trailing, m."""
    twist_amp: float = math.radians(12.0)
    """Amplitude of the upper-body counter-twist (against the turn), rad."""
    twist_phase: float = 0.0
    """Phase offset of the upper-body twist relative to phi, rad."""

    def __post_init__(self):
        super().__post_init__()
        check_range("outside_extra", self.outside_extra, 0.0, 1.0)
        check_range("leg_twist_gain", self.leg_twist_gain, 0.0, 5.0)
        check_range("leg_twist_max", self.leg_twist_max, 0.0, math.pi / 2)
        check_range("pole_plant_L", self.pole_plant_L, 0.0, 2 * math.pi)
        check_range("pole_plant_R", self.pole_plant_R, 0.0, 2 * math.pi)
        check_range("pole_hold", self.pole_hold, 0.0, math.pi / 2)
        check_range("pole_swing", self.pole_swing, 0.0, math.pi, lo_open=True)
        check_range("pole_lift", self.pole_lift, 0.0, 1.0)
        check_range("twist_amp", self.twist_amp, -math.pi / 2, math.pi / 2)
        check_range("twist_phase", self.twist_phase, -2 * math.pi, 2 * math.pi)


def ski_tilts(traj, o) -> dict:
    """Tilt (n,) of each ski, rad: linear in C_f, the outside ski (R in a left turn) more."""
    base = tilt_gain(traj, o.tilt_gain) * traj.C_f
    outside_is_right = traj.C_f > 0
    return {s: np.clip(base * (1.0 + o.outside_extra * np.where(outside_is_right == (s == "R"),
                                                                  1.0, 0.0)),
                       -o.tilt_max, o.tilt_max) for s, _ in SIDES}


class SkierMapping(Mapping):
    sport = "skier"
    Options = SkierOptions

    def ski_layout(self, traj, o):
        """Fore-aft offset (m), yaw (rad) and heel lift (rad) of each ski/boot: all zero here;
        the telemark skier overrides it."""
        z = np.zeros(len(traj))
        return {s: (z, z, z) for s, _ in SIDES}

    def pose(self, b, traj, o, spec):
        skel = b.skel
        th, (right, fwd, up), full, length = lean_on_spring_legs(b, traj, o)
        ankle_z = float(skel.rest_of("foot.L")[2, 3])
        tilts = ski_tilts(traj, o)
        layout = self.ski_layout(traj, o)
        drop = np.zeros(len(traj))
        for _ in range(3):      # the hips drop if a leg cannot reach its boot (Section 7 IK)
            set_pelvis(b, th, length, ankle_z, drop)
            ankles = self.place_skis(b, spec, th, tilts, layout)
            extra = hip_drop(b, ankles, 0.97)
            if not np.any(extra > 1e-9):
                break
            drop = drop + extra
        knee_fwd = carry_vec(b, B.LEAN, fwd)
        # Leg twist: when the ski is on edge more than the body leans, the knee turns in.
        twist = {s: np.clip(-o.leg_twist_gain * (tilts[s] - th), -o.leg_twist_max,
                            o.leg_twist_max) for s, _ in SIDES}
        legs_to(b, ankles, knee_fwd, twist, {s: B.side("ski", s) for s, _ in SIDES})
        self.feet(b, layout)
        knee = 0.5 * (knee_flexion(b, "L") + knee_flexion(b, "R"))
        bend_waist(b, right, o.waist_ratio * knee)
        # Upper-body counter-twist in phase with the turn (phase 0..180 deg is a left turn).
        twist_upper_body(b, up, -o.twist_amp * np.sin(traj.phi + o.twist_phase))
        level_head(b, th, o.head_level)
        self.arms_and_poles(b, traj, o, right, fwd, up)

    def place_skis(self, b, spec, th, tilts, layout) -> dict:
        """Set both skis on the ground under the body axis; return the ankle targets."""
        skel = b.skel
        ankles = {}
        for s, _ in SIDES:
            ski, foot = B.side("ski", s), B.side("foot", s)
            hip = b.unposed(B.side("thigh", s))[:, :3, 3]
            a_rest = skel.rest_of(foot)[:3, 3]
            dy, yaw, _ = layout[s]
            # The foot goes where the leaned body axis through the hip meets the ankle height.
            xy = np.stack([hip[:, 0] + np.tan(th) * (hip[:, 2] - a_rest[2]), a_rest[1] + dy], 1)
            R = rot_z(yaw) @ rot_y(-tilts[s]) @ skel.rest_of(ski)[:3, :3]
            place_on_ground(b, spec, ski, R, a_rest, xy)
            ankles[s] = self.ankle_on_ski(b, s, layout)
        return ankles

    def ankle_on_ski(self, b, s, layout):
        return carried(b, B.side("foot", s), B.side("ski", s))[:, :3, 3]

    def feet(self, b, layout):
        """The boots are already glued to the skis (toes follow the feet)."""

    def arms_and_poles(self, b, traj, o, right, fwd, up):
        """Arm IK to a hand target that swings forward for the plant; the pole aims from the
        grip to a tip that touches the ground within ``pole_hold`` of the plant phase."""
        skel = b.skel
        chest = b.pose(B.CHEST)[:, :3, :3] @ skel.rest_of(B.CHEST)[:3, :3].T
        for s, sx in SIDES:
            plant = o.pole_plant_L if s == "L" else o.pole_plant_R
            w = phase_window(traj.phi, plant, o.pole_hold, o.pole_swing)[:, None]
            neutral = sx * HAND_NEUTRAL[0] * right + HAND_NEUTRAL[1] * fwd + HAND_NEUTRAL[2] * up
            planted = sx * HAND_PLANT[0] * right + HAND_PLANT[1] * fwd + HAND_PLANT[2] * up
            shoulder = b.unposed(B.side("upper_arm", s))[:, :3, 3]
            target = shoulder + np.einsum("nij,nj->ni", chest, (1 - w) * neutral + w * planted)
            elbow_dir = chest @ (sx * 0.4 * right - fwd - 0.3 * up)     # elbows back and out
            ik_limb(b, B.side("upper_arm", s), B.side("forearm", s), target, elbow_dir)
            pole = B.side("pole", s)
            grip = b.unposed(pole)[:, :3, 3]
            length = skel.length(pole)
            beta = POLE_AIM_TRAIL + w[:, 0] * (POLE_AIM_PLANT - POLE_AIM_TRAIL)
            horiz = (sx * np.sin(beta))[:, None] * right + np.cos(beta)[:, None] * fwd
            dz = o.pole_lift * (1.0 - w[:, 0]) - grip[:, 2]
            rho = np.sqrt(np.maximum(length * length - dz * dz, 0.0))
            axis = (rho[:, None] * horiz + dz[:, None] * up) / length
            b.set_pose(pole, frame_from_yx(axis, np.cross(axis, up)), grip)

