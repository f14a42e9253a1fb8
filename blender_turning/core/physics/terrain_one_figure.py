"""One figure on terrain on Python floats: the right-hand side of the terrain loop fused.

:func:`.model.rhs` and :func:`.model.rk4_step` serve
arrays (the planner's batch, a trajectory's columns); stepping one figure through them costs
numpy's per-call dispatch at every operation, ~10x the flat fused path (:mod:`.one_figure`).
Here one RK4 stage is one function on floats with the body's constants bound as locals, as
:mod:`.one_figure` does on flat ground, written out from the same equations:

- the foot's frame (docs/TERRAIN.md Section 1; :func:`.terrain.surface_frame`) from the
  surface's derivatives on floats (``HeightField.slopes_one``,
  :meth:`.terrain.Plane.derivatives_one`), written through the slope along the heading
  ``p = h_x c + h_y s`` and across it ``a = h_x s - h_y c`` (``c, s`` the heading's cosine and
  sine, ``w = sqrt(1 + p^2)``, ``n_z = 1 / sqrt(1 + h_x^2 + h_y^2)``): with ``t = (c, s, p) / w``
  and ``n = (-h_x, -h_y, 1) n_z``, ``b = n x t`` has ``b_z = -n_z a / w``, so the lateral
  gravity is ``g n_z a / w``, the plumb lean ``atan(-a / w)``, the turn gain
  ``(t_x b_y - t_y b_x) / (t_x^2 + t_y^2) = n_z w^2`` and the bend gain
  ``(t_x n_y - t_y n_x) / (t_x^2 + t_y^2) = n_z a w`` (:func:`.terrain.surface_frame`'s numbers
  to round-off, ~25 fewer operations a stage);
- the controller's lean law about the equilibrium lean (:func:`.model.steering`,
  :func:`.model.equilibrium_lean`: the plumb lean along the course ``H``,
  ``atan((h_y cos H - h_x sin H) / sqrt(1 + q^2))``, ``q = h_x cos H + h_y sin H``, read once
  when it is constant, else the plumb lean) and Eq. (1) on terrain (:func:`.model.inverse_cf`),
  docs/TERRAIN.md Section 6;
- Section 3's bounds on ``C_f`` (:func:`.dynamics.bound_cf`);
- Eq. (21), Eq. (2) on terrain, the normal force and the speed equation
  (:func:`.model.rhs`, docs/TERRAIN.md Sections 2-3), with the braking force at the foot
  bounded by the grip when :attr:`TerrainStage.brake` is set (docs/skidding.md Section 2).

``tests/test_model_kernels.py`` holds this stage to :func:`.model.rhs` under
:func:`.model.steering` to 1e-12, ``tests/test_terrain_fast.py`` whole runs to the array loop.
"""
from __future__ import annotations

import math

from ..controllers.base import Controller
from .dynamics import PHYSICAL_MARGIN
from .params import BodyParams, Limits
from .model import Resistance

__all__ = ["TerrainStage"]


class TerrainStage:
    """The float right-hand side of one figure on ``ground`` under ``controller``.

    :attr:`derivatives` gives the surface at a point, :meth:`lean` the lean the controller's
    law sees there (from the equilibrium lean, :func:`.model.equilibrium_lean`), :attr:`stage`
    one RK4 stage.  The controller's speed may change between calls
    (:meth:`.Controller.follow_speed`); the law reads the state's speed."""

    def __init__(self, body: BodyParams, limits: Limits, resistance: Resistance, ground,
                 controller: Controller):
        # (h_x, h_y, h_xx, h_xy, h_yy) at a point: the height itself is not needed.
        slopes, one = getattr(ground, "slopes_one", None), getattr(ground, "derivatives_one", None)
        self.derivatives = slopes if slopes is not None else (lambda x, y: one(x, y)[1:]) \
            if one is not None else (lambda x, y: [float(v) for v in ground.derivatives(x, y)[1:]])
        self.ground, self.controller = ground, controller
        # The course the plumb lean is taken along (plumb_lean_along): read once, as its cosine
        # and sine when constant; else kept for the time last asked (a step's stages 2 and 3
        # share one), and asked again by :meth:`lean` at each step's start (the brake's course
        # moves between steps, :class:`.braking.TargetSpeed`).
        self._heading = getattr(controller, "heading", None)
        H = getattr(self._heading, "constant_value", None)
        self._course = [None, 1.0, 0.0] if H is None else [math.inf, math.cos(H), math.sin(H)]
        self.brake = None
        """The braking command of the step (a :class:`.grip.FootBrake`, bounded at every stage
        as :func:`.model.rhs` bounds it) or ``None``: the carved model."""
        self.foot = [0.0, 0.0, 0.0, 0.0]
        """The last braked stage's ``(F_brake / m, F_lat / m, N / m, hold)``, m/s^2
        (:mod:`.grip`): ``hold`` the braking force over the mass that would hold the speed
        (the speed's rate without the brake over the foot's speed ratio)."""
        self.stage, self.lean, self.use_law = self._build(body, limits, resistance)

    def _along(self, t):
        """``(cos H, sin H)`` of the course at ``t``."""
        course = self._course
        if course[0] != t and course[0] != math.inf:
            H = self._heading(t)
            course[0], course[1], course[2] = t, math.cos(H), math.sin(H)
        return course[1], course[2]

    def _build(self, body, limits, resistance):
        g, l, J = body.g, body.l, body.J
        mu, kd = resistance.mu, resistance.drag_k(body.m)
        law_J, law_l = self.controller.body.J, self.controller.body.l
        cmax, rate = limits.C_f_max, limits.dC_f_max
        rated = rate != math.inf
        sin, cos, sqrt, atan = math.sin, math.cos, math.sqrt, math.atan
        copysign, margin = math.copysign, PHYSICAL_MARGIN
        neg_g, neg_cmax = -g, -cmax
        derivatives, law = self.derivatives, self.controller.lean_law
        # The equilibrium lean: along the course (0), the plumb lean (1).
        kind = 0 if self._heading is not None else 1
        course, along = self._course, self._along
        fixed = course[0] == math.inf                   # a constant course: (cos H, sin H)
        cH0, sH0 = course[1], course[2]
        row = [None, 0.0]                       # the last lean's dv and equilibrium lean
        foot = self.foot

        def lean(t, x, y, d, theta_v, dv):
            """``theta_v`` from the equilibrium lean (:func:`.model.equilibrium_lean`) at
            ``(x, y)`` heading ``d`` (``dv``: :attr:`derivatives` there), at the start of a
            step: the course is read anew, and the step's first stage (given this same ``dv``:
            the same point, time and heading) takes the equilibrium from here."""
            if kind == 1:                                       # plumb_lean
                hx, hy = dv[0], dv[1]
                c, s = cos(d), sin(d)
                p = hx * c + hy * s
                eq = atan((hy * c - hx * s) / sqrt(1.0 + p * p))
            else:                                               # plumb_lean_along
                hx, hy = dv[0], dv[1]
                if fixed:
                    cH, sH = cH0, sH0
                else:
                    course[0] = None
                    cH, sH = along(t)
                q = hx * cH + hy * sH
                eq = atan((hy * cH - hx * sH) / sqrt(1.0 + q * q))
            row[0], row[1] = dv, eq
            return theta_v - eq

        def stage(t, x, y, d, th, om, V, anchor, tau, dv=None):
            """``(x', y', theta_dir', theta_v', omega_v', V_cm', alpha_v, V_f, C_f)``."""
            hx, hy, hxx, hxy, hyy = derivatives(x, y) if dv is None else dv
            # The foot's frame (docs/TERRAIN.md Section 1) through the slope along the heading
            # p: t = (c, s, p) / sqrt(1 + p^2), n = (-hx, -hy, 1) nz (module doc).
            c, s = cos(d), sin(d)
            p = hx * c + hy * s
            w = sqrt(1.0 + p * p)
            tz = p / w
            nz = 1.0 / sqrt(1.0 + hx * hx + hy * hy)
            across = hx * s - hy * c                  # -b_z / (nz it): the slope across
            ww = w * w
            kappa = (hxx * c * c + 2.0 * hxy * c * s + hyy * s * s) * nz / ww
            g_n = g * nz
            g_b = g_n * across / w
            sn, cs = sin(th), cos(th)
            VV = V * V
            if law is None:
                cf = 0.0 * th                                   # straight: C_f = 0
            else:
                # The lean law about the equilibrium lean, then Eq. (1) on terrain.
                if dv is not None and dv is row[0]:
                    eq = row[1]                                 # the row's, from lean
                elif kind == 0:                                 # plumb_lean_along the course
                    if fixed:
                        cH, sH = cH0, sH0
                    else:
                        cH, sH = (course[1], course[2]) if course[0] == t else along(t)
                    q = hx * cH + hy * sH
                    eq = atan((hy * cH - hx * sH) / sqrt(1.0 + q * q))
                else:                                           # plumb_lean
                    eq = atan(-across / w)
                k = ((g_n + VV * kappa) * sn + g_b * cs - law(t, th - eq, om) * law_J)
                den = k * law_l * sn + VV * cs
                cf = k / den if den > 0.0 else copysign(math.inf, k)
            # Section 3: |C_f| <= C_f_max, the physical branch on the side of the lean, the rate.
            ls = l * sn
            if ls > 0.0:                              # max, min of floats without the calls
                lo, hi = neg_cmax, margin / ls
                hi = hi if hi < cmax else cmax
            elif ls < 0.0:
                lo, hi = margin / ls, cmax
                lo = lo if lo > neg_cmax else neg_cmax
            else:
                lo, hi = neg_cmax, cmax
            cf = lo if cf < lo else hi if cf > hi else cf
            if rated and anchor is not None:
                step = rate * tau
                lo = anchor - step
                if cf < lo:
                    cf = lo
                else:
                    hi = anchor + step
                    cf = hi if cf > hi else cf
            # Eq. (21), Eq. (2) on terrain, the normal force and the speed (Sections 2-3).
            ratio = 1.0 / (1.0 - cf * ls)
            V_f = V * ratio
            G_n = g_n + V_f * V_f * kappa
            alpha = (G_n * sn + (g_b - V * V_f * cf) * cs) / J
            # N / m, and theta_dir' = V_f (C_f turn_gain + kappa_n bend_gain) (module doc).
            N_m = G_n - l * (alpha * sn + om * om * cs)
            turn = V_f * nz * (cf * ww + kappa * across * w)
            u = V_f / w
            # The speed: gravity on the body, friction at the foot, drag, the lean's share
            # (docs/TERRAIN.md Section 4).
            dV = neg_g * tz - mu * N_m * ratio - kd * VV + l * om * cs * V_f * cf
            fb = self.brake
            if fb is not None:                        # docs/skidding.md Section 2
                F_lat = V * V_f * cf + l * (alpha * cs - om * om * sn) - g_b   # foot_lateral
                b = fb.bound(N_m, F_lat, th)
                foot[0], foot[1], foot[2], foot[3] = b, F_lat, N_m, dV / ratio
                dV -= b * ratio
            return (u * c, u * s, turn, om, alpha, dV, alpha, V_f, cf)

        def use_law(step_law):
            """The law the coming stages ask (:meth:`.Controller.step_law` of the step)."""
            nonlocal law
            law = step_law

        return stage, lean, use_law
