"""The grip at the foot: the friction circle that bounds the snow's (road's) force
(docs/skidding.md Sections 1-2).

The force the ground puts on the foot lies in the ground's tangent plane.  Its part across the
travel ``F_lat`` turns the figure (the model's lateral balance, :func:`foot_lateral`), its part
against the travel ``F_brake`` brakes it, and the two share one circle of radius
``mu_grip N`` (``N`` the normal contact force, :func:`.model.rhs`):
``F_lat^2 + F_brake^2 <= (mu_grip N)^2`` (:func:`brake_limit`).

- **Snow** (:data:`SNOW`): the edged ski (board) cuts a platform into the snow; the snow holds a
  force within ``phi`` (its shear angle) of the ski base's normal, so a ski edged at ``e``
  holds the ratio ``tan(e + phi)`` of tangential to normal force, at most ``mu_max`` (the
  snow's shear strength); hard pack holds more than soft snow.  A skidding ski's force is
  perpendicular to the ski (the cutting force of Mossner et al. 2008, J. ASTM Int. 5(8),
  JAI101387: the snow sheared by the edge across the ski), so a ski turned ``skid`` from the
  travel both turns and brakes: ``tan(skid) = F_brake / F_lat`` (:func:`skid_angle`).
- **A tyre** (:func:`tyre`): Coulomb's circle, ``mu_grip = mu`` (dry asphalt about 0.9, wet
  0.5, gravel 0.35).

Every function works on floats and on numpy arrays (:mod:`.xp`).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..validate import check

from .xp import Scalar, backend

__all__ = ["Grip", "SNOW", "TYRE", "tyre", "snow", "foot_lateral", "brake_limit",
           "skid_angle", "FootBrake", "SKID_MAX_TURNING", "SKID_MAX_STOP"]

SKID_MAX_TURNING = math.radians(60.0)
"""The largest skid angle in a skidded turn, rad: past it the ski is a brake across the travel,
not a turning ski (measured skidded turns: skid angles up to ~40-60 deg, docs/skidding.md)."""
SKID_MAX_STOP = 0.5 * math.pi
"""A stop or a side-slip: the ski straight across the travel."""


@dataclass(frozen=True)
class Grip:
    """A friction circle (module docstring): a tyre's ``mu``, or snow's ``(phi, mu_max)``."""

    kind: str
    """``"snow"`` or ``"tyre"``."""
    mu: float
    """A tyre's friction coefficient; snow's largest force ratio (its shear strength)."""
    shear_angle: float = 0.0
    """Snow only: how far from the ski base's normal the snow holds the force, rad."""
    name: str = ""
    """What the user chose (``"hard"``, ``"soft"``, ``"dry"``, a number...)."""

    def __post_init__(self):
        if self.kind not in ("snow", "tyre"):
            raise ValueError(f"grip kind = {self.kind!r} is not 'snow' or 'tyre'")
        check("grip", self.mu, "grip")                          # ranges: core/ranges.py
        check("shear_angle", self.shear_angle, "grip_shear_angle")

    def mu_at(self, edge):
        """``mu_grip`` of a ski edged at ``edge`` (rad; a tyre's is its ``mu``)."""
        if self.kind == "tyre":
            return self.mu
        if backend(edge) is Scalar:
            return min(math.tan(min(abs(edge) + self.shear_angle, 0.49 * math.pi)), self.mu)
        a = np.minimum(np.abs(edge) + self.shear_angle, 0.49 * math.pi)
        return np.minimum(np.tan(a), self.mu)


def tyre(mu: float, name: str = "") -> Grip:
    """A tyre on a road of friction coefficient ``mu``."""
    return Grip("tyre", float(mu), name=name or f"{mu:g}")


def snow(hardness: str) -> Grip:
    """:data:`SNOW` ``[hardness]``, with the error of a bad name."""
    try:
        return SNOW[hardness]
    except KeyError:
        raise ValueError(f"snow = {hardness!r} is not one of {', '.join(SNOW)}") from None


#: Snow by hardness (docs/skidding.md Section 1).  Brown (1989, "On the skiability of snow",
#: ASTM STP 1022, 329-336) machined snow with a loaded edge and found the critical angle of the
#: force from the snow's normal past which the edge no longer holds but skids: 40-70 deg on the
#: snows he measured, higher the stronger the snow in shear against its hardness.  Hard pack
#: holds 45 deg (a ratio of 1: a hockey stop at about 1 g); a race piste (prepared for the most
#: hold: watered, icy) the top of Brown's range, 70 deg (a ratio of 2.75, the force of a racer
#: carving at Reid et al.'s 65-71 deg edges, Front. Sports Act. Living 2:25, 2020); soft snow
#: gives way earlier and less.
SNOW = {"hard": Grip("snow", 1.0, math.radians(30.0), "hard"),
        "soft": Grip("snow", 0.6, math.radians(20.0), "soft"),
        "race": Grip("snow", math.tan(math.radians(70.0)), math.radians(30.0), "race")}

#: Tyres by surface: dry asphalt 0.9, wet 0.5, gravel 0.35 (docs/skidding.md Section 1).
TYRE = {"dry": tyre(0.9, "dry"), "wet": tyre(0.5, "wet"), "gravel": tyre(0.35, "gravel")}


def foot_lateral(l, frame, V, V_f, C_f, theta_v, omega_v, alpha_v):
    """``F_lat / m``: the tangential force across the travel the foot needs, m/s^2 (to the
    left positive; docs/skidding.md Section 1): the ground's reaction ``m (a_cm - g)`` across
    the travel, the centre of mass's centripetal acceleration ``V V_f C_f`` (the paper's
    ``k``) and its acceleration about the foot ``l (alpha_v cos theta_v - omega_v^2 sin
    theta_v)``, less the gravity to the left ``g_b``; its normal part is :func:`.model.rhs`'s
    ``N / m``."""
    xp = backend(theta_v, omega_v, alpha_v)
    s, c = xp.sin(theta_v), xp.cos(theta_v)
    return V * V_f * C_f + l * (alpha_v * c - omega_v * omega_v * s) - frame.g_lateral


def brake_limit(mu_grip, N_m, F_lat, skid_max):
    """The largest braking force over the mass, m/s^2: what the circle
    ``F_lat^2 + F_brake^2 <= (mu_grip N)^2`` leaves (0 when the turn takes it all), and at most
    ``|F_lat| tan(skid_max)`` (a skid of at most ``skid_max``; no bound for ``pi / 2``)."""
    xp = backend(mu_grip, N_m, F_lat)
    b = xp.maximum((mu_grip * N_m) ** 2 - F_lat * F_lat, 0.0) ** 0.5
    if skid_max < SKID_MAX_STOP:
        b = xp.minimum(b, xp.abs(F_lat) * math.tan(skid_max))
    return b


def skid_angle(brake, F_lat, side=1.0):
    """The skid angle of a ski whose force (perpendicular to it) has the components
    ``(F_brake, F_lat)``: ``ski_heading - theta_dir``, rad, with the sign of ``F_lat`` (the
    tail slides out of the turn); ``side`` (+1 / -1) where ``F_lat`` is 0."""
    xp = backend(brake, F_lat)
    s = xp.where(F_lat > 0.0, 1.0, xp.where(F_lat < 0.0, -1.0, side))
    return s * xp.atan2(brake, xp.abs(F_lat))


@dataclass(frozen=True)
class FootBrake:
    """A braking command at the foot, bounded by the grip (:meth:`bound`):
    :func:`.model.rhs`'s ``brake``."""

    command: float
    """The braking force over the mass asked for, m/s^2 (>= 0)."""
    grip: Grip
    skid_max: float = SKID_MAX_TURNING
    """The largest skid angle allowed, rad (:data:`SKID_MAX_TURNING`, :data:`SKID_MAX_STOP`)."""
    edge: float = 0.0
    """The least edge angle of the ski while it brakes, rad (the lean's if larger)."""

    def bound(self, N_m, F_lat, theta_v):
        """The braking force over the mass the grip gives, m/s^2: the command within
        :func:`brake_limit` at the edge angle ``max(|theta_v|, edge)``."""
        xp = backend(N_m, F_lat, theta_v)
        mu = self.grip.mu_at(xp.maximum(xp.abs(theta_v), self.edge))
        return xp.minimum(brake_limit(mu, N_m, F_lat, self.skid_max), self.command)
