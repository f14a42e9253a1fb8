"""The trajectory contract: columns, resampling, CSV and JSON."""
import math

import numpy as np
import pytest

from blender_turning.core import COLUMNS, PhaseEllipse, Trajectory, simulate, slalom_start


@pytest.fixture(scope="module")
def traj():
    from blender_turning.core import preset
    fig = preset("skier")
    w, tm = 2 * math.pi / 2, math.radians(23)
    return simulate(fig, PhaseEllipse(fig.body, w, tm, heading=0.0), 8.0, dt=0.005,
                    state0=slalom_start(fig.body, w, tm))


def test_columns_are_the_contract(traj):
    assert tuple(traj.columns()) == COLUMNS
    assert all(len(v) == len(traj) for v in traj.columns().values())
    assert np.all((traj.phi >= 0) & (traj.phi < 2 * math.pi))
    np.testing.assert_allclose(np.diff(traj.s), 0.5 * (traj.V_f[1:] + traj.V_f[:-1]) * 0.005)


@pytest.mark.parametrize("fps", [24, 25, 30, 60])
def test_resample_matches_a_fine_simulation(traj, fps):
    r = traj.resample(fps)
    assert np.allclose(np.diff(r.t), 1 / fps)
    # Compare to the fine samples at the same instants: subsample the 200 Hz run where the frame
    # times coincide with its grid (every frame for 25 fps; common instants otherwise).
    idx = np.round(r.t / 0.005).astype(int)
    exact = np.abs(idx * 0.005 - r.t) < 1e-9
    for col in ("x", "y", "theta_dir", "theta_v", "omega_v", "s"):
        np.testing.assert_allclose(getattr(r, col)[exact], getattr(traj, col)[idx[exact]],
                                   atol=1e-9)
    # Between samples: resample every 4th sample (a 50 Hz run of the same motion) and compare
    # with the 200 Hz samples.  Cubic Hermite with exact derivatives errs by ~h^2 |jump in
    # alpha_v| / 8 at the controller's kinks: well under 1e-4 rad and 1 mm here.
    coarse = Trajectory(traj.data[:, ::4], traj.meta)
    rc = coarse.resample(fps)
    assert np.abs(rc.theta_v - r.theta_v).max() < 1e-4
    assert np.hypot(rc.x - r.x, rc.y - r.y).max() < 1e-3
    assert np.abs(np.angle(np.exp(1j * (rc.phi - r.phi)))).max() < 1e-3


@pytest.mark.parametrize("ground", [None, "rolls"])
def test_a_resample_from_a_later_frame_is_the_whole_ones_tail(traj, ground):
    """``first``: the later frames only (a Live Preview window), bit for bit the whole
    resample's (computed from the samples about them alone)."""
    if ground is not None:
        from blender_turning.core import preset
        from blender_turning.core.ground.terrain_gen import ski_slope
        ground = ski_slope(length=200.0, width=200.0, slope_deg=0.0, cell=1.0)
        fig = preset("cyclist")
        traj = simulate(fig, PhaseEllipse(fig.body, 2.0, math.radians(4), heading=0.0), 8.0,
                        state0=(-95.0, 10.0, 0.0, 0.0, 0.14, 3.0), ground=ground)
    whole = traj.resample(24, ground=ground)
    tail = traj.resample(24, ground=ground, first=150)
    assert len(whole) == 193 and len(tail) == 43
    np.testing.assert_array_equal(tail.data, whole.data[:, 150:])


def test_resampled_phase_is_continuous(traj):
    r = traj.resample(24)
    step = np.abs(np.angle(np.exp(1j * np.diff(r.phi))))
    # The phase advances by about omega0 / fps a frame, wrapping at 2 pi without a jump.
    assert step.max() < 2 * math.pi / 2.0 / 24 * 1.5
    assert np.all(np.diff(np.unwrap(r.phi)) > 0)


def test_csv_and_json_round_trip(traj, tmp_path):
    traj.to_csv(tmp_path / "t.csv")
    header = (tmp_path / "t.csv").read_text().splitlines()[0]
    assert header == ",".join(COLUMNS)
    back = Trajectory.from_csv(tmp_path / "t.csv")
    np.testing.assert_array_equal(back.data, traj.data)
    traj.to_json(tmp_path / "t.json")
    back = Trajectory.from_json(tmp_path / "t.json")
    np.testing.assert_array_equal(back.data, traj.data)
    assert back.meta["preset"] == "skier"


def test_failed_write_leaves_no_file(traj, tmp_path):
    bad = tmp_path / "missing" / "t.csv"
    with pytest.raises(OSError):
        traj.to_csv(bad)
    assert not bad.exists() and list(tmp_path.iterdir()) == []
