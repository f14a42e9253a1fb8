"""One stage of the search on flat ground at a constant speed (Section 6.1), fused for speed.

:meth:`.problem.Problem.simulate_stage` integrates a batch of nodes through
:meth:`.problem.Problem._rhs` (:func:`..dynamics.steer`): some 40 numpy calls per right-hand
side, 25 right-hand sides per stage, whatever the batch's size.  On flat ground at a constant
speed ``V``, for a figure whose physical limit cannot bind (``C_f_max l <= 0.9``, every preset),
this module computes the same numbers, operation for operation (bit for bit on a libm whose
``sin``/``cos`` numpy and ``math`` share; ``tests/test_planner_flat_stage.py``), with far fewer
calls:

- The curvature does not depend on the state there.  :func:`..dynamics.bound_cf` clips the
  demand ``C0 + u tau`` to ``+-C_f_max`` (its physical limit ``0.9 / (l |sin theta_v|) >= 0.9 / l
  >= C_f_max`` never binds) and then to ``anchor +- dC_f_max step``; the anchors chain through the
  steps' first stages only.  So :func:`curvatures` computes every RK4 stage's ``C_f`` of the
  whole stage first, for all nodes at once (RK4's second and third stages share theirs).
- The right-hand side (Eq. 21: ``V_f = V / (1 - C_f l sin theta_v)``; Eq. 2: ``alpha_v =
  (g sin theta_v - C_f V V cos theta_v V_f / V) / J``) is 14 numpy calls writing into
  preallocated rows, ``sin`` and ``cos`` of the heading and the lean taken together.
- Small batches (the warm start follows one plan node by node, the dead-end test has q nodes)
  run on Python floats instead (:func:`_columns`), where a numpy call costs more than its work.

Both return the states at every step's end; the caller (``simulate_stage``) derives the
distance travelled, the path distance, the fall and the collision test from them.
"""
from __future__ import annotations

import math

import numpy as np

#: Batches of at most this many nodes run on Python floats (measured: BENCHMARKS.md).
SCALAR_COLUMNS = 24


def applies(problem) -> bool:
    """Does the fused stage compute exactly what ``Problem._rhs`` does for ``problem``?"""
    return problem.flat_rhs and problem.speed.is_constant and not problem._physical_binds


def curvatures(C0, u, h, steps, cmax, rate, t_stage):
    """Every RK4 stage's curvature over one stage of ``steps`` steps of ``h`` seconds, for nodes
    with curvature ``C0`` and ``dC_f/dt = u`` (shape ``(m,)`` each), bounded as
    :func:`..dynamics.bound_cf` does (module docstring).  Returns ``(CF, end)``: ``CF[k]`` of
    shape ``(3, m)`` holds step ``k``'s first, second-and-third and fourth stage's ``C_f``;
    ``end`` is the curvature at the end of the stage (the next stage's ``C0``)."""
    half = 0.5 * h
    taus = []
    for k in range(steps):              # the same floats as simulate_stage's tau, tau + h / 2...
        tau = k * h
        taus += [tau, tau + half, tau + h]
    taus.append(t_stage)
    D = C0 + u * np.array(taus)[:, None]
    D = np.minimum(np.maximum(D, -cmax), cmax)
    sh, shalf = rate * h, rate * half
    first = np.empty((steps, len(C0)))
    a = C0
    for k in range(steps):              # each step's first stage: rate-bounded from the last's
        a = first[k] = np.minimum(np.maximum(D[3 * k], a - sh), a + sh)
    end = np.minimum(np.maximum(D[-1], a - sh), a + sh)
    CF = np.empty((steps, 3, len(C0)))
    CF[:, 0] = first
    CF[:, 1] = np.minimum(np.maximum(D[1:-1:3], first - shalf), first + shalf)
    CF[:, 2] = np.minimum(np.maximum(D[2:-1:3], first - sh), first + sh)
    return CF, end


def integrate(x0, CF, h, V, body):
    """RK4 of the state ``x0`` (shape ``(5, m)``) through the curvatures ``CF`` (from
    :func:`curvatures`); returns the states at every step boundary, shape ``(steps + 1, 5, m)``
    (``[0]`` is ``x0``)."""
    if x0.shape[1] <= SCALAR_COLUMNS:
        return _columns(x0, CF, h, V, body)
    steps, _, m = CF.shape
    l, g, J = body.l, body.g, body.J
    CFL = CF * l                                   # dynamics.steer's cf * body.l
    CFV = CF * V * V                               # ... and cf * V * V, in its order
    half, h6 = 0.5 * h, h / 6.0
    P = np.empty((steps + 1, 5, m))
    P[0] = x0
    K = np.empty((4, 5, m))
    xs, tmp = np.empty((5, m)), np.empty((5, m))
    T = np.empty((4, m))            # cos(heading), sin(heading), cos(lean), sin(lean)
    r, a = np.empty(m), np.empty(m)

    def rhs(x, j, out):
        np.cos(x[2:4], out=T[0::2])
        np.sin(x[2:4], out=T[1::2])
        s, c = T[3], T[2]
        np.multiply(CFL[k, j], s, out=r)            # ratio = 1 / (1 - cf l sin th)  (Eq. 21)
        np.subtract(1.0, r, out=r)
        np.divide(1.0, r, out=r)
        np.multiply(CFV[k, j], c, out=a)           # alpha = (g s - cf V V c ratio) / J  (Eq. 2)
        np.multiply(a, r, out=a)
        np.multiply(V, r, out=r)                   # V_f
        np.multiply(g, s, out=out[4])
        np.subtract(out[4], a, out=out[4])
        np.divide(out[4], J, out=out[4])
        np.multiply(r, T[0:2], out=out[0:2])
        np.multiply(r, CF[k, j], out=out[2])
        out[3] = x[4]

    for k in range(steps):
        x = P[k]
        rhs(x, 0, K[0])
        np.add(x, np.multiply(half, K[0], out=tmp), out=xs)
        rhs(xs, 1, K[1])
        np.add(x, np.multiply(half, K[1], out=tmp), out=xs)
        rhs(xs, 1, K[2])
        np.add(x, np.multiply(h, K[2], out=tmp), out=xs)
        rhs(xs, 2, K[3])
        np.add(K[1], K[2], out=tmp)
        np.multiply(2.0, tmp, out=tmp)
        np.add(K[0], tmp, out=tmp)
        np.add(tmp, K[3], out=tmp)
        np.multiply(h6, tmp, out=tmp)
        np.add(x, tmp, out=P[k + 1])
    return P


def _columns(x0, CF, h, V, body):
    """:func:`integrate` on Python floats, one node at a time (the same operations)."""
    steps, _, m = CF.shape
    l, g, J = body.l, body.g, body.J
    sin, cos = math.sin, math.cos
    half, h6 = 0.5 * h, h / 6.0
    cfs = CF.transpose(2, 0, 1).tolist()
    out = np.empty((m, steps + 1, 5))
    for j, (x, y, d, th, om) in enumerate(x0.T.tolist()):
        rows = [(x, y, d, th, om)]
        for c1, c2, c4 in cfs[j]:
            s = sin(th)
            r = 1.0 / (1.0 - c1 * l * s)
            vf = V * r
            ax, ay, ad, at, ao = vf * cos(d), vf * sin(d), vf * c1, om, \
                (g * s - c1 * V * V * cos(th) * r) / J
            d2, th2 = d + half * ad, th + half * at
            s = sin(th2)
            r = 1.0 / (1.0 - c2 * l * s)
            vf = V * r
            bx, by, bd, bt, bo = vf * cos(d2), vf * sin(d2), vf * c2, om + half * ao, \
                (g * s - c2 * V * V * cos(th2) * r) / J
            d3, th3 = d + half * bd, th + half * bt
            s = sin(th3)
            r = 1.0 / (1.0 - c2 * l * s)
            vf = V * r
            cx, cy, cd, ct, co = vf * cos(d3), vf * sin(d3), vf * c2, om + half * bo, \
                (g * s - c2 * V * V * cos(th3) * r) / J
            d4, th4 = d + h * cd, th + h * ct
            s = sin(th4)
            r = 1.0 / (1.0 - c4 * l * s)
            vf = V * r
            ex, ey, ed, et, eo = vf * cos(d4), vf * sin(d4), vf * c4, om + h * co, \
                (g * s - c4 * V * V * cos(th4) * r) / J
            x = x + h6 * (ax + 2.0 * (bx + cx) + ex)
            y = y + h6 * (ay + 2.0 * (by + cy) + ey)
            d = d + h6 * (ad + 2.0 * (bd + cd) + ed)
            th = th + h6 * (at + 2.0 * (bt + ct) + et)
            om = om + h6 * (ao + 2.0 * (bo + co) + eo)
            rows.append((x, y, d, th, om))
        out[j] = rows
    return out.transpose(1, 2, 0)
