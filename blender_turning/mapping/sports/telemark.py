"""The telemark skier (Section 7): "Turning for a telemark skier is achieved by separating the
skis and placing them at an angle with respect to each other.  Inverse kinematics defines the
position of the legs.  The remaining motions are similar to that of the skier."

The outside ski leads (the right ski in a left turn, ``C_f > 0``): the skis are ``separation``
apart fore and aft, smoothly swapping through ``tanh(C_f / lead_curvature)``.  Each ski is
yawed to be tangent to the foot's circle of curvature ``C_f`` at its fore-aft offset ``y``:
``yaw = C_f y``, so the angle between them is ``C_f`` times their separation.  The trailing
boot rises on its toes (the heel lifts about the ball of the foot), the toes stay flat on the
ski.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.physics.params import BodyParams, Figure, Limits, check_range
from ...core.sports import Retarget, Sport, register_sport
from ...core.physics.model import Resistance
from .. import bones as B
from .common import carried, rotate_about
from .skier import SkierMapping, SkierOptions


@dataclass(frozen=True)
class TelemarkOptions(SkierOptions):
    """The skier's parameters, a deeper stance, and the telemark position."""

    stance: float = 0.86
    """Hip-to-ankle length at the static force m g, fraction of the full leg length."""
    separation: float = 0.55
    """Fore-aft distance between the boots in a fully developed turn, m."""
    lead_curvature: float = 0.03
    """Curvature at which the lead is tanh(1) = 76 % developed, 1/m."""
    heel_max: float = math.radians(45.0)
    """Heel lift of the trailing boot at full separation, rad."""

    def __post_init__(self):
        super().__post_init__()
        check_range("separation", self.separation, 0.0, 1.2)
        check_range("lead_curvature", self.lead_curvature, 0.0, 10.0, lo_open=True)
        check_range("heel_max", self.heel_max, 0.0, math.radians(80.0))


class TelemarkMapping(SkierMapping):
    sport = "telemark"
    Options = TelemarkOptions

    def ski_layout(self, traj, o):
        lead = 0.5 * o.separation * np.tanh(np.asarray(traj.C_f) / o.lead_curvature)
        out = {}
        for s, sign in (("L", -1.0), ("R", 1.0)):
            dy = sign * lead                                # the right ski leads a left turn
            yaw = traj.C_f * dy                             # tangent to the circle of curvature
            heel = o.heel_max * np.clip(-dy / (0.5 * o.separation), 0.0, 1.0) \
                if o.separation > 0 else np.zeros_like(dy)
            out[s] = (dy, yaw, heel)
        return out

    def _foot_pose(self, b, s, heel):
        """The boot on its ski with the heel lifted by ``heel`` (n,) about the ball."""
        foot, ski = B.side("foot", s), B.side("ski", s)
        p = carried(b, foot, ski)
        ball = carried(b, B.side("toe", s), ski)[:, :3, 3]
        axis = p[:, :3, 0]                       # the boot's lateral axis (X, to its right)
        R = np.stack([rotate_about(p[:, :3, k], axis, -heel) for k in range(3)], axis=-1)
        ankle = ball + rotate_about(p[:, :3, 3] - ball, axis, -heel)
        return R, ankle

    def ankle_on_ski(self, b, s, layout):
        return self._foot_pose(b, s, layout[s][2])[1]

    def feet(self, b, layout):
        for s in ("L", "R"):
            R, _ = self._foot_pose(b, s, layout[s][2])
            b.set_pose(B.side("foot", s), R)
            toe = B.side("toe", s)
            b.set_pose(toe, carried(b, toe, B.side("ski", s))[:, :3, :3])


#: The sport's record (docs/registry.md): its preset, resistance, rig, mapping and labels.
SPORT = register_sport(Sport(
    name="telemark", label="Telemark", description="Telemark skier", number=2,
    figure=Figure(
        "telemark", BodyParams(m=75.0, l=0.925, I_v=9.4, V_cm=8.0),
        Limits(C_f_max=0.125, dC_f_max=0.5, theta_fall=math.radians(55)),
        """Telemark skier.  The same 75 kg adult (1.78 m) in the telemark lunge, which lowers
        the hips and folds the legs under the body: centre of mass 0.925 m from the foot point
        and roll inertia 9.4 kg m^2 about it, from Dempster's segment data (Winter,
        Biomechanics and Motor Control of Human Movement, 4th ed. 2009, Table 4.1) on the
        built-in telemark figure's own pose, averaged over a 2 s, 23 deg slalom
        (scripts/telemark_body.py; the skier's pose gives 0.99 m, 11.1 kg m^2); a gentler
        8 m/s.  The turn comes from the angle between the skis (Section 3), which the split
        stance limits to about an 8 m radius: |C_f| <= 0.125; changing the lead ski is slower
        than an edge change: 0.5."""),
    # Telemark: the skier's skis and air, a more upright lunge.
    resistance=Resistance(mu=0.05, CdA=0.55, rho=1.007),
    plan_curvature_rate=0.3,
    styles=("carve", "skid", "wedge"),
    mapping=TelemarkMapping(),
    bones=(B.ROOT, B.LEAN) + B.HUMAN + B.SKI + B.POLE,
    # The trailing heel lifts off its ski: the skis go with the toes, flat on them, and the
    # leg's IK puts the ball of each foot (the toe bone's head) on the built-in's.
    retarget=Retarget(attach={"ski.L": "toe.L", "ski.R": "toe.R", "pole.L": "hand.L",
                              "pole.R": "hand.R"}, anchor="toe"),
))
