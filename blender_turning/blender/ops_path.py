"""``turning.follow_path``: the path-following controller (Section 6) on a Bezier curve, around
the ground footprints of a collection's objects.  Modal with a progress bar; ESC cancels and leaves
the scene exactly as it was (nothing is written until the plan is complete)."""
from __future__ import annotations

import math
from dataclasses import replace

import bpy

from ..core.errors import PlanInfeasible
from ..core.follow_problem import DEFAULT_CLEARANCE
from ..core.obstacles import Obstacles
from . import bake, crowd_job, follow_ground
from .follow_job import Cancelled, FollowJob
from .ops_bake import apply_bake
from .ops_common import check_figure, end_modal, poll_figure, report_error
from .pipeline import map_track, on_ground, surface_heights, surface_normals
from .props import figure_settings
from .scene_adapters import (FrameRange, SceneInputError, bezier_control_points,
                             figure_from_settings, obstacle_footprints)

#: Distance the plan keeps from every obstacle footprint, m.


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
                f"{name!r} (collection {collection.name!r}; the plan keeps {DEFAULT_CLEARANCE} m from "
                "every obstacle): move the path's first point or the obstacle, or take the "
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


def nearest_obstacle(exc, footprints) -> str:
    """`` (nearest obstacle: 'Wall', 0.4 m away)`` for a plan that failed, or ``''``."""
    if not isinstance(exc, PlanInfeasible) or not footprints:
        return ""
    gaps = [float(Obstacles(polygons=[p]).min_distance(exc.position)[0]) for _, p in footprints]
    k = min(range(len(gaps)), key=gaps.__getitem__)
    return f" (nearest obstacle: {footprints[k][0]!r}, {max(gaps[k], 0.0):.1f} m away)"


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


class TURNING_OT_follow_path(crowd_job.CrowdOptions, bpy.types.Operator):
    """Plan the selected figures' turns along their path curves around the obstacles, and bake
    them (several figures: in worker processes, one progress bar, avoiding each other in their
    Planning Order)"""

    bl_idname = "turning.follow_path"
    bl_label = "Follow Path"
    bl_options = {"REGISTER", "UNDO"}

    _job = None
    _crowd = None                       # several figures: a crowd_job.CrowdFollow
    _timer = None

    @classmethod
    def poll(cls, context):
        if not poll_figure(cls, context):
            return False
        if not crowd_job.follow_figures(context):
            cls.poll_message_set("Set the figure's path curve first (Follow Path > Path)")
            return False
        return True

    def _start(self, context):
        fig = crowd_job.follow_figures(context)[0]
        try:
            return fig, prepare(context, fig)
        except Exception as exc:
            report_error(self, "Follow Path", fig.name, exc)
            return fig, None

    def _complete(self, context, fig, job):
        if job.error is not None:
            if isinstance(job.error, Cancelled):
                self.report({"WARNING"}, "Follow Path cancelled; the scene is unchanged")
                return {"CANCELLED"}
            note = nearest_obstacle(job.error, getattr(job, "footprints", ()))
            note += follow_ground.edge_note(job.error, getattr(job, "mesh_ground", None),
                                            job.problem.reach())
            return report_error(self, "Follow Path", fig.name, job.error, note)
        try:
            frames = finish(context, fig, job, job.result)
        except Exception as exc:
            return report_error(self, "Follow Path", fig.name, exc)
        self.report({"INFO"}, f"Follow Path: baked {fig.name} over frames "
                              f"{frames.start}-{frames.end}{follow_ground.target_speed_note(fig)}")
        return {"FINISHED"}

    def execute(self, context):
        figs = crowd_job.follow_figures(context)
        if crowd_job.needs_crowd(figs):
            return crowd_job.run_crowd_inline(self, context, figs)
        fig, job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        try:
            job.result = job.run()
        except Exception as exc:
            job.error = exc
        return self._complete(context, fig, job)

    def invoke(self, context, event):
        if context.window is None:                       # background / scripted: plan inline
            return self.execute(context)
        figs = crowd_job.follow_figures(context)
        if crowd_job.needs_crowd(figs):
            self._crowd = crowd_job.prepare_crowd(self, context, figs)
            if self._crowd is None:
                return {"CANCELLED"}
            self._begin_modal(context)
            self._crowd.start()
            crowd_job.status(context, self._crowd)
            return {"RUNNING_MODAL"}
        fig, job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        # By session id, not name or Python reference: the user may rename the figure while it
        # plans, and an undo step reloads every ID (a kept reference would dangle).
        self._fig_uid, self._job = fig.session_uid, job
        self._begin_modal(context)
        job.start()
        context.workspace.status_text_set("Follow Path: planning... (Esc to cancel)")
        return {"RUNNING_MODAL"}

    def _begin_modal(self, context):
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)

    def _cleanup(self, context):
        end_modal(self, context)

    def cancel(self, context):
        """Blender ends the operator without an event (a file is opened, or Blender quits): stop
        the planner thread (or the worker processes) and write nothing."""
        if getattr(self, "_crowd", None) is not None:      # (tests' stand-ins lack it)
            self._crowd.cancel()
        if self._job is not None:
            self._job.cancel(wait=True)
        self._cleanup(context)

    def modal(self, context, event):
        if getattr(self, "_crowd", None) is not None:
            return crowd_job.crowd_modal(self, context, event)
        job = self._job
        if event.type == "ESC":
            job.cancel(wait=True)
            self._cleanup(context)
            self.report({"WARNING"}, "Follow Path cancelled; the scene is unchanged")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        finished = job.done()           # read first: the thread may end between the two reads
        context.window_manager.progress_update(100 if finished else int(100 * job.progress))
        if not finished:
            return {"RUNNING_MODAL"}
        self._cleanup(context)
        fig = next((o for o in bpy.data.objects if o.session_uid == self._fig_uid), None)
        if fig is None or figure_settings(fig) is None:
            self.report({"ERROR"}, "Follow Path: the figure was deleted while planning; "
                                   "the scene is unchanged")
            return {"CANCELLED"}
        return self._complete(context, fig, job)


classes = (TURNING_OT_follow_path,)
register, unregister = bpy.utils.register_classes_factory(classes)
