"""How a preset's figure holds its speed on a slope (docs/skidding.md Section 8): the style
(``wedge``, ``skid``) and the target speed it skis at unless told otherwise.  The beginner and
the recreational skier (``mapping/sports/skier_presets.py``) have one; the command line's
``--style`` and ``--target-speed``, and Blender's Speed Control settings, start from it."""
from __future__ import annotations

from dataclasses import dataclass

from ..physics.skidding import STYLES
from ..validate import check_range

__all__ = ["SpeedHabit", "HABITS", "habit_of"]


@dataclass(frozen=True)
class SpeedHabit:
    """A preset's speed control on a slope."""

    style: str
    """How it brakes: one of :data:`.skidding.STYLES`."""
    target_speed: float
    """The speed it holds on a slope, m/s."""

    def __post_init__(self):
        if self.style not in STYLES:
            raise ValueError(f"style = {self.style!r} is not one of {', '.join(STYLES)}")
        check_range("target_speed", self.target_speed, 0.0, 100.0, lo_open=True)


HABITS: dict = {}
"""Preset name -> :class:`SpeedHabit` (filled by the presets' modules)."""


def habit_of(name) -> SpeedHabit | None:
    """The speed habit of the preset ``name``, ``None`` when it has none."""
    return HABITS.get(name) if isinstance(name, str) else None
