"""A snowboarder's stance: Section 7's built-in rider stands regular (left foot
forward); a goofy rider (right foot forward) is its mirror image across the line of travel, .L
and .R swapped, riding the mirrored run.  numpy only."""
from __future__ import annotations

import numpy as np

from ...core.registry import SPORTS
from .. import bones as B
from ..base import BoneChannels, PoseTrack
from ..kinematics import Skeleton, quat_continuous, quat_from_matrix, rigid_inverse
from ..rig_spec import load_rig

__all__ = ["STANCES", "mirrored_trajectory", "unmirror_props", "MirroredSkeleton",
           "builtin_skeleton", "mirror_poses", "goofy_track"]

#: Sports with a stance: the built-in rides ``regular`` (left foot forward); ``goofy`` is its
#: mirror image (see :func:`mirrored_trajectory`).
STANCES = SPORTS.view("stances", lambda s: s.stances)
_S4 = np.diag([-1.0, 1.0, 1.0, 1.0])        # mirror across the travel line (x -> -x)


def mirrored_trajectory(traj):
    """The mirror image of ``traj`` across its own line of travel: lean, its rate and
    acceleration, curvature and the skid change sign, the phase moves half a cycle; where the
    foot goes (x, y, theta_dir) stays.  A goofy rider on ``traj`` is the mirror image, .L and .R
    swapped, of a regular rider on this (Section 7's snowboarder rides regular)."""
    cols = traj.columns()
    for c in ("theta_v", "omega_v", "alpha_v", "C_f", "skid"):    # a ski turned left: right
        cols[c] = -np.asarray(cols[c])
    cols["ski_heading"] = np.asarray(cols["theta_dir"]) + cols["skid"]
    cols["phi"] = np.mod(np.asarray(cols["phi"]) + np.pi, 2 * np.pi)
    return type(traj).from_columns(cols, traj.meta)


def unmirror_props(props: dict) -> dict:
    """State properties of a mirrored run (``STATE_PROPS``) back to the run itself."""
    out = dict(props)
    for p in ("turn_lean", "turn_curvature", "turn_skid"):
        if p in out:
            out[p] = -np.asarray(out[p])
    if "turn_phase" in out:
        out["turn_phase"] = np.mod(np.asarray(out["turn_phase"]) + np.pi, 2 * np.pi)
    return out


class MirroredSkeleton:
    """A built-in skeleton mirrored across its travel line with .L and .R swapped."""

    def __init__(self, skel):
        self._skel = skel

    def rest_of(self, name):
        return _S4 @ self._skel.rest_of(B.mirror(name)) @ _S4


_SKELETONS = {}         # (sport, mirror) -> (the rig spec it was built from, skeleton)


def builtin_skeleton(sport: str, mirror: bool = False):
    """The built-in rig of ``sport`` (its rest frames by ``rest_of``), or its mirror image:
    built once per rig spec and shared (read-only; every retarget step asks for it several
    times, and building it costs about a millisecond)."""
    spec = load_rig(sport)
    built = _SKELETONS.get((sport, mirror))
    if built is None or built[0] is not spec:
        skel = Skeleton.from_spec(spec)
        skel.rest.setflags(write=False)
        built = (spec, MirroredSkeleton(skel) if mirror else skel)
        _SKELETONS[(sport, mirror)] = built
    return built[1]


def mirror_poses(poses: dict) -> dict:
    """Armature-space poses (n, 4, 4) by bone -> their mirror image, .L and .R swapped."""
    return {n: _S4 @ poses[B.mirror(n)] @ _S4 for n in poses}


def goofy_track(sport: str, mirrored_track: PoseTrack) -> PoseTrack:
    """The built-in rig of ``sport`` riding goofy: ``mirrored_track`` is its regular mapping of
    the mirrored run (:func:`mirrored_trajectory`); every bone is given the pose of its mirror
    image (.L and .R swapped), as local channels on the same rig (rotation on every bone,
    location where the bone is not connected), and the state properties are unmirrored."""
    skel = Skeleton.from_spec(load_rig(sport))
    n = len(mirrored_track)
    poses = mirror_poses(skel.fk(mirrored_track.bones, n))
    bones = {}
    for i, name in enumerate(skel.names):
        parent = skel.parents[i]
        base = skel.rest_relative(name)
        base = np.broadcast_to(base, (n, 4, 4)) if parent is None else poses[parent] @ base
        local = rigid_inverse(base) @ poses[name]
        bones[name] = BoneChannels(
            location=None if skel.connected[i] else local[:, :3, 3],
            rotation=quat_continuous(quat_from_matrix(local[:, :3, :3])))
    return PoseTrack(mirrored_track.frames, mirrored_track.location, mirrored_track.rotation,
                     bones, unmirror_props(mirrored_track.props))
