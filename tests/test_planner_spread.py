"""The planner's choices spread over the curvature left (``PlannerSettings.spread = "range"``;
docs/racing.md, "The planner's curvature lattice"): each choice stays within Section 6.1's
bounds, the largest brings ``C_f`` exactly to its bound, the search stays exact (the exhaustive
optimum around a pole; the receding horizon's plans with and without its speed-ups are in
tests/test_planner_race.py)."""

import numpy as np
import pytest

from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.planner import PlannerSettings, branch_and_bound, exhaustive

from test_planner_race import racer


def test_the_choices_split_the_curvature_left_within_the_rate():
    p = racer(q=9, rate=2.06, spread="range")
    lim, T = p.limits, p.settings.t_stage
    C0 = np.linspace(-lim.C_f_max, lim.C_f_max, 41)
    u = p.rates(C0[:, None], np.arange(9)[None, :])            # (41, 9)
    assert (np.abs(u) <= lim.dC_f_max * (1 + 1e-12)).all()
    end = C0[:, None] + u * T
    assert (np.abs(end) <= lim.C_f_max * (1 + 1e-12)).all()
    np.testing.assert_array_equal(u[:, 4], 0.0)                 # the middle one holds C_f
    # rate 2.06 over 0.2 s (0.412 1/m) is more than the 0.259 1/m to the bound from 0 or past it:
    # the largest choice ends on the bound, the others split the way there in equal steps.
    up = C0 >= lim.C_f_max - lim.dC_f_max * T
    np.testing.assert_allclose(end[up, 8], lim.C_f_max, rtol=1e-12)
    np.testing.assert_allclose(np.diff(end[up, 4:], axis=1),
                               np.repeat((lim.C_f_max - C0[up, None]) / 4, 4, 1), atol=1e-12)
    # From 0.153 1/m (the even lattice's 6.53 m, a step below the bound) the even choices reach
    # only 0.256 or the clip; these give 0.180, 0.206 (4.85 m) and 0.233 too.
    c = lim.C_f_max - 2 * lim.dC_f_max * T / 8
    got = c + p.rates(np.array([c]), np.arange(5, 9)) * T
    np.testing.assert_allclose(got, c + (lim.C_f_max - c) * np.arange(1, 5) / 4, rtol=1e-12)
    even = racer(q=9, rate=2.06)
    np.testing.assert_array_equal(even.rates(0.1, np.arange(9)), even.u_values)
    with pytest.raises(ValueError, match="spread = 'wide' is not one of rate, range"):
        PlannerSettings(spread="wide")


@pytest.mark.parametrize("leg", [0.0, 3.0])
def test_the_search_returns_the_exhaustive_optimum_round_a_pole(leg):
    poles = Obstacles(segments=[((8.0, 0.6), (8.0, -12.0))], clearance=0.3)
    p = racer(N=3, q=5, obstacles=poles, rate=2.06, spread="range", leg_force_max=leg)
    start = np.array([0.0, 0.0, 0.3, 0.1, 0.0])
    for C0, heading, lean in ((0.0, 0.3, 0.1), (0.15, 0.3, 0.1), (0.24, 0.5, 0.6),
                              (-0.2, -0.2, -0.5), (0.259, 0.6, 0.8)):
        start = np.array([0.0, 0.0, heading, lean, 0.0])
        f, choices = exhaustive(p, start, C0)
        plan = branch_and_bound(p, start, C0)
        if choices is None:               # every branch needs more than 3 BW or falls: none
            assert not plan.feasible and leg
            continue
        assert plan.choices == choices
        assert plan.f_opt == pytest.approx(f, rel=1e-9)
        assert plan.u[0] == p.rates(np.array([C0]), [choices[0]])[0]
    # Not the even spread's optimum from the same state: the choices are other rates (measured
    # 0.304 against 0.345 without the leg-force limit, 0.309 against 0.387 with it).
    start = np.array([0.0, 0.0, 0.3, 0.1, 0.0])
    even = racer(N=3, q=5, obstacles=poles, rate=2.06, leg_force_max=leg)
    assert exhaustive(even, start, 0.15)[0] > exhaustive(p, start, 0.15)[0] * (1 + 1e-6)


def test_a_child_with_a_siblings_rate_is_simulated_once():
    """On the bound the curvature left is 0: the rates towards it are all 0, the same branch as
    holding it, and only that one is simulated; off it every child is.  The tree's counts: the
    root's children (N = 1, no warm start)."""
    p = racer(N=1, q=5, rate=2.06, spread="range", warm_start=False)
    start = np.zeros(5)
    for C0, children in ((p.limits.C_f_max, 3), (-p.limits.C_f_max, 3), (0.2, 5), (0.0, 5)):
        assert branch_and_bound(p, start, C0).stats.generated == children

