"""The one-figure fast path's controller laws and heading table on floats (core/physics/one_figure.py,
the controllers' float laws) against the array formulas they must equal (the right-hand side
itself against the model: tests/test_model_kernels.py).  Both evaluate the same expressions in
the same order, so they agree to round-off; 1e-12 relative leaves room for libm differences
between numpy and math."""
import math

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.controllers.ellipse import LAWS, LAWS_ONE
from blender_turning.core.controllers.heading_table import heading_table

TWO_PI = 2 * math.pi


@pytest.mark.parametrize("law", sorted(LAWS))
def test_ellipse_law_on_floats_equals_the_array_law(law):
    """Random states plus the special ones where the branches meet: the axes, the target ellipse,
    the lines |x| = 1 and |y| = 1 (with ulps either side), the origin disc and slow states."""
    w, tm = TWO_PI / 2, math.radians(23)
    amax = 2 * w * w * tm
    rng = np.random.default_rng(5)
    th = list(rng.uniform(-0.8, 0.8, 400))
    om = list(rng.uniform(-3, 3, 400))
    edges_th = [0.0, tm, -tm, tm * (1 + 1e-15), -tm * (1 - 1e-15), 0.5 * tm, 1.2 * tm, 1e-4]
    edges_om = [0.0, w * tm, -w * tm, w * tm * (1 - 1e-15), 0.3 * w * tm, 0.01, -1.5 * w * tm,
                1e-4]
    for a in edges_th:
        for b in edges_om:
            th.append(a), om.append(b)
            th.append(-a), om.append(b)
    th, om = np.array(th), np.array(om)
    ellipse_alpha, ellipse_alpha_one = LAWS[law]
    for tmax, w0 in ((tm, w), (1.3 * tm, 0.8 * w)):
        vec = ellipse_alpha(th, om, tmax, w0, amax)
        one = [ellipse_alpha_one(float(a), float(b), tmax, w0, amax) for a, b in zip(th, om)]
        np.testing.assert_allclose(one, vec, rtol=0, atol=1e-12 * amax)
        # a step's law of both half-turns (PhaseEllipse.step_law): the same floats, bit for bit
        e, f = (tmax, w0, amax), (0.9 * tmax, 1.1 * w0, amax)
        step = LAWS_ONE[law](e, f)
        assert [step(0.0, float(a), float(b)) for a, b in zip(th, om)] == [
            ellipse_alpha_one(float(a), float(b), *(e if a >= 0.0 else f))
            for a, b in zip(th, om)]


def test_table_value_and_beta_solve_on_floats_equal_the_array_versions():
    table = heading_table(preset("skier").body)
    rng = np.random.default_rng(6)
    # Inside the grid and beyond it on every side (clamped).
    tms = np.concatenate([rng.uniform(0.005, 1.1, 60), [0.001, 1.2, 0.3]])
    ws = np.concatenate([rng.uniform(0.4, 16.0, 60), [0.3, 3.0, 20.0]])
    np.testing.assert_allclose([table.value_one(float(a), float(b)) for a, b in zip(tms, ws)],
                               table(tms, ws), rtol=1e-13, atol=1e-15)
    for tm, w in zip(tms[::3], ws[::3]):
        base = table.value_one(float(tm), float(w))
        for wanted in (0.5 * base, base, 1.3 * base, 10.0 * base, -1.0):   # last two unreachable
            one = table.solve_beta(float(tm), float(w), float(wanted))
            arr = table.solve_beta(np.array([tm]), np.array([w]), np.array([wanted]))[0]
            assert isinstance(one, float)
            assert one == pytest.approx(arr, abs=1e-9)


@pytest.mark.parametrize("controller", ["ellipse", "open-loop"])
def test_one_figure_equals_a_batch_of_one_under_changing_schedules(controller):
    """The float loop reads constant schedules once and calls the others at every stage: with
    frequency, sharpness and heading all changing mid-run it must still equal the numpy step
    (same formulas, same order; 1e-9 over 12 s of accumulated round-off)."""
    from blender_turning.core import OpenLoop, PhaseEllipse, Schedule, run
    fig = preset("skier")
    t = [0.0, 4.0, 8.0, 12.0]
    w = Schedule.sampled(t, [TWO_PI / 2.0, TWO_PI / 1.6, TWO_PI / 2.4, TWO_PI / 2.0])
    tm = Schedule.sampled(t, np.radians([15.0, 25.0, 20.0, 12.0]))
    make = (lambda: PhaseEllipse(fig.body, w, tm, heading=Schedule.sampled(t, np.radians(
        [0.0, 10.0, -10.0, 5.0])))) if controller == "ellipse" else (lambda: OpenLoop(fig.body, w, tm))
    s0 = np.array([0.0, 0.0, 0.0, 0.0, TWO_PI / 2.0 * math.radians(15.0)])
    one = run(fig.body, fig.limits, make(), s0, 12.0)
    batch = run(fig.body, fig.limits, make(), s0[:, None], 12.0)
    for k in ("x", "y", "theta_dir", "theta_v", "omega_v", "C_f", "phi"):
        np.testing.assert_allclose(one.columns[k], batch.columns[k][:, 0], rtol=0, atol=1e-9)
