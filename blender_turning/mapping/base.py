"""The contract between the mapping layer (Section 7) and the Blender bake.

A sport mapping turns a :class:`~blender_turning.core.Trajectory` (already resampled to the
animation's frame rate) into a :class:`PoseTrack`: for every frame, the armature object's
transform and each animated bone's pose channels, exactly the values the bake writes into
F-curves.  Everything is numpy arrays with ``n`` frames first; no bpy, no mathutils.

Conventions (Blender's): bone channels are in the bone's own rest frame (``PoseBone.location``
and ``PoseBone.rotation_quaternion`` with mode ``'QUATERNION'``, quaternions ``(w, x, y, z)``);
the object's rotation is Euler XYZ in radians.  The armature's rest pose faces +Y with Z up.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: Custom properties baked onto the armature object (animated), with the trajectory column each
#: comes from.  Users drive their own extras from these.
STATE_PROPS = {"turn_phase": "phi", "turn_lean": "theta_v", "turn_curvature": "C_f",
               "turn_leg_force": "F_leg", "turn_speed": "V_f", "turn_skid": "skid"}


@dataclass(frozen=True)
class BoneChannels:
    """Animated channels of one pose bone: ``location`` (n, 3) and/or ``rotation`` (n, 4)
    w,x,y,z."""

    location: np.ndarray | None = None
    rotation: np.ndarray | None = None

    def __post_init__(self):
        for name, shape in (("location", 3), ("rotation", 4)):
            v = getattr(self, name)
            if v is not None:
                v = np.ascontiguousarray(v, float)
                if v.ndim != 2 or v.shape[1] != shape:
                    raise ValueError(f"{name} must have shape (n, {shape}), not {v.shape}")
                object.__setattr__(self, name, v)


@dataclass(frozen=True)
class PoseTrack:
    """All animated values of one figure over ``n`` frames."""

    frames: np.ndarray
    """(n,) scene frame numbers (floats; integers for a bake on every frame)."""
    location: np.ndarray
    """(n, 3) armature object location, m (the foot point on the ground)."""
    rotation: np.ndarray
    """(n, 3) armature object rotation, Euler XYZ, rad (heading about Z)."""
    bones: dict = field(default_factory=dict)
    """bone name -> :class:`BoneChannels`."""
    props: dict = field(default_factory=dict)
    """custom property name -> (n,) values (see ``STATE_PROPS``)."""

    def __post_init__(self):
        n = len(self.frames)
        for name in ("location", "rotation"):
            if np.shape(getattr(self, name)) != (n, 3):
                raise ValueError(f"{name} must have shape ({n}, 3)")
        for bone, ch in self.bones.items():
            for arr in (ch.location, ch.rotation):
                if arr is not None and len(arr) != n:
                    raise ValueError(f"bone {bone!r} has {len(arr)} frames, not {n}")
        for prop, arr in self.props.items():
            if np.shape(arr) != (n,):
                raise ValueError(f"property {prop!r} must have shape ({n},)")

    def __len__(self) -> int:
        return len(self.frames)

    def rows(self, a: int, b: int) -> "PoseTrack":
        """Frames ``a:b`` of the track (a window of it)."""
        def take(v):
            return None if v is None else v[a:b]

        return PoseTrack(take(self.frames), take(self.location), take(self.rotation),
                         {k: BoneChannels(take(ch.location), take(ch.rotation))
                          for k, ch in self.bones.items()},
                         {k: take(v) for k, v in self.props.items()})


class Mapping:
    """Base of the sport mappings (Section 7): one subclass per sport, registered in
    ``MAPPINGS``.

    A subclass sets ``sport`` (also the rig's name in ``rigs/``) and ``Options`` (a frozen
    dataclass of its parameters, SI units), and implements :meth:`pose`, which fills a
    :class:`~blender_turning.mapping.kinematics.PoseBuilder` from the trajectory.  :meth:`map`
    does the rest: it loads and checks the rig, places the object on the foot point with the
    heading, and bakes the state properties.
    """

    sport: str = ""
    Options: type = type(None)

    def pose(self, builder, traj, options, spec) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def map(self, traj, options=None, frames=None, normal=None, surface=None) -> PoseTrack:
        """``normal``: (n, 3) surface normals at the foot on terrain (``None``: flat ground);
        the object then stands on the surface (:mod:`.surface`); ``surface``: the ground's
        height, ``surface(x, y) -> z``, for the pole plants (:class:`.surface.Placement`)."""
        from .bones import REQUIRED, require
        from .kinematics import PoseBuilder, Skeleton, quat_continuous
        from .rig_spec import load_rig
        from .surface import Placement

        options = self.Options() if options is None else options
        if not isinstance(options, self.Options):
            raise TypeError(f"options for {self.sport!r} must be {self.Options.__name__}, "
                            f"not {type(options).__name__}")
        spec = load_rig(self.sport)
        require(spec.bone_names, REQUIRED[self.sport], f"rig {spec.name!r}")
        n = len(traj)
        frames = np.arange(n, dtype=float) + 1.0 if frames is None else np.asarray(frames, float)
        builder = PoseBuilder(Skeleton.from_spec(spec), n)
        builder.placement = Placement(traj, normal, surface)
        self.pose(builder, traj, options, spec)
        skel = builder.skel
        bones = {}
        for name in skel.names:   # parent-before-child order, for a readable bake
            rot, loc = builder.rot.get(name), builder.loc.get(name)
            if skel.connected[skel.i(name)]:
                loc = None
            if rot is None and loc is None:
                continue
            bones[name] = BoneChannels(location=loc,
                                       rotation=None if rot is None else quat_continuous(rot))
        # The object carries the foot point and the heading: the rig faces +Y, theta_dir is
        # measured counter-clockwise from +x (docs/ARCHITECTURE.md Section 4); on terrain it
        # stands on the surface (mapping/surface.py).
        location, rotation = builder.placement.origin, builder.placement.euler
        props = {prop: np.array(getattr(traj, col), float) for prop, col in STATE_PROPS.items()}
        return PoseTrack(frames, location, rotation, bones, props)
