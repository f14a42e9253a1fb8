"""A crowd task's parametric figures run on floats below ``BATCH_FROM`` figures and as one numpy
batch from there (crowd/kernels.py); both kernels give the same trajectories."""
import math

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.controllers.feasible import TURN_KEY, TurnsFollowed
from blender_turning.crowd import Crowd, CrowdFigure, Turns, kernels, run_crowd

SKIER = preset("skier")


def _figures():
    """Per-figure ellipses, heading control, time offsets, both first turns, a fall within the
    span and a fall after the figure's span (its shot ends before it would fall)."""
    rng = np.random.default_rng(1)
    figs = [CrowdFigure(f"f{k}", SKIER, Turns(float(rng.uniform(1.8, 2.2)),
                                              float(np.radians(rng.uniform(18, 25))),
                                              math.radians(5 * (k % 3))),
                        (0.0, 4.0 * k), "left" if k % 2 else "right", 0.5 * (k % 4))
            for k in range(8)]
    falls = Turns(1.0, math.radians(55), 0.0)                   # falls at t = 0.2 s
    return tuple(figs) + (CrowdFigure("falls", SKIER, falls),
                          CrowdFigure("ends_first", SKIER, falls, time_offset=15.9))


def test_floats_and_the_batch_give_the_same_trajectories():
    """Same model, two kernels: they differ by round-off only, measured at most 3e-14 m,
    6e-15 rad, 4e-12 N over 16 s (the order of the sums' last bits); 1e-12 relative (and 1e-12
    absolute for values near zero) leaves a factor of 100 and fails on any changed term."""
    figs = _figures()
    floats = kernels.run_turns(0.02, 16.0, figs, "floats")
    batch = kernels.run_turns(0.02, 16.0, figs, "batch")
    assert [at for _, at, _ in floats] == [at for _, at, _ in batch] == [None] * 8 + [0.2, None]
    for (a, _, _), (b, _, _) in zip(floats, batch):
        assert a.keys() == b.keys()
        for c in a:
            assert a[c].shape == b[c].shape
            np.testing.assert_allclose(a[c], b[c], rtol=1e-12, atol=1e-12, err_msg=c)
    assert len(floats[-1][0]["t"]) == 6                         # 0.1 s at 0.02 s, no fall


def _mixed():
    """Members asking leans the skier's bounds hold at their period and members asking more,
    with heading control (a task's figures all hold one or none), and time offsets."""
    return tuple(CrowdFigure(f"m{k}", SKIER,
                             Turns(2.0 if k % 2 else 1.6, math.radians(20 if k % 2 else 50),
                                   math.radians(5 * (k % 3))),
                             (0.0, 4.0 * k), time_offset=0.5 * (k % 4))
                 for k in range(8))


def test_each_member_of_a_batch_reports_the_lean_it_reached():
    """A batch keeps each figure's record of the turns it followed: its report is the one the
    same figure run alone gives (the same turns, bounds and words; the leans over the run to
    1e-12 rad), and says a member's lean was limited exactly when the floats' report does."""
    figs = _mixed()
    floats = kernels.run_turns(0.02, 8.0, figs, "floats")
    batch = kernels.run_turns(0.02, 8.0, figs, "batch")
    limited = [r is not None and r.limited for _, _, r in floats]
    assert limited == [k % 2 == 0 for k in range(8)]
    for (_, _, a), (_, _, b) in zip(floats, batch):
        assert b is not None and b.limited == a.limited
        assert b.describe() == a.describe()
        assert [t.bound for t in b.turns] == [t.bound for t in a.turns]
        assert abs(b.lo - a.lo) < 1e-12 and abs(b.hi - a.hi) < 1e-12


@pytest.mark.parametrize("kernel", ["floats", "batch"])
def test_a_crowds_limited_members_carry_their_lean_report(monkeypatch, kernel):
    """Every member whose lean its bounds limited has the report in its trajectory's meta (what
    the CLI's summary and output print), and only those."""
    monkeypatch.setattr(kernels, "kernel_for", lambda n: kernel)
    res = run_crowd(Crowd("c", _mixed(), duration=8.0))
    for k, r in enumerate(res.figures):
        turn = r.trajectory.meta.get(TURN_KEY)
        assert (turn is not None) == (k % 2 == 0), r.name
        if turn is not None:
            report = TurnsFollowed.from_dict(turn)
            assert report.limited and report.worst.lean < math.radians(50) - 1e-3


def test_a_crowd_reports_the_same_falls_on_either_kernel(monkeypatch):
    figs = _figures()
    by = {}
    for k in ("floats", "batch"):
        monkeypatch.setattr(kernels, "kernel_for", lambda n, k=k: k)
        by[k] = run_crowd(Crowd("c", figs, duration=16.0))
    for a, b in zip(by["floats"].figures, by["batch"].figures):
        assert (a.status, a.message) == (b.status, b.message)
    assert by["batch"]["falls"].message == "fell over at t = 0.20 s"
    assert by["batch"]["ends_first"].status == "ok"


@pytest.mark.parametrize("count", [1, kernels.BATCH_FROM - 1, kernels.BATCH_FROM])
def test_the_kernel_follows_the_number_of_figures(monkeypatch, count):
    """Below ``BATCH_FROM`` every figure is stepped alone (a state of shape (5,)), from it all
    in one call (shape (5, count))."""
    shapes, real = [], kernels.run

    def run(body, limits, controller, state0, *args, **kw):
        shapes.append(np.shape(state0))
        return real(body, limits, controller, state0, *args, **kw)

    monkeypatch.setattr(kernels, "run", run)
    lead = CrowdFigure("lead", SKIER, Turns(2.0, math.radians(20), 0.0))
    figs = [lead] + [CrowdFigure(f"f{k}", SKIER, lead.controller, (0.0, 2.0 * k))
                     for k in range(1, count)]
    res = run_crowd(Crowd("c", figs, duration=0.1))
    assert not res.failed
    assert shapes == ([(5,)] * count if count < kernels.BATCH_FROM else [(5, count)])


def test_an_unknown_kernel_is_refused_by_name():
    with pytest.raises(ValueError, match="kernel = 'gpu' is not one of floats, batch"):
        kernels.run_turns(0.02, 1.0, _figures()[:1], "gpu")
