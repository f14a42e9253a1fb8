"""Open-loop periodic turning (Section 4, Fig. 4):
``alpha_v = -omega0^2 theta_max sin(omega0 t)``."""
from __future__ import annotations

from ..physics.params import BodyParams
from .phase import open_loop_alpha
from .schedule import Schedule
from .base import Controller
from .registry import ControllerType, register_controller


class OpenLoop(Controller):
    """Eq. (5) as a function of time only.  With schedules, the phase is the integral of omega0
    (so a change of frequency does not jump the phase)."""

    def __init__(self, body: BodyParams, omega0, theta_max, phase0: float = 0.0):
        super().__init__(body)
        self.omega0 = Schedule.of(omega0)
        self.theta_max = Schedule.of(theta_max)
        self._phi = phase0
        self._t = None

    def begin_step(self, t, state):
        if self._t is not None:
            # Trapezoid on omega0(t): exact for constant or linearly interpolated schedules.
            self._phi += 0.5 * (self.omega0(self._t) + self.omega0(t)) * (t - self._t)
        self._t = t

    def lean_law(self, t, theta_v, omega_v):
        tau = t - self._t
        w = self.omega0(t)
        phi = self._phi + 0.5 * (self.omega0(self._t) + w) * tau
        return open_loop_alpha(phi, self.theta_max(t), w)

    def target(self, t):
        return self.omega0(t), self.theta_max(t)


register_controller(ControllerType(
    name="open-loop", label="Open Loop",
    description="Section 4: the lean follows theta_max sin(omega0 t), no feedback",
    make=lambda fig, omega0, theta_max, heading, law: OpenLoop(fig.body, omega0, theta_max)))
