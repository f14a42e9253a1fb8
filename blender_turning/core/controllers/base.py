"""The contract every steering controller meets: one lean law.

A controller says what lean acceleration it wants, :meth:`Controller.lean_law` ``(t, theta_v,
omega_v) -> alpha_v``, with ``theta_v`` the lean from the equilibrium lean (upright on flat
ground; on a slope the plumb lean, :func:`..physics.model.equilibrium_lean`).  The model turns
the demand into the foot's curvature by Eq. (1) with the controller's :attr:`~Controller.body`
(closed form, physical root: :func:`..physics.dynamics.inverse_cf` on flat ground,
:func:`..physics.model.inverse_cf` on any ground) and bounds it (Section 3,
:func:`..physics.dynamics.bound_cf`); every kernel asks the same law.

The simulation steps a controller (:func:`..physics.simulate.simulate`): once before the first
step it is given the figure's limits (:meth:`~Controller.begin_run`), once per accepted step it
is told the time and the state with the lean from the equilibrium lean
(:meth:`~Controller.begin_step`, where it may update its memory), and at each of the step's
integrator stages its lean law is asked (pure: no memory change; one figure on floats asks the
law :meth:`~Controller.step_law` gives for the step).  States have shape ``(5, n)``
or ``(5,)``; the law gets floats for one figure and arrays for a batch.
"""
from __future__ import annotations

import math

import numpy as np

from ..physics.params import BodyParams, reached_speed


class Controller:
    """Base class: a controller that demands a lean acceleration (:meth:`lean_law`).

    ``lean_law = None`` (:class:`.straight.Straight`) demands nothing: the foot runs straight
    (``C_f = 0``) and the lean does what gravity makes it do."""

    def __init__(self, body: BodyParams):
        self._body, self._speed = body, None      # the body, and a speed followed since
        self.nominal_body = body
        """The body the controller was made for."""

    @property
    def body(self) -> BodyParams:
        """The body the controller steers (Eq. 1 is solved with it), at the current speed
        (:meth:`follow_speed`)."""
        if self._speed is not None:
            self._body, self._speed = self.nominal_body.at_speed(self._speed), None
        return self._body

    def follow_speed(self, V_cm: float) -> None:
        """Steer at the forward speed ``V_cm`` from now on (a speed that varies over time):
        :attr:`body` is the body at that speed (made when next asked: on terrain the speed
        changes every step, and few steps ask).

        Eq. (1) is solved with the current ``V_cm``; the paper keeps ``V_cm`` constant in
        Sections 3-5, and lets it vary along the path in Section 6 (the planner's speed
        profile)."""
        # (the check's call only for a speed that fails it)
        self._speed = float(V_cm) if 0.0 < V_cm < math.inf else reached_speed(V_cm)

    def changes_between(self, V_a: float, V_b: float) -> bool:
        """Does following the speed from ``V_a`` to ``V_b`` change the controller at a speed
        in between (beyond the speed itself: a table taken anew)?  A run stepping coarsely
        (:func:`..physics.terrain_sim.simulate_free`'s ``stride``) steps finely there."""
        return False

    def begin_run(self, limits) -> None:
        """Called once before the first step with the figure's :class:`..params.Limits` (a
        controller may keep its demand within them)."""

    def begin_step(self, t: float, state: np.ndarray) -> None:
        """Called once at the start of each step with the accepted state (the lean from the
        equilibrium lean)."""

    def lean_law(self, t: float, theta_v, omega_v):
        """The lean acceleration ``alpha_v`` (rad/s^2) demanded at time ``t`` for the lean
        ``theta_v`` (rad, from the equilibrium lean) and its rate ``omega_v`` (rad/s): floats
        for one figure, arrays for a batch."""
        raise NotImplementedError

    def step_law(self, t: float):
        """The lean law the integrator stages of the step begun at ``t`` ask, after
        :meth:`begin_step` (one figure on floats): :meth:`lean_law` itself here; a controller
        whose law stays the same over a step may return a faster function of ``(t, theta_v,
        omega_v)`` with the same values."""
        return self.lean_law

    def target(self, t: float):
        """``(omega0, theta_max)`` of the ellipse the motion is following now (for the phase)."""
        raise NotImplementedError
