"""Guards for the half-turn's heading change (core/controllers/heading_table.py), the feasible turns
(core/controllers/feasible.py) and receding-horizon following (core/planner/receding.py): each
checks a property against an independent computation, so that the mutants of scripts/mutate.py
(a dropped term, a flipped bracket, a loosened bound, the wrong stage applied) go red."""
import math
from pathlib import Path

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.controllers.feasible import (BOUNDS, CF_SHARE, LEAN_MARGIN,
                                                       RATE_SHARE, ellipse_needs,
                                                       feasible_turns)
from blender_turning.core.physics.dynamics import inverse_cf
from blender_turning.core.controllers.heading_table import BETA_MAX, BETA_MIN, heading_table
from blender_turning.core.physics.params import Limits
from blender_turning.core.course.scene import load_scene

SKIER = preset("skier")
ROOT = Path(__file__).resolve().parents[1]


# -- heading_table -------------------------------------------------------------------------------

def test_the_float_heading_change_is_the_array_one():
    """``value_one`` (floats, the one-figure controller) against ``__call__`` (arrays), both
    terms of the closed form: over leans 1-60 deg and periods 0.7-6 s (measured: 2e-16
    relative, the same interpolation in another order)."""
    table = heading_table(SKIER.body)
    rng = np.random.default_rng(1)
    th, w = rng.uniform(0.02, 1.05, 200), 2 * math.pi / rng.uniform(0.7, 6.0, 200)
    want = table(th, w)
    got = np.array([table.value_one(float(a), float(b)) for a, b in zip(th, w)])
    np.testing.assert_allclose(got, want, rtol=1e-12)
    # The inertia term matters here: up to 44% of the change (at the shortest periods).
    J, V = SKIER.body.J, SKIER.body.V_cm
    assert np.max(w * J * th / V / want) > 0.3


@pytest.mark.parametrize("which", ["floats", "arrays"])
def test_beta_solves_eq8_or_stops_at_the_nearest_end(which):
    """Eq. (8): ``dtheta(beta theta_max, omega0 / beta) = wanted`` to 1e-10 rad where it can
    be met; a change beyond the range gives the end nearest to it (the largest beta for too
    much turn, the smallest for too little), on floats and arrays alike."""
    table = heading_table(SKIER.body)
    tm, w = math.radians(20), math.pi
    lo_change, hi_change = (table.value_one(b * tm, w / b) for b in (BETA_MIN, BETA_MAX))
    wanted = np.concatenate([np.linspace(lo_change, hi_change, 9)[1:-1],
                             [lo_change - 0.3, hi_change + 0.3]])
    if which == "floats":
        beta = np.array([table.solve_beta(tm, w, float(x)) for x in wanted])
    else:
        beta = table.solve_beta(np.full(len(wanted), tm), np.full(len(wanted), w), wanted)
    np.testing.assert_allclose(table(beta[:-2] * tm, w / beta[:-2]), wanted[:-2], atol=1e-10)
    assert beta[-2] == BETA_MIN and beta[-1] == BETA_MAX


# -- feasible turns ------------------------------------------------------------------------------

def _needs_by_simulation(body, tm, w):
    """The ellipse's needs from Eq. (1) along ``theta_v = tm sin(w t)`` (``alpha_v = -w^2
    theta_v``), the rate by finite differences in time: independent of the closed forms."""
    t = np.linspace(0.0, 0.5 * math.pi / w, 20001)
    th = tm * np.sin(w * t)
    cf = inverse_cf(body, th, -w * w * th)
    rate = np.abs(np.gradient(cf, t))
    return cf.max(), (cf * body.l * np.sin(th)).max(), rate.max()


@pytest.mark.parametrize("tm_deg, period", [(15, 1.5), (25, 2.0), (35, 3.0), (10, 0.8),
                                            (55, 3.0)])
def test_ellipse_needs_are_what_following_it_takes(tm_deg, period):
    """Peak C_f, peak C_f l sin th and peak |dC_f/dt| of the closed forms against Eq. (1) along
    the ellipse (the rate by central differences over 20,000 steps of a quarter turn: measured
    agreement 2e-4 relative, the 65 phases of the closed form sampling the peak).  The rate
    peaks at the lean's zero crossing, where only ``k'`` counts, except for deep, slow turns:
    at 55 deg and 3 s it peaks at 37 deg of lean, where the ``k V^2 sin th`` term is 4% of it."""
    tm, w = math.radians(tm_deg), 2 * math.pi / period
    got = ellipse_needs(SKIER.body, tm, w)
    want = _needs_by_simulation(SKIER.body, tm, w)
    np.testing.assert_allclose(got[:3], want, rtol=2e-3)
    assert got[3] == pytest.approx(tm)


def test_the_feasible_lean_keeps_its_margins():
    """Loose curvature bounds: the lean stops LEAN_MARGIN short of theta_fall.  The skier's at
    10 m/s: at the largest feasible lean the binding bound's need is its share of the bound
    (C_f at CF_SHARE C_f_max at a 2 s period, |dC_f/dt| at RATE_SHARE dC_f_max at 1 s), and
    1% more lean is infeasible."""
    loose = feasible_turns(SKIER.body, Limits(C_f_max=math.inf, theta_fall=math.radians(60)))
    assert loose.max_lean(2 * math.pi / 4.0) == pytest.approx(math.radians(60) - LEAN_MARGIN,
                                                              abs=1e-8)
    table = feasible_turns(SKIER.body, SKIER.limits)
    for period, bound, allowed in ((2.0, "C_f_max", CF_SHARE * SKIER.limits.C_f_max),
                                   (1.0, "dC_f_max", RATE_SHARE * SKIER.limits.dC_f_max)):
        w = 2 * math.pi / period
        lean = table.max_lean(w)
        assert table.bound(w) == bound
        k = BOUNDS.index(bound)
        # Linear interpolation between the table's frequencies: 1e-3 of the need.
        assert ellipse_needs(SKIER.body, lean, w)[k] == pytest.approx(allowed, rel=1e-3)
        assert ellipse_needs(SKIER.body, 1.01 * lean, w)[k] > allowed


def test_beta_range_ends_are_the_feasible_edges():
    """Each end of ``beta_range`` inside [BETA_MIN, BETA_MAX] is where the modified half-turn
    ``(beta theta_max, omega0 / beta)`` meets the lean bound: feasible at the end, not 1%
    past it."""
    table = feasible_turns(SKIER.body, SKIER.limits)
    w = 2 * math.pi / 2.0
    tm = 0.8 * table.max_lean(w)
    lo, hi = table.beta_range(tm, w)
    assert BETA_MIN <= lo < 1.0 < hi <= BETA_MAX
    for b, past in ((lo, lo / 1.01), (hi, hi * 1.01)):
        if b in (BETA_MIN, BETA_MAX):
            continue
        assert b * tm <= table.max_lean(w / b) * (1 + 1e-9)
        assert past * tm > table.max_lean(w / past)
    assert hi < BETA_MAX                                    # the sharp end is a real bound


# -- receding-horizon following ------------------------------------------------------------------

@pytest.fixture(scope="module")
def followed():
    """The first 4 s of the slalom scene (14 replannings, every rate of the choice used)."""
    setup = load_scene(ROOT / "scenes" / "slalom.json").setup()
    return setup, setup.run(duration=4.0)


def test_each_replanning_applies_its_plans_first_stage(followed):
    """Over each stage the curvature moves at the rate its replanning chose (the plan's first
    stage): ``C_f(t + t_stage) - C_f(t) = u t_stage``, to round-off."""
    setup, res = followed
    traj = res.trajectory
    t_stage = setup.settings.t_stage
    assert len(res.replans) >= 10
    for r in res.replans:
        k0 = int(np.argmin(np.abs(traj.t - r.t)))
        k1 = int(np.argmin(np.abs(traj.t - (r.t + t_stage))))
        assert traj.C_f[k1] - traj.C_f[k0] == pytest.approx(r.u * t_stage, abs=1e-12)
    assert len({round(r.u, 9) for r in res.replans}) > 2           # not one rate throughout


def test_the_followed_trajectory_columns_are_consistent(followed):
    """``s`` is the foot's distance: within 5e-3 m of the chords of its track over 4 s
    (measured 2.0e-3 m with the trapezoid of V_f at the planner's 0.05 s samples; a left sum is
    1.4e-2 m off), and every sample's ``V_f`` and ``alpha_v``, the last one's too, are Eqs.
    (21) and (2) at its own state and curvature (to round-off: 1e-12 of g / J)."""
    setup, res = followed
    tr = res.trajectory
    chords = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(tr.x), np.diff(tr.y)))])
    assert np.abs(tr.s - chords).max() < 5e-3
    b = setup.figure.body
    sn, cs = np.sin(tr.theta_v), np.cos(tr.theta_v)
    np.testing.assert_allclose(tr.V_f, b.V_cm / (1.0 - tr.C_f * b.l * sn), rtol=1e-12)
    alpha = (b.g * sn - tr.C_f * b.V_cm ** 2 * cs / (1.0 - tr.C_f * b.l * sn)) / b.J
    np.testing.assert_allclose(tr.alpha_v, alpha, rtol=0, atol=1e-12 * b.g / b.J)
