"""One figure on terrain on Python floats: the right-hand side of the terrain loop fused.

:func:`.terrain_dynamics.terrain_steer` and :func:`.terrain_dynamics.terrain_rk4_step` serve
arrays (the planner's batch, a trajectory's columns); stepping one figure through them costs
numpy's per-call dispatch at every operation, ~10x the flat fused path (:mod:`.one_figure`).
Here one RK4 stage is floats only, through the same formulas, each written once for floats and
arrays: the foot's frame (:func:`.terrain.frame_terms`, docs/TERRAIN.md Section 1, the height
field's bicubic as a per-cell polynomial, :meth:`.terrain.HeightField.derivatives_one`), the
controller's lean law about the local plumb lean and Eq. (1) on terrain
(:func:`.terrain_dynamics.terrain_inverse_cf`, docs/TERRAIN.md Section 6), Section 3's bounds on
``C_f`` (as :func:`.dynamics.bound_cf`, written out on floats as :mod:`.one_figure` does) and
Eqs. (2), (21) and the speed equation on terrain (:func:`.terrain_dynamics.terrain_rates`,
docs/TERRAIN.md Sections 2-3).  ``tests/test_terrain_fast.py`` ties it to the array path.
"""
from __future__ import annotations

import math

from .controllers.base import Controller
from .dynamics import PHYSICAL_MARGIN
from .params import BodyParams, Limits
from .terrain import frame_terms
from .terrain_dynamics import Resistance, terrain_inverse_cf, terrain_rates

__all__ = ["TerrainStage"]


class TerrainStage:
    """The float right-hand side of one figure on ``ground`` under ``controller``.

    :meth:`frame` is the foot's frame at a point (vectors as 3-tuples), :meth:`lean` the lean
    the controller's law sees (from its equilibrium lean), and :meth:`stage` one RK4 stage.
    The controller's speed may change between calls (:meth:`.Controller.follow_speed`): the law
    reads it on every call."""

    def __init__(self, body: BodyParams, limits: Limits, resistance: Resistance, ground,
                 controller: Controller):
        self.body, self.limits, self.resistance = body, limits, resistance
        self.controller = controller
        one = getattr(ground, "derivatives_one", None)
        self._derivatives = one if one is not None else (
            lambda x, y: [float(v) for v in ground.derivatives(x, y)])
        if type(controller).terrain_cf_law is Controller.terrain_cf_law:
            self._demand = self._lean_law           # the base law, fused with the frame
            self._alpha = controller.scalar_alpha_law()
        else:
            law = controller.terrain_cf_law(ground)  # a law of its own (Straight: C_f = 0)
            self._demand = lambda t, st, fr: law(t, st)

    def frame(self, x: float, y: float, theta_dir: float):
        """:func:`.terrain.surface_frame` on floats, vectors as tuples."""
        return frame_terms(*self._derivatives(x, y), math.cos(theta_dir), math.sin(theta_dir),
                           self.body.g, math.sqrt)

    def lean(self, t: float, theta_v: float, fr) -> float:
        """``theta_v`` from the controller's equilibrium lean at ``fr`` (what its law and
        :meth:`~.Controller.begin_step` see: :meth:`.Controller.relative_state`)."""
        return theta_v - self.controller.equilibrium_lean(fr, t)

    def _lean_law(self, t, st, fr):
        """:meth:`.Controller.terrain_cf_law` at a frame already computed."""
        c = self.controller
        x, y, d, th, om, V = st
        alpha = self._alpha(t, (x, y, d, th - c.equilibrium_lean(fr, t), om))
        return terrain_inverse_cf(c.body, fr, th, alpha, V)

    def stage(self, t: float, st, fr, anchor, tau: float):
        """One stage at state ``st`` (6 floats) with its frame ``fr`` (:meth:`frame`): the
        demanded ``C_f`` bounded as in Section 3 (size, physical branch on the side of the lean,
        rate from ``anchor`` over ``tau``; ``anchor`` None: no rate bound), then
        :func:`.terrain_dynamics.terrain_rates`.  Returns ``(x', y', theta_dir', theta_v',
        omega_v', V_cm', alpha_v, V_f, N, C_f)``."""
        cf = self._demand(t, st, fr)
        th = st[3]
        s = math.sin(th)
        ls = self.body.l * s
        lim = self.limits
        cmax = lim.C_f_max
        # Section 3's physical branch binds only on the side the body leans to.
        lo = -cmax if ls >= 0.0 else max(-cmax, PHYSICAL_MARGIN / ls)
        hi = cmax if ls <= 0.0 else min(cmax, PHYSICAL_MARGIN / ls)
        cf = lo if cf < lo else hi if cf > hi else cf
        if anchor is not None and lim.dC_f_max != math.inf:
            step = lim.dC_f_max * tau
            cf = anchor - step if cf < anchor - step else anchor + step if cf > anchor + step \
                else cf
        return (*terrain_rates(self.body, self.resistance, fr, fr.t[0], fr.t[1], cf, s,
                               math.cos(th), st[4], st[5]), cf)
