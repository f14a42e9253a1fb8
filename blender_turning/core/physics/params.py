"""Body parameters, limits and the sports' presets (SI units, radians).

The physical model is the inverted pendulum of Section 3 (Fig. 2): a mass ``m`` at height ``l``
above a steerable "foot", roll inertia ``I_v`` about the centre of mass (Eq. 13), moving forward
at a constant ``V_cm``.  Everything here is a frozen dataclass validated in ``__post_init__``
against the one table of ranges (:mod:`.ranges`): a bad value raises ``ValueError`` naming the
field, the value and the allowed range.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property

from ..ranges import RANGES
from ..registry import SPORT_PRESETS, SPORTS, ChainView
from ..validate import check, check_range

__all__ = ["BodyParams", "Limits", "Figure", "PRESETS", "preset", "check_range"]


@dataclass(frozen=True)
class BodyParams:
    """The inverted pendulum of Fig. 2."""

    m: float = 75.0
    """Mass of the body, kg."""
    l: float = 1.0
    """Height of the centre of mass above the foot, m."""
    I_v: float = 12.0
    """Roll moment of inertia about the centre of mass (Eq. 13), kg m^2."""
    V_cm: float = 10.0
    """Forward speed of the centre of mass, m/s (constant, Section 3)."""
    g: float = 9.81
    """Gravitational acceleration, m/s^2."""

    def __post_init__(self):
        for name in ("m", "l", "I_v", "V_cm", "g"):
            check(name, getattr(self, name), name)
        if not RANGES["J"].contains(self.J):
            raise ValueError(f"I_v = {self.I_v:g} kg m^2 with m = {self.m:g} kg and l = "
                             f"{self.l:g} m gives J = (I_v + l^2 m) / (m l) = {self.J:.4g} m, "
                             f"outside the allowed range {RANGES['J']}")

    def at_speed(self, V_cm: float) -> "BodyParams":
        """This body moving at ``V_cm`` (m/s), a speed the model reached: ``replace(self,
        V_cm=V_cm)`` without the table of ranges (which bounds what a user gives, not what the
        physics makes: docs/TERRAIN.md Section 3); only a positive finite speed is a speed.
        On terrain the speed is a state and the controller follows it every step
        (:meth:`.controllers.base.Controller.follow_speed`), where ``replace``'s full check
        cost ~4 us a step."""
        reached_speed(V_cm)
        body = object.__new__(type(self))
        body.__dict__.update(self.__dict__)
        body.__dict__["V_cm"] = float(V_cm)
        return body

    @cached_property
    def J(self) -> float:
        """``(I_v + l^2 m) / (m l)``: the inertia term of Eqs. (1), (2) and (9), m."""
        return (self.I_v + self.l * self.l * self.m) / (self.m * self.l)


def reached_speed(V_cm: float) -> float:
    """``V_cm`` (m/s) as a float, a speed the model reached (:meth:`BodyParams.at_speed`): only
    a positive finite speed is a speed."""
    if not 0.0 < V_cm < math.inf:
        raise ValueError(f"V_cm = {V_cm!r} m/s is not a positive finite speed")
    return float(V_cm)


@dataclass(frozen=True)
class Limits:
    """Bounds on the steering and the lean (Sections 3, 5.1 and 6.1)."""

    C_f_max: float = math.inf
    """Largest |C_f|, 1/m (a ski's sidecut, a bicycle's steering lock)."""
    dC_f_max: float = math.inf
    """Largest |dC_f/dt|, 1/(m s) (how fast the foot can change its curvature)."""
    theta_fall: float = math.radians(60.0)
    """|theta_v| beyond which the figure has fallen, rad."""

    def __post_init__(self):
        for name in ("C_f_max", "dC_f_max"):       # +inf: no bound (a research setting)
            if getattr(self, name) != math.inf:
                check(name, getattr(self, name), name)
        check("theta_fall", self.theta_fall, "theta_fall")


@dataclass(frozen=True)
class Figure:
    """A sport preset: a body and its limits."""

    name: str
    body: BodyParams
    limits: Limits
    doc: str = field(default="", compare=False)


#: The preset figures, ``name -> Figure``: a live view of the sport registry (:mod:`.sports`;
#: each sport's record holds its body and limits, with their sources), then of the sports'
#: own presets (:mod:`.equipment`: the racers and the carver).
PRESETS = ChainView(SPORTS.view("figure"), SPORT_PRESETS.view("figure"))


def preset(name: str, **body_overrides) -> Figure:
    """The preset ``name`` with optional body overrides (``m=80``, ``V_cm=12`` ...)."""
    key = name.lower()
    if key not in PRESETS:
        raise ValueError(f"preset = {name!r} is not one of {', '.join(PRESETS)}")
    fig = PRESETS[key]
    if body_overrides:
        fig = replace(fig, body=replace(fig.body, **body_overrides))
    return fig
