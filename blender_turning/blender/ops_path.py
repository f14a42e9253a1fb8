"""``turning.follow_path``: the path-following controller (Section 6) on a Bezier curve, around
the ground footprints of a collection's objects.  Modal with a progress bar; ESC cancels and leaves
the scene exactly as it was (nothing is written until the plan is complete)."""
from __future__ import annotations

import math
from dataclasses import replace

import bpy

from ..core.errors import TurningError
from .follow_job import Cancelled, FollowJob
from .ops_bake import apply_bake
from .ops_common import context_figure, poll_figure
from .pipeline import map_track
from .scene_adapters import (FrameRange, SceneInputError, bezier_control_points,
                             figure_from_settings, obstacle_footprints)


def prepare(context, fig) -> FollowJob:
    """Read the scene into a planning job (raises ``ValueError`` naming the bad input)."""
    s = fig.turning
    if s.path is None:
        raise SceneInputError("no path curve set (Follow Path > Path)")
    depsgraph = context.evaluated_depsgraph_get()      # also brings world matrices up to date
    control = bezier_control_points(s.path)
    footprints = obstacle_footprints(s.obstacles, depsgraph)
    figure = figure_from_settings(s)
    if s.plan_curvature_rate > 0:
        figure = replace(figure, limits=replace(figure.limits, dC_f_max=s.plan_curvature_rate))
    return FollowJob(figure, control, footprints)


def finish(context, fig, job, result):
    """Write a finished plan: frame range to fit, F-curves, foot track.  Returns the frames."""
    scene = context.scene
    fps = scene.render.fps / scene.render.fps_base
    n = int(math.floor(result.trajectory.duration * fps + 1e-9))
    frames = FrameRange(scene.frame_start, scene.frame_start + max(n, 1), fps)
    traj = result.trajectory.resample(fps, start=0.0)
    traj = type(traj)(traj.data[:, :frames.end - frames.start + 1], traj.meta)
    track = map_track(fig.turning.sport, traj, frames, obj=fig)   # may raise: nothing written
    scene.frame_end = frames.end
    apply_bake(fig, traj, track)
    return frames


class TURNING_OT_follow_path(bpy.types.Operator):
    """Plan the active figure's turns along its path curve around the obstacles, and bake them"""

    bl_idname = "turning.follow_path"
    bl_label = "Follow Path"
    bl_options = {"REGISTER", "UNDO"}

    _job = None
    _timer = None

    @classmethod
    def poll(cls, context):
        if not poll_figure(cls, context):
            return False
        if context_figure(context).turning.path is None:
            cls.poll_message_set("Set the figure's path curve first (Follow Path > Path)")
            return False
        return True

    def _start(self, context):
        fig = context_figure(context)
        try:
            return fig, prepare(context, fig)
        except (ValueError, TurningError) as exc:
            self.report({"ERROR"}, f"Follow Path: {fig.name}: {exc}")
            return fig, None

    def _complete(self, context, fig, job):
        if job.error is not None:
            if isinstance(job.error, Cancelled):
                self.report({"WARNING"}, "Follow Path cancelled; the scene is unchanged")
                return {"CANCELLED"}
            if isinstance(job.error, (ValueError, TurningError)):
                self.report({"ERROR"}, f"Follow Path: {fig.name}: {job.error}")
                return {"CANCELLED"}
            raise job.error
        try:
            frames = finish(context, fig, job, job.result)
        except (ValueError, TurningError) as exc:
            self.report({"ERROR"}, f"Follow Path: {fig.name}: {exc}")
            return {"CANCELLED"}
        note = "" if job.result.reached_end else " (stopped before the end of the path)"
        self.report({"INFO"}, f"Follow Path: baked {fig.name} over frames "
                              f"{frames.start}-{frames.end}{note}")
        return {"FINISHED"}

    def execute(self, context):
        fig, job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        try:
            job.result = job.run()
        except (Cancelled, ValueError, TurningError) as exc:
            job.error = exc
        return self._complete(context, fig, job)

    def invoke(self, context, event):
        if context.window is None:                       # background / scripted: plan inline
            return self.execute(context)
        fig, job = self._start(context)
        if job is None:
            return {"CANCELLED"}
        self._fig_name, self._job = fig.name, job
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        job.start()
        context.workspace.status_text_set("Follow Path: planning... (Esc to cancel)")
        return {"RUNNING_MODAL"}

    def _cleanup(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
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
        fig = bpy.data.objects.get(self._fig_name)
        if fig is None:
            self.report({"ERROR"}, "Follow Path: the figure was deleted while planning")
            return {"CANCELLED"}
        return self._complete(context, fig, job)


classes = (TURNING_OT_follow_path,)
register, unregister = bpy.utils.register_classes_factory(classes)
