"""Section 7: the physical state -> per-bone pose channels. numpy only, one module per sport.

``map_trajectory(sport, traj)`` turns a trajectory into a :class:`PoseTrack` for the sport's rig
(``rigs/<sport>.json``).  Each sport's module registers its record (:mod:`..core.sports`: preset,
mapping, rig, labels); the imports below are the built-in sports, in the order Blender lists them.
``MAPPINGS`` is the registry's view ``sport -> Mapping``.
"""
from __future__ import annotations

import numpy as np

from ..core.registry import SPORTS
from .base import STATE_PROPS, BoneChannels, Mapping, PoseTrack
from .bones import MissingBoneError
# The built-in sports register in this order (skier, snowboarder, telemark, cyclist).
from .sports.skier import SkierMapping, SkierOptions
from .sports import skier_presets  # noqa: F401 - registers the beginner and recreational presets
from .sports.snowboarder import SnowboarderMapping, SnowboarderOptions
from .sports.telemark import TelemarkMapping, TelemarkOptions
from .sports.cyclist import CyclistMapping, CyclistOptions

#: ``sport -> Mapping``, a live view of the sport registry.
MAPPINGS = SPORTS.view("mapping")

__all__ = ["STATE_PROPS", "BoneChannels", "Mapping", "PoseTrack", "MAPPINGS", "map_trajectory",
           "MissingBoneError",
           "SkierOptions", "SnowboarderOptions", "TelemarkOptions", "CyclistOptions"]


def map_trajectory(sport: str, traj, options=None, frame_start: int = 1,
                   fps: float | None = None, normal=None, surface=None) -> PoseTrack:
    """Map ``traj`` onto the rig of ``sport``: one pose per sample, at frames
    ``frame_start + k``.  With ``fps`` the trajectory is first resampled at that rate (one
    sample per frame); without it the samples are used as they are (already resampled).
    ``normal`` ((n, 3), per sample): the surface normal at the foot on terrain; the figure then
    stands on the surface (:mod:`.surface`); ``surface(x, y) -> z``: the ground's height, where
    the poles are planted (default: the plane under the foot)."""
    if sport not in MAPPINGS:
        raise ValueError(f"sport = {sport!r} is not one of {', '.join(MAPPINGS)}")
    if fps is not None:
        if normal is not None:
            raise ValueError("normal is per sample of the trajectory as given: resample first")
        traj = traj.resample(fps)
    if len(traj) == 0:
        raise ValueError("the trajectory has no samples")
    frames = float(frame_start) + np.arange(len(traj), dtype=float)
    return MAPPINGS[sport].map(traj, options, frames, normal, surface)
