"""The contract every steering controller meets.

A controller is stepped by :func:`blender_turning.core.physics.simulate.simulate`: once before the first
step it is given the figure's limits (``begin_run``), once per accepted
step it is told the time and state (``begin_step``, where it may update its memory), and during
the step's integrator stages it is asked for the demanded foot curvature (``desired_cf``, pure:
no memory change).  The integrator bounds the demand (``dynamics.bound_cf``).  States have shape
``(5, n)`` or ``(5,)``; every method works on either.
"""
from __future__ import annotations

import numpy as np

from ..physics.dynamics import THETA_V, inverse_cf
from ..physics.one_figure import scalar_inverse_cf
from ..physics.params import BodyParams
from ..ground.terrain import surface_frame
from ..physics import model
from ..physics.model import plumb_lean, plumb_lean_along


class Controller:
    """Base class: a controller that demands a lean acceleration and steers by Eq. (1)."""

    def __init__(self, body: BodyParams):
        self.body = body
        self.nominal_body = body
        """The body the controller was made for; :attr:`body` carries the current speed."""

    def follow_speed(self, V_cm: float) -> BodyParams:
        """Steer at the forward speed ``V_cm`` from now on (a speed that varies over time);
        returns the body at that speed.

        Eq. (1) is solved with the current ``V_cm``; the paper keeps ``V_cm`` constant in
        Sections 3-5, and lets it vary along the path in Section 6 (the planner's speed profile)."""
        self.body = self.nominal_body.at_speed(float(V_cm))
        return self.body

    def begin_run(self, limits) -> None:
        """Called once before the first step with the figure's :class:`..params.Limits` (a
        controller may keep its demand within them)."""

    def begin_step(self, t: float, state: np.ndarray) -> None:
        """Called once at the start of each step with the accepted state."""

    def desired_alpha(self, t: float, state: np.ndarray):
        raise NotImplementedError

    def desired_cf(self, t: float, state: np.ndarray):
        """The curvature that produces :meth:`desired_alpha` (Eq. 1, physical root)."""
        return inverse_cf(self.body, state[THETA_V], self.desired_alpha(t, state))

    def scalar_cf_law(self):
        """``f(t, state) -> C_f`` for one figure on floats (:mod:`..one_figure`): the same
        demand as :meth:`desired_cf`, which a subclass may specialise for speed."""
        if type(self).desired_cf is not Controller.desired_cf:
            return self.desired_cf
        inverse, alpha = scalar_inverse_cf(self.body), self.desired_alpha
        return lambda t, state: inverse(state[THETA_V], alpha(t, state))

    def scalar_alpha_law(self):
        """``f(t, state) -> alpha_v`` for one figure on floats: :meth:`desired_alpha`, which a
        subclass may specialise for speed (the terrain stepper, :mod:`..terrain_one_figure`,
        asks it about the lean from the equilibrium lean)."""
        return self.desired_alpha

    def terrain_cf_law(self, ground):
        """``f(t, state) -> C_f`` on terrain (``state`` = ``(x, y, theta_dir, theta_v, omega_v,
        V_cm)``, docs/TERRAIN.md Section 6): the lean law is asked about the lean from the
        local plumb lean (:meth:`equilibrium_lean`), so the lean oscillates about the
        equilibrium, not about the surface normal; its ``alpha_v`` is turned into ``C_f`` by
        Eq. (1) on terrain at the current speed.  :meth:`begin_step` sees the same relative
        lean (:meth:`relative_state`).  One figure: the law gets Python floats."""
        g = self.body.g

        def law(t, st):
            if type(st[0]) is not float:
                st = [float(v) for v in st]
            fr = surface_frame(ground, st[0], st[1], st[2], g)
            rel = (st[0], st[1], st[2], float(st[3] - self.equilibrium_lean(fr, t)), st[4])
            return model.inverse_cf(self.body, fr, st[3], self.desired_alpha(t, rel), st[5])

        return law

    def relative_state(self, ground, state, t=0.0):
        """``state`` (6 terrain rows) as the lean law sees it at time ``t``: 5 floats, the lean
        taken from :meth:`equilibrium_lean`."""
        x, y, d, th, om = (float(v) for v in state[:5])
        fr = surface_frame(ground, x, y, d, self.body.g)
        return (x, y, d, float(th - self.equilibrium_lean(fr, t)), om)

    def equilibrium_lean(self, frame, t):
        """The lean the law oscillates about (docs/TERRAIN.md Section 6): the plumb lean of the
        commanded mean heading when the controller holds one (it does not swing with each
        turn's heading, which would force the lean at the turn's own frequency; a target speed's
        command, :mod:`..braking`, moves continuously), else of the current heading."""
        heading = getattr(self, "heading", None)
        if heading is None:
            return plumb_lean(frame)
        return plumb_lean_along(frame, heading(t), self.body.g)

    def target(self, t: float):
        """``(omega0, theta_max)`` of the ellipse the motion is following now (for the phase)."""
        raise NotImplementedError
