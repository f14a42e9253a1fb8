"""The cyclist's tyre grip (core/physics/grip.py, core/physics/skidding.py, docs/skidding.md Section 5): a
lean asked beyond what the tyre holds is limited to ``atan(mu)`` with a report, and braking
within the friction circle stops in the distance the grip allows, ``v^2 / (2 mu g)``."""
import math

import numpy as np
import pytest

from blender_turning.cli import main
from blender_turning.core import PhaseEllipse, Trajectory, preset, simulate, slalom_start
from blender_turning.core.controllers.straight import Straight
from blender_turning.core.physics.grip import TYRE, tyre
from blender_turning.core.physics.params import Limits
from blender_turning.core.physics.skidding import Skidding


def _lean_run(mu, lean_deg=48.0):
    """A 3 s slalom asking ``lean_deg``, the controller's fall bound relaxed to 70 deg so that
    only the grip limits the lean (the preset's own table stops at ~36 deg)."""
    fig = preset("cyclist")
    lim = Limits(C_f_max=fig.limits.C_f_max, dC_f_max=fig.limits.dC_f_max,
                 theta_fall=math.radians(70))
    ctl = PhaseEllipse(fig.body, 2 * math.pi / 3, math.radians(lean_deg), heading=0.0,
                       limits=lim)
    ctl.begin_run(fig.limits)
    s0 = slalom_start(fig.body, *ctl.target(0.0), 0.0)
    traj = simulate(fig, ctl, 12.0, 0.02, s0, skidding=Skidding("carve", tyre(mu)))
    assert math.degrees(ctl.theta_max(0.0)) == pytest.approx(lean_deg)     # given back
    return traj


def test_a_lean_beyond_the_tyres_grip_is_limited_with_a_report():
    """48 deg asked: free (mu 2) it leans 48.0 deg; on dry asphalt (mu 0.9) the lean is held to
    atan(0.9) = 42.0 deg (measured peak 42.6: the ellipse's overshoot), on wet (0.5) to 26.6
    (measured 29.6), each with the report."""
    free = _lean_run(2.0)
    assert math.degrees(np.abs(free.theta_v).max()) == pytest.approx(48.0, abs=0.1)
    assert "grip_limited" not in free.meta
    for mu, lim, over in ((0.9, 42.0, 1.0), (0.5, 26.6, 3.5)):
        traj = _lean_run(mu)
        peak = math.degrees(np.abs(traj.theta_v).max())
        assert lim - 0.5 < peak < lim + over
        assert f"limited to {lim:.1f} deg" in traj.meta["grip_limited"]


def test_the_presets_grip_is_dry_asphalt_and_the_cli_warns(tmp_path, capsys):
    assert TYRE["dry"].mu == 0.9
    out = tmp_path / "c.csv"
    assert main(["simulate", "--preset", "cyclist", "--lean-deg", "40", "--period", "3",
                 "--grip", "0.5", "--duration", "3", "--out", str(out)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("simulate: warning: the lean asked (40.0 deg")
    assert "limited to 26.6 deg" in err[0]
    traj = Trajectory.from_csv(out)
    assert np.all(traj.V_cm == traj.V_cm[0])            # carving on flat: the paper's speed


@pytest.mark.parametrize("mu", [0.9, 0.5, 0.35])
def test_braking_stops_within_the_distance_the_grip_allows(mu):
    """Straight at 10 m/s, full brake at t = 0: the distance is v^2 / (2 mu g) within 10%
    (measured 5.66, 10.17, 14.54 m against 5.66, 10.19, 14.56: rolling resistance and drag take
    a little, the last step below 0.5 m/s adds a little)."""
    fig = preset("cyclist")
    body = fig.body
    traj = simulate(fig, Straight(body), 5.0, 0.02, (0.0, 0.0, 0.0, 0.0, 0.0, 10.0),
                    skidding=Skidding("carve", tyre(mu), stop_at=0.0))
    bound = 10.0 ** 2 / (2 * mu * body.g)
    assert traj.s[-1] == pytest.approx(bound, rel=0.10)
    assert traj.V_cm[-1] == 0.0 and np.all(traj.skid == 0.0)
    assert traj.brake.max() == pytest.approx(mu * body.g, rel=0.01)
