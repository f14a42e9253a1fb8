"""``simulate`` on a slope from the command line: the terrain flags, the straight
controller, the z and V_cm columns, and bad input (one line, exit 2, no file)."""
import math

import numpy as np
import pytest

from blender_turning.cli import main
from blender_turning.core import COLUMNS, Trajectory, preset
from blender_turning.core.physics.model import RESISTANCE


def test_flat_runs_are_unchanged_and_carry_z_and_speed(tmp_path):
    out = tmp_path / "flat.csv"
    assert main(["simulate", "--duration", "3", "--out", str(out)]) == 0
    again = tmp_path / "flat0.csv"
    assert main(["simulate", "--duration", "3", "--slope-deg", "0", "--out", str(again)]) == 0
    assert out.read_text() == again.read_text()
    traj = Trajectory.from_csv(out)
    assert out.read_text().splitlines()[0] == ",".join(COLUMNS)
    assert np.all(traj.z == 0.0) and np.all(traj.V_cm == preset("skier").body.V_cm)


def test_straight_run_down_a_slope_uses_the_sports_resistance(tmp_path, capsys):
    """On a slope the skier's snow friction and drag apply unless given: the straight run's speed
    is the closed form with RESISTANCE["skier"]; with --friction 0 --drag-area 0 it is free
    fall along the slope."""
    sigma = math.radians(18)
    body = preset("skier").body
    res = RESISTANCE["skier"]
    out = tmp_path / "s.csv"
    assert main(["simulate", "--controller", "straight", "--slope-deg", "18", "--downhill-deg",
                 "-90", "--heading-deg", "-90", "--duration", "10", "--out", str(out)]) == 0
    assert "speed 10.0-" in capsys.readouterr().out
    traj = Trajectory.from_csv(out)
    A = body.g * (math.sin(sigma) - res.mu * math.cos(sigma))
    k = res.drag_k(body.m)
    V_T = math.sqrt(A / k)
    np.testing.assert_allclose(traj.V_cm, V_T * np.tanh(math.sqrt(A * k) * traj.t
                                                        + math.atanh(body.V_cm / V_T)), rtol=1e-6)
    np.testing.assert_allclose(traj.z, traj.y * math.tan(sigma), rtol=1e-12)
    free = tmp_path / "free.csv"
    assert main(["simulate", "--controller", "straight", "--slope-deg", "18", "--heading-deg",
                 "-90", "--duration", "4", "--friction", "0", "--drag-area", "0",
                 "--out", str(free)]) == 0
    traj = Trajectory.from_csv(free)
    np.testing.assert_allclose(traj.V_cm, body.V_cm + body.g * math.sin(sigma) * traj.t,
                               rtol=1e-12)


def test_target_speed_and_frames_on_a_slope(tmp_path):
    out = tmp_path / "t.csv"
    assert main(["simulate", "--slope-deg", "18", "--heading-deg", "-90", "--target-speed",
                 "12", "--style", "carve", "--duration", "30", "--fps", "24", "--out",
                 str(out)]) == 0
    traj = Trajectory.from_csv(out)
    assert np.allclose(np.diff(traj.t), 1 / 24)
    # carving brakes by turning only: it traverses wide (skidding keeps a 25 m corridor)
    assert traj.V_cm.max() < 22.0 and traj.x.max() - traj.x.min() > 60.0


@pytest.mark.parametrize("args, flag", [
    (["--slope-deg", "61"], "--slope-deg"),
    (["--slope-deg", "-1"], "--slope-deg"),
    (["--slope-deg", "nan"], "--slope-deg"),
    (["--downhill-deg", "inf"], "--downhill-deg"),
    (["--friction", "-0.1"], "--friction"),
    (["--friction", "nan"], "--friction"),
    (["--drag-area", "-1"], "--drag-area"),
    (["--air-density", "3"], "--air-density"),
    (["--target-speed", "0"], "--target-speed"),
    (["--target-speed", "5", "--controller", "open-loop"], "heading"),
])
def test_bad_terrain_flags(tmp_path, capsys, args, flag):
    out = tmp_path / "o.csv"
    assert main(["simulate", "--duration", "1", "--out", str(out), *args]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and flag in err
    assert not out.exists()
