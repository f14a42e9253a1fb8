"""The batch API: per-figure ellipses with heading control, and a fallen figure
that stops alone while the others go on."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import FellOver, PhaseEllipse, preset, run, simulate

FIG = preset("skier")
BODY = FIG.body
# 2 s / 23 deg, 2 s / 8 deg (inside Eq. 11/12's small-angle range), 3 s / 30 deg, 1.5 s / 5 deg:
# the batch's figures take both of the "auto" directional paths at once.
W = 2 * math.pi / np.array([2.0, 2.0, 3.0, 1.5])
TM = np.radians([23.0, 8.0, 30.0, 5.0])
HEADING = 0.3
# The beta solve stops at 1e-9 rad of heading per half-turn, on floats for one figure and on
# arrays for a batch, so the two runs agree to that solve, not to round-off (measured 1.1e-8).
SAME = 1e-7


def starts(n):
    s = np.zeros((5, n))
    s[4] = (W * TM)[:n]
    return s


def one_figure(k, state0, duration):
    ctl = PhaseEllipse(BODY, float(W[k]), float(TM[k]), heading=HEADING)
    return run(BODY, FIG.limits, ctl, state0, duration)


def assert_same_run(batch_cols, k, single_cols, upto=None):
    for name in ("x", "y", "theta_dir", "theta_v", "omega_v", "C_f", "F_leg", "phi"):
        a, b = batch_cols[name][:upto, k], single_cols[name][:upto]
        d = np.abs(a - b)
        if name == "phi":
            d = np.abs(np.angle(np.exp(1j * (a - b))))
        assert d.max() < SAME * max(1.0, np.abs(b).max()), (k, name)


def test_per_figure_ellipses_with_heading_control():
    ctl = PhaseEllipse(BODY, W, TM, heading=HEADING)
    r = run(BODY, FIG.limits, ctl, starts(4), 12.0)
    assert r.falls == () and r.fell_at is None
    assert r.columns["theta_v"].shape == (601, 4)
    for k in range(4):
        assert_same_run(r.columns, k, one_figure(k, starts(4)[:, k], 12.0).columns)


def test_a_fallen_figure_stops_alone():
    s0 = starts(3)
    s0[3, 1], s0[4, 1] = 0.8, 2.0                    # figure 1 leans 46 deg and falls on
    with pytest.raises(FellOver) as fell:
        simulate(FIG, PhaseEllipse(BODY, float(W[1]), float(TM[1]), heading=HEADING), 6.0,
                 state0=s0[:, 1])
    r = run(BODY, FIG.limits, PhaseEllipse(BODY, W[:3], TM[:3], heading=HEADING), s0, 6.0)
    assert r.falls == ((1, fell.value.t),) and r.fell_at == fell.value.t
    cols = r.columns
    assert cols["t"].shape == (301, 3)                # the others ran the whole 6 s
    for k in (0, 2):
        assert_same_run(cols, k, one_figure(k, s0[:, k], 6.0).columns)
    i = int(round(fell.value.t / 0.02))
    assert_same_run(cols, 1, fell.value.trajectory.columns(), upto=i + 1)
    assert abs(cols["theta_v"][i, 1]) > FIG.limits.theta_fall
    assert np.all(np.isnan(cols["theta_v"][i + 1:, 1]))
    assert np.all(np.isfinite(cols["theta_v"][:, [0, 2]]))


def test_the_run_ends_when_every_figure_has_fallen():
    s0 = starts(2)
    s0[3], s0[4] = [0.8, 0.9], [2.0, 1.0]
    r = run(BODY, FIG.limits, PhaseEllipse(BODY, W[:2], TM[:2], heading=HEADING), s0, 6.0)
    assert [k for k, _ in r.falls] == [0, 1] and r.falls[0][1] < r.falls[1][1]
    assert r.columns["t"][-1, 0] == pytest.approx(r.falls[1][1])


def test_a_batch_run_again_under_other_limits_follows_their_table():
    # A batch keeps its per-figure feasible ellipses for its constant schedules; a new run under
    # tighter limits (a new feasibility table) must ski what a fresh controller skis under them.
    tight = replace(FIG.limits, C_f_max=0.5 * FIG.limits.C_f_max)
    ctl = PhaseEllipse(BODY, W, TM, heading=HEADING)
    run(BODY, FIG.limits, ctl, starts(4), 4.0)
    again = run(BODY, tight, ctl, starts(4), 4.0).columns
    fresh = run(BODY, tight, PhaseEllipse(BODY, W, TM, heading=HEADING), starts(4), 4.0).columns
    assert not np.array_equal(again["theta_v"], run(BODY, FIG.limits, ctl, starts(4),
                                                    4.0).columns["theta_v"])
    for name in ("theta_v", "theta_dir", "C_f"):
        assert np.array_equal(again[name], fresh[name]), name
