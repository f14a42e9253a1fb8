"""Terrain: the surface frame, the extended model's reduction to flat ground and its closed-form
cases (docs/TERRAIN.md)."""
import math

import numpy as np
import pytest

from blender_turning.core import preset
from blender_turning.core.controllers.open_loop import open_loop_alpha
from blender_turning.core.physics.dynamics import inverse_cf, leg_force, rk4_step, steer
from blender_turning.core.physics.params import Limits
from blender_turning.core.ground.terrain import FLAT, HeightField, Plane, surface_frame
from blender_turning.core.physics import model
from blender_turning.core.physics.model import RESISTANCE, Resistance

SKIER = preset("skier")
FREE = Limits(theta_fall=math.radians(80))       # no C_f bounds: the closed forms assume none
NONE = Resistance()


def _run(ground, res, state0, law, duration, dt, body=SKIER.body, limits=FREE, held=False):
    """RK4 on the model's state as ``core.physics.simulate`` steps: the curvature at the start of each
    step is bounded against the previous step's and anchors the step's stages."""
    states = [np.asarray(state0, float)]
    anchor = None
    for i in range(int(round(duration / dt))):
        st, t = states[-1], i * dt
        anchor = model.rhs(body, limits, ground, law(t, st), st, anchor, dt, res, held)[1]
        states.append(model.rk4_step(body, limits, ground, st, t, dt, law, anchor, res, held))
    return np.array(states)


def test_plane_frame_is_orthonormal_and_splits_gravity():
    rng = np.random.default_rng(3)
    sigma, D = math.radians(25), math.radians(40)
    plane = Plane(sigma, D)
    x, y, d = rng.uniform(-50, 50, 50), rng.uniform(-50, 50, 50), rng.uniform(-4, 4, 50)
    fr = surface_frame(plane, x, y, d, 9.81)
    for u, v in [(fr.t, fr.t), (fr.b, fr.b), (fr.n, fr.n)]:
        np.testing.assert_allclose(np.sum(u * v, 0), 1.0, atol=1e-15)
    for u, v in [(fr.t, fr.b), (fr.t, fr.n), (fr.b, fr.n)]:
        np.testing.assert_allclose(np.sum(u * v, 0), 0.0, atol=1e-15)
    np.testing.assert_allclose(fr.g_normal, 9.81 * math.cos(sigma), rtol=1e-15)
    # The in-surface part is g sin(sigma) along the fall line, whatever the heading.
    np.testing.assert_allclose(np.hypot(fr.g_along, fr.g_lateral), 9.81 * math.sin(sigma),
                               rtol=1e-14)
    # Heading straight down the fall line: all of it along the track, to the left of nothing.
    down = surface_frame(plane, 0.0, 0.0, D, 9.81)
    assert down.g_along == pytest.approx(9.81 * math.sin(sigma), rel=1e-15)
    assert down.g_lateral == pytest.approx(0.0, abs=1e-15)
    # Heading 90 deg left of the fall line: downhill is to the right (g_lateral < 0).
    across = surface_frame(plane, 0.0, 0.0, D + math.pi / 2, 9.81)
    assert across.g_lateral == pytest.approx(-9.81 * math.sin(sigma), rel=1e-14)


def test_height_field_reproduces_planes_and_quadratics():
    cell = 2.0
    xs = np.arange(0, 41) * cell
    X, Y = np.meshgrid(xs, xs)
    plane = Plane(math.radians(20), math.radians(-30), x0=3.0, y0=-2.0, z0=5.0)
    field = HeightField(plane.derivatives(X, Y)[0], 0.0, 0.0, cell)
    rng = np.random.default_rng(4)
    # Everywhere on the grid, including the border cells (the padding is linear).
    px, py = rng.uniform(0, 80, 200), rng.uniform(0, 80, 200)
    for a, b in zip(field.derivatives(px, py), plane.derivatives(px, py)):
        np.testing.assert_allclose(a, b, atol=1e-11)
    # A bowl and a saddle: exact one cell in from the border (central differences are exact).
    a, b, c = 0.01, -0.004, 0.006
    bowl = HeightField(a * X * X + b * X * Y + c * Y * Y, 0.0, 0.0, cell)
    px, py = rng.uniform(2, 78, 200), rng.uniform(2, 78, 200)
    h, hx, hy, hxx, hxy, hyy = bowl.derivatives(px, py)
    np.testing.assert_allclose(h, a * px * px + b * px * py + c * py * py, atol=1e-11)
    np.testing.assert_allclose(hx, 2 * a * px + b * py, atol=1e-12)
    np.testing.assert_allclose(hy, b * px + 2 * c * py, atol=1e-12)
    np.testing.assert_allclose(hxx, 2 * a, atol=1e-12)
    np.testing.assert_allclose(hxy, b, atol=1e-12)
    np.testing.assert_allclose(hyy, 2 * c, atol=1e-12)
    with pytest.raises(ValueError, match="off the terrain"):
        bowl.derivatives(81.0, 5.0)


def test_flat_ground_without_resistance_is_the_papers_model():
    rng = np.random.default_rng(5)
    n = 200
    state = np.array([rng.uniform(-9, 9, n), rng.uniform(-9, 9, n), rng.uniform(-3, 3, n),
                      rng.uniform(-0.8, 0.8, n), rng.uniform(-2, 2, n)])
    cf = rng.uniform(-0.15, 0.15, n)
    lim = SKIER.limits
    old, cf0, a0, vf0 = steer(SKIER.body, lim, cf, state, cf * 0.9, 0.02)
    new, cf1, a1, vf1, _, _ = model.rhs(SKIER.body, lim, FLAT, cf,
                                        (*state, np.full(n, SKIER.body.V_cm)), cf * 0.9, 0.02,
                                        held=True)
    np.testing.assert_array_equal(cf1, cf0)
    for u, v in zip(new[:5], old):
        np.testing.assert_allclose(u, v, rtol=1e-14, atol=1e-14)
    np.testing.assert_array_equal(new[5], 0.0)          # the paper's held speed
    # A whole 20 s slalom (the open-loop 2 s / 23 deg turn of Section 4): same to 1e-12.
    w, th_max = math.pi, math.radians(23)
    law = lambda t, s: inverse_cf(SKIER.body, s[3], open_loop_alpha(w * t, th_max, w))  # noqa
    s_old = np.zeros(5)
    anchor = None
    for i in range(1000):
        t = i * 0.02
        anchor = steer(SKIER.body, lim, law(t, s_old), s_old, anchor, 0.02)[1]
        s_old = rk4_step(SKIER.body, lim, s_old, t, 0.02, law, anchor)
    s_new = _run(FLAT, NONE, [0, 0, 0, 0, 0, SKIER.body.V_cm], law, 20.0, 0.02, limits=lim,
                 held=True)[-1]
    assert abs(s_old[3]) > 0.3                     # a real slalom, not a straight run
    np.testing.assert_allclose(s_new[:5], s_old, rtol=0, atol=1e-12)
    assert s_new[5] == SKIER.body.V_cm


def test_straight_run_down_the_fall_line_follows_the_closed_form():
    """``dV/dt = g (sin s - mu cos s) - k V^2``: ``V = V_T tanh(sqrt(A k) t + atanh(V0/V_T))``."""
    sigma, D = math.radians(18), math.radians(-70)
    res = RESISTANCE["skier"]
    body = SKIER.body
    A = body.g * (math.sin(sigma) - res.mu * math.cos(sigma))
    k = res.drag_k(body.m)
    V_T = math.sqrt(A / k)
    V0 = 2.0
    traj = _run(Plane(sigma, D), res, [0, 0, D, 0, 0, V0], lambda t, s: 0.0, 30.0, 0.01)
    t = np.arange(len(traj)) * 0.01
    V = V_T * np.tanh(math.sqrt(A * k) * t + math.atanh(V0 / V_T))
    np.testing.assert_allclose(traj[:, 5], V, rtol=1e-6)
    assert traj[-1, 5] > 0.9 * V_T                       # it got near terminal speed
    np.testing.assert_allclose(traj[:, 3], 0.0, atol=1e-15)   # stays upright
    # Energy: the drop equals the kinetic energy gained plus friction and drag work.
    ground = Plane(sigma, D)
    z = ground.derivatives(traj[:, 0], traj[:, 1])[0]
    Vs = traj[:, 5]
    N = body.m * body.g * math.cos(sigma)
    power = res.mu * N * Vs + body.m * k * Vs ** 3
    work = _simpson(power, 0.01)
    drop = body.m * body.g * (z[0] - z[-1])
    assert drop == pytest.approx(0.5 * body.m * (Vs[-1] ** 2 - V0 ** 2) + work, rel=1e-6)


def _simpson(f, h):
    assert len(f) % 2 == 1
    return h / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum())


@pytest.mark.parametrize("beta_deg", [20, 60, 90, 135, -45])
def test_traverse_holds_the_plumb_lean(beta_deg):
    """On a traverse at in-surface angle ``beta`` to the fall line the plumb line leans uphill
    from the normal by ``atan(tan sigma |sin beta|)``; started there, ``C_f = 0`` holds it."""
    sigma, D = math.radians(30), math.radians(15)
    plane = Plane(sigma, D)
    beta = math.radians(beta_deg)
    # The horizontal heading of the in-surface direction at beta: tan(delta) = tan(beta)/cos(s).
    heading = D + math.atan2(math.sin(beta), math.cos(beta) * math.cos(sigma))
    fr = surface_frame(plane, 0.0, 0.0, heading, 9.81)
    fall = np.array([math.cos(D) * math.cos(sigma), math.sin(D) * math.cos(sigma),
                     -math.sin(sigma)])
    assert float(fall @ fr.t) == pytest.approx(math.cos(beta), abs=1e-15)
    lean = math.atan(math.tan(sigma) * abs(math.sin(beta)))
    # Downhill is on the right for beta > 0 (heading CCW of the fall line): lean left, uphill.
    theta0 = math.copysign(lean, math.sin(beta))
    res = RESISTANCE["skier"]
    traj = _run(plane, res, [0, 0, heading, theta0, 0, 5.0], lambda t, s: 0.0, 2.0, 0.01)
    np.testing.assert_allclose(traj[:, 3], theta0, atol=1e-12)
    np.testing.assert_allclose(traj[:, 2], heading, atol=1e-12)
    # The wrong side falls away from the plumb line fast.
    off = _run(plane, res, [0, 0, heading, -theta0, 0, 5.0], lambda t, s: 0.0, 0.5, 0.01)
    assert abs(off[-1, 3] + theta0) > 0.05


def test_lean_energy_balance_on_a_turning_run():
    """The lean's energy ``(I_v + m l^2) omega^2 / 2 + m l G_n cos th`` changes by the power of
    the lateral forces, ``m l omega cos th (g_b - a_lat)`` (docs/TERRAIN.md Section 4)."""
    sigma, D = math.radians(20), 0.0
    plane = Plane(sigma, D)
    body = SKIER.body
    res = RESISTANCE["skier"]
    law = lambda t, s: 0.1 * math.sin(2.0 * t)            # noqa: E731
    dt = 0.002
    traj = _run(plane, res, [0, 0, 0.2, 0.1, 0, 8.0], law, 6.0, dt)
    t = np.arange(len(traj)) * dt
    (_, _, _, om, alpha, _), cf, _, V_f, _, fr = model.rhs(
        body, FREE, plane, np.array([law(tt, None) for tt in t]), traj.T, resistance=res)
    th, V = traj[:, 3], traj[:, 5]
    I_foot = body.I_v + body.m * body.l ** 2
    E = 0.5 * I_foot * om ** 2 + body.m * body.l * fr.g_normal * np.cos(th)
    P = body.m * body.l * om * np.cos(th) * (fr.g_lateral - V * V_f * cf)
    assert abs(E[-1] - E[0]) > 50.0                       # the balance is not trivially 0 = 0
    assert E[-1] - E[0] == pytest.approx(_simpson(P, dt), rel=1e-6)


def test_normal_force_is_the_leg_forces_normal_part():
    """``N`` (friction's load) is the normal component of Appendix A's leg force on terrain:
    ``F_along cos th + (I_v alpha / l) sin th``; on flat ground the leg force is today's."""
    rng = np.random.default_rng(8)
    n = 100
    bowl = HeightField(*_bowl())
    state = (rng.uniform(-20, 20, n), rng.uniform(-20, 20, n), rng.uniform(-3, 3, n),
             rng.uniform(-0.7, 0.7, n), rng.uniform(-2, 2, n), rng.uniform(2, 15, n))
    cf = rng.uniform(-0.15, 0.15, n)
    body = SKIER.body
    _, cf, alpha, V_f, N, fr = model.rhs(body, FREE, bowl, cf, state)
    th, om, V = state[3], state[4], state[5]
    _, along = model.leg_force(body, th, om, alpha, cf, V, V_f, fr)
    np.testing.assert_allclose(N, along * np.cos(th) + body.I_v * alpha / body.l * np.sin(th),
                               rtol=1e-12, atol=1e-9)
    flat = surface_frame(FLAT, state[0], state[1], state[2], body.g)
    V_f0 = V / (1 - cf * body.l * np.sin(th))
    F, along = model.leg_force(body, th, om, alpha, cf, V, V_f0, flat)
    F0, along0 = leg_force(body, th, om, alpha, cf, V_cm=V)
    np.testing.assert_allclose(F, F0, rtol=1e-13)
    np.testing.assert_allclose(along, along0, rtol=1e-13, atol=1e-9)


def _bowl():
    xs = np.arange(-30, 31) * 1.0
    X, Y = np.meshgrid(xs, xs)
    return 0.01 * X * X - 0.003 * X * Y + 0.02 * Y * Y - 0.1 * X, -30.0, -30.0, 1.0


def test_constant_curvature_draws_a_circle_in_the_slope():
    """``C_f`` is the curvature in the surface: held constant on a plane, the foot draws a circle
    of radius ``1 / C_f`` in the inclined plane (the horizontal heading turns unevenly)."""
    plane = Plane(math.radians(35), 0.4)
    C = 0.1
    state0 = [0, 0, 1.0, math.atan(100 * C / 9.81), 0, 10.0]
    traj = _run(plane, NONE, state0, lambda t, s: C, 1.5, 0.005)
    p = np.array([traj[:, 0], traj[:, 1], plane.derivatives(traj[:, 0], traj[:, 1])[0]])
    fr = surface_frame(plane, 0.0, 0.0, 1.0, 9.81)
    centre = p[:, :1] + fr.b[:, None] / C
    radius = np.linalg.norm(p - centre, axis=0)
    np.testing.assert_allclose(radius, 1 / C, rtol=1e-9)
    assert float(np.sum(fr.n[:, None] * (p - centre), 0).max()) < 1e-9      # in the plane
    assert abs(traj[-1, 2] - traj[0, 2]) > 1.0                               # it turned


def test_mirror_across_the_fall_line():
    plane = Plane(math.radians(25), 0.0)                  # fall line along +x
    res = RESISTANCE["snowboarder"]
    law = lambda t, s: 0.15 * math.sin(1.7 * t + 0.3)     # noqa: E731
    a = _run(plane, res, [0, 1.0, 0.3, 0.05, 0.1, 7.0], law, 8.0, 0.02)
    b = _run(plane, res, [0, -1.0, -0.3, -0.05, -0.1, 7.0], lambda t, s: -law(t, s), 8.0, 0.02)
    flip = np.array([1, -1, -1, -1, -1, 1])
    np.testing.assert_allclose(b, a * flip, rtol=0, atol=1e-12)


def test_inverse_is_the_forward_law_inverted():
    rng = np.random.default_rng(6)
    plane = Plane(math.radians(28), 1.0)
    n = 100
    th, d, V = rng.uniform(-0.7, 0.7, n), rng.uniform(-3, 3, n), rng.uniform(2, 20, n)
    alpha = rng.uniform(-3, 3, n)
    fr = surface_frame(plane, 0.0, 0.0, d, 9.81)
    cf = model.inverse_cf(SKIER.body, fr, th, alpha, V)
    ok = np.isfinite(cf) & (1 - cf * SKIER.body.l * np.sin(th) > 0.1)
    assert ok.sum() > 80
    _, _, a2, _, _, _ = model.rhs(SKIER.body, FREE, plane, cf[ok],
                                      (0 * V[ok], 0 * V[ok], d[ok], th[ok], 0 * V[ok], V[ok]))
    np.testing.assert_allclose(a2, alpha[ok], atol=1e-10)


def test_bad_terrain_is_refused():
    with pytest.raises(ValueError, match="slope"):
        Plane(math.radians(75), 0.0)
    with pytest.raises(ValueError, match="cell"):
        HeightField(np.zeros((3, 3)), 0, 0, 0.0)
    with pytest.raises(ValueError, match="finite"):
        HeightField(np.array([[0, 1], [np.nan, 2]]), 0, 0, 1.0)
    with pytest.raises(ValueError, match="mu"):
        Resistance(mu=-0.1)
