"""The alpine skier (Section 7, Fig. 5 and Fig. 20 for the inputs).

Section 7: the legs act as a spring driven by ``F_leg`` (stiffness ``k_s``), the knee bend comes
from two-bone IK on the resulting leg length and the waist bend is tied to the knee bend; the
ski tilt is linear in ``C_f`` with the outside (weight-bearing) ski tilted slightly more; when
``theta_v`` and the ski tilt disagree the leg is twisted in or out; the poles are planted at
``phi`` = 30 and 210 deg, just before each turn; the upper body twists in phase with the turn.
On a preset's carving skis the skier angulates as racers do (docs/racing.md): shins on the
skis' edge angle, hips and knees inside the turn, the upper body more upright, the centre of
mass of the posed figure on ``theta_v``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.physics.params import BodyParams, Figure, Limits, check_range
from ...core.equipment import (Carving, SportPreset, carving_limits, carving_of,
                              register_preset)
from ...core.sports import Retarget, Sport, register_sport
from ...core.physics.model import Resistance
from .. import bones as B
from ..base import Mapping
from .common import (add_local_rotation, carried, height_on_ground, ik_limb, lean, leg_lengths,
                     limb_frames, phase_window, place_on_ground, rot_y, rot_z, smoothstep)
from ..kinematics import (frame_from_yx, norm, on_sphere_within, rigid_inverse,
                          stack_dot, two_bone_ik)
from .skid_pose import SkidPose, equipment_length, knee_direction, ski_front
from .snow import (AngulationOptions, angulation_back, bend_waist, carry_vec, centre_on_lean,
                   hip_drop, knee_flexion, lean_on_spring_legs, legs_to, level_head, set_pelvis,
                   tilt_gain, twist_upper_body)

SIDES = (("L", -1.0), ("R", 1.0))

# Hand (wrist) targets from the shoulder in the chest's axes (outwards, forwards, up), m, for the
# built-in's arm (``SkierOptions.plant_reach`` times them for another): held in front of the
# hips, reaching forwards and down for the plant.  The pole's tip points 15 deg out
# from straight ahead when planted and 150 deg (behind, outwards) when trailing.
HAND_NEUTRAL = (0.06, 0.30, -0.36)
HAND_PLANT = (0.10, 0.40, -0.33)
POLE_AIM_PLANT, POLE_AIM_TRAIL = math.radians(15.0), math.radians(150.0)
#: An arm whose grip offset moved less than this (m) in an aiming pass has settled: another pass
#: would give the same numbers to rounding, so it leaves the loop.
SETTLED = 1e-12
@dataclass(frozen=True)
class SkierOptions(AngulationOptions):
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
    """Half-width in phase of the pole's plant, rad: the tip touches down before the plant phase
    and stays in its hole (world space) within this of it, for as long as the arm can follow."""
    pole_swing: float = math.radians(70.0)
    """Phase over which the pole swings between planted and trailing, rad."""
    pole_swing_time: float = 0.6
    """Shortest time the pole takes to swing forward from trailing to a plant, s: at a quick
    rhythm the swing starts earlier in phase than ``pole_swing`` (after the last plant's
    lift-out), and a plant with less time than this since that lift-out is not made (the pole
    stays trailing).  It bounds how fast the free pole turns about its grip."""
    pole_lift: float = 0.35
    """Height of the pole tip when trailing, m."""
    plant_scale: float = 1.0
    """Size of the figure shown relative to the built-in rig (retargeting's ``k``, which scales
    the pose about the foot point): the pole holes are planned to stay put in that figure's
    world."""
    plant_reach: float = 1.0
    """The shown figure's arm length over ``plant_scale`` times the built-in's: the hand's
    targets from the shoulder scale with it (a shorter arm swings the pole as the built-in's
    does, at the same angles, and plants it nearer), and a plant lasts only as long as that arm
    can follow the figure past its hole."""
    twist_amp: float = math.radians(12.0)
    """Amplitude of the upper-body counter-twist (against the turn), rad."""
    twist_phase: float = 0.0
    """Phase offset of the upper-body twist relative to phi, rad."""
    knee_in_max: float = math.radians(35.0)
    """With angulation: the largest turn of a knee in or out about its hip-to-ankle line, rad
    (within the hip's 45 deg of internal and external rotation, AAOS normal ranges)."""

    def __post_init__(self):
        super().__post_init__()
        check_range("outside_extra", self.outside_extra, 0.0, 1.0)
        check_range("leg_twist_gain", self.leg_twist_gain, 0.0, 5.0)
        check_range("leg_twist_max", self.leg_twist_max, 0.0, math.pi / 2)
        check_range("pole_plant_L", self.pole_plant_L, 0.0, 2 * math.pi)
        check_range("pole_plant_R", self.pole_plant_R, 0.0, 2 * math.pi)
        check_range("pole_hold", self.pole_hold, 0.0, math.pi / 2)
        check_range("pole_swing", self.pole_swing, 0.0, math.pi, lo_open=True)
        check_range("pole_swing_time", self.pole_swing_time, 0.0, 5.0)
        check_range("pole_lift", self.pole_lift, 0.0, 1.0)
        check_range("plant_scale", self.plant_scale, 0.1, 10.0)
        check_range("plant_reach", self.plant_reach, 0.1, 10.0)
        check_range("twist_amp", self.twist_amp, -math.pi / 2, math.pi / 2)
        check_range("twist_phase", self.twist_phase, -2 * math.pi, 2 * math.pi)
        check_range("knee_in_max", self.knee_in_max, 0.0, math.pi / 2)


def ski_tilts(traj, o) -> dict:
    """Tilt (n,) of each ski, rad: linear in C_f, the outside ski (R in a left turn) more
    (Section 7); on a preset's carving skis (core/equipment.py) the edge angle that carves
    C_f by the sidecut relation, R_sc cos(edge) = 1 / |C_f|, both skis alike, unclipped."""
    carving = carving_of(traj.meta.get("preset"))
    if carving is not None:
        edge = carving.edge_angle(traj.C_f)
        return {s: edge for s, _ in SIDES}
    base = tilt_gain(traj, o.tilt_gain) * traj.C_f
    outside_is_right = traj.C_f > 0
    return {s: np.clip(base * (1.0 + o.outside_extra * np.where(outside_is_right == (s == "R"),
                                                                  1.0, 0.0)),
                       -o.tilt_max, o.tilt_max) for s, _ in SIDES}


def shank_twist(b, s: str, ankle, pole, edge) -> np.ndarray:
    """The twist (n,) rad of leg ``s``'s knee about its hip-to-ankle line (``common.ik_limb``'s
    ``twist``, from the knee's ``pole``) that stands its shin, knee to ankle, at ``edge`` (n,)
    from vertical across the travel, as the ski's base stands (a ski boot holds the shin square
    to the ski across it): the knee moves on the circle the two-bone IK allows; of the two
    twists that reach the angle the smaller; where none does, the one nearest it."""
    thigh, shin = B.side("thigh", s), B.side("shin", s)
    base = b.unposed(thigh)
    root = base[:, :3, 3]
    l1, l2 = leg_lengths(b.skel, thigh, shin)
    mid, end = two_bone_ik(root, ankle, l1, l2, pole)
    k = (end - root) / norm(end - root, keepdims=True)
    centre = root + np.sum((mid - root) * k, axis=1, keepdims=True) * k
    h = norm(mid - centre, keepdims=True)
    u = (mid - centre) / np.maximum(h, 1e-12)
    v = np.cross(k, u)
    # The shin (knee - ankle) at `edge` across the travel is square to n = (cos e, 0, sin e).
    n = np.stack([np.cos(edge), np.zeros_like(edge), np.sin(edge)], 1)
    A, Bv, C = (h[:, 0] * np.sum(u * n, 1), h[:, 0] * np.sum(v * n, 1),
                np.sum((centre - end) * n, 1))
    r = np.hypot(A, Bv)
    alpha = np.arctan2(Bv, A)
    spread = np.arccos(np.clip(-C / np.maximum(r, 1e-12), -1.0, 1.0))
    wrap = lambda x: (x + np.pi) % (2.0 * np.pi) - np.pi      # noqa: E731
    a, c = wrap(alpha + spread), wrap(alpha - spread)
    return np.where(np.abs(a) <= np.abs(c), a, c)


class SkierMapping(Mapping):
    sport = "skier"
    Options = SkierOptions

    def ski_layout(self, traj, o):
        """Fore-aft offset (m), yaw (rad) and heel lift (rad) of each ski/boot: all zero here;
        the telemark skier overrides it."""
        z = np.zeros(len(traj))
        return {s: (z, z, z) for s, _ in SIDES}

    def pose(self, b, traj, o, spec):
        """Section 7's pose; on a preset's carving skis with angulation, a racer's: the skis on
        the edge angle ``edge`` that carves C_f stand further on edge than the body leans
        ``theta_v``; the shins stand on the skis' edge angle (square to the ski's base across
        it, :func:`shank_twist`), the pelvis and the upper body stand ``angulation`` times the
        edge's excess over the lean more upright than ``theta_v`` (at most ``angulation_max``),
        turned at the hip joints, and the legs lean further by the amount that keeps the centre
        of mass of the posed figure on ``theta_v`` (:func:`.snow.centre_on_lean`)."""
        carving = carving_of(traj.meta.get("preset"))
        if carving is None or o.angulation == 0.0:
            return self._pose(b, traj, o, spec)
        back = angulation_back(traj.theta_v, carving.edge_angle(traj.C_f), o)
        centre_on_lean(b, traj.theta_v,
                       lambda builder, extra: self._pose(builder, traj, o, spec, back, extra))

    def _pose(self, b, traj, o, spec, back=None, extra=0.0):
        """The pose; with angulation (``back`` (n,) rad, not None) the legs lean ``extra`` (n,)
        rad beyond ``theta_v``, the pelvis and the upper body ``back + extra`` rad back toward
        upright about the hip joints, the shins on the skis' edge angle."""
        skel = b.skel
        th, (right, fwd, up), full, length = lean_on_spring_legs(b, traj, o, equipment_length(spec))
        skid = SkidPose(traj)       # the skis across the travel (docs/skidding.md Section 8)
        skid.lean_back(b)
        skid.turn_hips(b, up)
        angulated = back is not None
        if angulated:
            lean(b, extra)
            th = th + extra
            add_local_rotation(b, B.HIPS, fwd, back + extra)  # the pelvis at the hip joints
        ankle_z = float(skel.rest_of("foot.L")[2, 3])
        tilts = skid.tilts(ski_tilts(traj, o))
        layout = skid.layout(self.ski_layout(traj, o))
        drop = np.zeros(len(traj))
        for _ in range(3):      # the hips drop if a leg cannot reach its boot (Section 7 IK)
            set_pelvis(b, th, length, ankle_z, drop)
            ankles = self.place_skis(b, spec, th, tilts, layout, skid)
            more = hip_drop(b, ankles, 0.97)
            if not np.any(more > 1e-9):
                break
            drop = drop + more
        knee_fwd = carry_vec(b, B.LEAN, fwd)
        if skid.active:                                 # the knees point along the skis
            knee_fwd = knee_direction(knee_fwd, skid.body_skid())
        if angulated:   # the knees in: each shin on its ski's edge angle where that is the
            # further (a ski flatter than the legs lean, at the edge change: along the legs)
            twist = {s: np.clip(shank_twist(b, s, ankles[s], knee_fwd,
                                            np.where(tilts[s] * th > th * th, tilts[s], th)),
                                -o.knee_in_max, o.knee_in_max) for s, _ in SIDES}
        else:   # Leg twist: when the ski is on edge more than the body leans, the knee turns in.
            twist = {s: np.clip(-o.leg_twist_gain * (tilts[s] - th), -o.leg_twist_max,
                                o.leg_twist_max) for s, _ in SIDES}
        legs_to(b, ankles, knee_fwd, twist, {s: B.side("ski", s) for s, _ in SIDES})
        self.feet(b, layout)
        knee = 0.5 * (knee_flexion(b, "L") + knee_flexion(b, "R"))
        bend_waist(b, right, o.waist_ratio * knee)
        # Upper-body counter-twist in phase with the turn (phase 0..180 deg is a left turn).
        twist_upper_body(b, up, -o.twist_amp * np.sin(traj.phi + o.twist_phase))
        skid.counter_rotate(b, up)
        level_head(b, th - (back + extra if angulated else 0.0), o.head_level)  # its own lean
        self.arms_and_poles(b, traj, o, right, fwd, up)

    def place_skis(self, b, spec, th, tilts, layout, skid=None) -> dict:
        """Set both skis on the ground under the body axis (a wedge's boots spread by
        ``skid``, a :class:`.skid_pose.SkidPose`); return the ankle targets."""
        skel = b.skel
        ankles = {}
        for s, _ in SIDES:
            ski, foot = B.side("ski", s), B.side("foot", s)
            hip = b.unposed(B.side("thigh", s))[:, :3, 3]
            a_rest = skel.rest_of(foot)[:3, 3]
            dy, yaw, _ = layout[s]
            # The foot goes where the leaned body axis through the hip meets the ankle's height
            # on its ski (on edge, the ski's lowest edge on the snow).
            R = stack_dot(rot_z(yaw) @ rot_y(-tilts[s]), skel.rest_of(ski)[:3, :3])
            z = height_on_ground(b, spec, ski, R, a_rest)
            xy = np.stack([hip[:, 0] + np.tan(th) * (hip[:, 2] - z), a_rest[1] + dy], 1)
            if skid is not None and skid.active:
                xy[:, 0] += skid.spread(ski_front(skel, spec, ski, a_rest), abs(a_rest[0]))[s]
            place_on_ground(b, spec, ski, R, a_rest, xy)
            ankles[s] = self.ankle_on_ski(b, s, layout)
        return ankles

    def ankle_on_ski(self, b, s, layout):
        return carried(b, B.side("foot", s), B.side("ski", s))[:, :3, 3]

    def feet(self, b, layout):
        """The boots are already glued to the skis (toes follow the feet)."""

    def arms_and_poles(self, b, traj, o, right, fwd, up):
        """Arm IK to a hand target that swings forward for the plant; the pole aims from the
        grip to a tip that touches the ground within ``pole_hold`` of the plant phase.

        Once planted the tip stays where it went in on the snow (world space) while the figure
        moves past it: the pole pivots about its tip and the hand follows, on the sphere of the
        pole's length about the tip, for as long as the arm reaches; then the pole lifts and
        swings back to trailing over ``pole_swing`` of phase.
        """
        skel = b.skel
        chest = stack_dot(b.pose(B.CHEST)[:, :3, :3], skel.rest_of(B.CHEST)[:3, :3].T)
        # The hand holds a planted pole between the elbow at a right angle and 98% of the arm's
        # length from the shoulder (of the arm shown: plant_reach times the built-in's).
        l1, l2 = (o.plant_reach * skel.length(B.side(bone, "L"))
                  for bone in ("upper_arm", "forearm"))
        reach = (math.hypot(l1, l2), 0.98 * (l1 + l2))
        place = b.placement
        sides = []
        for s, sx in SIDES:
            plant = o.pole_plant_L if s == "L" else o.pole_plant_R
            d = (traj.phi - plant + math.pi) % (2.0 * math.pi) - math.pi   # signed, wrapped
            w = phase_window(traj.phi, plant, o.pole_hold, o.pole_swing)
            neutral, planted = (o.plant_reach * (sx * x * right + y * fwd + z * up)
                                for x, y, z in (HAND_NEUTRAL, HAND_PLANT))
            shoulder = b.unposed(B.side("upper_arm", s))[:, :3, 3]
            hand = shoulder + np.einsum("nij,nj->ni", chest,
                                        (1 - w)[:, None] * neutral + w[:, None] * planted)
            elbow_dir = stack_dot(chest, sx * 0.4 * right - fwd - 0.3 * up)  # elbows back, out
            pole = B.side("pole", s)
            length = skel.length(pole)
            arm = _Arm(b, B.side("upper_arm", s), B.side("forearm", s), elbow_dir, pole)

            # Free swing first; its grip sits `offset` from the wrist the IK aims.
            grip, wrist = arm.reach(hand)
            offset = grip - wrist
            free = hand + offset
            free_axis = (sx, length, o.pole_lift, right, fwd, up)

            def planned(fw):
                """The plants of the swings ``fw``: the holes and touch-downs from the swing
                forward (a frame past the plant phase at a quick rhythm has the free pole
                trailing already)."""
                w_tip = np.where(fw.past, w, fw.w_aim)
                return _plan_plants(place, d, o.pole_hold, fw,
                                    grip + length * _free_axis(grip, w_tip, *free_axis), free,
                                    shoulder + offset, length, reach, o.plant_scale)

            # The free pole swings forward (and down) for the plant only, over at least
            # pole_swing_time: after the plant it trails, as a pole dragged out of its hole
            # does, until the swing to the next plant made.  It does not swing to a plant the
            # arm cannot hold (the next one has the time).
            fw = _swing_forward(traj.t, d, o.pole_hold, o.pole_swing, o.pole_swing_time)
            plan = planned(fw)
            if plan.missed.any():
                fw = _swing_forward(traj.t, d, o.pole_hold, o.pole_swing, o.pole_swing_time,
                                    plan.missed)
                plan = planned(fw)
            swing = (fw.w_aim,) + free_axis
            sides.append((arm, plan, free, offset, length, swing, elbow_dir, pole))
        # Both arms aim in one loop (each frame and side is solved on its own).
        aimed = _aim(*zip(*(side[:5] for side in sides)))
        for (arm, plan, _, _, length, swing, elbow_dir, pole), (aim_wrist, grip) in zip(sides,
                                                                                         aimed):
            lift = plan.u[plan.after, None]
            ik_limb(b, arm.upper, arm.lower, aim_wrist, elbow_dir)     # the arm's pose, once
            axis = _free_axis(grip, *swing)
            # Held: aim at the hole.  Lifting off: at a point moving from the hole to the free
            # swing's tip (both on or above the snow, so the tip stays out of it).
            aim = plan.tip_at.copy()
            aim[plan.after] = ((1 - lift) * aim[plan.after]
                               + lift * (grip + length * axis)[plan.after])
            moving = plan.held | plan.after
            to = aim[moving] - grip[moving]
            axis[moving] = to / norm(to, keepdims=True)
            free_tip = ~plan.planted          # a planted tip is in its hole, on the snow
            axis[free_tip] = _out_of_snow(place, grip[free_tip], axis[free_tip], length,
                                          o.plant_scale, plan.hole[free_tip], free_tip)
            b.set_pose(pole, frame_from_yx(axis, np.cross(axis, up)), grip)


def _free_axis(grip, w_aim, sx, length, lift, right, fwd, up):
    """The free pole's direction (n, 3) from its grip: trailing at ``POLE_AIM_TRAIL`` from ahead,
    swinging to ``POLE_AIM_PLANT`` by ``w_aim`` (n,), its tip ``lift`` (m) up when trailing
    (``sx`` the side's sign, ``length`` the pole's), coming down late in the swing (as
    ``1 - w_aim**2``: a swing forward of ``pole_swing_time`` starts low no earlier)."""
    beta = POLE_AIM_TRAIL + w_aim * (POLE_AIM_PLANT - POLE_AIM_TRAIL)
    horiz = (sx * np.sin(beta))[:, None] * right + np.cos(beta)[:, None] * fwd
    dz = lift * (1.0 - w_aim * w_aim) - grip[:, 2]
    rho = np.sqrt(np.maximum(length * length - dz * dz, 0.0))
    return (rho[:, None] * horiz + dz[:, None] * up) / length


def _targets(plan, free, length):
    """The grip's targets of the plan ``plan`` (the free swing's grips ``free`` elsewhere)."""
    lift = plan.u[plan.after, None]
    target = free.copy()
    target[plan.held] = plan.grip_at[plan.held]
    target[plan.after] = (1 - lift) * plan.grip_at[plan.after] + lift * free[plan.after]
    # ... never nearer the hole than the pole is long, or the tip would go into the snow.
    out = target[plan.after] - plan.tip_at[plan.after]
    r = norm(out, keepdims=True)
    target[plan.after] = plan.tip_at[plan.after] + out * np.maximum(r, length) / r
    return target


def _aim(arms, plans, frees, offsets, lengths):
    """Each arm (one per side) aimed at its plan's targets (:func:`_targets`) from the free
    swing's grip offsets ``offsets``: returns ``(wrist aimed at, grip reached)`` per arm.

    The offset turns with the hand: aim again with the new one.  Each frame is solved on its
    own, so a frame whose offset no longer moves (a free swing, after one pass) would only give
    the same numbers again: it leaves the loop, the rest go on; an arm whose every grip is
    within 2e-4 m of its target is done.  The arms' frames go through one IK per pass."""
    n = len(frees[0])
    arm = _Arm.joined(arms)
    target = np.concatenate([_targets(*a) for a in zip(plans, frees, lengths)])
    offset = np.concatenate(offsets)
    grip = target.copy()
    aim_wrist = target - offset
    sides = [slice(k * n, (k + 1) * n) for k in range(len(arms))]
    moving = [np.arange(k * n, (k + 1) * n) for k in range(len(arms))]
    for _ in range(12):
        live = [k for k in range(len(arms)) if moving[k] is not None]
        if not live:
            break
        idx = np.concatenate([moving[k] for k in live])
        aim_wrist[idx] = target[idx] - offset[idx]
        g, wr = arm.reach(aim_wrist[idx], idx)
        step = np.max(np.abs(g - wr - offset[idx]), axis=1, initial=0.0)
        grip[idx], offset[idx] = g, g - wr
        at = 0
        for k in live:
            mine = step[at:at + len(moving[k])]
            at += len(moving[k])
            if np.max(np.abs(grip[sides[k]] - target[sides[k]]), initial=0.0) < 2e-4:
                moving[k] = None                                      # ~10x per two passes
            else:
                moving[k] = moving[k][mine > SETTLED]
    return [(aim_wrist[k], grip[k]) for k in sides]


class _Arm:
    """The arm's two-bone IK (``common.ik_limb``) solved without writing the pose, for the
    aiming loop of ``arms_and_poles``: only the arm moves while it aims (the chest, and the
    hand's and the pole's rest offsets from the forearm, stay put), so where a wrist target puts
    the wrist and the pole's grip follows from the two limb rotations alone, not through the
    builder's quaternions and pose chain (the same values to rounding).  Everything is per
    frame, so two arms joined (:meth:`joined`) are solved as one over both arms' frames."""

    def __init__(self, b, upper, lower, elbow_dir, pole):
        skel = b.skel
        base = b.unposed(upper)
        n = b.n
        self.upper, self.lower = upper, lower
        self.root, self.hinge, self.elbow = base[:, :3, 3], base[:, :3, 0], elbow_dir
        self.l1, self.l2 = (np.full((n, 1), v) for v in leg_lengths(skel, upper, lower))
        # The lower bone's head in the upper bone's frame, and the wrist along the lower's Y.
        self.lower_head = np.repeat(skel.rest_relative(lower)[None, :3, 3], n, axis=0)
        self.fore = np.full((n, 1), skel.length(lower))
        # The grip in the lower bone's frame (through the hand, posed or not).
        self.grip = (rigid_inverse(b.pose(lower)) @ b.unposed(pole))[:, :3, 3]

    @classmethod
    def joined(cls, arms):
        """One solver over the frames of ``arms`` one after the other."""
        arm = cls.__new__(cls)
        arm.upper = arm.lower = None
        for key in ("root", "hinge", "elbow", "l1", "l2", "lower_head", "fore", "grip"):
            setattr(arm, key, np.concatenate([getattr(a, key) for a in arms]))
        return arm

    def reach(self, wrist, idx=slice(None)):
        """Aim the wrist (the forearm's tail) of frames ``idx`` at ``wrist`` (k, 3); return
        ``(grip, wrist)``, where the pole's grip and the wrist then are (armature space)."""
        root = self.root[idx]
        r_up, r_low, _ = limb_frames(root, self.hinge[idx], wrist, self.elbow[idx],
                                     self.l1[idx], self.l2[idx])
        head = root + np.einsum("nij,nj->ni", r_up, self.lower_head[idx])
        return (head + np.einsum("nij,nj->ni", r_low, self.grip[idx]),
                head + self.fore[idx] * r_low[:, :, 1])


#: The last part of the swing to a plant, as a fraction of its duration (``_Swings.span``): the
#: tip comes to rest in its hole over it (world space), instead of landing at the figure's speed
#: and sliding.  Coming to rest where the free swing would land, it first speeds up (by up to two
#: thirds of the free tip's speed, at the smoothstep's steepest), so the span is short: at most
#: ``pole_swing`` of phase and half of ``pole_swing_time``, past the swing's fast middle.
APPROACH = 0.5
#: A tip coming down to its hole or lifting out of it is at least ``STEEP`` times its horizontal
#: distance from the hole above the snow, up to ``RISE`` (m) (1: within 45 deg of straight down
#: onto it): within ``RISE`` of the snow it is over its hole, so it goes in and comes out there,
#: not skimming the snow at the figure's speed (a quick rhythm gives the swing in and the
#: lift-off 1-3 frames).
STEEP, RISE = 1.0, 0.10
#: The points along a free pole, as fractions of its length from the grip, kept on or above the
#: snow besides its tip (:func:`_out_of_snow`): every 10 cm of the built-in's 1.15 m pole, so a
#: crest narrower than that is all that could still reach between two of them.
POLE_POINTS = tuple(np.arange(1, 11) / 11.0)


def _world(place, p, idx, k):
    """Armature-space points ``p`` (m, 3) of frames ``idx`` in the world of the figure ``k``
    times the built-in's size (scaled about the foot point, as retargeting scales the pose)."""
    return place.origin[idx] + k * np.einsum("nij,nj->ni", place.R[idx], p)


def _local(place, P, idx, k):
    """World points ``P`` (m, 3) of the figure ``k`` times the size, in the built-in's armature
    space of frames ``idx`` (the inverse of :func:`_world`)."""
    P = np.broadcast_to(P, (len(idx), 3))
    return place.to_local(place.origin[idx] + (P - place.origin[idx]) / k, idx)


def _ground(place, P, idx):
    """The height (m,) of the snow under world points ``P`` (m, 3) of frames ``idx``: the Ground
    mesh's, or without one the plane under the foot (through the origin, normal to its +Z)."""
    if place.surface is not None:
        return np.asarray(place.surface(P[:, 0], P[:, 1]), float)
    o, nrm = place.origin[idx], place.R[idx][:, :, 2]
    return o[:, 2] - (nrm[:, 0] * (P[:, 0] - o[:, 0]) + nrm[:, 1] * (P[:, 1] - o[:, 1])) / nrm[:, 2]


def _clearance(place, P, idx, hole):
    """How high world points ``P`` (m, 3) of frames ``idx`` must be: the snow under them, plus
    ``STEEP`` times their horizontal distance from ``hole`` ((m, 3) world, NaN rows: none;
    infinite: ``RISE`` everywhere), at most ``RISE``."""
    r = np.nan_to_num(np.hypot(P[:, 0] - hole[:, 0], P[:, 1] - hole[:, 1]), nan=0.0)
    return _ground(place, P, idx) + np.minimum(STEEP * r, RISE)


def _out_of_snow(place, grip, axis, length, k, hole, frames):
    """The pole's directions ``axis`` (m, 3) of ``frames`` (a mask or indices) from its grips
    ``grip`` (armature space, the built-in's size; the figure shown ``k`` times it) turned up
    about the grip wherever the tip would be lower than :func:`_clearance` (``hole`` (m, 3)
    world, NaN rows: none) allows: the
    tip keeps its bearing from the grip and rises on the sphere of the pole's length (a fixed
    point of a few passes; a grip too low for any turn to clear it points the pole up).  The
    points :data:`POLE_POINTS` along it stay on or above the snow too: the pole turns up until
    the steepest of them clears it (a crest between the grip and the tip)."""
    idx = np.arange(len(place.origin))[frames]
    g = _world(place, grip, idx, k)
    a = np.einsum("nij,nj->ni", place.R[idx], axis)
    L = k * length
    rows = np.arange(len(idx))          # the poles still turning up (the others stay as they are)
    for _ in range(4):
        gr, ar, ir = g[rows], a[rows], idx[rows]
        need = _clearance(place, gr + L * ar, ir, hole[rows])
        tip = (need - gr[:, 2]) / L
        inner = np.max([(_ground(place, gr + f * L * ar, ir) - gr[:, 2]) / (f * L)
                        for f in POLE_POINTS], axis=0)
        low = (gr[:, 2] + L * ar[:, 2] < need - 1e-9) | (ar[:, 2] < inner - 1e-9)
        if not low.any():
            break
        rows, z = rows[low], np.clip(np.maximum(tip, inner)[low], -1.0, 1.0)
        flat = a[rows, :2] / np.maximum(np.hypot(a[rows, 0], a[rows, 1]), 1e-12)[:, None]
        a[rows] = np.column_stack([flat * np.sqrt(1.0 - z * z)[:, None], z])
    return np.einsum("nji,nj->ni", place.R[idx], a)


def _clear_of_snow(place, grip, tip, idx):
    """Whether the poles from ``grip`` to ``tip`` (m, 3) world of frames ``idx`` keep the points
    :data:`POLE_POINTS` along them on or above the snow (within 1 mm: a hole is on it)."""
    return np.min([(p := grip + f * (tip - grip))[:, 2] - _ground(place, p, idx)
                   for f in POLE_POINTS], axis=0) > -1e-3


def _approach(place, t, span, tips, free, P, i0, length, held, after, tip_at, grip_at, hole,
              k=1.0) -> None:
    """The frames before the plant at ``i0`` within ``span`` (s) of it: the tip goes from the
    free swing's to the hole ``P`` (world) along a smoothstep in time, so that it arrives at
    rest, and comes down onto the hole (:func:`_clearance`); the grip is the pole's length from
    it towards the free swing's grip.  Frames of an earlier plant stay."""
    j = i0 - 1
    while j >= 0 and t[i0] - span < t[j] and not (held[j] or after[j]):
        j -= 1
    idx = np.arange(j + 1, i0)
    if not len(idx):
        return
    s = smoothstep((t[idx] - (t[i0] - span)) / span)[:, None]
    world = (1.0 - s) * _world(place, tips[idx], idx, k) + s * P
    hole[idx] = P
    world[:, 2] = np.maximum(world[:, 2], _clearance(place, world, idx, hole[idx]))
    local = _local(place, world, idx, k)
    away = free[idx] - local
    held[idx], tip_at[idx] = True, local
    grip_at[idx] = local + length * away / norm(away, keepdims=True)


@dataclass
class _Swings:
    w_aim: np.ndarray     # (n,) the free pole's aim: 0 trailing -> 1 at the plant
    made: np.ndarray      # (n,) bool: from the swing forward to a plant made to its lift-out
    past: np.ndarray      # (n,) bool: of those, past the plant phase
    span: np.ndarray      # (n,) s: the swing's, at most ``swing`` of phase and least / 2
    lift: np.ndarray      # (n,) s: the lift-out's duration, over a plant's frames
    t: np.ndarray         # (n,) s: the frames' times


def _swing_forward(t, d, hold, swing, least, skip=None) -> _Swings:
    """The swings forward to the plants and the lift-outs after them (``d`` (n,) the signed
    phase from the plant, rad, at times ``t`` (n,) s).  A swing forward takes ``swing`` of phase
    but at least ``least`` seconds, from trailing (``w_aim`` 0) to the plant's window (``hold``
    of the plant phase, 1) along a smoothstep in time; a lift-out ``swing`` of phase but at
    least ``least / 3``.  So the free pole turns no faster than the swing's angle times 1.5 /
    ``least`` whatever the rhythm (``span``: the part the tip comes down to its hole over,
    :data:`APPROACH`).  A swing starts no earlier than the last plant's lift-out
    ends; a plant with less than ``least`` from there, or with a frame in ``skip`` (n,) bool,
    is not made and the pole stays trailing through it (a quick rhythm plants less often)."""
    n = len(d)
    w_aim, made, past = np.zeros(n), np.zeros(n, bool), np.zeros(n, bool)
    span, lift = np.zeros(n), np.zeros(n)
    rate = np.maximum(np.abs(np.gradient(np.unwrap(d), t)) if n > 1 else 0.0, 1e-9)
    win = np.abs(d) <= hold
    edges = np.diff(np.concatenate([[False], win, [False]]).astype(np.int8))
    free_at = -np.inf                  # when the last plant made has lifted out
    for a, e in zip(np.nonzero(edges > 0)[0], np.nonzero(edges < 0)[0]):
        if t[a] - free_at < least or (skip is not None and skip[a:e].any()):
            continue
        start = max(t[a] - max(swing / rate[a], least), free_at)
        before = (t > start) & (np.arange(n) < a)
        w_aim[before] = smoothstep((t[before] - start) / (t[a] - start))
        w_aim[a:e] = np.where(d[a:e] <= 0.0, 1.0, 0.0)
        span[before] = span[a] = min(t[a] - start, swing / rate[a], least / 2.0)
        # The lift-out ends by its duration after the window's last frame.
        free_at = t[e - 1] + max(swing / rate[a], least / 3.0)
        stop = int(np.searchsorted(t, free_at))
        made[before] = made[a:stop] = True
        past[a:stop] = d[a:stop] > 0.0
        lift[before] = lift[a:stop] = free_at - t[e - 1]
    return _Swings(w_aim, made, past, span, lift, t)


def on_snow(place, p):
    """The world points ``p`` (m, 3) moved onto the ground (vertically; the plane under the foot
    when there is no Ground mesh, where they already are)."""
    if place.surface is None:
        return p
    p = np.array(p, float)
    p[:, 2] = place.surface(p[:, 0], p[:, 1])
    return p


@dataclass
class _Plants:
    held: np.ndarray      # (n,) bool: the tip is in the snow (or coming down to its hole)
    after: np.ndarray     # (n,) bool: lifting off after a plant
    u: np.ndarray         # (n,) 0 at lift-off -> 1 when the pole swings free again
    tip_at: np.ndarray    # (n, 3) armature-space hole in the snow while held and lifting off
    grip_at: np.ndarray   # (n, 3) armature-space grip while held (and at lift-off after)
    hole: np.ndarray      # (n, 3) world: the hole coming down, held and lifting off; NaN else
    planted: np.ndarray   # (n,) bool: the tip in its hole (held, not coming down to it)
    missed: np.ndarray    # (n,) bool: the touch-downs of plants the arm could not hold


def _plan_plants(place, d, hold, fw, tips, free, shoulder, length, reach,
                 scale: float = 1.0) -> _Plants:
    """Where each plant goes into the snow and how long it can stay (see arms_and_poles); the
    holes stay put in the world of the figure ``scale`` times the built-in's size.

    ``d`` is the signed phase from the plant, ``fw`` the swings forward to the plants made
    (:func:`_swing_forward`), ``tips`` and ``free`` the swing forward's tip and
    the free swing's grip (armature space), ``shoulder`` the shoulder shifted by the grip's
    offset from the wrist, so that ``reach[0] <= |grip - shoulder| <= reach[1]`` says the arm
    holds it.  A plant whose hole the arm cannot hold from the touch-down on is not made: the
    pole swings on above the snow (``missed``, for a plan without that swing)."""
    n = len(d)
    held, after = np.zeros(n, bool), np.zeros(n, bool)
    u = np.ones(n)
    tip_at, grip_at = tips.copy(), free.copy()
    hole = np.full((n, 3), np.nan)
    # In the snow within `hold` of the plant, and from the moment the swinging tip touches it.
    inside = fw.made & ((np.abs(d) <= hold) | ((d < 0) & (tips[:, 2] < 1e-3)))
    edges = np.diff(np.concatenate([[False], inside, [False]]).astype(np.int8))
    starts, ends = np.nonzero(edges > 0)[0], np.nonzero(edges < 0)[0]     # runs [i0, i1)
    if not len(starts):
        return _Plants(held, after, u, tip_at, grip_at, hole, held.copy(), held.copy())
    # Every run's frame by frame, all runs at once (the plan below does not change them).
    # The holes: where the swinging tips meet the snow.
    flat = tips[starts].copy()
    flat[:, 2] = 0.0
    holes = on_snow(place, _world(place, flat, starts, scale))
    idx = np.concatenate([np.arange(i0, i1) for i0, i1 in zip(starts, ends)])
    local = _local(place, np.repeat(holes, ends - starts, axis=0), idx, scale)
    # The grip on the sphere of the pole's length about the hole: towards the free swing's
    # grip, turned about the hole as far as needed for the hand to hold it (the pole's angle
    # changes, the tip stays put); the plant ends where no point of it is in reach.
    away = free[idx] - local
    to, ok = on_sphere_within(local, length, away / norm(away, keepdims=True),
                              shoulder[idx], *reach)   # and its line out of the snow:
    grips = local + length * to
    ok &= _clear_of_snow(place, _world(place, grips, idx, scale),
                         np.repeat(holes, ends - starts, axis=0), idx)
    offs = np.concatenate([[0], np.cumsum(ends - starts)])
    planted, missed = np.zeros(n, bool), np.zeros(n, bool)
    for P, i0, a, e in zip(holes, starts, offs[:-1], offs[1:]):
        # The whole swing forward keeps clear of the snow but over its hole (a rise on the way
        # would catch the tip), the last part of it comes to rest there; a swing to a plant not
        # made keeps RISE clear of the snow throughout (an infinitely far hole).
        aim = P if ok[a] else np.inf
        j = i0 - 1
        while j >= 0 and fw.made[j] and d[j] < 0.0 and not after[j]:
            j -= 1
        hole[j + 1:i0] = aim
        if ok[a]:
            _approach(place, fw.t, fw.span[i0] * APPROACH, tips, free, P, i0, length, held,
                      after, tip_at, grip_at, hole, scale)
            k = e - a if ok[a:e].all() else int(np.argmin(ok[a:e]))
            idx, grip = np.arange(i0, i0 + k), grips[a:a + k]
            held[idx], tip_at[idx], grip_at[idx], hole[idx] = True, local[a:a + k], grip, P
            planted[idx] = True
            r = idx[-1]
        else:
            # Not made: the swing forward ends where its tip is the frame before the plant
            # phase (above the snow), and swings back from there as from a hole in the air.
            r = max(int(np.searchsorted(d[i0:e - a + i0] > 0.0, True)) + i0 - 1, 0)
            missed[i0:i0 + e - a] = True
            P, grip = _world(place, tips[r:r + 1], np.array([r]), scale)[0], free[r:r + 1]
        # Lift off: from the last held pose to the free swing (:func:`_swing_forward`).
        dd = fw.t[r + 1:] - fw.t[r]
        j = r + 1 + int(np.searchsorted(dd, fw.lift[r]))
        u[r + 1:j] = smoothstep(dd[:j - r - 1] / fw.lift[r])
        after[r + 1:j], grip_at[r + 1:j] = True, grip[-1]
        hole[i0:j][np.isnan(hole[i0:j, 0])] = aim
        # The pole still aims at the hole it leaves (the figure moves away from it, so the tip
        # rises off the snow along that line) while it swings free.
        tip_at[r + 1:j] = _local(place, P, np.arange(r + 1, j), scale)
    return _Plants(held, after, u, tip_at, grip_at, hole, planted, missed)


#: The sport's record (docs/registry.md): its preset, resistance, rig, mapping and labels.
SPORT = register_sport(Sport(
    name="skier", label="Skier", description="Alpine skier on slalom skis", number=0,
    figure=Figure(
        "skier", BodyParams(m=75.0, l=1.0, I_v=12.0, V_cm=10.0),
        Limits(C_f_max=1 / 6, dC_f_max=0.67, theta_fall=math.radians(60)),
        """Alpine skier on slalom skis.  75 kg adult; centre of mass ~1.0 m above the skis in an
        athletic stance; roll inertia about the centre of mass of a 1.75 m adult ~12 kg m^2
        (m (0.4 m)^2); 10 m/s, a brisk recreational slalom.  A slalom ski has a ~12 m sidecut
        radius; edged and bent it carves ~R cos(edge angle), about 6 m at 60 deg, so
        |C_f| <= 1/6 1/m.  Edge to edge takes ~0.5 s: |dC_f/dt| <= 2 (1/6) / 0.5 ~ 0.67."""),
    # Waxed skis on groomed snow: kinetic friction 0.02-0.1 (Colbeck 1992, "A review of the
    # processes that control snow friction", CRREL Monograph 92-2); 0.05 for a ski carving
    # at speed.  Drag area of an alpine skier turning in a giant-slalom stance 0.4-0.6 m^2
    # (Meyer, Le Pelley & Borrani 2012, Med. Sci. Sports Exerc. 44(6)); air at ~2000 m, the
    # ISA density there (1.007 kg/m^3).
    resistance=Resistance(mu=0.05, CdA=0.5, rho=1.007),
    plan_curvature_rate=0.2,
    styles=("carve", "skid", "wedge"),
    mapping=SkierMapping(),
    bones=(B.ROOT, B.LEAN) + B.HUMAN + B.SKI + B.POLE,
    retarget=Retarget(attach={"ski.L": "foot.L", "ski.R": "foot.R", "pole.L": "hand.L",
                              "pole.R": "hand.R"}),
))


# -- the sport's own presets with race equipment (core/equipment.py, docs/racing.md) ---------
# Slalom: FIS, Specifications for Alpine Competition Equipment (edition 2023/24), men's SL ski
# at least 165 cm; the FIS sets no SL radius, and men's SL race skis of 165 cm have sidecut
# radii of 12.5-13 m.  Reid et al. 2020 (Front. Sports Act. Living 2:25) measured edge angles
# up to 71.0 +- 1.9 deg in slalom: edge_max 75 deg.  Edge to edge in ~0.3 s (Reid's 10 m
# gates at 12 m/s take 0.9 s a turn; the edge change is a third of it).
SL_SKI = Carving(length=1.65, sidecut_radius=12.5, edge_max=math.radians(75.0))
register_preset(SportPreset(
    name="slalom_racer", sport="skier", label="Slalom Racer", carving=SL_SKI,
    figure=Figure(
        "slalom_racer", BodyParams(m=85.0, l=0.95, I_v=13.6, V_cm=12.0),
        carving_limits(SL_SKI, 0.3, math.radians(85)),
        """A World Cup slalom racer on FIS slalom skis (165 cm, sidecut radius 12.5 m).  85 kg
        (men's technical racers are 80-95 kg); centre of mass 0.95 m above the skis in a
        racing stance; roll inertia scaled from the skier's by the mass (12 kg m^2 x 85 / 75);
        12 m/s, Reid et al.'s slalom speed.  |C_f| <= 1 / (12.5 m cos 75 deg) = 0.309 1/m;
        edge to edge in 0.3 s; the hip touches the snow from ~80 deg and the racer has fallen
        past 85 deg."""),
))

# Giant slalom: FIS (from 2017/18), men's GS ski at least 193 cm, sidecut radius at least
# 30 m.  Edge to edge in ~0.5 s.  Drag area: elite slalom and GS racers in a wind tunnel,
# Cd*S 0.23 +- 0.03 m^2 in a tuck to 0.66 +- 0.09 m^2 standing high (Elfmark, Ettema, Supej &
# Holmberg 2022, Appl. Sci. 12(2):902); recreational skiers in GS postures 0.4-0.6 m^2 (Meyer,
# Le Pelley & Borrani 2012, Med. Sci. Sports Exerc. 44(6)).  A racer's compact GS stance:
# 0.4 m^2 (the recreational skier's 0.5 stays the sport's).
GS_SKI = Carving(length=1.93, sidecut_radius=30.0, edge_max=math.radians(75.0))
register_preset(SportPreset(
    name="gs_racer", sport="skier", label="GS Racer", carving=GS_SKI, drag_area=0.4,
    figure=Figure(
        "gs_racer", BodyParams(m=85.0, l=1.0, I_v=13.6, V_cm=18.0),
        carving_limits(GS_SKI, 0.5, math.radians(85)),
        """A giant slalom racer on FIS GS skis (193 cm, sidecut radius 30 m).  85 kg, centre of
        mass 1.0 m, roll inertia 13.6 kg m^2; 18 m/s, a GS speed.  |C_f| <= 1 / (30 m cos
        75 deg) = 0.129 1/m; edge to edge in 0.5 s; fallen past 85 deg."""),
))
