"""The telemark skier's own body (issue 8): boots that bend at the ball of the foot (a shell on
the foot, bellows and duckbill toe on the toe), longer narrower skis with a toe binding, so the
trailing heel lifts off the ski without the boot going through it."""
import math

import numpy as np
import pytest

from blender_turning.core import preset, simulate
from blender_turning.core.controllers import PhaseEllipse
from blender_turning.mapping import map_trajectory
from blender_turning.mapping.common import mesh_points
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
    sk = Skeleton.from_spec(spec)
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
