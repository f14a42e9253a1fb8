"""The beginner and the recreational skier (mapping/sports/skier_presets.py, core/controllers/speed_habits.py,
docs/skidding.md Section 8): presets of the skier with their skis, and the speed habit they
ski at on a slope unless told otherwise (a wedge at 4.5 m/s; skidded turns at 10.5 m/s, the
recreational speeds Stepan et al. 2023 measured, 9.0-12.4 m/s)."""
import math

import numpy as np
import pytest

from blender_turning.cli import main
from blender_turning.core import PRESETS, Trajectory, preset
from blender_turning.core.equipment import carving_of, sport_of
from blender_turning.core.controllers.speed_habits import SpeedHabit, habit_of


def _sim(tmp_path, *args):
    out = tmp_path / "o.csv"
    assert main(["simulate", "--heading-deg", "-90", "--out", str(out), *map(str, args)]) == 0
    return Trajectory.from_csv(out)


def test_the_presets_are_skiers_with_their_skis_and_habits():
    for name, style, speed in (("beginner", "wedge", 4.5), ("recreational", "skid", 10.5)):
        assert name in PRESETS and sport_of(name) == "skier"
        assert habit_of(name) == SpeedHabit(style, speed)
        assert preset(name).body.V_cm == speed
        c = carving_of(name)
        assert preset(name).limits.C_f_max == pytest.approx(
            1 / (c.sidecut_radius * math.cos(c.edge_max)), rel=1e-12)
    assert habit_of("skier") is None and habit_of(None) is None
    with pytest.raises(ValueError, match="style"):
        SpeedHabit("plough", 4.0)
    with pytest.raises(ValueError, match="target_speed"):
        SpeedHabit("wedge", 0.0)


def test_the_beginner_wedges_at_a_ski_school_pace(tmp_path, capsys):
    """On 18 deg, no flags: the wedge at 4.5 m/s (measured: 4.79 m/s over the last 30 s, the
    half-angle up to 15.5 deg); the goal's 4 +- 1 m/s."""
    traj = _sim(tmp_path, "--preset", "beginner", "--slope-deg", "18", "--duration", "60")
    assert "style wedge" in capsys.readouterr().out
    late = traj.t >= 30.0
    assert abs(traj.V_cm[late].mean() - 4.5) < 1.0
    assert np.abs(traj.skid).max() > math.radians(10)


def test_the_recreational_skier_skids_at_recreational_speeds(tmp_path, capsys):
    """On 25 deg, no flags: skidded turns at 10.5 m/s (measured: 10.92 m/s over the last 30 s,
    20.4 m at most from the fall line through the start); Stepan et al.'s 9.0-12.4 m/s."""
    traj = _sim(tmp_path, "--preset", "recreational", "--slope-deg", "25", "--duration", "60")
    assert "style skid" in capsys.readouterr().out
    late = traj.t >= 30.0
    assert 9.0 <= traj.V_cm[late].mean() <= 12.4
    assert np.abs(traj.x).max() < 30.0


def test_flags_override_the_habit_and_flat_ground_has_none(tmp_path):
    carved = _sim(tmp_path, "--preset", "beginner", "--slope-deg", "8", "--duration", "5",
                  "--style", "carve")
    assert np.all(carved.brake == 0.0)
    fast = _sim(tmp_path, "--preset", "beginner", "--slope-deg", "8", "--duration", "5",
                "--target-speed", "3")
    assert fast.brake.max() > 0.0
    flat = _sim(tmp_path, "--preset", "beginner", "--duration", "3")
    assert np.all(flat.skid == 0.0) and np.all(flat.V_cm == 4.5)
