"""``turning.follow_path``: the path-following controller (Section 6) on a Bezier curve, around
the ground footprints of a collection's objects.  Modal with a progress bar; ESC cancels and leaves
the scene exactly as it was (nothing is written until the plan is complete)."""
from __future__ import annotations

import bpy
from bpy.props import FloatProperty

from ...core.errors import PlanInfeasible
from ...core.course.obstacles import Obstacles
from ..anim import user_action
from ..jobs import crowd_job
from ..scene import follow_ground
from ..scene.figure_context import check_figure, end_modal, poll_figure, report_error
from ..jobs.follow_job import Cancelled
from ..scene.follow_scene import finish, prepare
from ..jobs.model_notes import WARN_DISTANCE, follow_note, warn_distance
from ..props.figure import figure_settings


def nearest_obstacle(exc, footprints) -> str:
    """`` (nearest obstacle: 'Wall', 0.4 m away)`` for a plan that failed, or ``''``."""
    if not isinstance(exc, PlanInfeasible) or not footprints:
        return ""
    gaps = [float(Obstacles(polygons=[p]).min_distance(exc.position)[0]) for _, p in footprints]
    k = min(range(len(gaps)), key=gaps.__getitem__)
    return f" (nearest obstacle: {footprints[k][0]!r}, {max(gaps[k], 0.0):.1f} m away)"


class TURNING_OT_follow_path(crowd_job.CrowdOptions, bpy.types.Operator):
    """Plan the selected figures' turns along their path curves around the obstacles, and bake
    them (several figures: in worker processes, one progress bar, avoiding each other in their
    Planning Order)"""

    bl_idname = "turning.follow_path"
    bl_label = "Follow Path"
    bl_options = {"REGISTER", "UNDO"}

    warn_distance: FloatProperty(
        name="Warn Beyond", default=WARN_DISTANCE, min=0.0, soft_max=20.0, unit="LENGTH",
        description="Warn when the planned foot track strays farther than this from the drawn "
                    "path (the report always gives the largest distance and where)")

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
        before = user_action.stashes([fig])
        try:
            frames = finish(context, fig, job, job.result)
        except Exception as exc:
            return report_error(self, "Follow Path", fig.name, exc)
        stashed = user_action.stash_note(fig, before)
        if stashed:
            self.report({"WARNING"}, f"Follow Path: {fig.name}: {stashed}")
        level, note = follow_note(job.path, job.result.trajectory, frames.start, frames.fps,
                                  warn_distance(self))
        if level == "INFO":
            self.report({level}, f"Follow Path: {fig.name}: {note}")
        self.report({"INFO"}, f"Follow Path: baked {fig.name} over frames "
                              f"{frames.start}-{frames.end}{follow_ground.target_speed_note(fig)}")
        if level != "INFO":                   # last: the status bar shows the last report
            self.report({level}, f"Follow Path: {fig.name}: {note}")
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
