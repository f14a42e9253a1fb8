"""The terrain model's derivation (docs/TERRAIN.md), checked symbolically with sympy (a test-only
dependency) and against the numeric code at sample points."""
import math

import numpy as np
import pytest
import sympy as sp                     # a pinned test-only dependency (requirements.txt)

from blender_turning.core.ground.terrain import HeightField, Plane, surface_frame


def _num(expr, subs):
    return float(expr.subs(subs).evalf(30))


def test_lean_equation_from_newton_euler():
    """Newton for the body and Euler about its centre of mass, in the foot's frame, give the
    lean acceleration the code uses: ``J alpha = G_n sin th + (g_b - a_lat) cos th``."""
    th, om, al, l, m, I, g_n, g_b, a_lat, a_n = sp.symbols(
        "theta omega alpha l m I_v g_n g_b a_lat a_n", real=True)
    # Frame (b, n) in the plane across the track; t = b x n... out of the page.  2-D vectors.
    e_l = sp.Matrix([sp.sin(th), sp.cos(th)])                  # foot -> centre of mass
    e_th = sp.Matrix([sp.cos(th), -sp.sin(th)])                # direction of increasing lean
    gravity = sp.Matrix([g_b, -g_n])                           # gravity's (b, n) components
    # Centre of mass acceleration: the track's (a_lat along b, a_n along n) plus the lean's.
    a_cm = sp.Matrix([a_lat, a_n]) + l * (al * e_th - om ** 2 * e_l)
    R = m * (a_cm - gravity)                                   # ground reaction on the foot
    arm = -l * e_l                                             # centre of mass -> foot
    # Torque about the centre of mass, positive toward increasing lean (b x n = -t here:
    # a rotation from n toward b increases theta, i.e. torque component -(arm x R)).
    torque = -(arm[0] * R[1] - arm[1] * R[0])
    alpha = sp.solve(sp.Eq(I * al, torque), al)[0]
    G_n = g_n + a_n
    J = (I + l ** 2 * m) / (m * l)
    assert sp.simplify(alpha - (G_n * sp.sin(th) + (g_b - a_lat) * sp.cos(th)) / J) == 0
    # Flat ground (g_n = g, g_b = 0, a_n = 0) and a_lat = V V_f C_f: the paper's Eq. (2).
    V, C, g = sp.symbols("V C_f g", positive=True)
    V_f = V / (1 - C * l * sp.sin(th))                         # Eq. (21)
    eq2 = l * m * (g * sp.sin(th) - C * V ** 2 * sp.cos(th) / (1 - C * l * sp.sin(th))) / (
        I + l ** 2 * m)
    flat = alpha.subs({g_n: g, g_b: 0, a_n: 0, a_lat: V * V_f * C})
    assert sp.simplify(flat - eq2) == 0
    # The normal contact force used for friction is R's n component.
    N = m * (G_n - l * (al * sp.sin(th) + om ** 2 * sp.cos(th)))
    assert sp.simplify(R[1] - N) == 0
    # The lean's energy changes by the lateral forces' power (the balance the model keeps).
    E = (I + m * l ** 2) * om ** 2 / 2 + m * l * G_n * sp.cos(th)
    dE = sp.diff(E, th) * om + sp.diff(E, om) * alpha
    assert sp.simplify(dE - m * l * om * sp.cos(th) * (g_b - a_lat)) == 0


def test_plane_gravity_split_and_plumb_lean():
    """On a plane of slope sigma, heading at in-surface angle beta to the fall line: gravity
    splits into ``g cos s`` (normal), ``g sin s cos b`` (along) and ``-g sin s sin b`` (left);
    the plumb lean is ``atan(tan s sin b)``."""
    s, b, g = sp.symbols("sigma beta g", positive=True)
    fall = sp.Matrix([sp.cos(s), 0, -sp.sin(s)])               # the fall line along +x
    across = sp.Matrix([0, 1, 0])
    n = sp.Matrix([sp.sin(s), 0, sp.cos(s)])
    t = sp.cos(b) * fall + sp.sin(b) * across
    left = n.cross(t)
    gv = sp.Matrix([0, 0, -g])
    assert sp.simplify(-gv.dot(n) - g * sp.cos(s)) == 0
    assert sp.simplify(gv.dot(t) - g * sp.sin(s) * sp.cos(b)) == 0
    assert sp.simplify(gv.dot(left) + g * sp.sin(s) * sp.sin(b)) == 0
    th = sp.atan(sp.tan(s) * sp.sin(b))
    # Equilibrium of the lean equation with no turning: G_n sin th + g_b cos th = 0.
    assert sp.simplify(g * sp.cos(s) * sp.sin(th) + gv.dot(left) * sp.cos(th)) == 0
    # The code's frame at sample values agrees.
    for sig, bet in [(0.3, 0.4), (0.5, 2.0), (0.2, -1.0)]:
        heading = math.atan2(math.sin(bet), math.cos(bet) * math.cos(sig))
        fr = surface_frame(Plane(sig, 0.0), 0.0, 0.0, heading, 9.81)
        sub = {s: sig, b: bet, g: 9.81}
        assert fr.g_along == pytest.approx(_num(gv.dot(t), sub), abs=1e-13)
        assert fr.g_lateral == pytest.approx(_num(gv.dot(left), sub), abs=1e-13)
        for i in range(3):
            assert fr.t[i] == pytest.approx(_num(t[i], sub), abs=1e-15)


def test_curved_surface_normal_curvature_and_heading_rate():
    """For ``z = h(x, y)`` (a general quadratic), a foot path with in-surface (geodesic)
    curvature ``C`` and the surface's normal curvature ``kappa`` along it turns its horizontal
    heading at ``C turn_gain + kappa bend_gain`` per metre, and ``kappa`` is Euler's
    ``II(t, t) / I(t, t)``: both from the curve's own geometry."""
    x, y, u, d = sp.symbols("x y u d", real=True)
    a, b, A, B, Cq = sp.Rational(1, 5), sp.Rational(-1, 7), sp.Rational(1, 20), \
        sp.Rational(-1, 30), sp.Rational(1, 25)
    h = a * x + b * y + (A * x ** 2 + 2 * B * x * y + Cq * y ** 2) / 2
    x0, y0 = sp.Rational(3, 2), sp.Rational(-2, 3)
    # The surface curve above the horizontal line through (x0, y0) with heading d.
    cx, cy = x0 + u * sp.cos(d), y0 + u * sp.sin(d)
    r = sp.Matrix([cx, cy, h.subs({x: cx, y: cy})])
    dr = r.diff(u)
    speed = sp.sqrt(dr.dot(dr))
    ddr_s = (dr.diff(u) * speed - dr * speed.diff(u)) / speed ** 3   # d^2 r / ds^2
    grad = sp.Matrix([-h.diff(x), -h.diff(y), 1])
    n = grad / sp.sqrt(grad.dot(grad))
    kappa = ddr_s.dot(n.subs({x: cx, y: cy}))
    ground = HeightField(
        *_sampled_quadratic(lambda X, Y: float(a) * X + float(b) * Y
                            + (float(A) * X * X + 2 * float(B) * X * Y + float(Cq) * Y * Y) / 2))
    for dd in (0.0, 0.7, 2.5, -1.9):
        fr = surface_frame(ground, float(x0), float(y0), dd, 9.81)
        assert fr.kappa_n == pytest.approx(_num(kappa, {d: dd, u: 0}), rel=1e-10)
    # Heading rate: theta = atan2(t_y, t_x) with dt/ds = C b + kappa n (Darboux frame).
    tx, ty, bx, by, nx, ny, C, k = sp.symbols("t_x t_y b_x b_y n_x n_y C kappa", real=True)
    dtx, dty = C * bx + k * nx, C * by + k * ny
    dtheta = (tx * dty - ty * dtx) / (tx ** 2 + ty ** 2)
    turn_gain = (tx * by - ty * bx) / (tx ** 2 + ty ** 2)
    bend_gain = (tx * ny - ty * nx) / (tx ** 2 + ty ** 2)
    assert sp.simplify(dtheta - (C * turn_gain + k * bend_gain)) == 0


def _sampled_quadratic(f):
    xs = np.arange(-10, 11) * 1.0
    X, Y = np.meshgrid(xs, xs)
    return f(X, Y), -10.0, -10.0, 1.0


def test_straight_run_closed_form_solves_the_speed_equation():
    t, A, k, V0 = sp.symbols("t A k V_0", positive=True)
    V_T = sp.sqrt(A / k)
    V = V_T * sp.tanh(sp.sqrt(A * k) * t + sp.atanh(V0 / V_T))
    assert sp.simplify(sp.diff(V, t) - (A - k * V ** 2)) == 0
    assert sp.simplify(V.subs(t, 0) - V0) == 0
