"""Reading a figure's Follow Path settings into a planning job (:class:`.follow_job.FollowJob`):
its path curve, the footprints of its obstacles (never its own objects), its body and limits, and
its Ground mesh; and writing a finished plan (:func:`finish`).  Shared by Follow Path on one
figure and on several, by Add Crowd and by Live Preview."""
from __future__ import annotations

import math
from dataclasses import replace

from ...core.course.follow_problem import DEFAULT_CLEARANCE
from ...core.course.obstacles import Obstacles
from ..anim import bake
from . import follow_ground
from ..anim.figure_bake import apply_bake
from .figure_context import check_figure
from ..jobs.follow_job import FollowJob
from ..jobs.pipeline import map_track, on_ground, surface_heights, surface_normals
from .scene_adapters import (FrameRange, SceneInputError, bezier_control_points,
                             figure_from_settings, obstacle_footprints)


def own_objects(fig) -> set:
    """The figure's own objects, never its obstacles: its armature, body and equipment (children),
    its foot track, its path curve and its Ground mesh."""
    own = {fig, *fig.children_recursive}
    s = fig.turning
    own.update(o for o in (s.foot_track, s.path, s.ground) if o is not None)
    return own


def check_start_clear(control, footprints, collection) -> None:
    """Refuse a path that starts inside an obstacle (with the clearance), naming the obstacle."""
    start = control[:1]
    for name, poly in footprints:
        gap = float(Obstacles(polygons=[poly], clearance=DEFAULT_CLEARANCE).min_distance(start)[0])
        if gap <= DEFAULT_CLEARANCE:
            raise SceneInputError(
                f"the path starts {'inside' if gap < 0 else f'{gap:.2f} m from'} obstacle "
                f"{name!r} (collection {collection.name!r}; the plan keeps {DEFAULT_CLEARANCE} m "
                "from every obstacle): move the path's first point or the obstacle, or take the "
                "object out of the collection")


def prepare(context, fig) -> FollowJob:
    """Read the scene into a planning job (raises ``ValueError`` naming the bad input)."""
    s = fig.turning
    if s.path is None:
        raise SceneInputError("no path curve set (Follow Path > Path)")
    check_figure(fig)
    depsgraph = context.evaluated_depsgraph_get()      # also brings world matrices up to date
    control = bezier_control_points(s.path)
    footprints = obstacle_footprints(s.obstacles, depsgraph, exclude=own_objects(fig))
    check_start_clear(control, footprints, s.obstacles)
    figure = figure_from_settings(s)
    if s.plan_curvature_rate > 0:
        figure = replace(figure, limits=replace(figure.limits, dC_f_max=s.plan_curvature_rate))
    figure, ground, terrain = follow_ground.plan_inputs(context, fig, figure, depsgraph)
    job = FollowJob(figure, control, footprints, clearance=DEFAULT_CLEARANCE, **terrain)
    follow_ground.check_path_on_ground(s.path, job.path, ground)     # flat: nothing to check
    job.footprints = footprints                        # names, for the report of a failed plan
    job.mesh_ground = ground
    return job


def finish(context, fig, job, result):
    """Write a finished plan: frame range to fit, F-curves, foot track.  Returns the frames."""
    scene = context.scene
    fps = scene.render.fps / scene.render.fps_base
    n = int(math.floor(result.trajectory.duration * fps + 1e-9))
    frames = FrameRange(scene.frame_start, scene.frame_start + max(n, 1), fps)
    ground = getattr(job, "mesh_ground", None)
    traj = result.trajectory.resample(fps, start=0.0, ground=getattr(ground, "field", None))
    traj = type(traj)(traj.data[:, :frames.end - frames.start + 1], traj.meta)
    if ground is not None:
        traj = on_ground(traj, ground)    # the foot on the mesh, as a terrain Bake Turns
    check_figure(fig)                     # the rig may have changed while the plan ran
    track = map_track(fig.turning.sport, traj, frames, obj=fig,   # may raise: nothing written
                      normal=surface_normals(traj, ground), surface=surface_heights(ground))
    bake.check_track(fig, track)
    scene.frame_end = frames.end
    apply_bake(fig, traj, track)
    return frames
