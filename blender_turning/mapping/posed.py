"""The built-in figures' body as posed by their mapping: the centre of mass's distance from the
foot and the roll inertia, frame by frame (what the telemark's body parameters are fitted to:
scripts/telemark_body.py).  Apart from :mod:`.anthropometry` because it maps a whole run, so it
needs the package, which the sports' mappings (and so :mod:`.anthropometry`) are part of."""
from __future__ import annotations

import numpy as np

from . import map_trajectory
from .anthropometry import centre_and_roll_inertia
from .kinematics import Skeleton
from .rig_spec import load_rig

__all__ = ["posed_body"]


def posed_body(sport: str, traj, mass: float):
    """``(l (n,), I_v (n,))`` of the built-in ``sport`` figure posed by its Section 7 mapping of
    ``traj`` (one sample per frame): the centre of mass's distance from the foot point across
    the travel (the armature's XZ plane) and the roll inertia about it, for ``mass`` kg."""
    skel = Skeleton.from_spec(load_rig(sport))
    P = skel.fk(map_trajectory(sport, traj).bones, len(traj))
    com, inertia = centre_and_roll_inertia(P, skel, mass)
    return np.hypot(com[:, 0], com[:, 2]), inertia
