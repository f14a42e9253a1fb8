"""Figure settings -> trajectory -> pose track: the whole computation before anything is written.

Operators and headless jobs call :func:`figure_pose_track`, then :func:`..bake.bake_pose_track`.
Everything that can fail (bad settings, a fall, a mapping error) fails here, before the scene is
touched.

On a Ground mesh (``turning.ground``, docs/TERRAIN.md) the mesh is read once into a height field
(:func:`.ground.read_ground`; pass it in as ``ground`` to share it between figures), the core
simulates on it with the figure's friction, drag and target speed (the speed is then a state:
the Speed setting at the first frame is where it starts), the foot's height on every frame is a
ray cast onto the mesh, and the figure stands in the local surface (the mapping gets the smooth
field's normal at the foot).  Without a Ground mesh the ground is flat at the Start height.
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...core import DEFAULT_DT, simulate
from ...core.ground.terrain import surface_frame
from .model_notes import with_turn
from ..scene.scene_adapters import (FrameRange, SceneInputError, controller_from_settings,
                                    figure_from_settings, resistance_from_settings,
                                    skidding_from_settings, speed_schedule, start_state,
                                    target_schedule)


def map_track(sport: str, traj, frames: FrameRange, options=None, obj=None, normal=None,
              surface=None, rows=None, fitted="read"):
    """The sport's Section 7 mapping of ``traj`` (already at ``frames.fps``) to a pose track;
    retargeted onto ``obj`` when it is a figure made from the user's own rig.
    ``normal`` ((n, 3)): the surface normal at the foot on every frame (terrain); ``surface``:
    the ground's height (:func:`surface_heights`); ``rows`` ``(a, b)``: the track's frames
    ``a:b`` only, the others mapped as their context (a user's rig is retargeted on those);
    ``fitted``: ``obj``'s :func:`..scene.retarget_adapter.fitted_rig` when already read."""
    from ...mapping import map_trajectory      # the mapping layer's entry point
    from ..scene import retarget_adapter
    if obj is not None and (retarget_adapter.is_user_rig(obj) or retarget_adapter.mirrored(obj)):
        return retarget_adapter.figure_track(obj, traj, frames, options, normal, surface, rows,
                                             fitted)
    track = map_trajectory(sport.lower(), traj, options, frame_start=frames.start,
                           normal=normal, surface=surface)
    return track if rows is None else track.rows(*rows)


def first_frame(offset: float, fps: float) -> int:
    """Frames after the bake's first at which a figure starting ``offset`` s late has its first
    key: the first frame at or after its start (as :func:`..crowd.poses.map_task` counts)."""
    return math.ceil(offset * fps - 1e-9)


def on_crowd_clock(traj, offset: float):
    """``traj`` (on the figure's own clock, ``t = 0`` at its start) with ``t`` on the scene's
    clock: ``offset`` s later (the crowd's clock, :mod:`..crowd.runner`)."""
    if offset == 0.0:
        return traj
    cols = traj.columns()
    cols["t"] = cols["t"] + offset
    return type(traj).from_columns(cols, {**traj.meta, "time_offset": offset})


def started(frames: FrameRange, offset: float) -> FrameRange:
    """The frames a figure starting ``offset`` s after ``frames.start`` is keyed on."""
    k0 = first_frame(offset, frames.fps)
    if frames.start + k0 >= frames.end:
        raise SceneInputError(f"Start Offset (turning.crowd.time_offset) = {offset:g} s starts "
                              f"the figure at frame {frames.start + k0}, not before the last "
                              f"frame {frames.end}: lower it or bake more frames")
    return FrameRange(frames.start + k0, frames.end, frames.fps)


def resampled(traj, frames: FrameRange, ground=None, origin: int | None = None, skip: int = 0):
    """``traj`` at every frame of ``frames`` (exactly ``end - start + 1`` samples) but the first
    ``skip``; ``ground``: the surface it ran on (terrain).  ``traj``'s ``t = 0`` is frame
    ``origin`` (default ``frames.start``; a figure with a start offset is keyed from a later
    frame)."""
    origin = frames.start if origin is None else origin
    out = traj.resample(frames.fps, start=(frames.start - origin) / frames.fps, ground=ground,
                        first=skip)
    n = frames.end - frames.start + 1 - skip
    if len(out) < n:
        raise ValueError(f"the trajectory covers {len(out)} of {n} frames")
    return type(out)(out.data[:, :n], out.meta)


def ground_of(obj, depsgraph=None):
    """The figure's Ground mesh read into a :class:`.ground.MeshGround`, or ``None`` (flat)."""
    mesh = obj.turning.ground
    if mesh is None:
        return None
    import bpy
    from ..scene.ground import read_ground
    return read_ground(mesh, depsgraph or bpy.context.evaluated_depsgraph_get())


def _with_z(traj, z):
    return type(traj).from_columns({**traj.columns(), "z": np.asarray(z, float)}, traj.meta)


def on_ground(traj, ground):
    """``traj`` with its foot height ``z`` on every row a ray cast onto ``ground`` (a
    :class:`.ground.MeshGround`): exactly on the mesh, not on its smooth field."""
    return _with_z(traj, ground.heights(traj.x, traj.y))


def simulate_figure(obj, frames: FrameRange, start=None, height=None, ground="read",
                    coarse_dt: float | None = None, stride: int = 1, skip: int = 0):
    """Simulate the figure ``obj`` (its ``turning`` settings) over ``frames`` from ``start``
    (``(x, y, theta_dir)``, default its Start settings); the trajectory at every frame.
    ``height``: the flat ground's height (default the Start setting's z); ``ground``: its Ground
    mesh as read by :func:`ground_of` (default: read it here).  Raises ``ValueError`` or the
    core's ``TurningError`` (``FellOver``, ``Stopped``, ``LeftTerrain``).

    A figure with a Start Offset (``turning.crowd.time_offset``, a crowd's follower) runs on its
    own clock from that many seconds after the first frame, as the core's crowd does
    (:mod:`..crowd.runner`): its trajectory is ``t = offset`` + its own time, sampled at the
    frames from the first at or after its start (:func:`started`), its keyed settings read on
    its own clock (the value keyed at frame ``f`` acts ``offset`` s later).

    A preview (Live Preview's drag step): ``coarse_dt``, the step on the paper's own model (flat
    ground, a Speed that is not keyed, no skidding); ``stride``, on a Ground mesh without a
    Target Speed or skidding, the core's coarse steps about the lean's zero crossings
    (:func:`...core.physics.terrain_sim.simulate_free`).  Elsewhere both are ignored.
    ``skip``: the first frames the trajectory leaves out (as the whole range's samples after
    them, bit for bit)."""
    s = obj.turning
    if isinstance(ground, str):
        ground = ground_of(obj)
    offset = float(s.crowd.time_offset)
    shown = started(frames, offset)
    speed = speed_schedule(obj, frames)
    figure = figure_from_settings(s)
    # The body at the first frame's speed (a keyed speed's property value is the current frame's).
    figure = replace(figure, body=replace(figure.body, V_cm=speed(0.0)))
    controller = controller_from_settings(obj, figure, frames)
    state0 = start_state(obj, controller, start)
    skidding = skidding_from_settings(obj, frames)
    paper = ground is None and skidding is None and speed.constant_value is not None
    dt = coarse_dt if coarse_dt is not None and paper else DEFAULT_DT
    duration = frames.duration - offset + 2 * dt
    if ground is None:
        if skidding is not None and speed.constant_value is None:
            raise SceneInputError("a Stop or a Style other than Carve (turning.skid) brakes the "
                                  "figure: the Speed cannot be keyed as well")
        traj = simulate(figure, controller, duration, dt, state0=state0, meta={"figure": obj.name},
                        speed=None if skidding is not None else speed, skidding=skidding)
        traj = with_turn(traj, controller)             # the lean reached, when not the asked
        traj = resampled(on_crowd_clock(traj, offset), shown, origin=frames.start, skip=skip)
        z0 = float(s.start[2]) if height is None else float(height)
        return _with_z(traj, np.full(len(traj), z0))
    target = target_schedule(obj, frames)
    if target is not None and not s.use_heading:
        raise SceneInputError("Target Speed (turning.terrain.target_speed) steers the turns "
                              "across the hill about the Heading: turn on Hold Heading")
    stride = stride if target is None and skidding is None else 1
    traj = simulate(figure, controller, duration, dt,
                    state0=(*state0, speed(0.0)),
                    meta={"figure": obj.name, "ground_object": ground.name},
                    ground=ground.field, resistance=resistance_from_settings(s),
                    target_speed=target, skidding=skidding, stride=stride,
                    keep=skip / frames.fps if offset == 0.0 else 0.0)
    traj = resampled(on_crowd_clock(with_turn(traj, controller), offset), shown, ground.field,
                     frames.start, skip)
    return on_ground(traj, ground)


def surface_normals(traj, ground) -> np.ndarray | None:
    """(n, 3) unit normals of ``ground`` (a :class:`.ground.MeshGround`) under the foot, from its
    smooth field (continuous from frame to frame); ``None`` on flat ground."""
    if ground is None:
        return None
    fr = surface_frame(ground.field, traj.x, traj.y, traj.theta_dir, 9.81)
    return np.asarray(fr.n, float).T


def surface_heights(ground):
    """``(x, y) -> z`` of ``ground`` (a :class:`.ground.MeshGround`: the mesh's own heights);
    ``None`` on flat ground."""
    return None if ground is None else ground.heights


def figure_pose_track(obj, frames: FrameRange, options=None, start=None, height=None,
                      ground="read"):
    """``(trajectory, pose track)`` of the figure ``obj`` over ``frames`` (see
    :func:`simulate_figure`)."""
    if isinstance(ground, str):
        ground = ground_of(obj)
    traj = simulate_figure(obj, frames, start, height, ground)
    shown = started(frames, float(obj.turning.crowd.time_offset))
    return traj, map_track(obj.turning.sport, traj, shown, options, obj,
                           surface_normals(traj, ground), surface_heights(ground))
