"""Carving equipment and the sports' own presets (docs/racing.md).

**The sidecut relation.**  A ski (or board) of sidecut radius ``R_sc`` -- the radius of the arc
through its tip, waist and tail edges, seen from above -- tilted on edge by ``phi`` and pressed
into the snow until its whole edge touches it, bends into an arc whose projection on the snow
has the radius

    R = R_sc cos(phi)                                                       (Howe 2001)

(J. Howe, *The New Skiing Mechanics*, 2nd ed., McIntire 2001, ch. 6; derived by Lieu & Mote,
"Mechanics of the turning snow ski", ASTM STP 860, 1985: the edge's sidecut depth
``d = L^2 / (8 R_sc)`` of a ski of contact length ``L`` is, on edge, a bend ``d / cos(phi)`` of
the ski's centre line, which over the same length is an arc of radius ``L^2 cos(phi) / (8 d)``).
The relation assumes the ski is bent into full edge contact: a racer's load bends a racing ski
that far (its flex is made for it); a lighter load or a stiffer ski carves a wider arc, which the
figure's curvature then shows as a skid.  So the edge angle that carves a curvature ``C``
(the foot's ``C_f``, Section 3) is

    phi(C) = arccos(1 / (R_sc |C|))    for |C| >= 1 / R_sc,

and 0 below it (a ski flat on the snow runs straight or skids).  ``edge_max``: the largest edge
angle the figure reaches (the boot touches the snow beyond it), which bounds the curvature:
``C_f_max = 1 / (R_sc cos(edge_max))``.

**The edge a lean can hold.**  A racer stands the skis further on edge than the body leans: the
hips and knees angulate inside the turn, the upper body stays more upright (Reid et al. 2020,
*Alpine Ski Motion Characteristics in Slalom*, Front. Sports Act. Living 2:25: edge angles of
65.7 and 71.0 deg; docs/racing.md).  The angulation has a limit ``A`` (the hips and knees
bend only so far sideways), so the edge angle on the inside of a lean ``theta_v`` (the leg
line's inclination, Section 3) is at most ``min(edge_max, max(0, theta_v sgn(C) + A))``, and by
the sidecut relation the curvature carved at a lean is bounded:

    R_sc |C| cos(min(edge_max, max(0, theta_v sgn(C) + A))) <= 1,

a flat ski (an edge of 0) carving at most ``1 / R_sc``.  :class:`EdgeLimit` tests it; the path
planner clips branches that break it (core/planner/problem.py).

**Presets of a sport.**  A :class:`SportPreset` is a registered sport's figure with its own body,
limits and :class:`Carving` (the racers, the Eurocarver): it is a ``--preset`` of the command
line, a scene's ``figure.preset``, an item of Blender's Sport Presets menu, and the mapping
shows its equipment (``meta["preset"]`` of a trajectory names it).  numpy-free.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

from .physics.params import Figure, Limits
from .registry import SPORT_PRESETS, SPORTS
from .validate import check_range

__all__ = ["Carving", "SportPreset", "SPORT_PRESETS", "register_preset", "carving_of",
           "sport_of", "carving_limits", "EdgeLimit", "edge_limit_of", "ANGULATION"]

#: The largest angulation (the skis' edge angle over the leg line's lean, rad) a racer's hips and
#: knees make: docs/racing.md, "The racer's line".
ANGULATION = math.radians(15.0)


@dataclass(frozen=True)
class Carving:
    """A carving ski or board (SI units, radians)."""

    length: float
    """Length of the ski or board, m (its tip to its tail)."""
    sidecut_radius: float
    """R_sc, m: the radius of its edge's arc seen from above."""
    edge_max: float
    """The largest edge angle the figure reaches, rad (the boot or the hip touches the snow)."""

    def __post_init__(self):
        check_range("length", self.length, 0.5, 3.0)
        check_range("sidecut_radius", self.sidecut_radius, 1.0, 100.0)
        check_range("edge_max", self.edge_max, 0.0, math.radians(85.0), lo_open=True)

    @property
    def C_f_max(self) -> float:
        """The sharpest curvature it carves, ``1 / (R_sc cos(edge_max))``, 1/m."""
        return 1.0 / (self.sidecut_radius * math.cos(self.edge_max))

    def radius(self, edge: float) -> float:
        """The radius carved on edge at ``edge`` (rad): ``R_sc cos(edge)``, m."""
        return self.sidecut_radius * math.cos(edge)

    def edge_angle(self, C_f):
        """The edge angle (rad, signed as ``C_f``) that carves the curvature ``C_f`` (1/m):
        ``arccos(1 / (R_sc |C_f|))``, 0 where the curvature is below ``1 / R_sc``.  Floats or
        numpy arrays."""
        import numpy as np
        c = np.asarray(C_f, float)
        cos = 1.0 / np.maximum(self.sidecut_radius * np.abs(c), 1.0)
        out = np.sign(c) * np.arccos(cos)
        return float(out) if np.ndim(out) == 0 else out


@dataclass(frozen=True, eq=False)
class SportPreset:
    """A preset of a registered sport: its own figure and carving equipment."""

    name: str
    """Lowercase key: the CLI's ``--preset``, a scene's ``preset``, ``meta["preset"]``."""
    sport: str
    """The registered sport it is a preset of (its rig, mapping and resistance)."""
    label: str
    """What Blender's Sport Presets menu shows."""
    figure: Figure
    """Its body and limits (Section 3); ``figure.name`` is ``name``."""
    carving: Carving
    """The ski or board the mapping shows on edge (the sidecut relation)."""
    drag_area: float | None = None
    """Its own drag area ``C_d A``, m^2, when its stance differs from the sport's (a racer's
    compact stance); ``None``: the sport's."""
    angulation: float = ANGULATION
    """The largest edge angle over the lean its body makes, rad (:class:`EdgeLimit`)."""

    def __post_init__(self):
        check_range("angulation", self.angulation, 0.0, math.radians(45.0))
        if self.sport not in SPORTS:
            raise ValueError(f"preset {self.name!r}: sport = {self.sport!r} is not one of "
                             f"{', '.join(SPORTS)}")
        if self.name in SPORTS:
            raise ValueError(f"preset {self.name!r}: the name is a sport's")
        if not isinstance(self.figure, Figure) or self.figure.name != self.name:
            raise ValueError(f"preset {self.name!r}: figure must be a core Figure named "
                             f"{self.name!r}")
        if not isinstance(self.carving, Carving):
            raise ValueError(f"preset {self.name!r}: carving must be a Carving")
        if not isinstance(self.label, str) or not self.label.strip():
            raise ValueError(f"preset {self.name!r}: label = {self.label!r} is not a "
                             "non-empty string")
        if self.drag_area is not None:
            check_range(f"preset {self.name!r}: drag_area", self.drag_area, 0.0, 2.0)

    @property
    def resistance(self):
        """Its sport's friction and drag, with its own drag area when it has one."""
        res = SPORTS.lookup(self.sport).resistance
        return res if self.drag_area is None else replace(res, CdA=self.drag_area)

    @property
    def plan_curvature_rate(self) -> float:
        """Its sport's planner rate, scaled by how much faster its own edge changes are."""
        record = SPORTS.lookup(self.sport)
        return record.plan_curvature_rate * self.figure.limits.dC_f_max / \
            record.figure.limits.dC_f_max


@dataclass(frozen=True)
class EdgeLimit:
    """The curvature a lean can carve (module docstring, "The edge a lean can hold")."""

    carving: Carving
    angulation: float
    """A, rad: the largest edge angle over the lean."""

    def holds(self, theta_v, C_f):
        """Where ``R_sc |C_f| cos(min(edge_max, max(0, theta_v sgn(C_f) + A))) <= 1`` (numpy
        arrays of the lean, rad, and the curvature, 1/m, broadcast; a relative 1e-9 for the
        rounding of ``C_f_max`` itself, whose product is 1)."""
        import numpy as np
        c = self.carving
        edge = np.clip(np.sign(C_f) * theta_v + self.angulation, 0.0, c.edge_max)
        return c.sidecut_radius * np.abs(C_f) * np.cos(edge) <= 1.0 + 1e-9


def edge_limit_of(name) -> EdgeLimit | None:
    """The :class:`EdgeLimit` of the preset ``name`` (a figure's name), ``None`` for a sport's
    own figure (its curvature bounds are Section 3's alone)."""
    record = SPORT_PRESETS.get(name) if isinstance(name, str) else None
    return None if record is None else EdgeLimit(record.carving, record.angulation)


def carving_limits(carving: Carving, t_edge: float, theta_fall: float) -> Limits:
    """The limits of a figure on ``carving``: ``C_f_max = 1 / (R_sc cos(edge_max))`` (the
    sidecut relation) and ``dC_f_max = 2 C_f_max / t_edge``, from one edge's sharpest curvature
    to the other's in the edge change's time ``t_edge`` (s); ``theta_fall`` (rad)."""
    c = carving.C_f_max
    return Limits(C_f_max=c, dC_f_max=2.0 * c / t_edge, theta_fall=theta_fall)


def register_preset(record: SportPreset, replace: bool = False) -> SportPreset:
    """Register a sport's preset (a name already taken is refused unless ``replace``)."""
    if not isinstance(record, SportPreset):
        raise ValueError(f"preset: {record!r} is not a SportPreset record")
    return SPORT_PRESETS.register(record, replace)


def sport_of(name: str) -> str:
    """The sport of the preset ``name``: ``name`` itself for a sport, else its preset's sport."""
    if name in SPORT_PRESETS:
        return SPORT_PRESETS[name].sport
    return name


def carving_of(name) -> Carving | None:
    """The carving equipment of the preset ``name`` (``meta["preset"]``), ``None`` for a sport's
    own preset (which shows Section 7's linear tilt) or anything else."""
    record = SPORT_PRESETS.get(name) if isinstance(name, str) else None
    return None if record is None else record.carving
