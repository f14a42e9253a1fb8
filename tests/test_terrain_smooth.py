"""A height field smooth enough to integrate (core/ground/terrain.py, docs/TERRAIN.md Section 1): the
surface is C2, so its curvature, and with it the right-hand side of the turning model, is
continuous across cell edges, and a run on it converges as the step shrinks, to the solution an
adaptive solver finds from the model's right-hand side."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import PhaseEllipse, preset, simulate, slalom_start
from blender_turning.core.physics.params import Limits
from blender_turning.core.ground.terrain import HeightField
from blender_turning.core.physics.model import RESISTANCE, rhs as model_rhs, steering as model_steering

ROUGH = HeightField(np.random.default_rng(11).normal(0.0, 0.4, (9, 12)), -3.0, 1.0, 0.7)


def _edge_pairs(field, axis, per_edge=7):
    """Points on every interior cell edge across ``axis`` (0: the lines x = const, 1: y = const),
    as the same point seen from the cell before (the float just below the edge) and after."""
    rng = np.random.default_rng(2)
    x_lo, _, y_lo, _ = field.extent
    n_edges, n_along = (field.nx, field.ny) if axis == 0 else (field.ny, field.nx)
    before, after = [], []
    for k in range(1, n_edges - 1):
        edge = (x_lo if axis == 0 else y_lo) + k * field.cell
        along = (y_lo if axis == 0 else x_lo) + rng.uniform(0, (n_along - 1) * field.cell,
                                                            per_edge)
        for a in along:
            lo, hi = math.nextafter(edge, -math.inf), edge
            before.append((lo, a) if axis == 0 else (a, lo))
            after.append((hi, a) if axis == 0 else (a, hi))
    return before, after


@pytest.mark.parametrize("axis", [0, 1])
def test_second_derivatives_are_continuous_across_cell_edges(axis):
    """On a rough random grid (no smoothness in the data to hide behind), the height, both
    slopes and all three second derivatives agree on either side of every interior cell edge,
    at points along the edge (not only at the grid points), on floats and on arrays.

    Tolerance: the two sides are one float apart (~1e-16 m), so they differ by |h'''| 1e-16 plus
    round-off in the cell polynomials: measured 9e-14 of a column's size at most, 2e-14 of the
    largest; bound 1e-11 of the largest.  The Catmull-Rom bicubic this field replaced was C1
    only: on this grid its h_xx jumped by 0.35 of its size across x edges and h_yy by 0.55
    across y edges (its slopes agreed to 1e-14)."""
    before, after = _edge_pairs(ROUGH, axis)
    one_b = np.array([ROUGH.derivatives_one(x, y) for x, y in before])
    one_a = np.array([ROUGH.derivatives_one(x, y) for x, y in after])
    arr_b = np.array(ROUGH.derivatives(*np.array(before).T)).T
    arr_a = np.array(ROUGH.derivatives(*np.array(after).T)).T
    scale = np.abs(one_a).max(0)
    assert np.all(scale[3:] > 1.0)                           # a grid that really bends
    for b, a in ((one_b, one_a), (arr_b, arr_a)):
        np.testing.assert_allclose(b, a, rtol=0, atol=1e-11 * scale.max())


def test_the_surface_passes_through_the_grid_and_keeps_quadratics():
    """Interpolating: every grid point comes back (to round-off); a quadratic comes back
    exactly between them, with its curvature (central differences are exact for it)."""
    j, i = np.mgrid[0:ROUGH.ny, 0:ROUGH.nx]
    x, y = ROUGH.x0 + i * ROUGH.cell, ROUGH.y0 + j * ROUGH.cell
    np.testing.assert_allclose(ROUGH.derivatives(x, y)[0], ROUGH._h[2:-2, 2:-2], rtol=0,
                               atol=1e-14)
    c = 1.5
    X, Y = np.meshgrid(np.arange(12) * c, np.arange(10) * c)
    bowl = HeightField(0.03 * X * X - 0.02 * X * Y + 0.05 * Y * Y + 0.3 * X, 0.0, 0.0, c)
    rng = np.random.default_rng(4)
    px, py = rng.uniform(2 * c, 9 * c, 200), rng.uniform(2 * c, 7 * c, 200)  # off the border
    h, hx, hy, hxx, hxy, hyy = bowl.derivatives(px, py)
    np.testing.assert_allclose(h, 0.03 * px * px - 0.02 * px * py + 0.05 * py * py + 0.3 * px,
                               atol=1e-12)
    np.testing.assert_allclose(hx, 0.06 * px - 0.02 * py + 0.3, atol=1e-12)
    np.testing.assert_allclose(hy, -0.02 * px + 0.1 * py, atol=1e-12)
    for got, want in ((hxx, 0.06), (hxy, -0.02), (hyy, 0.1)):
        np.testing.assert_allclose(got, want, atol=1e-12)


# -- convergence of a run ------------------------------------------------------------------------

SKIER = preset("skier")
# The controller's step-wise parts kept out of the comparison, so that what is left is the
# surface: no rate bound on C_f (it anchors on the step's start, a discrete construct) and a
# C_f bound the 23 deg slalom never reaches (below it the feasible lean switches table at 0.5
# m/s steps of speed, at a step-dependent instant).  No course: directional control plans beta
# at lean crossings found step by step.
SMOOTH = replace(SKIER, limits=Limits(C_f_max=1.0, theta_fall=math.radians(60)))
W, TM, FALL = math.pi, math.radians(23), -math.pi / 2
START = (*slalom_start(SKIER.body, W, TM, FALL, 0.0, 40.0), 8.0)


def _rolling():
    """A 6 deg slope down -y with two sets of rolls 1.5 m and 0.8 m high, 31-47 m long, on 2 m
    cells: the skier (snow friction, drag) runs 8 to 13 m/s, 390 m down in 40 s."""
    cell = 2.0
    xs, ys = np.arange(-150, 150.1, cell), np.arange(-500, 60.1, cell)
    X, Y = np.meshgrid(xs, ys)
    H = (math.tan(math.radians(6)) * Y + 1.5 * np.sin(2 * math.pi * Y / 47 + 0.3)
         + 0.8 * np.sin(2 * math.pi * X / 31) * np.cos(2 * math.pi * Y / 37))
    return HeightField(H, float(xs[0]), float(ys[0]), cell)


ROLLING = _rolling()


def _run(dt):
    return simulate(SMOOTH, PhaseEllipse(SMOOTH.body, W, TM), 40.0, dt, START, ground=ROLLING,
                    resistance=RESISTANCE["skier"])


@pytest.fixture(scope="module")
def fine():
    return _run(0.00125)


def test_a_run_on_a_height_field_converges_as_the_step_shrinks(fine):
    """40 s of a slalom over the rolls: the lean at dt = 0.02 s is within 0.05 deg of the lean at
    dt = 0.00125 s at every common sample.  Measured: 0.024 deg (0.001 deg at dt = 0.005 s);
    the Catmull-Rom bicubic (C1, its curvature jumping at every cell edge) gave 1.14 deg (0.24
    at dt = 0.005 s)."""
    coarse = _run(0.02)
    assert len(coarse) == 2001 and len(fine) == 32001           # 40 s, on the field throughout
    assert np.ptp(fine.V_cm) > 4.0 and np.degrees(np.abs(fine.theta_v).max()) > 20.0
    diff = np.degrees(np.abs(coarse.theta_v - fine.theta_v[::16]))
    assert diff.max() < 0.05, diff.max()


def test_the_fine_run_is_the_adaptive_solution_of_the_model(fine):
    """The same 40 s by scipy's DOP853 at rtol = atol = 1e-10 from the model's right-hand side
    (:func:`..core.physics.model.rhs` under :func:`..core.physics.model.steering`, the
    reference the fused stepper is held to): the dt = 0.00125 s run's lean is within 0.005 deg of it at every 0.02 s.
    Measured: 1.8e-4 deg (the dt = 0.02 s run: 0.024 deg); the reference itself moves 4.9e-4
    deg from rtol 1e-9 to 1e-10, so the bound is 10 times what the reference can resolve and
    28 times the measured gap.  The Catmull-Rom bicubic (C1): 0.041 deg, and DOP853 needed
    98,000 evaluations against 41,000 here (its step control stumbles at every kink of the
    right-hand side)."""
    from scipy.integrate import solve_ivp

    ctl = PhaseEllipse(SMOOTH.body, W, TM)
    ctl.begin_run(SMOOTH.limits)
    law, res = model_steering(ctl, ROLLING), RESISTANCE["skier"]

    def rhs(t, y):
        st = y.tolist()
        ctl.follow_speed(st[5])               # as the loop does (the law does not use it here)
        return model_rhs(SMOOTH.body, SMOOTH.limits, ROLLING, float(law(t, st)),
                         st, resistance=res)[0]

    t_eval = np.arange(2001) * 0.02
    sol = solve_ivp(rhs, (0.0, 40.0), np.array(START), method="DOP853", t_eval=t_eval,
                    rtol=1e-10, atol=1e-10)
    assert sol.success, sol.message
    diff = np.degrees(np.abs(fine.theta_v[::16] - sol.y[3]))
    assert diff.max() < 0.005, diff.max()
