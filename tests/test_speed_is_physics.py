"""The speed is the model's (docs/TERRAIN.md Section 3): the table of ranges bounds what a user
gives, not what the figure reaches; a run ends early only as a physical event with its time,
position and reason."""
import math

import numpy as np
import pytest

from blender_turning.cli import main
from blender_turning.core import Trajectory, preset, simulate
from blender_turning.core.controllers import Straight
from blender_turning.core.errors import FellOver, LeftTerrain, RunEnded, Stopped
from blender_turning.core.physics.model import HeightField, Plane, Resistance

TUCK = Resistance(mu=0.03, CdA=0.15, rho=1.007)   # a speed skier's tuck, air at ~2000 m
PITCH = math.radians(44)


def _terminal(m=90.0):
    A = 9.81 * (math.sin(PITCH) - TUCK.mu * math.cos(PITCH))
    return A, TUCK.drag_k(m), math.sqrt(A / TUCK.drag_k(m))


def test_a_straight_tuck_reaches_the_closed_form_terminal_speed():
    """90 kg, C_d A 0.15 m^2, mu 0.03 on a 44 deg pitch: ``V_T = sqrt(g (sin s - mu cos s) / k)``
    = 88.7 m/s, far past the 60 m/s a user may give as a start speed.  The speed follows
    ``V_T tanh(sqrt(A k) t + atanh(V0 / V_T))`` (measured 2e-10 relative over 120 s)."""
    fig = preset("skier", m=90.0, V_cm=20.0)
    controller = Straight(fig.body)
    traj = simulate(fig, controller, 120.0, 0.02, (0.0, 0.0, 0.0, 0.0, 0.0),
                    ground=Plane(PITCH, 0.0), resistance=TUCK)
    A, k, V_T = _terminal()
    assert V_T == pytest.approx(88.7, abs=0.05)
    assert traj.t[-1] == pytest.approx(120.0)
    V = V_T * np.tanh(math.sqrt(A * k) * traj.t + math.atanh(20.0 / V_T))
    np.testing.assert_allclose(traj.V_cm, V, rtol=1e-8)
    assert traj.V_cm[-1] > 88.0
    # The controller's body is at the speed reached too (made when asked), unchecked by the
    # user's 60 m/s.
    assert controller.body.V_cm == traj.V_cm[-1]


def test_the_command_line_runs_the_tuck_past_60_m_s(tmp_path):
    """The same run from the command line: exit 0 and a trajectory at terminal speed (the run
    used to abort at 60 m/s as if the user had typed a bad value)."""
    out = tmp_path / "tuck.csv"
    assert main(["simulate", "--controller", "straight", "--mass", "90", "--speed", "20",
                 "--slope-deg", "44", "--downhill-deg", "0", "--heading-deg", "0",
                 "--friction", "0.03", "--drag-area", "0.15", "--air-density", "1.007",
                 "--duration", "60", "--out", str(out)]) == 0
    traj = Trajectory.from_csv(out)
    assert traj.V_cm.max() > 80.0


def test_a_user_start_speed_is_still_checked():
    """What a user gives stays bounded by the table of ranges."""
    with pytest.raises(ValueError, match="V_cm"):
        preset("skier", V_cm=61.0)
    assert main(["simulate", "--speed", "61"]) == 2


def test_runs_that_end_early_are_physical_events_with_time_position_and_reason():
    fig = preset("skier")
    # Stops: a gentle slope against heavy friction.
    with pytest.raises(Stopped) as stop:
        simulate(fig, Straight(fig.body), 60.0, 0.02, (0.0, 0.0, 0.0, 0.0, 0.0, 3.0),
                 ground=Plane(math.radians(2), 0.0), resistance=Resistance(mu=0.3))
    # Leaves the terrain: a 40 m wide height field.
    xs = np.arange(0.0, 41.0, 2.0)
    field = HeightField(np.zeros((len(xs), len(xs))), 0.0, 0.0, 2.0)
    with pytest.raises(LeftTerrain) as left:
        simulate(fig, Straight(fig.body), 20.0, 0.02, (20.0, 20.0, 0.0, 0.0, 0.0, 10.0),
                 ground=field, resistance=Resistance(mu=0.01))
    # Falls: leaning out of a straight run on flat ground.
    with pytest.raises(FellOver) as fell:
        simulate(fig, Straight(fig.body), 10.0, 0.02, (0.0, 0.0, 0.0, 0.3, 0.5))
    for e in (stop.value, left.value, fell.value):
        assert isinstance(e, RunEnded)
        traj = e.trajectory
        assert e.t == pytest.approx(traj.t[-1]) and 0.0 < e.t
        assert e.position == pytest.approx((traj.x[-1], traj.y[-1]))
        assert f"at t = {e.t:.2f} s at ({e.position[0]:.1f}, {e.position[1]:.1f}) m" in str(e)
        assert e.reason == str(e)
    assert left.value.position[0] == pytest.approx(40.0, abs=0.25)
    assert stop.value.trajectory.V_cm[-1] < 0.5
