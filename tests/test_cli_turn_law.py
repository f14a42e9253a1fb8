"""The CLI's turn-control options: --law, the --dt range and the summary line that says
which turn was followed."""
import pytest

from blender_turning.cli import main
from blender_turning.core import Trajectory


def test_summary_states_the_turn_followed(capsys):
    """The skier's default turn at 6 m/s needs more C_f than the ski allows: the figure follows
    a shallower turn at the same period, says so, and does not fall (it fell at 3.36 s).  The
    bound named is that of the half-turn directional control flattens (STEER_BETAS: a flatter,
    faster half-turn needs more C_f rate); 14.13 deg (the former fixed 85 % room: 12.50)."""
    assert main(["simulate", "--speed", "6", "--duration", "60"]) == 0
    out = capsys.readouterr().out
    assert "turn lean 14.13 deg at period 2.000 s (asked 23.00 deg; limited by dC_f_max" in out
    assert main(["simulate", "--duration", "4"]) == 0
    assert capsys.readouterr().out.rstrip().endswith("turn lean 23.00 deg at period 2.000 s")


def test_law_paper_is_the_apex_chattering_law(tmp_path):
    """E1 with mass 70 kg and I_v 6.3: the default law's F_leg peak is the open loop's
    1.2737 m g; the paper's law overshoots it by 4%."""
    peaks = {}
    for law in ("smooth", "paper"):
        out = tmp_path / f"{law}.csv"
        assert main(["simulate", "--mass", "70", "--inertia", "6.3", "--duration", "30",
                     "--law", law, "--out", str(out)]) == 0
        tr = Trajectory.from_csv(out)
        peaks[law] = tr.F_leg[tr.t > 4].max() / (70 * 9.81)
    assert peaks["smooth"] == pytest.approx(1.27374, abs=1e-4)
    assert peaks["paper"] > 1.32


@pytest.mark.parametrize("dt", ["0.05", "0.1", "0.0005"])
def test_dt_outside_the_accurate_range_is_refused(dt, capsys):
    assert main(["simulate", "--dt", dt, "--duration", "2"]) == 2
    err = capsys.readouterr().err
    assert f"--dt = {dt} is outside the allowed range [0.001, 0.03]" in err
