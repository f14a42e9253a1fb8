"""The model's reference right-hand side (core/physics/model.py) against geometry, and the fast kernels
behind it against the reference (not against each other): the numpy batch and the float stepper
on flat ground at the paper's held speed (core/physics/dynamics.py, core/physics/one_figure.py), the float
stepper on any ground (core/physics/terrain_one_figure.py) and the planner's fused flat stage
(core/planner/flat_stage.py), on Flat, a Plane and curved ground, the curved-surface terms
included."""
import math
from dataclasses import replace

import numpy as np
import pytest

from blender_turning.core import PhaseEllipse, preset
from blender_turning.core.physics import model
from blender_turning.core.controllers import Straight
from blender_turning.core.physics.dynamics import PHYSICAL_MARGIN, forward_alpha, inverse_cf, steer
from blender_turning.core.physics.model import RESISTANCE, Flat, HeightField, Plane
from blender_turning.core.physics.one_figure import rhs as float_rhs
from blender_turning.core.physics.params import Limits
from blender_turning.core.planner import flat_stage
from blender_turning.core.ground.terrain import surface_frame
from blender_turning.core.ground.terrain_gen import ski_slope
from blender_turning.core.physics.terrain_one_figure import TerrainStage

SKIER = preset("skier")
BODY = SKIER.body
FREE = Limits(theta_fall=math.radians(80))
W, TM = math.pi, math.radians(23)


class Swell:
    """``h = a sin(kx x + ky y) + s x``: an analytic surface curved everywhere (its exact
    derivatives; the ground protocol :func:`.terrain.surface_frame` reads)."""

    a, kx, ky, s = 1.5, 0.21, 0.13, -0.3
    flat = False

    def derivatives(self, x, y):
        x, y = np.asarray(x, float), np.asarray(y, float)
        ph = self.kx * x + self.ky * y
        S, C = self.a * np.sin(ph), self.a * np.cos(ph)
        return (S + self.s * x, self.kx * C + self.s, self.ky * C, -self.kx ** 2 * S,
                -self.kx * self.ky * S, -self.ky ** 2 * S)


def _foot_curve(ground, law, state0, dt, n):
    """RK4 of the reference model (FREE limits) from ``state0`` under ``C_f = law(t)``; returns
    the states, the bounded ``C_f`` and the foot's 3-D positions."""
    st, anchor, rows, cfs = np.array(state0, float), None, [], []
    for i in range(n):
        t = i * dt
        anchor = model.rhs(BODY, FREE, ground, law(t), st.tolist(), anchor, dt)[1]
        rows.append(st.copy())
        cfs.append(anchor)
        st = model.rk4_step(BODY, FREE, ground, st, t, dt, lambda tt, s: law(tt), anchor)
    S = np.array(rows)
    z = np.asarray(ground.derivatives(S[:, 0], S[:, 1])[0], float)
    return S, np.array(cfs), np.stack([S[:, 0], S[:, 1], z], 1)


@pytest.mark.parametrize("ground", [Swell(), ski_slope(length=200.0, width=200.0, cell=2.0),
                                    Plane(math.radians(25), 0.7), Flat()],
                         ids=["swell", "mogul height field", "plane", "flat"])
@pytest.mark.parametrize("C", [0.0, 0.06])
def test_the_foot_path_has_the_commanded_geodesic_curvature(ground, C):
    """From the foot's 3-D track alone (second differences of ``(x, y, h(x, y))``): it moves at
    ``V_f`` along the surface, and its curvature vector ``d^2 r / ds^2`` has the commanded
    ``C_f`` along ``b = n x t`` (the geodesic curvature, docs/TERRAIN.md Section 1) and the
    surface's ``kappa_n`` along ``n``.  The heading rate's curved-ground term
    ``V_f kappa_n bend_gain`` is what keeps ``C = 0`` a geodesic on curved ground.  Measured
    (dt 1 ms, central differences): |k.n - kappa_n| at most 1.9e-5 1/m on the height field's
    moguls (kappa_n up to 0.31 1/m; the central differences' own O(dt^2) error: 7.4e-5 at
    2 ms, 4.7e-6 at 0.5 ms), |k.b - C_f| 9e-7, 4e-7 on the swell; the bound is 3x the largest
    (dropping the curved-ground term misses by ~0.08 1/m)."""
    x0, y0 = (-60.0, -60.0) if isinstance(ground, HeightField) else (0.0, 0.0)   # moguls
    dt, n = 0.001, 3000
    S, cf, P = _foot_curve(ground, lambda t: C * math.cos(0.8 * t), (x0, y0, 0.4, 0.15, 0.3, 9.0),
                           dt, n)
    dP = (P[2:] - P[:-2]) / (2 * dt)
    ddP = (P[2:] - 2 * P[1:-1] + P[:-2]) / dt ** 2
    speed = np.linalg.norm(dP, axis=1)
    V_f = S[1:-1, 5] / (1.0 - cf[1:-1] * BODY.l * np.sin(S[1:-1, 3]))
    np.testing.assert_allclose(speed, V_f, rtol=8e-5)
    T = dP / speed[:, None]
    K = (ddP - T * (ddP * T).sum(1)[:, None]) / speed[:, None] ** 2     # d^2 r / ds^2
    fr = surface_frame(ground, S[1:-1, 0], S[1:-1, 1], S[1:-1, 2], BODY.g)
    b, nn = np.asarray(fr.b).T, np.asarray(fr.n).T
    inside = np.ones(len(K), bool)
    if isinstance(ground, HeightField):
        # The spline's third derivative jumps at cell edges (C2), so a second difference across
        # an edge is off by O(dt) there: keep the stencils inside one cell.
        cell = np.floor((P[:, :2] - [ground.x0, ground.y0]) / ground.cell)
        inside = np.all((cell[2:] == cell[1:-1]) & (cell[:-2] == cell[1:-1]), 1)
        assert inside.mean() > 0.9
    np.testing.assert_allclose((K * b).sum(1)[inside], cf[1:-1][inside], rtol=0, atol=6e-5)
    np.testing.assert_allclose((K * nn).sum(1)[inside], np.asarray(fr.kappa_n)[inside], rtol=0,
                               atol=6e-5)
    if not getattr(ground, "flat", False) and not isinstance(ground, Plane):
        assert np.abs(fr.kappa_n).max() > 0.02                    # the ground is curved here


def _random_states(rng, n, lo_V=2.0, hi_V=25.0, box=(-9, 9, -9, 9)):
    x_lo, x_hi, y_lo, y_hi = box
    return np.stack([rng.uniform(x_lo, x_hi, n), rng.uniform(y_lo, y_hi, n),
                     rng.uniform(-4, 4, n), rng.uniform(-1.2, 1.2, n), rng.uniform(-3, 3, n),
                     rng.uniform(lo_V, hi_V, n)])


@pytest.mark.parametrize("name,C_f_max", [("skier", None), ("cyclist", 2.0)])
def test_flat_kernels_are_the_model_at_the_held_speed(name, C_f_max):
    """:func:`.dynamics.steer` under :func:`.dynamics.inverse_cf` (arrays) and
    :func:`.one_figure.rhs` (floats, Eq. 1 fused into the stage) against :func:`.model.rhs` on
    ``Flat()`` with the paper's held speed under :func:`.model.inverse_cf` of the same lean
    accelerations: every bound in play (demands beyond C_f_max, demands off the physical branch
    that Eq. 1 makes infinite, the physical branch binding for a cyclist with C_f_max l > 0.9,
    rate bounds with and without an anchor).  Round-off: 1e-12 of each output's scale."""
    fig = preset(name)
    if C_f_max is not None:
        fig = replace(fig, limits=replace(fig.limits, C_f_max=C_f_max))
    body, limits = fig.body, fig.limits
    rng = np.random.default_rng(3)
    n = 400
    S = _random_states(rng, n)
    S[5] = body.V_cm
    cmax = limits.C_f_max
    # The lean accelerations Eq. (2) gives for curvatures up to 3 C_f_max, and some far beyond
    # any curvature's reach (Eq. 1 has no physical root: an infinite demand).
    alpha = forward_alpha(body, S[3], rng.uniform(-3 * cmax, 3 * cmax, n))
    alpha[::17], alpha[1::17] = 1e4, -1e4
    frame = surface_frame(Flat(), S[0], S[1], S[2], body.g)
    demand = model.inverse_cf(body, frame, S[3], alpha, S[5])
    assert np.isinf(demand).sum() > 10                             # unreachable demands
    anchor, tau = rng.uniform(-cmax, cmax, n), rng.choice([0.0, 0.01, 0.02], n)
    hits = 0
    for with_anchor in (True, False):
        a = anchor if with_anchor else None
        ref, cf, alpha_v, V_f, _, _ = model.rhs(body, limits, Flat(), demand, tuple(S), a, tau,
                                                held=True)
        held_V = np.broadcast_arrays(*ref)[5]
        # Rows compared: the five rates of the paper's state, C_f, alpha_v, V_f.
        ref = np.array([*np.broadcast_arrays(*ref[:5]), cf, alpha_v, V_f])
        scale = np.maximum(np.abs(np.where(np.isfinite(ref), ref, 0)).max(1), 1.0)
        batch_d, b_cf, b_alpha, b_V = steer(body, limits, inverse_cf(body, S[3], alpha), S[:5],
                                            a, tau)
        batch = np.array([*np.broadcast_arrays(*batch_d), b_cf, b_alpha, b_V])
        np.testing.assert_allclose(batch / scale[:, None], ref / scale[:, None], rtol=0,
                                   atol=1e-12)
        for j in range(n):
            stage = float_rhs(body, limits, lambda t, th, om, c=float(alpha[j]): c, body)
            got = stage(0.0, *S[:5, j].tolist(), None if a is None else float(a[j]),
                        float(tau[j]))
            np.testing.assert_allclose(np.array(got) / scale, ref[:, j] / scale, rtol=0,
                                       atol=1e-12)
        hits += int(np.count_nonzero(np.abs(cf * body.l * np.sin(S[3])) > PHYSICAL_MARGIN - 1e-12))
    assert np.all(held_V == 0.0)                                   # held
    if C_f_max is not None:
        assert hits > 10                                           # the physical bound binds


class _Sharp(Straight):
    """Demands beyond every bound: lean accelerations so large that Eq. (1) asks for ``C_f``
    near ``1 / (l sin theta_v)`` (past the physical branch's bound) or has no physical root
    (an infinite demand, clamped to ``C_f_max``)."""

    def lean_law(self, t, theta_v, omega_v):
        return 1e5 * math.sin(7.0 * omega_v + 13.0 * theta_v)


@pytest.mark.parametrize("ground", [Flat(), Plane(math.radians(25), 0.7, 1.0, -2.0, 3.0),
                                    Swell(), ski_slope(length=120.0, width=120.0, cell=2.0)],
                         ids=["flat", "plane", "swell", "mogul height field"])
def test_the_float_stepper_is_the_model(ground):
    """One stage of :class:`.terrain_one_figure.TerrainStage` (any ground, floats) against
    :func:`.model.rhs` under the controller's steering (:func:`.model.steering`), with the rate
    bound active and the physical branch binding: to 1e-12 of each output's scale (``V_f`` for
    the foot's velocity,
    ``1 + V_f (|C_f| + |kappa_n|)`` for the heading rate, ``g + V_f^2 |kappa_n| + V V_f |C_f|``
    for the accelerations; ``V_f`` reaches 10 V on the physical bound)."""
    rng = np.random.default_rng(8)
    res = RESISTANCE["skier"]
    box = getattr(ground, "extent", (-50, 50, -50, 50))
    hits = 0
    for ctl, limits in ((PhaseEllipse(BODY, W, TM, heading=-math.pi / 2), SKIER.limits),
                        (PhaseEllipse(BODY, W, TM), SKIER.limits),
                        (Straight(BODY), SKIER.limits), (_Sharp(BODY), Limits(C_f_max=10.0))):
        ctl.begin_run(limits)
        stage = TerrainStage(BODY, limits, res, ground, ctl).stage
        law = model.steering(ctl, ground)
        S = _random_states(rng, 200, box=(box[0] + 1, box[1] - 1, box[2] + 1, box[3] - 1))
        S[3] *= 0.5
        for st in S.T.tolist():
            anchor, tau = float(rng.normal(0.0, 0.05)), 0.01
            got = stage(0.3, *st, anchor, tau)
            d, cf, alpha, V_f, _, fr = model.rhs(BODY, limits, ground, float(law(0.3, st)), st,
                                                 anchor, tau, res)
            ref = [*d, alpha, V_f, cf]
            G = BODY.g + V_f * V_f * abs(fr.kappa_n) + st[5] * V_f * abs(cf)
            scale = [V_f, V_f, 1.0 + V_f * (abs(cf) + abs(fr.kappa_n)), 1, G, G, G, V_f, 1]
            np.testing.assert_allclose(np.array(got) / scale, np.array(ref) / scale, rtol=0,
                                       atol=1e-12)
            hits += abs(cf * BODY.l * math.sin(st[3])) > PHYSICAL_MARGIN - 1e-12
    assert hits > 30


def test_the_fused_planner_stage_is_the_model():
    """:func:`.planner.flat_stage.integrate` (the numpy rows and the float columns) against the
    reference model's RK4 on ``Flat()`` at the held speed under the stage's law
    ``C_f = C0 + u tau``, bounded at every RK4 stage from the curvature at the step's start
    (:func:`.planner.flat_stage.curvatures`): to 1e-12 (round-off over 15 steps)."""
    fig = preset("skier")
    body, lim = fig.body, replace(fig.limits, dC_f_max=0.3)
    rng = np.random.default_rng(11)
    steps, h = 15, 0.02
    beyond = 0
    for m in (3, flat_stage.SCALAR_COLUMNS + 6):
        x0 = np.stack([rng.uniform(0, 9, m), rng.uniform(-3, 3, m), rng.normal(0, 0.4, m),
                       rng.normal(0, 0.3, m), rng.normal(0, 1.0, m)])
        C0 = rng.uniform(-1.5, 1.5, m) * lim.C_f_max
        u = rng.choice([-0.3, -0.15, 0.0, 0.15, 0.3], m)
        CF, _ = flat_stage.curvatures(C0, u, h, steps, lim.C_f_max, lim.dC_f_max, steps * h)
        P = flat_stage.integrate(x0, CF, h, body.V_cm, body)
        for j in range(m):
            law = lambda t, s, j=j: C0[j] + u[j] * t                # noqa: E731
            st = np.append(x0[:, j], body.V_cm)
            anchor = C0[j]
            for k in range(steps):
                t = k * h
                anchor = model.rhs(body, lim, Flat(), law(t, st), st.tolist(), anchor, h,
                                   held=True)[1]
                st = model.rk4_step(body, lim, Flat(), st, t, h, law, anchor, held=True)
                np.testing.assert_allclose(P[k + 1, :, j], st[:5], rtol=0, atol=1e-12)
        beyond += int(np.count_nonzero(np.abs(C0) > lim.C_f_max))
    assert beyond > 3                                             # the size bound binds
