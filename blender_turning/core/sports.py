"""One record per sport (docs/registry.md): everything the add-on knows of a sport, in one place.

A :class:`Sport` holds the sport's physics (its preset body and limits, Section 3; what slows it
on a slope; the planner's steering rate), its display model (the Section 7 mapping and the
rig spec it poses, ``rigs/<name>.json``), how it goes onto a user's own rig (:class:`Retarget`)
and how Blender shows it (label, description, icon, the number a .blend file stores).  A sport's
module makes its record and calls :func:`register_sport`; every reader (scene and crowd files,
render jobs), command-line choice list, Blender enum, menu, preset and validator takes the
sports from :data:`SPORTS`.

The core reads only the physics fields; the mapping and retargeting fields are the mapping
layer's data, which the core carries without importing it.  numpy-free, standard library only.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from .physics.grip import Grip
from .physics.params import Figure
from .physics.skidding import STYLES
from .registry import SPORTS
from .physics.model import Resistance
from .validate import check

__all__ = ["Sport", "Retarget", "SPORTS", "register_sport", "unregister_sport", "sport"]


@dataclass(frozen=True, eq=False)
class Retarget:
    """How the sport's motion goes onto a user's own armature
    (:mod:`..mapping.retarget.retarget`)."""

    attach: dict
    """Equipment bone of the built-in rig -> the joint it is rigid with on the user's rig."""
    tracks: dict = field(default_factory=dict)
    """Equipment that turns about its own axle to face another piece (Blender: Damped Track)."""
    spin: tuple = ()
    """Equipment that rolls with the distance travelled (about its own Y axis, the axle)."""
    slide: dict = field(default_factory=dict)
    """Equipment that slides along another piece's Y axis: ``piece -> (along, state property)``."""
    seated: bool = False
    """The pelvis sits on the equipment (a saddle): it goes where the built-in's goes."""
    anchor: str | None = None
    """Where a foot meets its equipment when not at the ankle (``"toe"``: the ball of the foot)."""

    def __post_init__(self):
        if not self.attach or not all(isinstance(k, str) and isinstance(v, str)
                                      for k, v in self.attach.items()):
            raise ValueError(f"attach = {self.attach!r} is not a non-empty mapping of "
                             "equipment bone -> joint")
        for name in ("tracks", "slide"):
            bad = [k for k in getattr(self, name) if k not in self.attach]
            if bad:
                raise ValueError(f"{name} names {bad[0]!r}, which attach does not")
        bad = [k for k in self.spin if k not in self.attach]
        if bad:
            raise ValueError(f"spin names {bad[0]!r}, which attach does not")


@dataclass(frozen=True, eq=False)
class Sport:
    """A sport: one record, registered once (:func:`register_sport`)."""

    name: str
    """Lowercase key: the CLI's ``--preset``, a scene's ``preset``, the rig's name."""
    label: str
    """What Blender shows (the Sport enum, Add > Turning Figure, the presets menu)."""
    description: str
    """The enum item's tooltip."""
    figure: Figure
    """The preset body and limits (Section 3); its ``name`` is ``name``."""
    resistance: Resistance
    """Friction and drag on a slope (docs/TERRAIN.md Section 3), with their sources."""
    plan_curvature_rate: float
    """Largest |dC_f/dt| the path planner tries, 1/(m s) (gentler than the figure's limit)."""
    number: int
    """The value a .blend file stores for this sport's enum item: never change it once a file
    has been saved with the sport (the built-ins are 0-3)."""
    mapping: object
    """The Section 7 mapping (a :class:`..mapping.base.Mapping` whose ``sport`` is ``name``)."""
    bones: tuple
    """The bones the sport's rig must have (the mapping keys them)."""
    rig_file: str | None = None
    """The rig spec (JSON, :mod:`..mapping.rig_spec`); ``None``: ``rigs/<name>.json``."""
    retarget: Retarget | None = None
    """How it goes onto a user's rig; ``None``: Make Figure does not offer the sport."""
    stances: tuple = ()
    """``("regular", "goofy")`` for a sport ridden either way round (the goofy rider is the
    regular one's mirror image, :mod:`..mapping.retarget.stance`); ``()``: one way only."""
    snow_tracks: tuple = (0.045, (-0.11, 0.11))
    """The grooves the equipment cuts in snow, as the render job draws them: ``(half width,
    lateral offsets)``, m (skis: two narrow ones a hip's width apart)."""
    icon: str = "NONE"
    """A Blender icon name for the enum item."""
    grip: Grip | None = None
    """The friction circle at the foot (docs/skidding.md); ``None``: snow, as hard as the user
    says (:data:`.grip.SNOW`)."""
    styles: tuple = ("carve", "skid")
    """How the figure may brake (:data:`.skidding.STYLES`): skis add ``wedge``, a board
    ``slip``."""

    def __post_init__(self):
        for name in ("label", "description"):
            if not isinstance(getattr(self, name), str) or not getattr(self, name).strip():
                raise ValueError(f"sport {self.name!r}: {name} = {getattr(self, name)!r} is "
                                 "not a non-empty string")
        if not isinstance(self.figure, Figure) or self.figure.name != self.name:
            raise ValueError(f"sport {self.name!r}: figure must be a core Figure named "
                             f"{self.name!r}, not {self.figure!r}")
        if not isinstance(self.resistance, Resistance):
            raise ValueError(f"sport {self.name!r}: resistance must be a Resistance, not "
                             f"{self.resistance!r}")
        check("plan_curvature_rate", self.plan_curvature_rate, "plan_curvature_rate")
        if not isinstance(self.number, int) or isinstance(self.number, bool) or \
                not 0 <= self.number < 2 ** 20:
            raise ValueError(f"sport {self.name!r}: number = {self.number!r} is not a whole "
                             "number in [0, 2^20)")
        if getattr(self.mapping, "sport", None) != self.name or \
                not callable(getattr(self.mapping, "map", None)):
            raise ValueError(f"sport {self.name!r}: mapping must be a Mapping whose sport is "
                             f"{self.name!r}, not {self.mapping!r}")
        if not self.bones or not all(isinstance(b, str) for b in self.bones):
            raise ValueError(f"sport {self.name!r}: bones must name the rig's bones")
        if self.retarget is not None and not isinstance(self.retarget, Retarget):
            raise ValueError(f"sport {self.name!r}: retarget must be a Retarget or None")
        if self.grip is not None and not isinstance(self.grip, Grip):
            raise ValueError(f"sport {self.name!r}: grip must be a core.physics.grip.Grip or None")
        if "carve" not in self.styles or not set(self.styles) <= set(STYLES):
            raise ValueError(f"sport {self.name!r}: styles = {self.styles!r} must hold 'carve' "
                             f"and only {', '.join(STYLES)}")
        if self.stances not in ((), ("regular", "goofy")):
            raise ValueError(f"sport {self.name!r}: stances = {self.stances!r} is not () or "
                             "('regular', 'goofy')")

    @property
    def key(self) -> str:
        """The Blender enum identifier (``"SKIER"``), which .blend files and scripts use."""
        return self.name.upper()

    def rig_path(self, rigs_dir) -> Path:
        """The rig spec's file: ``rig_file``, or ``<rigs_dir>/<name>.json``."""
        return Path(self.rig_file) if self.rig_file is not None else \
            Path(rigs_dir) / f"{self.name}.json"


def register_sport(record: Sport, replace: bool = False) -> Sport:
    """Register ``record`` (a name or number already taken is refused unless ``replace``)."""
    if not isinstance(record, Sport):
        raise ValueError(f"sport: {record!r} is not a Sport record")
    return SPORTS.register(record, replace)


def unregister_sport(name: str) -> None:
    """Remove the sport ``name`` (a test's or a script's own sport)."""
    SPORTS.unregister(name)


def sport(name: str) -> Sport:
    """The registered sport ``name`` (``"skier"``; the enum's ``"SKIER"`` too)."""
    return SPORTS.lookup(name.lower() if isinstance(name, str) else name)
