"""The cyclist (Section 7): "The bicyclist requires only a simple calculation to determine how
the front wheel should be turned to achieve the given curvature C_f.  Inverse kinematics is used
to keep the hands on the handlebars.  The pedals move as a function of the distance travelled.
Inverse kinematics is used to keep the feet on the pedals."

Bike and rider lean together by ``theta_v`` about the line through the wheels' contact points
(the rig's Y axis at z = 0).  The rig's steering axis (the fork bone) is raked like a real
bicycle's: a 72 deg head angle and a 45 mm fork offset, so 6 cm of trail.  Steering turns the fork
about that axis; the front wheel's rise or drop as it steers and leans is taken up by sliding it
along the axis, so its lowest point stays on the ground.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.physics.params import BodyParams, Figure, Limits, check_range
from ...core.sports import Retarget, Sport, register_sport
from ...core.physics.grip import TYRE
from ...core.physics.model import Resistance
from .. import bones as B
from ..base import Mapping
from .common import add_local_rotation, carried, ik_limb, lean, tyre_radius
from .snow import carry_vec

SIDES = (("L", -1.0), ("R", 1.0))


@dataclass(frozen=True)
class CyclistOptions:
    """Parameters of the cyclist mapping (SI units, angles in radians)."""

    wheel_radius: float | None = None
    """Rolling radius of the wheels, m; None takes the tyre radius from the rig."""
    gear_ratio: float = 2.0
    """Chainring teeth / sprocket teeth: wheel revolutions per crank revolution."""
    wheelbase: float | None = None
    """Distance between the hubs, m; None measures it on the rig."""
    steer_max: float = math.radians(45.0)
    """Largest steer angle of the fork, rad."""

    def __post_init__(self):
        if self.wheel_radius is not None:
            check_range("wheel_radius", self.wheel_radius, 0.05, 2.0)
        check_range("gear_ratio", self.gear_ratio, 0.1, 10.0)
        if self.wheelbase is not None:
            check_range("wheelbase", self.wheelbase, 0.2, 5.0)
        check_range("steer_max", self.steer_max, 0.0, math.pi / 2, lo_open=True, hi_open=True)


def steer_angle(C_f, theta_v, wheelbase: float, steer_max: float, caster: float = 0.0):
    """Fork angle (rad, positive = left) for the curvature ``C_f`` at lean ``theta_v``, about a
    steering axis tilted back from the bike's vertical by ``caster`` (90 deg - head angle).

    A bicycle whose front wheel rolls ``delta_g`` off the frame's heading follows
    ``C = tan(delta_g) / wheelbase`` (the rear axle's curvature; the foot point is close to it).
    The wheel rolls along the line where its plane meets the ground, ``atan(a_y / a_x)`` off the
    frame for the axle ``a``.  Steering by ``delta`` about the raked axis turns the axle ``(1, 0,
    0)`` into ``(cos delta, cos(caster) sin delta, sin(caster) sin delta)``; leaning by
    ``theta_v`` makes ``a_x = cos delta cos theta_v - sin(caster) sin delta sin theta_v``.  Hence
    ``tan(delta) = wheelbase C_f cos(theta_v) / (cos(caster) + wheelbase C_f sin(caster)
    sin(theta_v))`` (with no caster: ``wheelbase C_f cos(theta_v)``).
    """
    k = wheelbase * np.asarray(C_f)
    return np.clip(np.arctan2(k * np.cos(theta_v),
                              math.cos(caster) + k * math.sin(caster) * np.sin(theta_v)),
                   -steer_max, steer_max)


class CyclistMapping(Mapping):
    sport = "cyclist"
    Options = CyclistOptions

    def pose(self, b, traj, o, spec):
        skel = b.skel
        th = np.asarray(traj.theta_v, float)
        lean(b, th)
        front, rear = skel.rest_of(B.WHEEL_F)[:3, 3], skel.rest_of(B.WHEEL_R)[:3, 3]
        wheelbase = o.wheelbase or float(np.linalg.norm((front - rear)[:2]))
        r_tyre = tyre_radius(spec)
        radius = o.wheel_radius or r_tyre
        up = np.array([0.0, 0.0, 1.0])

        # Steering: a rotation about the fork's own (raked) axis.
        fork_axis = skel.rest_of(B.FORK)[:3, 1]
        caster = math.atan2(-fork_axis[1], fork_axis[2])
        delta = steer_angle(traj.C_f, th, wheelbase, o.steer_max, caster)
        add_local_rotation(b, B.FORK, fork_axis, delta)

        # Wheels and crank turn with the distance travelled (rolling without slip): forward
        # rolling is a negative rotation about the axle (+X, the bones' Y axes).  A part of a
        # run (meta "s_start": the distance at the run's first frame) turns them as the run does.
        s = np.asarray(traj.s, float) - float(traj.meta.get("s_start", traj.s[0]))
        wheel_angle = s / radius
        crank_angle = wheel_angle / o.gear_ratio
        axle = np.array([1.0, 0.0, 0.0])
        for wheel in (B.WHEEL_F, B.WHEEL_R):
            add_local_rotation(b, wheel, axle, -wheel_angle)
        add_local_rotation(b, B.CRANK, axle, -crank_angle)
        # The pedals stay level with the frame (the rider's feet keep them so).
        for pedal in B.PEDAL:
            b.set_pose(pedal, carried(b, pedal, B.FRAME)[:, :3, :3])

        # Keep the steered and leaned front tyre on the ground: its lowest point is
        # hub_z - r sqrt(1 - a_z^2) for the axle direction a.
        hub = b.pose(B.WHEEL_F)
        a = hub[:, :3, 1]
        low = hub[:, 2, 3] - r_tyre * np.sqrt(np.maximum(1.0 - a[:, 2] ** 2, 0.0))
        slide = -low / carry_vec(b, B.FORK, fork_axis)[:, 2]
        loc = skel.rest_of(B.WHEEL_F)[:3, :3].T @ fork_axis
        b.set_local(B.WHEEL_F, location=slide[:, None] * loc)

        # Rider: feet on the pedals, hands on the handlebar (analytic IK, Section 7).
        right, fwd = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
        for side, sx in SIDES:
            foot, pedal = B.side("foot", side), B.side("pedal", side)
            ankle = carried(b, foot, pedal)[:, :3, 3]
            knee_dir = carry_vec(b, B.FRAME, fwd + 0.15 * sx * right)
            ik_limb(b, B.side("thigh", side), B.side("shin", side), ankle, knee_dir)
            b.set_pose(foot, carried(b, foot, pedal)[:, :3, :3])
            hand = B.side("hand", side)
            wrist = carried(b, hand, B.FORK)[:, :3, 3]
            elbow_dir = carry_vec(b, B.FRAME, 0.5 * sx * right - 0.4 * fwd - 0.75 * up)
            ik_limb(b, B.side("upper_arm", side), B.side("forearm", side), wrist, elbow_dir)
            b.set_pose(hand, carried(b, hand, B.FORK)[:, :3, :3])


#: The sport's record (docs/registry.md): its preset, resistance, rig, mapping and labels.
SPORT = register_sport(Sport(
    name="cyclist", label="Cyclist", description="Cyclist on a road bicycle", number=3,
    figure=Figure(
        "cyclist", BodyParams(m=85.0, l=1.0, I_v=15.0, V_cm=6.0),
        Limits(C_f_max=0.5, dC_f_max=2.0, theta_fall=math.radians(55)),
        """Cyclist on a road bicycle.  Rider and bicycle 85 kg, centre of mass ~1.0 m, I_v 15 kg
        m^2 (the bicycle adds roll inertia); 6 m/s.  A 1.0 m wheelbase with ~27 deg of usable
        steer gives C_f = tan(27 deg) / 1.0 ~ 0.5; the bar goes lock to lock in ~0.5 s:
        |dC_f/dt| <= 2.0.  A bicycle steers sharper and faster than a ski (Section 5.2).  The
        bicycle lies on the road (pedal and bar down) past ~55 deg; dry asphalt's grip
        (mu ~0.9) holds about 42 deg, which a cyclist reaches (docs/racing.md)."""),
    # Road tyres on smooth asphalt: rolling resistance 0.003-0.006; a rider on the hoods
    # 0.3-0.4 m^2 (Wilson & Papadopoulos 2004, "Bicycling Science", 3rd ed., Ch. 4-5); sea level.
    resistance=Resistance(mu=0.005, CdA=0.36, rho=1.225),
    plan_curvature_rate=0.5,
    grip=TYRE["dry"],
    mapping=CyclistMapping(),
    bones=(B.ROOT, B.LEAN) + B.HUMAN + (B.FRAME, B.FORK, B.WHEEL_F, B.WHEEL_R, B.CRANK) + B.PEDAL,
    # The rider sits on the frame (seated: the hips go where the built-in's go), steers the
    # fork (the hands are carried by it) and pedals (the feet are carried by the pedals).  The
    # crank turns to face the right pedal; the wheels roll with the distance travelled (no bone
    # of the rider turns with them: a driver turns them) and the front wheel slides along the
    # fork by turn_fork_slide, which keeps the steered and leaned tyre on the ground.
    retarget=Retarget(attach={"frame": "spine", "wheel.R": "spine", "crank": "spine",
                              "fork": "hand.L", "wheel.F": "hand.L", "pedal.L": "foot.L",
                              "pedal.R": "foot.R"},
                      tracks={"crank": "pedal.R"}, spin=("wheel.F", "wheel.R"),
                      slide={"wheel.F": ("fork", "turn_fork_slide")}, seated=True),
))
