"""The snowboarder (Section 7): "The bend at the knees and waist are calculated based upon the
leg force, as with the skier.  The upper body is made to twist in phase with C_f.  Tilting the
snowboard with respect to the body is easily accomplished by bending at the ankles.  The arms
are moved to lead the twisting motion of the upper body slightly."

The rig rides regular (left foot forward, facing +X, the toe edge on the right of travel), so a
left turn (``C_f > 0``) is a heelside turn.  The board is tilted linearly in ``C_f`` and set on
its edge on the ground; the boots are glued to it, so the ankles take up the difference between
the board's tilt and the body's lean ``theta_v``.  On a preset's carving board (the carver) the
board stands on the edge angle that carves C_f by the sidecut relation, the rider angulates
where that edge exceeds the lean (hips and knees inside the turn, the upper body more upright)
(docs/racing.md).  On either board the legs lean so that the centre of mass of the posed figure
leans ``theta_v`` (the side-on rider's waist bend is across the travel).
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
from .common import add_local_rotation, carried, lean, place_on_ground, rot_y, rot_z
from .skid_pose import SkidPose, equipment_length, knee_direction
from .snow import (COM_PASSES, AngulationOptions, angulation_back, bend_waist, carry_vec,
                   centre_on_lean, hip_drop, knee_flexion, lean_on_spring_legs, legs_to,
                   level_head, set_pelvis, tilt_gain, twist_upper_body)

SIDES = ("L", "R")
#: Trial poses of the carver's centre of mass (:func:`.snow.centre_on_lean`): on edge past the
#: lean the side-on rider's centre moves less linearly with the legs' lean than a skier's (the
#: hips drop to reach the board, the waist bends across the travel); two leave it up to 0.031
#: deg off theta_v, three within 0.0001 deg (measured, tests/test_mapping_racing.py).
CARVER_PASSES = 3


@dataclass(frozen=True)
class SnowboarderOptions(AngulationOptions):
    """Parameters of the snowboarder mapping (SI units, angles in radians)."""

    stance: float = 0.92
    """Hip-to-ankle length at the static force m g, fraction of the full leg length."""
    waist_ratio: float = 0.3
    """Forward bend at the waist per radian of knee bend, rad/rad (less than the skier's: the
    lean already pitches a side-on rider forwards or back)."""
    twist_gain: float = 2.5
    """Upper-body twist per unit curvature, rad m (towards the turn)."""
    twist_max: float = math.radians(40.0)
    """Largest upper-body twist, rad."""
    arm_lead: float = 0.15
    """How far ahead in time the arms anticipate the twist, s."""
    arm_gain: float = 1.0
    """Arm swing about the chest's up axis per radian of twist still to come
    (twist ``arm_lead`` later minus twist now), rad/rad."""
    arm_spread: float = math.radians(35.0)
    """How far the arms are held out from the body, rad."""

    def __post_init__(self):
        super().__post_init__()
        check_range("twist_gain", self.twist_gain, -100.0, 100.0)
        check_range("twist_max", self.twist_max, 0.0, math.pi / 2)
        check_range("arm_lead", self.arm_lead, 0.0, 2.0)
        check_range("arm_gain", self.arm_gain, 0.0, 5.0)
        check_range("arm_spread", self.arm_spread, 0.0, math.pi / 2)


class SnowboarderMapping(Mapping):
    sport = "snowboarder"
    Options = SnowboarderOptions

    def pose(self, b, traj, o, spec):
        """Section 7's pose; on a preset's carving board, the carver's: the board on the edge
        angle that carves C_f by the sidecut relation; where it stands further on edge than the
        body leans, the pelvis and the upper body stand ``angulation`` times the excess more
        upright than ``theta_v`` (at most ``angulation_max``), turned at the hip joints about
        the travel.  On either board the legs lean by the amount that keeps the centre of mass
        of the posed figure on ``theta_v`` (:func:`.snow.centre_on_lean`: the rider's forward
        bend at the waist is across the travel and moves it, 8.4 deg at a carver's apex)."""
        carving = carving_of(traj.meta.get("preset"))    # a preset's board: the sidecut relation
        if carving is None:
            tilt = np.clip(tilt_gain(traj, o.tilt_gain) * traj.C_f, -o.tilt_max, o.tilt_max)
            back, passes = np.zeros(len(traj)), COM_PASSES
        else:
            tilt = carving.edge_angle(traj.C_f)
            back, passes = angulation_back(traj.theta_v, tilt, o), CARVER_PASSES
        centre_on_lean(b, traj.theta_v, lambda builder, extra: self._pose(
            builder, traj, o, spec, tilt, back, extra), passes)

    def _pose(self, b, traj, o, spec, tilt, back, extra):
        """The pose with the board on ``tilt`` (n,) rad, the legs leaning ``extra`` (n,) rad
        beyond ``theta_v``, the pelvis and the upper body ``back + extra`` rad back toward
        upright about the hip joints (``back``: the angulation, zero on the sport's own
        board)."""
        skel = b.skel
        th, (right, fwd, up), full, length = lean_on_spring_legs(b, traj, o, equipment_length(spec))
        skid = SkidPose(traj)       # the board across the travel (docs/skidding.md Section 8)
        skid.lean_back(b)
        skid.turn_hips(b, up)
        lean(b, extra)
        th = th + extra
        add_local_rotation(b, B.HIPS, (0.0, 1.0, 0.0), back + extra)  # at the hip joints
        ankle_rest = {s: skel.rest_of(B.side("foot", s))[:3, 3] for s in SIDES}
        anchor = 0.5 * (ankle_rest["L"] + ankle_rest["R"])
        R = rot_y(-skid.tilt(tilt)) @ skel.rest_of(B.BOARD)[:3, :3]
        if skid.active:
            R = rot_z(skid.yaw()) @ R
        drop = np.zeros(len(traj))
        for _ in range(3):      # the hips drop if a leg cannot reach its boot
            set_pelvis(b, th, length, float(anchor[2]), drop)
            hip = 0.5 * (b.unposed("thigh.L")[:, :3, 3] + b.unposed("thigh.R")[:, :3, 3])
            xy = np.stack([hip[:, 0] + np.tan(th) * (hip[:, 2] - anchor[2]),
                           np.full(len(traj), anchor[1])], 1)
            place_on_ground(b, spec, B.BOARD, R, anchor, xy)
            ankles = {s: carried(b, B.side("foot", s), B.BOARD)[:, :3, 3] for s in SIDES}
            extra = hip_drop(b, ankles, 0.97)
            if not np.any(extra > 1e-9):
                break
            drop = drop + extra
        # The boots are bound to the board: the ankles bend to tilt it (Section 7).
        knee_fwd = carry_vec(b, B.LEAN, fwd)
        if skid.active:
            knee_fwd = knee_direction(knee_fwd, skid.body_skid())
        legs_to(b, ankles, knee_fwd, None, {s: B.BOARD for s in SIDES})
        knee = 0.5 * (knee_flexion(b, "L") + knee_flexion(b, "R"))
        bend_waist(b, right, o.waist_ratio * knee)
        twist = np.clip(o.twist_gain * traj.C_f, -o.twist_max, o.twist_max)
        twist_upper_body(b, up, twist)
        skid.counter_rotate(b, up)
        level_head(b, th - (back + extra), o.head_level)  # its own lean
        # Arms out to the sides, swinging ahead of the twist: the twist arm_lead seconds later.
        ahead = np.clip(o.twist_gain * np.interp(traj.t + o.arm_lead, traj.t, traj.C_f),
                        -o.twist_max, o.twist_max)
        for s, sx in (("L", -1.0), ("R", 1.0)):
            arm = B.side("upper_arm", s)
            add_local_rotation(b, arm, fwd, np.full(len(traj), -sx * o.arm_spread))
            add_local_rotation(b, arm, up, o.arm_gain * (ahead - twist))


#: The sport's record (docs/registry.md): its preset, resistance, rig, mapping and labels.
SPORT = register_sport(Sport(
    name="snowboarder", label="Snowboarder", description="Carving snowboarder", number=1,
    figure=Figure(
        "snowboarder", BodyParams(m=70.0, l=0.95, I_v=10.0, V_cm=8.0),
        Limits(C_f_max=0.2, dC_f_max=0.8, theta_fall=math.radians(60)),
        """Carving snowboarder.  70 kg, centre of mass 0.95 m, I_v 10 kg m^2; 8 m/s.  A board's
        ~7-8 m sidecut carves down to ~5 m: |C_f| <= 0.2; heel-to-toe edge change in ~0.5 s:
        |dC_f/dt| <= 0.8."""),
    # A snowboard's base slides like a ski's (Colbeck 1992); the rider stands sideways and
    # higher: the top of Meyer et al.'s range.
    resistance=Resistance(mu=0.05, CdA=0.6, rho=1.007),
    plan_curvature_rate=0.3,
    styles=("carve", "skid", "slip"),
    mapping=SnowboarderMapping(),
    bones=(B.ROOT, B.LEAN) + B.HUMAN + (B.BOARD,),
    # Regular stance: the left boot is the front one; the back boot is bound as exactly.
    retarget=Retarget(attach={"board": "foot.L"}),
    stances=("regular", "goofy"),
    snow_tracks=(0.14, (0.0,)),         # a board cuts one groove its width
))


# -- the sport's own presets with race equipment (core/equipment.py, docs/racing.md) ---------
# Eurocarving: a hard-boot alpine (carving) board, 163 cm with a 10 m sidecut radius (alpine
# boards: 155-185 cm, radii 8-14 m); the rider lays hand and hip on the snow, edge angles to
# ~80 deg.  Edge to edge in 0.4 s.
CARVING_BOARD = Carving(length=1.63, sidecut_radius=10.0, edge_max=math.radians(80.0))
register_preset(SportPreset(
    name="carver", sport="snowboarder", label="Carver (Eurocarve)", carving=CARVING_BOARD,
    figure=Figure(
        "carver", BodyParams(m=75.0, l=0.9, I_v=10.0, V_cm=12.0),
        carving_limits(CARVING_BOARD, 0.4, math.radians(85)),
        """A Eurocarving snowboarder on a hard-boot alpine board (163 cm, sidecut radius 10 m).
        75 kg, centre of mass 0.9 m in the low carving stance, roll inertia 10 kg m^2; 12 m/s.
        |C_f| <= 1 / (10 m cos 80 deg) = 0.576 1/m; edge to edge in 0.4 s; hand and hip touch
        the snow from ~80 deg, fallen past 85 deg."""),
))
