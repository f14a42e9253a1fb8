"""The fused stage (planner/flat_stage.py) computes what the generic RK4 through Problem._rhs
(dynamics.steer) computes, bit for bit; the fall table built from it is the table its definition
gives; the nearest path sample found among the samples near a batch is the nearest of all
(speed)."""
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.course.obstacles import Obstacles
from blender_turning.core.course.path import HermitePath, PathDistance
from blender_turning.core.planner import PlannerSettings, Problem, SpeedProfile, flat_stage
from blender_turning.core.planner.fall_table import FallTable
from blender_turning.core.ground.terrain import Plane
from blender_turning.core.physics.model import Resistance

FIELDS = ("state", "C_f", "s", "cost", "d_last", "collided", "fell")


def problem(name="skier", V=8.0, dcf=0.3, **settings):
    fig = preset(name)
    fig = replace(fig, body=replace(fig.body, V_cm=V), limits=replace(fig.limits, dC_f_max=dcf))
    path = HermitePath.from_points([[0, 0], [20, 3], [40, -3]], [[20, 0], [20, 0], [20, 0]])
    obs = Obstacles([[[12, -1], [12, -6]]], [[25, 2.5, 1.0]], [[[30, -2], [33, -2], [33, -5]]],
                    clearance=0.3)
    settings = {"n_stages": 4, "q": 5, **settings}
    return Problem(fig, PathDistance(path), obs, PlannerSettings(**settings))


def nodes(p, m, seed):
    """Nodes spread over the scene: leaning up to past the bound, turning hard, and curvatures
    beyond +-C_f_max so that the rate bound binds too."""
    rng = np.random.default_rng(seed)
    x = np.stack([rng.uniform(0, 35, m), rng.uniform(-4, 4, m), rng.normal(0, 0.4, m),
                  rng.normal(0, 0.3, m), rng.normal(0, 1.0, m)])
    cf = rng.uniform(-1.5, 1.5, m) * p.limits.C_f_max
    u = p.u_values[rng.integers(0, p.settings.q, m)]
    return x, cf, u, rng.uniform(0, 5, m), rng.uniform(0, 40, m)


def generic(p, *args):
    g = type(p).__new__(type(p))
    g.__dict__.update(p.__dict__)
    g._fused = False
    return g.simulate_stage(*args)


@pytest.mark.parametrize("m", [1, 2, flat_stage.SCALAR_COLUMNS, flat_stage.SCALAR_COLUMNS + 1,
                               300])
@pytest.mark.parametrize("name", ["skier", "cyclist", "snowboarder"])
def test_fused_stage_equals_the_generic_rk4_bit_for_bit(name, m):
    p = problem(name)
    assert p._fused
    args = nodes(p, m, seed=m)
    a, b = p.simulate_stage(*args), generic(p, *args)
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)
    if m == 300:        # the cases the sample holds: falls, collisions, the rate bound binding
        assert a.fell.any() and a.collided.any() and not a.fell.all()
        assert (np.abs(args[1]) > p.limits.C_f_max).any()


def test_fused_stage_applies_only_where_it_is_exact():
    assert problem()._fused
    flat = problem()
    varying = Problem(flat.figure, flat.distance, flat.obstacles, flat.settings,
                      SpeedProfile("time", [0.0, 5.0], [6.0, 8.0]))
    assert not varying._fused
    binds = problem(V=8.0)
    binds = Problem(replace(binds.figure, limits=replace(binds.limits, C_f_max=1.0)),
                    binds.distance, binds.obstacles, binds.settings)
    assert binds._physical_binds and not binds._fused
    slope = Problem(flat.figure, flat.distance, flat.obstacles, flat.settings, ground=Plane(0.1),
                    resistance=Resistance(mu=0.0, CdA=0.0))
    assert not slope._fused


def test_fall_table_is_its_definition():
    """T[i, j, k]: the first step at which the hardest-steering plan (dC_f/dt = +dC_f_max every
    stage) from grid state (theta, omega, C_f) passes the bound; never once the lean left the
    checked range.  Built here with the generic RK4, one stage after another."""
    p = problem("skier", V=7.0, n_stages=3)
    table = FallTable(p, n_theta=7, n_omega=9, n_cf=5)
    th, om, cf = np.meshgrid(table.theta, table.omega, table.cf, indexing="ij")
    m = th.size
    x = np.zeros((5, m))
    x[3], x[4] = th.ravel(), om.ravel()
    c = cf.ravel()
    T = np.full(m, -1)
    lost = np.zeros(m, bool)
    steps = p.settings.steps_per_stage
    g = type(p).__new__(type(p))
    g.__dict__.update(p.__dict__)
    for stage in range(3):
        P, c, _, _, _ = g._integrate(x, c, np.full(m, p.limits.dC_f_max), 0.0, np.zeros(m), False)
        for k in range(1, steps + 1):
            lean = P[k, 3]
            lost |= ~(lean >= -p._lean_checked)
            T[(T < 0) & ~lost & (lean > table.bound)] = stage * steps + k
        x = P[-1]
    assert (T > 0).any() and (T < 0).any()
    np.testing.assert_array_equal(np.where(table.T.ravel() > 10 ** 9, -1, table.T.ravel()), T)


@pytest.mark.parametrize("spread", [0.5, 5.0, 60.0])
def test_nearest_sample_among_the_near_ones_is_the_nearest_of_all(spread):
    path = HermitePath.from_points([[0, 0], [20, 3], [40, -3], [45, 10]],
                                   [[20, 0], [20, 0], [20, 0], [0, 15]])
    dist = PathDistance(path)
    rng = np.random.default_rng(int(spread * 10))
    for _ in range(20):
        P = rng.uniform(0, 40, 2) + rng.normal(0, spread, (int(rng.integers(8, 400)), 2))
        every = np.argmin(P @ dist._key_p + dist._key_s, axis=1)    # over all the samples
        np.testing.assert_array_equal(dist._nearest(P), every)
