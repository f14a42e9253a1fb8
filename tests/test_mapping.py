"""All four mappings: the registry, mirror symmetry, edge cases."""
import math

import numpy as np
import pytest

from blender_turning.core import Trajectory
from blender_turning.mapping import MAPPINGS, map_trajectory
from blender_turning.mapping.kinematics import Skeleton
from blender_turning.mapping.rig_spec import load_rig
from test_mapping_skier import run


def test_registry():
    assert set(MAPPINGS) == {"skier", "snowboarder", "telemark", "cyclist"}
    for sport, m in MAPPINGS.items():
        assert m.sport == sport and load_rig(sport).sport == sport


def mirrored(traj):
    c = dict(traj.columns())
    for k in ("y", "theta_dir", "theta_v", "omega_v", "alpha_v", "C_f"):
        c[k] = -c[k]
    c["phi"] = np.mod(c["phi"] + math.pi, 2 * math.pi)   # (theta_v, omega_v) -> -(...)
    return Trajectory.from_columns(c, traj.meta)


@pytest.mark.parametrize("sport", ["skier", "telemark"])
def test_mirrored_turn_gives_the_mirrored_pose(sport):
    """docs/ARCHITECTURE.md Section 4: mirroring (theta_v, C_f, theta_dir) maps solutions to
    solutions; the symmetric rigs must then mirror too: bone X.L of the mirrored run is bone X.R
    reflected in x = 0."""
    traj = run(sport, seconds=4.0)
    sk = Skeleton.from_spec(load_rig(sport))
    a = sk.fk(map_trajectory(sport, traj).bones, len(traj))
    b = sk.fk(map_trajectory(sport, mirrored(traj)).bones, len(traj))
    flip = np.array([-1.0, 1.0, 1.0])
    for name in sk.names:
        other = name[:-1] + {"L": "R", "R": "L"}[name[-1]] if name[-2:] in (".L", ".R") else name
        # heads and tails (the head plus the bone's Y axis) of every bone
        assert np.allclose(b[name][:, :3, 3], a[other][:, :3, 3] * flip, atol=1e-9), name
        assert np.allclose(b[name][:, :3, 1], a[other][:, :3, 1] * flip, atol=1e-9), name


@pytest.mark.parametrize("sport", sorted(MAPPINGS))
def test_straight_run_and_single_frame(sport):
    traj = run(sport, seconds=2.0)
    c = dict(traj.columns())
    for k in ("theta_v", "omega_v", "alpha_v", "C_f", "theta_dir", "phi"):
        c[k] = np.zeros_like(c[k])
    straight = Trajectory.from_columns(c, traj.meta)
    track = map_trajectory(sport, straight)
    for ch in track.bones.values():
        for arr in (ch.location, ch.rotation):
            assert arr is None or np.all(np.isfinite(arr))
    one = Trajectory.from_columns({k: v[:1] for k, v in traj.columns().items()}, traj.meta)
    assert len(map_trajectory(sport, one, frame_start=7)) == 1


def test_empty_trajectory_is_refused():
    traj = run("skier", seconds=1.0)
    empty = Trajectory.from_columns({k: v[:0] for k, v in traj.columns().items()})
    with pytest.raises(ValueError, match="no samples"):
        map_trajectory("skier", empty)


@pytest.mark.parametrize("sport", sorted(MAPPINGS))
def test_channels_are_what_blender_reads(sport):
    """Connected bones never get a location (Blender ignores it); quaternions are unit and
    sign-continuous; only the documented helper/equipment bones move their heads."""
    traj = run(sport, seconds=2.0)
    track = map_trajectory(sport, traj)
    spec = load_rig(sport)
    for name, ch in track.bones.items():
        if ch.location is not None:
            assert not spec.bone(name).connected, name
        if ch.rotation is not None:
            assert np.allclose(np.linalg.norm(ch.rotation, axis=1), 1.0)
            assert np.all(np.sum(ch.rotation[1:] * ch.rotation[:-1], axis=1) >= 0), name
    moved = {n for n, ch in track.bones.items() if ch.location is not None}
    assert moved <= {"spine", "ski.L", "ski.R", "pole.L", "pole.R", "board", "wheel.F"}
