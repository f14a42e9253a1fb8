"""Eqs. (1), (2), (21) and Appendix A, checked against each other and against physics."""
import math

import numpy as np
import pytest

from blender_turning.core import BodyParams, Limits, preset
from blender_turning.core.physics.dynamics import (bound_cf, forward_alpha, foot_speed, inverse_cf,
                                           leg_force, PHYSICAL_MARGIN)

BODIES = [preset(n).body for n in ("skier", "snowboarder", "telemark", "cyclist")]
rng = np.random.default_rng(1)
TH = rng.uniform(-1.0, 1.0, 2000)


@pytest.mark.parametrize("body", BODIES)
def test_inverse_then_forward_round_trip(body):
    alpha = rng.uniform(-8, 8, TH.size)
    cf = inverse_cf(body, TH, alpha)
    ok = np.isfinite(cf)
    assert ok.mean() > 0.9
    # Relative error ~ machine epsilon times the condition of Eq. (2): 1e-12 of the scale.
    np.testing.assert_allclose(forward_alpha(body, TH[ok], cf[ok]), alpha[ok], rtol=0, atol=1e-11)


@pytest.mark.parametrize("body", BODIES)
def test_forward_then_inverse_round_trip(body):
    s = np.sin(TH)
    cf = rng.uniform(-0.5, 0.5, TH.size)
    cf = np.clip(cf, -0.8 / (body.l * np.abs(s)), 0.8 / (body.l * np.abs(s)))  # physical branch
    alpha = forward_alpha(body, TH, cf)
    np.testing.assert_allclose(inverse_cf(body, TH, alpha), cf, rtol=0, atol=1e-12)


def test_vertical_body_with_no_acceleration_needs_no_curvature():
    for body in BODIES:
        assert inverse_cf(body, 0.0, 0.0) == 0.0
        assert forward_alpha(body, 0.0, 0.0) == 0.0


@pytest.mark.parametrize("body", BODIES)
def test_steady_turn_relation(body):
    # alpha_v = 0: tan(theta_v) = V_cm^2 C_cm / g with C_cm = C_f / (1 - C_f l sin theta_v).
    th = np.radians(np.linspace(-50, 50, 101))
    cf = inverse_cf(body, th, 0.0)
    c_cm = cf / (1 - cf * body.l * np.sin(th))
    np.testing.assert_allclose(np.tan(th), body.V_cm ** 2 * c_cm / body.g, atol=1e-12)


@pytest.mark.parametrize("body", BODIES)
def test_mirror_symmetry(body):
    alpha = rng.uniform(-5, 5, TH.size)
    np.testing.assert_allclose(inverse_cf(body, -TH, -alpha), -inverse_cf(body, TH, alpha),
                               atol=1e-14)
    cf = rng.uniform(-0.1, 0.1, TH.size)
    np.testing.assert_allclose(forward_alpha(body, -TH, -cf), -forward_alpha(body, TH, cf),
                               atol=1e-14)
    np.testing.assert_allclose(foot_speed(body, -TH, -cf), foot_speed(body, TH, cf), atol=1e-14)


def test_unreachable_demand_is_infinite_then_bounded():
    body = preset("skier").body
    th = math.radians(30)
    # A huge rightward acceleration while leaning left makes k l sin th + V^2 cos th negative.
    alpha = 1e4
    cf = inverse_cf(body, th, alpha)
    assert np.isinf(cf) and cf < 0
    lim = Limits(C_f_max=0.2)
    assert bound_cf(body, lim, cf, math.sin(th)) == pytest.approx(-0.2)
    # Toward the lean, the physical branch caps C_f below 1 / (l sin th).
    big = bound_cf(body, Limits(), 1e9, math.sin(th))
    assert big == pytest.approx(PHYSICAL_MARGIN / (body.l * math.sin(th)))
    assert 1 - big * body.l * math.sin(th) > 0


def test_rate_bound():
    body, lim = preset("skier").body, Limits(dC_f_max=0.5)
    assert bound_cf(body, lim, 0.1, 0.0, anchor=0.0, tau=0.02) == pytest.approx(0.01)
    assert bound_cf(body, lim, -0.1, 0.0, anchor=0.0, tau=0.02) == pytest.approx(-0.01)


def test_leg_force_is_weight_on_a_straight_vertical_run():
    for body in BODIES:
        F, along = leg_force(body, 0.0, 0.0, 0.0, 0.0)
        assert F == pytest.approx(body.m * body.g, rel=1e-14)
        assert along == pytest.approx(body.m * body.g, rel=1e-14)


def test_leg_force_in_a_steady_turn_is_along_the_leg():
    body = preset("cyclist").body
    th = math.radians(25)
    cf = inverse_cf(body, th, 0.0)
    F, along = leg_force(body, th, 0.0, 0.0, cf)
    c_cm = cf / (1 - cf * body.l * math.sin(th))
    lateral = body.V_cm ** 2 * c_cm
    assert F == pytest.approx(body.m * math.hypot(body.g, lateral), rel=1e-12)
    assert along == pytest.approx(F, rel=1e-12)


def test_params_validation_names_the_field():
    with pytest.raises(ValueError, match=r"m = -1 is outside the allowed range \[1, 1000\] kg"):
        BodyParams(m=-1)
    with pytest.raises(ValueError, match="V_cm = nan"):
        BodyParams(V_cm=float("nan"))
    with pytest.raises(ValueError, match="theta_fall"):
        Limits(theta_fall=2.0)
    with pytest.raises(ValueError, match="preset = 'surfer'"):
        preset("surfer")
