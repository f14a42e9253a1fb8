"""Straight running: ``C_f = 0`` (run-ins, and the closed-form checks of docs/TERRAIN.md).

The foot path has no curvature in the surface; the lean does what gravity makes it do (Eq. 2
with ``C_f = 0``): upright on flat ground or down the fall line it stays upright (an unstable
equilibrium, held to round-off), on a traverse started at the plumb lean it stays there.
"""
from __future__ import annotations

from .schedule import Schedule
from .base import Controller
from .registry import ControllerType, register_controller


class Straight(Controller):
    """``C_f = 0`` whatever the state.  ``omega0`` and ``theta_max`` only name the ellipse the
    phase column is measured against (``phi`` of :mod:`..phase`); the motion ignores them."""

    def __init__(self, body, omega0=1.0, theta_max=1.0):
        super().__init__(body)
        self.omega0, self.theta_max = Schedule.of(omega0), Schedule.of(theta_max)

    lean_law = None
    """No lean law: the model steers ``C_f = 0`` (:class:`.base.Controller`)."""

    def target(self, t):
        return self.omega0(t), self.theta_max(t)


register_controller(ControllerType(
    name="straight", label="Straight",
    description="Holds the body at its equilibrium lean: a straight run (a tuck down the hill)",
    make=lambda fig, omega0, theta_max, heading, law: Straight(fig.body, omega0, theta_max),
    start="straight"))
