"""The phase of a turn (Section 4, Fig. 3) and the open-loop lean law (Eqs. 3-5)."""
from __future__ import annotations

import numpy as np

from ..physics.xp import backend

TWO_PI = 2.0 * np.pi


def phase(theta_v, omega_v, theta_max, omega0):
    """``phi = atan2(theta_v / theta_max, omega_v / (omega0 theta_max))`` in ``[0, 2 pi)``.

    Section 4 writes ``arctan(y/x)``; atan2 is needed to tell the four quadrants apart.  Phase
    0..pi is a left turn (``theta_v > 0``).
    """
    y = np.asarray(theta_v) / theta_max
    x = np.asarray(omega_v) / (omega0 * theta_max)
    return np.mod(np.arctan2(y, x), TWO_PI)


def ellipse_radius(theta_v, omega_v, theta_max, omega0):
    """Normalised distance from the origin of the phase plane: 1 on the target ellipse."""
    return np.hypot(np.asarray(theta_v) / theta_max, np.asarray(omega_v) / (omega0 * theta_max))


def open_loop_alpha(phi, theta_max, omega0):
    """Eq. (5): ``alpha_v = -omega0^2 theta_max sin(phi)`` with ``phi = omega0 t``."""
    return -omega0 * omega0 * theta_max * backend(phi).sin(phi)
