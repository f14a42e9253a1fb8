"""The sport's equipment on the user's rig: where each piece sits at the rig's rest,
rigid with one of its joints exactly as on the built-in figure, so that in motion it lands where
the built-in's equipment is.  numpy only; the Blender side makes the objects and constraints."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import bones as B
from .bone_map import BoneMap
from ..sports.common import tyre_radius
from .retarget import ATTACH, SLIDE, SPIN, TRACKS, _rest_difference
from ..rig_spec import load_rig
from .stance import builtin_skeleton
from .user_rig import RigFit, UserRig, fit_rig

__all__ = ["EquipmentPiece", "equipment_rest"]


def _anchor(head, joint):
    """Where equipment rigid with ``joint`` is measured from: the joint's head, or for the
    pelvis the hip joints' midpoint (which :func:`solve_joints` puts on the built-in's)."""
    if joint == B.HIPS:
        return 0.5 * (head("thigh.L") + head("thigh.R"))
    return head(joint)


@dataclass(frozen=True)
class EquipmentPiece:
    name: str
    """The built-in rig's equipment bone (``ski.L``); its meshes are the built-in's."""
    joint: str
    """Our joint it is rigid with."""
    bone: str
    """The user's bone playing that joint."""
    rest: np.ndarray
    """(4, 4) its frame at the rig's rest, user armature space (like a bone's ``matrix_local``)."""
    size: float
    """Mesh scale: built-in metres -> the user's armature units (``k / s``)."""
    track: str | None = None
    """Another piece this one turns to face about its own Y axis (``TRACKS``), or ``None``."""
    track_axis: str = ""
    """Its local axis that points at ``track`` at rest: 'X', 'Z', 'NEGATIVE_X' or 'NEGATIVE_Z'."""
    spin: float = 0.0
    """Rotation about its own Y axis (the axle) per metre travelled, rad/m (``SPIN``): a wheel
    of the built-in's tyre radius ``r`` scaled by ``k`` rolls forwards at ``-1 / (k r)``, as the
    built-in's wheels do (Section 7: "as a function of the distance travelled")."""
    slide: tuple = ()
    """``(state property, (3,) unit axis)``: the piece slides along the axis (user armature
    space, at rest) by the property's value (world metres, ``SLIDE``), or ``()``."""


def equipment_rest(sport: str, rig: UserRig, bm: BoneMap, fit: RigFit | None = None,
                   mirror: bool = False) -> list:
    """Where each piece of the sport's equipment sits on the user's rig at rest: rigid with its
    joint exactly as on the built-in figure, through the same rest difference ``A`` as the
    motion (so that in motion it lands where the built-in's equipment is)."""
    if sport not in ATTACH:
        raise ValueError(f"sport = {sport!r}: retargeting supports {', '.join(ATTACH)}")
    fit = fit_rig(rig, bm, sport, mirror) if fit is None else fit
    skel = builtin_skeleton(sport, mirror)
    C, size = fit.C, fit.k / fit.scale
    out = []
    u_head = lambda j: rig.head(bm.bone(j))                # noqa: E731
    b_head = lambda j: skel.rest_of(j)[:3, 3]                # noqa: E731
    for piece, joint in ATTACH[sport].items():
        A = _rest_difference(bm, rig, skel, fit, joint)
        m = np.eye(4)
        m[:3, :3] = A.T @ C @ skel.rest_of(piece)[:3, :3]
        m[:3, 3] = _anchor(u_head, joint) + A.T @ (size * (C @ (b_head(piece)
                                                                 - _anchor(b_head, joint))))
        track = TRACKS.get(sport, {}).get(piece)
        axis = ""
        if track is not None:
            v = skel.rest_of(piece)[:3, :3].T @ (b_head(track) - b_head(piece))
            v[1] = 0.0                                       # about its own Y axis
            i = 0 if abs(v[0]) >= abs(v[2]) else 2
            axis = ("" if v[i] > 0 else "NEGATIVE_") + "XYZ"[i]
        spin = -1.0 / (fit.k * tyre_radius(load_rig(sport), piece)) \
            if piece in SPIN.get(sport, ()) else 0.0
        slide = ()
        if piece in SLIDE.get(sport, {}):
            along, prop = SLIDE[sport][piece]
            slide = (prop, A.T @ C @ skel.rest_of(along)[:3, 1])
        out.append(EquipmentPiece(piece, joint, bm.bone(joint), m, size, track, axis, spin,
                                  slide))
    return out
