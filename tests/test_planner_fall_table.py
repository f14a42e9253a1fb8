"""The fall table clips only nodes that fall whatever they do (planner/fall_table.py)."""
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.physics.dynamics import forward_alpha
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.planner import PlannerSettings, Problem
from blender_turning.core.planner.fall_table import _cooperative


def lean_problem(name="skier", V=7.0, N=4, q=5, dcf=0.3):
    fig = preset(name)
    fig = replace(fig, body=replace(fig.body, V_cm=V),
                  limits=replace(fig.limits, dC_f_max=dcf))
    return Problem(fig, PathDistance(HermitePath.from_polyline([[0, 0], [1, 0]]), 1),
                   Obstacles(), PlannerSettings(n_stages=N, q=q))


def survives(problem, x, cf, stages):
    """Exhaustively: does any plan of ``stages`` stages keep the lean within its bound?"""
    q = problem.settings.q
    X, C = x[:, None], np.array([cf])
    for _ in range(stages):
        m = X.shape[1]
        r = problem.simulate_stage(np.repeat(X, q, 1), np.repeat(C, q),
                                   np.tile(problem.u_values, m), np.zeros(m * q), np.zeros(m * q))
        ok = ~r.fell
        if not ok.any():
            return False
        X, C = r.state[:, ok], r.C_f[ok]
    return True


def test_doomed_nodes_really_fall():
    problem = lean_problem()
    table = problem.fall_table()
    assert table is not None
    rng = np.random.default_rng(0)
    st = problem.settings
    m = 400
    states = np.zeros((5, m))
    states[3] = rng.uniform(-st.theta_bound, st.theta_bound, m)
    states[4] = rng.uniform(-2.0, 2.0, m)
    cf = rng.uniform(-problem.limits.C_f_max, problem.limits.C_f_max, m)
    flagged = 0
    for stages in (1, 2, 3):
        doomed = table.doomed(states, cf, stages * st.steps_per_stage)
        flagged += int(doomed.sum())
        for j in np.flatnonzero(doomed)[:60]:
            assert not survives(problem, states[:, j], cf[j], stages)
        # And a node that can survive is never flagged.
        for j in np.flatnonzero(~doomed)[:20]:
            if survives(problem, states[:, j], cf[j], stages):
                assert not doomed[j]
    assert flagged > 50


def test_mirror_symmetric():
    problem = lean_problem()
    table = problem.fall_table()
    rng = np.random.default_rng(1)
    s = np.zeros((5, 200))
    s[3], s[4] = rng.uniform(-0.5, 0.5, 200), rng.uniform(-2, 2, 200)
    cf = rng.uniform(-0.15, 0.15, 200)
    np.testing.assert_array_equal(table.doomed(s, cf, 18), table.doomed(-s, -cf, 18))


def test_not_used_where_the_lean_is_not_monotone():
    # A fast cyclist with a sharp steering lock: alpha_v does not grow with theta_v everywhere.
    assert lean_problem("cyclist", V=7.0, dcf=0.4).fall_table() is None
    p = lean_problem()
    p2 = Problem(p.figure, p.distance, p.obstacles, replace(p.settings, fall_table=False,
                                                            viable_stages=0))
    assert p2.fall_table() is None
    # The dead-end test at the horizon (search.py) still asks the table for it.
    p3 = Problem(p.figure, p.distance, p.obstacles, replace(p.settings, fall_table=False))
    assert p3.fall_table() is not None


@pytest.mark.parametrize("name", ["skier", "snowboarder", "cyclist"])
def test_monotonicity_check_is_the_derivative_of_eq2(name):
    """The table rests on ``alpha_v`` (Eq. 2) growing with ``theta_v``; the check uses the closed
    form ``d alpha / d theta = (g cos th - C V^2 (C l - sin th) / (1 - C l sin th)^2) / J``.  It
    must say the same as Eq. 2 itself, differenced on a grid 3x finer, at every speed: the speed
    where it stops holding is 5.0 m/s for the cyclist and 8.0 m/s for the snowboarder (a sign
    error moves it to 7.9 and 9.0 m/s, a dropped square to 4.4 and 7.6 m/s: a 0.25 m/s grid of
    speeds sees either)."""
    for V in np.arange(2.0, 12.0, 0.25):
        p = lean_problem(name, V=float(V))
        th = np.linspace(-p._lean_checked, p._lean_checked, 2001)[:, None]
        C = np.linspace(-p.limits.C_f_max, p.limits.C_f_max, 401)[None, :]
        rising = bool(np.all(np.diff(forward_alpha(p.body, th, C), axis=0) > 0))
        assert _cooperative(p) == rising, (name, V)
