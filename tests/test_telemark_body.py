"""The telemark skier's own body: boots that bend at the ball of the foot (a shell on
the foot, bellows and duckbill toe on the toe), longer narrower skis with a toe binding, so the
trailing heel lifts off the ski without the boot going through it."""
import math

import numpy as np
import pytest

from blender_turning.core import preset, simulate
from blender_turning.core.controllers import PhaseEllipse
from blender_turning.mapping import map_trajectory
from blender_turning.mapping.sports.common import mesh_points
from blender_turning.mapping.kinematics import Skeleton
from blender_turning.mapping.rig_spec import load_rig


@pytest.fixture(scope="module")
def posed():
    fig = preset("telemark")
    traj = simulate(fig, PhaseEllipse(fig.body, omega0=math.pi, theta_max=math.radians(23),
                                      heading=0.0), duration=6.0).resample(24)
    spec = load_rig("telemark")
    return spec, Skeleton.from_spec(spec).fk(map_trajectory("telemark", traj).bones, len(traj))


def lowest_above_ski(spec, P, s):
    """Per frame, the lowest corner of the boot's shell (heel to ball) and of its toe above the
    ski's top, m."""
    ski = P[f"ski.{s}"]
    top = max(c[2] for c in mesh_points(spec, f"ski.{s}") if abs(c[2]) < 0.025)     # 0.02
    out = []
    for bone in (f"foot.{s}", f"toe.{s}"):
        corners = mesh_points(spec, bone)                                # bone frame
        local = np.linalg.inv(ski) @ P[bone]                             # bone in the ski's frame
        pts = np.einsum("nij,kj->nki", local[:, :3, :3], corners) + local[:, None, :3, 3]
        inside = np.abs(pts[..., 1] - 0.075) < 0.9                       # over the ski
        out.append(np.where(inside, pts[..., 2], np.inf).min(axis=1) - top)
        if bone.startswith("foot"):     # the heel: the shell's rearmost corner
            heel = pts[np.arange(len(pts)), np.argmin(pts[..., 1], axis=1), 2] - top
    return out + [heel]


def test_the_boots_bend_at_the_ball_and_stay_out_of_the_ski(posed):
    spec, P = posed
    assert {m.name for m in spec.meshes} >= {"boot.L", "boot_toe.L", "binding.R"}
    assert spec.meshes_of("toe.L")                 # the toe is dressed: the boot bends there
    for s in "LR":
        shell, toe, heel = lowest_above_ski(spec, P, s)
        assert min(shell.min(), toe.min()) > -1e-3                     # never through the ski
        assert np.ptp(toe) < 1e-3                                      # the toe stays down
        assert np.ptp(heel) > 0.05                                     # the heel lifts


def test_the_preset_body_is_the_telemark_lunge():
    """The core's telemark body is its own: the centre-of-mass distance and roll inertia of the
    built-in telemark figure in its lunge (Winter's segment data), averaged over the run, within
    the rounding of the preset (5 mm, 0.05 kg m^2; the roll inertia 0.06: the arms' pose over
    the pole plants moves the average, measured 9.350 kg m^2 with a swing forward of 70 deg of
    phase and 9.345 with one of at least 0.6 s); lower and lighter in roll than the skier's
    upright athletic stance measured the same way."""
    from blender_turning.mapping.posed import posed_body
    averaged = {}
    for sport in ("telemark", "skier"):
        body = preset(sport).body
        traj = simulate(preset(sport), PhaseEllipse(body, omega0=math.pi,
                                                    theta_max=math.radians(23), heading=0.0),
                        duration=6.0).resample(24)
        l, inertia = posed_body(sport, traj, body.m)
        averaged[sport] = (l.mean(), inertia.mean())
    body = preset("telemark").body
    assert abs(averaged["telemark"][0] - body.l) < 5e-3, averaged
    assert abs(averaged["telemark"][1] - body.I_v) < 0.06, averaged
    assert averaged["skier"][0] - body.l > 0.05 and averaged["skier"][1] - body.I_v > 1.0


def test_segment_data_is_a_whole_body():
    """Winter's fractions sum to the whole body; a rod along the roll axis adds nothing."""
    from blender_turning.mapping.anthropometry import SEGMENTS, centre_and_roll_inertia
    total = sum(f * (1 if k == "trunk_head_neck" else 2) for k, (f, _, _) in SEGMENTS.items())
    assert total == pytest.approx(1.0, abs=1e-12)
    skel = Skeleton.from_spec(load_rig("telemark"))
    P = skel.fk({}, 1)                       # the rest pose: standing upright
    com, inertia = centre_and_roll_inertia(P, skel, 75.0)
    assert com[0, 0] == pytest.approx(0.0, abs=1e-12)                  # symmetric left-right
    # Standing, the centre of mass is at ~55% of the stature above the soles (Winter 2009).
    stature = skel.rest_of("spine.006")[2, 3] + skel.length("spine.006") - 0.055
    assert 0.53 < (com[0, 2] - 0.055) / stature < 0.58
