"""Figure settings -> trajectory -> pose track: the whole computation before anything is written.

Operators and headless jobs call :func:`figure_pose_track`, then :func:`..bake.bake_pose_track`.
Everything that can fail (bad settings, a fall, a mapping error) fails here, before the scene is
touched.
"""
from __future__ import annotations

from dataclasses import replace

from ..core import DEFAULT_DT, simulate
from .scene_adapters import (FrameRange, controller_from_settings, figure_from_settings,
                             speed_schedule, start_state)


def map_track(sport: str, traj, frames: FrameRange, options=None, obj=None):
    """The sport's Section 7 mapping of ``traj`` (already at ``frames.fps``) to a pose track;
    retargeted onto ``obj`` when it is a figure made from the user's own rig (issue 8)."""
    from ..mapping import map_trajectory      # the mapping layer's entry point
    from . import retarget_adapter
    if obj is not None and (retarget_adapter.is_user_rig(obj) or retarget_adapter.mirrored(obj)):
        return retarget_adapter.figure_track(obj, traj, frames, options)
    return map_trajectory(sport.lower(), traj, options, frame_start=frames.start, fps=frames.fps)


def resampled(traj, frames: FrameRange):
    """``traj`` at every frame of ``frames`` (exactly ``end - start + 1`` samples)."""
    out = traj.resample(frames.fps, start=0.0)
    n = frames.end - frames.start + 1
    if len(out) < n:
        raise ValueError(f"the trajectory covers {len(out)} of {n} frames")
    return type(out)(out.data[:, :n], out.meta)


def simulate_figure(obj, frames: FrameRange, start=None):
    """Simulate the figure ``obj`` (its ``turning`` settings) over ``frames`` from ``start``
    (``(x, y, theta_dir)``, default its Start settings); the trajectory at every frame.  Raises
    ``ValueError`` or the core's ``FellOver``."""
    speed = speed_schedule(obj, frames)
    figure = figure_from_settings(obj.turning)
    # The body at the first frame's speed (a keyed speed's property value is the current frame's).
    figure = replace(figure, body=replace(figure.body, V_cm=speed(0.0)))
    controller = controller_from_settings(obj, figure, frames)
    traj = simulate(figure, controller, frames.duration + 2 * DEFAULT_DT,
                    state0=start_state(obj, controller, start), meta={"figure": obj.name},
                    speed=speed)
    return resampled(traj, frames)


def figure_pose_track(obj, frames: FrameRange, options=None, start=None):
    """``(trajectory, pose track)`` of the figure ``obj`` over ``frames``."""
    traj = simulate_figure(obj, frames, start)
    return traj, map_track(obj.turning.sport, traj, frames, options, obj)
